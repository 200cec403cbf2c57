//! Box (orthogonal range) queries: every pivot policy × median algorithm × leaf size gives
//! exactly the brute-force answer (same caller indices, ascending) for boxes through stored
//! points (so points lie on the faces), zero-extent boxes, boxes with infinite bounds, boxes
//! outside the points and boxes covering all; the batch equals the single queries for any
//! thread count; inverted and NaN boxes are refused with `InvalidBox`.

mod common;

use common::{points, to_f32, Kind, Rng, KINDS};
use nbhd::NeighborIndex;
use nbhd::{
    BruteForce, BuildOptions, KdTree, MedianAlgorithm, NbhdError, NonFinitePolicy, PivotPolicy,
    PointsView, Scalar,
};
use proptest::prelude::*;

const LEAF_SIZES: [usize; 3] = [1, 3, 12];

/// Boxes as `min ++ max`: random corners from stored coordinates (faces through points),
/// zero-extent in one and in all coordinates, half-infinite, all of space, and far away.
fn boxes<T: Scalar>(coords: &[T], d: usize, rng: &mut Rng) -> Vec<Vec<T>> {
    let n = coords.len() / d;
    let coord = |i: usize, j: usize| coords[i * d + j];
    let mut out = Vec::new();
    for _ in 0..6 {
        let (a, b) = (rng.below(n), rng.below(n));
        let mut bx = vec![T::ZERO; 2 * d];
        for j in 0..d {
            let (x, y) = (coord(a, j), coord(b, j));
            bx[j] = if x < y { x } else { y };
            bx[d + j] = if x < y { y } else { x };
        }
        out.push(bx.clone());
        // the same box flattened to the plane of point a in coordinate 0
        let mut flat = bx.clone();
        flat[0] = coord(a, 0);
        flat[d] = coord(a, 0);
        out.push(flat);
        // half-infinite in the last coordinate
        let mut half = bx;
        half[d - 1] = T::from_f64(f64::NEG_INFINITY);
        out.push(half);
    }
    // a single point as a box (zero extent everywhere): its duplicates exactly
    let p = rng.below(n);
    out.push((0..2 * d).map(|j| coord(p, j % d)).collect());
    // all of space, and a box far away from every point
    let mut all = vec![T::from_f64(f64::NEG_INFINITY); d];
    all.extend(vec![T::INFINITY; d]);
    out.push(all);
    let mut far = vec![T::from_f64(1e6); d];
    far.extend(vec![T::from_f64(2e6); d]);
    out.push(far);
    out
}

fn check_set<T: Scalar>(coords: &[T], d: usize, seed: u64) {
    let view = PointsView::from_flat(coords, d).unwrap();
    let brute = BruteForce::<T>::new(&view, NonFinitePolicy::Reject).unwrap();
    let mut rng = Rng::new(seed ^ 0xB0C5);
    let boxes = boxes(coords, d, &mut rng);
    let flat: Vec<T> = boxes.concat();
    let (mut want, mut got) = (Vec::new(), Vec::new());
    for pivot in PivotPolicy::ALL {
        for median in MedianAlgorithm::ALL {
            for leaf_size in LEAF_SIZES {
                let opts = BuildOptions {
                    pivot,
                    median,
                    leaf_size,
                    ..BuildOptions::default()
                };
                let tree = KdTree::<T>::build(&view, &opts).unwrap();
                for bx in &boxes {
                    let (min, max) = bx.split_at(d);
                    brute.in_box(min, max, &mut want).unwrap();
                    tree.in_box(min, max, &mut got).unwrap();
                    assert_eq!(got, want, "{pivot:?} {median:?} leaf {leaf_size} {bx:?}");
                }
                let one = tree.in_boxes(&flat, 1).unwrap();
                let many = tree.in_boxes(&flat, 3).unwrap();
                assert_eq!(one, many);
                assert_eq!(one.len(), boxes.len());
                for (i, bx) in boxes.iter().enumerate() {
                    let (min, max) = bx.split_at(d);
                    brute.in_box(min, max, &mut want).unwrap();
                    assert_eq!(one.row(i), &want[..]);
                }
            }
        }
    }
}

