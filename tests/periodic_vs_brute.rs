//! Periodic trees (a torus, `KdTree::build_periodic`, `DynamicKdTree::new_periodic`) against a
//! brute force written here from the definition: every axis difference taken at its nearest
//! image (`min(t, L − t)`), queries wrapped into `[0, L)`, rows ordered by `(key, index)`.
//! For p ∈ {1, 1.5, 2, 3, ∞}, f32 and f64, d ∈ {1, 2, 3, 5}, boxes periodic on every axis and
//! on some (open axes of size 0 beside them), every pivot policy: the static and the growing
//! tree give the brute force's neighbours and keys bit for bit for the k nearest, radius and
//! ε-k queries (inclusive and strict), on random points with points exactly at 0 and just
//! below L, on a grid of step L/4 (ties everywhere, points at exactly L/2 across the edge) and
//! on copies of a few points, with radii beyond L/2 and beyond L; queries shifted by whole
//! boxes give the same rows; tables are identical on 1 and 2 threads. Points outside the box
//! and bad boxes are refused.

mod common;

use common::keys::key;
use common::trees::static_and_growing;
use common::Rng;
use nbhd::{
    BuildOptions, DynamicKdTree, KdTree, NbhdError, Neighbor, NeighborIndex, Neighborhood,
    PivotPolicy, PointsView, Query, QueryOptions, Scalar, TableOptions,
};

const PS: [f64; 5] = [1.0, 1.5, 2.0, 3.0, f64::INFINITY];
const DIMS: [usize; 4] = [1, 2, 3, 5];

/// The box sizes of a test: `L` on every axis (`mixed` false) or on the even axes only, the
/// odd ones open (size 0); returned as given and as the brute force uses them (∞ for open).
fn boxes(d: usize, l: f64, mixed: bool) -> (Vec<f64>, Vec<f64>) {
    let given: Vec<f64> = (0..d)
        .map(|j| if mixed && j % 2 == 1 { 0.0 } else { l })
        .collect();
    let sizes = given
        .iter()
        .map(|&s| if s == 0.0 { f64::INFINITY } else { s })
        .collect();
    (given, sizes)
}

/// Points in the box `sizes` (open axes: in `[-1, 2)`): random with the first point at 0 and
/// the second just below L; a grid of step L/4; copies of a few points.
fn cloud(kind: usize, n: usize, sizes: &[f64], seed: u64) -> Vec<f64> {
    let mut rng = Rng::new(seed);
    let d = sizes.len();
    let mut v = Vec::with_capacity(n * d);
    for i in 0..n {
        for &l in sizes {
            let (lo, span) = if l.is_finite() { (0.0, l) } else { (-1.0, 3.0) };
            let x = match kind {
                0 if i == 0 && l.is_finite() => 0.0,
                0 if i == 1 && l.is_finite() => f64::from_bits(l.to_bits() - 1), // below L
                0 => lo + rng.unit() * span,
                1 => lo + rng.below(4) as f64 * span / 4.0,
                _ => lo + (rng.below(3) as f64 + 0.5) * span / 3.0,
            };
            v.push(if l.is_finite() && x >= l { 0.0 } else { x });
        }
    }
    v
}

/// The brute force's answer: every point (but `exclude`) by `(key, index)`, cut as `nbhd`
/// asks under `options` (exact).
fn brute<T: Scalar>(
    coords: &[T],
    sizes: &[T],
    q: &[T],
    exclude: Option<u32>,
    nbhd: Neighborhood<T>,
    options: &QueryOptions,
) -> Vec<Neighbor<T>> {
    let d = sizes.len();
    let mut all: Vec<Neighbor<T>> = coords
        .chunks_exact(d)
        .enumerate()
        .filter(|&(i, _)| Some(i as u32) != exclude)
        .map(|(i, p)| Neighbor {
            index: i as u32,
            sq_dist: key(options.metric, q, p, sizes),
        })
        .collect();
    all.sort_by(|a, b| a.cmp_by_distance(b));
    let admits = |r: T, nb: &Neighbor<T>| {
        let k = options.metric.key_of(r);
        if options.strict {
            nb.sq_dist < k
        } else {
            nb.sq_dist <= k
        }
    };
    match nbhd {
        Neighborhood::Knn { k } => all.truncate(k),
        Neighborhood::Radius { radius, .. } => all.retain(|nb| admits(radius, nb)),
        Neighborhood::KnnRadius { k, radius } => {
            all.retain(|nb| admits(radius, nb));
            all.truncate(k);
        }
    }
    all
}

