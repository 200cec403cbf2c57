//! The trees the property tests compare with a brute force: one static tree and one growing
//! tree over the same points, the growing one filled in three inserts (a large tree and two
//! small ones in its forest), both with small leaves so that every path of the traversal runs.

use nbhd::{BuildOptions, DynamicKdTree, KdTree, PivotPolicy, PointsView, Scalar};

/// A static and a growing tree over `coords` (dimension `d`) with `pivot` and leaves of 3
/// points; periodic with `boxsize` when given (`KdTree::build_periodic`,
/// `DynamicKdTree::new_periodic`), plain otherwise.
pub fn static_and_growing<T: Scalar>(
    coords: &[T],
    d: usize,
    boxsize: Option<&[f64]>,
    pivot: PivotPolicy,
) -> (KdTree<T>, DynamicKdTree<T>) {
    let opts = BuildOptions {
        pivot,
        leaf_size: 3,
        ..BuildOptions::default()
    };
    let view = PointsView::from_flat(coords, d).unwrap();
    let (tree, mut growing) = match boxsize {
        Some(b) => (
            KdTree::build_periodic(&view, &opts, b).unwrap(),
            DynamicKdTree::<T>::new_periodic(d, &opts, b).unwrap(),
        ),
        None => (
            KdTree::build(&view, &opts).unwrap(),
            DynamicKdTree::<T>::new(d, &opts).unwrap(),
        ),
    };
    let n = view.len();
    for part in [0..n / 2, n / 2..n * 3 / 4, n * 3 / 4..n] {
        if !part.is_empty() {
            growing
                .insert_flat(&coords[part.start * d..part.end * d])
                .unwrap();
        }
    }
    (tree, growing)
}