fn run(kind_index: usize, n: usize, d: usize, seed: u64) {
    let kind: Kind = KINDS[kind_index];
    let coords = points(kind, n, d, seed);
    check_set::<f64>(&coords, d, seed);
    check_set::<f32>(&to_f32(&coords), d, seed);
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 10, ..ProptestConfig::default() })]

    #[test]
    fn boxes_match_brute_force_1d(kind in 0..KINDS.len(), n in 1usize..120, seed in any::<u64>()) {
        run(kind, n, 1, seed);
    }

    #[test]
    fn boxes_match_brute_force_2d(kind in 0..KINDS.len(), n in 1usize..120, seed in any::<u64>()) {
        run(kind, n, 2, seed);
    }

    #[test]
    fn boxes_match_brute_force_3d(kind in 0..KINDS.len(), n in 1usize..200, seed in any::<u64>()) {
        run(kind, n, 3, seed);
    }

    #[test]
    fn boxes_match_brute_force_5d(kind in 0..KINDS.len(), n in 1usize..120, seed in any::<u64>()) {
        run(kind, n, 5, seed);
    }
}

#[test]
fn every_kind_in_3d() {
    for kind in 0..KINDS.len() {
        run(kind, 300, 3, 7 + kind as u64);
    }
}

#[test]
fn bad_boxes_are_refused() {
    let coords = points(Kind::Random, 50, 3, 1);
    let view = PointsView::from_flat(&coords, 3).unwrap();
    let tree = KdTree::<f64>::build(&view, &BuildOptions::default()).unwrap();
    let mut out = vec![7];
    let e = tree
        .in_box(&[0.0, 1.0, 0.0], &[1.0, 0.0, 1.0], &mut out)
        .unwrap_err();
    assert_eq!(
        e,
        NbhdError::InvalidBox {
            query: None,
            coordinate: 1,
            min: 1.0,
            max: 0.0
        }
    );
    assert!(matches!(
        tree.in_box(&[0.0, 0.0, f64::NAN], &[1.0; 3], &mut out),
        Err(NbhdError::InvalidBox { coordinate: 2, .. })
    ));
    assert!(matches!(
        tree.in_box(&[0.0; 2], &[1.0; 2], &mut out),
        Err(NbhdError::DimensionMismatch {
            expected: 3,
            got: 2
        })
    ));
    // a batch names the box
    let batch = [
        0.0,
        0.0,
        0.0,
        1.0,
        1.0,
        1.0,
        0.0,
        0.0,
        0.0,
        1.0,
        f64::NAN,
        1.0,
    ];
    assert!(matches!(
        tree.in_boxes(&batch, 2),
        Err(NbhdError::InvalidBox {
            query: Some(1),
            coordinate: 1,
            ..
        })
    ));
    assert!(matches!(
        tree.in_boxes(&batch[..7], 2),
        Err(NbhdError::BufferTooSmall { .. })
    ));
    // an empty batch is an empty result
    assert!(tree.in_boxes(&[], 0).unwrap().is_empty());
}

/// Skipped (non-finite) points are never in a box, not even one covering all of space.
#[test]
fn skipped_points_are_never_inside() {
    let coords = [0.0, 0.0, f64::NAN, 1.0, 2.0, 2.0];
    let view = PointsView::from_flat(&coords, 2).unwrap();
    let opts = BuildOptions {
        non_finite: NonFinitePolicy::Skip,
        ..BuildOptions::default()
    };
    let tree = KdTree::<f64>::build(&view, &opts).unwrap();
    let mut out = Vec::new();
    tree.in_box(&[f64::NEG_INFINITY; 2], &[f64::INFINITY; 2], &mut out)
        .unwrap();
    assert_eq!(out, [0, 2]);
}