/// The queries: stored points (with and without themselves), and free points — a stored
/// point moved, the corners 0 and L, points outside the box — each also shifted by whole
/// boxes (which must not change its row).
fn free_queries<T: Scalar>(coords: &[T], sizes: &[f64], rng: &mut Rng) -> Vec<Vec<T>> {
    let d = sizes.len();
    let n = coords.len() / d;
    let s = rng.below(n);
    let moved: Vec<f64> = (0..d)
        .map(|j| coords[s * d + j].to_f64() + (rng.unit() - 0.5) * 0.4)
        .collect();
    let per = |f: &dyn Fn(f64) -> f64| -> Vec<f64> {
        sizes
            .iter()
            .map(|&l| if l.is_finite() { f(l) } else { 0.5 })
            .collect()
    };
    let mut qs = vec![
        moved.clone(),
        per(&|_| 0.0),
        per(&|l| l),
        per(&|l| -0.3 * l),
        per(&|l| 1.7 * l),
    ];
    // whole boxes away: -L and +2L on the periodic axes
    for shift in [-1.0, 2.0] {
        qs.push(
            moved
                .iter()
                .zip(sizes)
                .map(|(&x, &l)| if l.is_finite() { x + shift * l } else { x })
                .collect(),
        );
    }
    qs.iter()
        .map(|q| q.iter().map(|&x| T::from_f64(x)).collect())
        .collect()
}

fn check<T: Scalar>(coords: &[T], given: &[f64], sizes: &[f64], options: &QueryOptions, seed: u64) {
    let d = given.len();
    let n = coords.len() / d;
    let sizes_t: Vec<T> = sizes.iter().map(|&l| T::from_f64(l)).collect();
    let mut rng = Rng::new(seed);
    let free = free_queries(coords, sizes, &mut rng);
    let stored: Vec<u32> = (0..3).map(|_| rng.below(n) as u32).collect();
    let l = sizes.iter().copied().find(|l| l.is_finite()).unwrap();
    for pivot in PivotPolicy::ALL {
        let (tree, growing) = static_and_growing(coords, d, Some(given), pivot);
        for radius in [0.3 * l, 0.6 * l, 1.5 * l] {
            let radius = T::from_f64(radius);
            let nbhds = [
                Neighborhood::Knn { k: 1 },
                Neighborhood::Knn { k: 5 },
                Neighborhood::Knn { k: n + 2 },
                Neighborhood::Radius {
                    radius,
                    sorted: true,
                },
                Neighborhood::KnnRadius { k: 4, radius },
            ];
            for nbhd in nbhds {
                let check_one = |query: Query<'_, T>, q: &[T], exclude: Option<u32>| {
                    let want = brute(coords, &sizes_t, q, exclude, nbhd, options);
                    let (mut got, mut grown) = (Vec::new(), Vec::new());
                    tree.search_with(query, nbhd, options, &mut got).unwrap();
                    growing
                        .search_with(query, nbhd, options, &mut grown)
                        .unwrap();
                    let what = format!("{options:?} {pivot:?} {nbhd:?} {query:?} box {given:?}");
                    assert_eq!(got, want, "tree: {what}");
                    assert_eq!(grown, want, "growing tree: {what}");
                };
                for &s in &stored {
                    let p = &coords[s as usize * d..(s as usize + 1) * d];
                    check_one(Query::stored(s), p, None);
                    check_one(Query::stored_excluding_self(s), p, Some(s));
                }
                for q in &free {
                    check_one(Query::point(q), q, None);
                }
            }
        }
        check_tables(
            &tree,
            &growing,
            coords,
            &sizes_t,
            options,
            T::from_f64(0.6 * l),
        );
    }
}

/// Tables: the plain methods and the tables answer periodically too, on 1 and 2 threads, for
/// both flavours, each row the brute force's.
fn check_tables<T: Scalar>(
    tree: &KdTree<T>,
    growing: &DynamicKdTree<T>,
    coords: &[T],
    sizes: &[T],
    options: &QueryOptions,
    radius: T,
) {
    let d = sizes.len();
    for nbhd in [
        Neighborhood::Knn { k: 4 },
        Neighborhood::Radius {
            radius,
            sorted: true,
        },
    ] {
        let table = |threads| TableOptions {
            threads,
            exclude_self: true,
            query: *options,
        };
        let one = tree.neighborhoods(nbhd, &table(1)).unwrap();
        let two = tree.neighborhoods(nbhd, &table(2)).unwrap();
        let grown = growing.neighborhoods(nbhd, &table(2)).unwrap();
        assert_eq!(one, two, "threads: {options:?} {nbhd:?}");
        assert_eq!(one, grown, "growing: {options:?} {nbhd:?}");
        let batch = tree
            .neighborhoods_of(&PointsView::from_flat(coords, d).unwrap(), nbhd, &table(2))
            .unwrap();
        for i in (0..coords.len() / d).step_by(5) {
            let p = &coords[i * d..(i + 1) * d];
            let want = brute(coords, sizes, p, Some(i as u32), nbhd, options);
            let row: Vec<Neighbor<T>> = one
                .indices_of(i)
                .iter()
                .zip(one.sq_dists_of(i))
                .map(|(&index, &sq_dist)| Neighbor { index, sq_dist })
                .collect();
            assert_eq!(row, want, "table row {i}: {options:?} {nbhd:?}");
            let with_self = brute(coords, sizes, p, None, nbhd, options);
            assert_eq!(
                batch.indices_of(i),
                with_self.iter().map(|n| n.index).collect::<Vec<_>>()
            );
        }
    }
}

fn run<T: Scalar>(n: usize, seed: u64) {
    for &d in &DIMS {
        for (l, mixed) in [(1.0, false), (0.7, true), (2.5, false)] {
            let (given, sizes) = boxes(d, l, mixed && d > 1);
            for kind in 0..3 {
                let coords: Vec<T> = cloud(kind, n, &sizes, seed + kind as u64)
                    .iter()
                    .map(|&x| T::from_f64(x))
                    .collect();
                // a coordinate that rounds up to L in `T` is not in the box: 0 instead
                let coords: Vec<T> = coords
                    .chunks_exact(d)
                    .flat_map(|p| {
                        p.iter().zip(&sizes).map(
                            |(&x, &l)| {
                                if x >= T::from_f64(l) {
                                    T::ZERO
                                } else {
                                    x
                                }
                            },
                        )
                    })
                    .collect();
                for p in PS {
                    let exact = QueryOptions::with_p(p).unwrap();
                    check(&coords, &given, &sizes, &exact, seed);
                }
                let strict = QueryOptions {
                    strict: true,
                    ..QueryOptions::with_p(2.0).unwrap()
                };
                check(&coords, &given, &sizes, &strict, seed);
                // the plain methods are the default options
                let (tree, _) =
                    static_and_growing(&coords, d, Some(&given), PivotPolicy::SlidingMidpoint);
                let mut plain = Vec::new();
                let q = vec![T::from_f64(-0.1); d];
                tree.knn(Query::point(&q), 3, &mut plain).unwrap();
                let sizes_t: Vec<T> = sizes.iter().map(|&l| T::from_f64(l)).collect();
                let want = brute(
                    &coords,
                    &sizes_t,
                    &q,
                    None,
                    Neighborhood::Knn { k: 3 },
                    &QueryOptions::default(),
                );
                assert_eq!(plain, want, "knn: d {d} box {given:?}");
            }
        }
    }
}

#[test]
fn periodic_queries_equal_the_brute_force_f64() {
    run::<f64>(60, 11);
}

#[test]
fn periodic_queries_equal_the_brute_force_f32() {
    run::<f32>(60, 23);
}

#[test]
fn points_outside_the_box_and_bad_boxes_are_refused() {
    let opts = BuildOptions::default();
    let pts = [0.5f64, 0.25, 0.0, 0.75, 0.5, 1.0];
    let view = PointsView::from_flat(&pts, 2).unwrap();
    // point 2 has y = 1.0 = L: outside [0, 1)
    match KdTree::<f64>::build_periodic(&view, &opts, &[1.0]) {
        Err(NbhdError::OutsidePeriod {
            index: 2,
            coordinate: 1,
            value,
            size,
        }) => assert_eq!((value, size), (1.0, 1.0)),
        other => panic!("{other:?}"),
    }
    // the same axis open: accepted; negative data on a periodic axis: refused
    assert!(KdTree::<f64>::build_periodic(&view, &opts, &[1.0, 0.0]).is_ok());
    let neg = PointsView::from_flat(&[0.5f64, -1e-300], 1).unwrap();
    assert!(matches!(
        KdTree::<f64>::build_periodic(&neg, &opts, &[1.0]),
        Err(NbhdError::OutsidePeriod { index: 1, .. })
    ));
    for bad in [vec![-1.0], vec![f64::NAN], vec![1.0, 1.0, 1.0], vec![1e-50]] {
        assert!(
            matches!(
                KdTree::<f32>::build_periodic(&view, &opts, &bad),
                Err(NbhdError::InvalidOption {
                    name: "boxsize",
                    ..
                })
            ),
            "{bad:?}"
        );
    }
    // no periodic axis: the plain tree
    let open = KdTree::<f64>::build_periodic(&view, &opts, &[0.0, f64::INFINITY]).unwrap();
    assert!(open.period().is_none());
    // a growing tree refuses the batch, naming the position in it, and keeps the earlier ones
    let mut growing = DynamicKdTree::<f64>::new_periodic(2, &opts, &[1.0]).unwrap();
    growing.insert_flat(&[0.1, 0.1]).unwrap();
    assert!(matches!(
        growing.insert_flat(&[0.2, 0.2, 0.3, 1.5]),
        Err(NbhdError::OutsidePeriod {
            index: 1,
            coordinate: 1,
            ..
        })
    ));
    assert_eq!((growing.len(), growing.next_index()), (1, 1));
    assert_eq!(growing.period().unwrap().sizes(), [1.0, 1.0]);
}

/// A radius beyond L/2 still counts each point once, at its nearest image (scipy's rule): on a
/// 1-D box of size 1 the farthest point is 0.5 away whatever the radius.
#[test]
fn each_point_counts_once_at_its_nearest_image() {
    let pts = [0.0f64, 0.25, 0.5, 0.75];
    let view = PointsView::from_flat(&pts, 1).unwrap();
    let tree = KdTree::build_periodic(&view, &BuildOptions::default(), &[1.0]).unwrap();
    let mut out = Vec::new();
    tree.radius(Query::point(&[0.0]), 10.0, &mut out).unwrap();
    let got: Vec<(u32, f64)> = out.iter().map(|n| (n.index, n.sq_dist)).collect();
    assert_eq!(got, [(0, 0.0), (1, 0.0625), (3, 0.0625), (2, 0.25)]);
}

/// Every k-nearest row of `a` and `b` for queries inside, on the edge of and outside the box
/// (wrapped): identical, bit for bit.
fn same_rows<T: Scalar>(a: &impl NeighborIndex<T>, b: &impl NeighborIndex<T>, d: usize, seed: u64) {
    let mut rng = Rng::new(seed);
    let (mut x, mut y) = (Vec::new(), Vec::new());
    for _ in 0..40 {
        let q: Vec<T> = (0..d)
            .map(|_| T::from_f64(rng.unit() * 3.0 - 1.0))
            .collect();
        a.knn(Query::point(&q), 7, &mut x).unwrap();
        b.knn(Query::point(&q), 7, &mut y).unwrap();
        assert_eq!(x, y, "query {q:?}");
    }
}

fn saved_round_trip<T: Scalar>() {
    use nbhd::Persist;
    let d = 3;
    for mixed in [false, true] {
        let (given, sizes) = boxes(d, 1.0, mixed);
        // rounded to T, a point just below L in f64 may reach L: wrapped to 0 as data must be
        let pts: Vec<T> = cloud(0, 300, &sizes, 17)
            .into_iter()
            .enumerate()
            .map(|(i, x)| match T::from_f64(x) {
                t if t.to_f64() >= sizes[i % d] => T::ZERO,
                t => t,
            })
            .collect();
        let view = PointsView::from_flat(&pts, d).unwrap();
        let tree = KdTree::<T>::build_periodic(&view, &BuildOptions::default(), &given).unwrap();
        let bytes = tree.to_bytes();
        let loaded = KdTree::<T>::from_bytes(&bytes).unwrap();
        assert_eq!(loaded.period(), tree.period());
        assert_eq!(loaded.to_bytes(), bytes, "saved again: the same bytes");
        same_rows(&tree, &loaded, d, 3);
        let mut growing =
            DynamicKdTree::<T>::new_periodic(d, &BuildOptions::default(), &given).unwrap();
        growing.insert_flat(&pts[..150 * d]).unwrap();
        growing.insert_flat(&pts[150 * d..]).unwrap();
        growing.remove(&[3, 40, 299]).unwrap();
        let bytes = growing.to_bytes();
        let loaded = DynamicKdTree::<T>::from_bytes(&bytes).unwrap();
        assert_eq!(loaded.period(), growing.period());
        assert_eq!(loaded.to_bytes(), bytes);
        same_rows(&growing, &loaded, d, 4);
        // an empty periodic growing tree keeps its box too
        let empty = DynamicKdTree::<T>::new_periodic(d, &BuildOptions::default(), &given).unwrap();
        let back = DynamicKdTree::<T>::from_bytes(&empty.to_bytes()).unwrap();
        assert_eq!(back.period(), empty.period());
    }
}

/// A saved periodic tree loads with its box (the payload's last section,
/// docs/tree-file-format.md) and answers every query as the saved one, bit for bit; a growing
/// one likewise; an open box is a plain tree and saves as one.
#[test]
fn saved_periodic_trees_load_with_their_box() {
    use nbhd::Persist;
    saved_round_trip::<f32>();
    saved_round_trip::<f64>();
    let view = PointsView::from_flat(&[0.1f64, 0.2, 0.9], 1).unwrap();
    let open = KdTree::<f64>::build_periodic(&view, &BuildOptions::default(), &[0.0]).unwrap();
    let plain = KdTree::<f64>::build(&view, &BuildOptions::default()).unwrap();
    assert_eq!(open.to_bytes(), plain.to_bytes());
}

/// Recomputes both checksums of a saved static tree after a change, as a crafted file would.
fn reseal(bytes: &mut [u8]) {
    let payload = crc32fast::hash(&bytes[128..]);
    bytes[96..100].copy_from_slice(&payload.to_ne_bytes());
    let header = crc32fast::hash(&bytes[..120]);
    bytes[120..124].copy_from_slice(&header.to_ne_bytes());
}

/// Crafted boxes are refused naming why: no periodic axis, a negative size, points outside
/// it, an unknown flag, and a file of the flag without its box (as nbhd wrote before it kept
/// the box).
#[test]
fn crafted_periodic_boxes_are_refused() {
    use nbhd::Persist;
    let view = PointsView::from_flat(&[0.1f64, 0.2, 0.9], 1).unwrap();
    let tree = KdTree::<f64>::build_periodic(&view, &BuildOptions::default(), &[1.0]).unwrap();
    let good = tree.to_bytes();
    let n = good.len();
    let with_size = |l: f64| {
        let mut b = good.clone();
        b[n - 8..].copy_from_slice(&l.to_ne_bytes());
        reseal(&mut b);
        KdTree::<f64>::from_bytes(&b).unwrap_err().to_string()
    };
    assert!(
        with_size(0.0).contains("no periodic axis"),
        "{}",
        with_size(0.0)
    );
    assert!(
        with_size(-1.0).contains("periodic box"),
        "{}",
        with_size(-1.0)
    );
    assert!(with_size(f64::NAN).contains("periodic box"));
    assert!(with_size(0.5).contains("outside"), "{}", with_size(0.5));
    let mut flag = good.clone();
    flag[28..32].copy_from_slice(&2u32.to_ne_bytes());
    reseal(&mut flag);
    let err = KdTree::<f64>::from_bytes(&flag).unwrap_err().to_string();
    assert!(err.contains("byte 28"), "{err}");
    let mut old = good[..n - 8].to_vec();
    let len = (old.len() - 128) as u64;
    old[88..96].copy_from_slice(&len.to_ne_bytes());
    reseal(&mut old);
    let err = KdTree::<f64>::from_bytes(&old).unwrap_err().to_string();
    assert!(err.contains("periodic box"), "{err}");
}
