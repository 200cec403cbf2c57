use super::*;
use crate::error::NbhdError;
use crate::query::brute::BruteForce;
use proptest::prelude::*;

/// SplitMix64 for reproducible test data from one proptest seed.
struct Rng(u64);

impl Rng {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [0, 1).
    fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n as u64) as usize
    }
}

#[derive(Clone, Copy, Debug)]
enum Shape {
    Random,
    /// Unit cube far from the origin: projections and f32 coordinates are coarsely rounded.
    Offset,
    /// Small integer grid: many exact distance ties and duplicates.
    Grid,
    Clustered,
    /// Half the points are copies of three points.
    Duplicates,
    Collinear,
    Identical,
    /// Coordinates around 1e-30: squared differences underflow in f32.
    Tiny,
}

const SHAPES: [Shape; 8] = [
    Shape::Random,
    Shape::Offset,
    Shape::Grid,
    Shape::Clustered,
    Shape::Duplicates,
    Shape::Collinear,
    Shape::Identical,
    Shape::Tiny,
];

fn make_points(shape: Shape, n: usize, d: usize, rng: &mut Rng) -> Vec<f64> {
    let mut pts = Vec::with_capacity(n * d);
    let random = |rng: &mut Rng| (0..d).map(|_| rng.range(-10.0, 10.0)).collect::<Vec<_>>();
    match shape {
        Shape::Random => (0..n * d).for_each(|_| pts.push(rng.range(-10.0, 10.0))),
        Shape::Offset => (0..n * d).for_each(|_| pts.push(1e4 + rng.unit())),
        Shape::Grid => (0..n * d).for_each(|_| pts.push(rng.below(4) as f64)),
        Shape::Tiny => (0..n * d).for_each(|_| pts.push(rng.range(-1e-30, 1e-30))),
        Shape::Clustered => {
            let centres: Vec<Vec<f64>> = (0..3).map(|_| random(rng)).collect();
            for _ in 0..n {
                let c = &centres[rng.below(3)];
                pts.extend(c.iter().map(|x| x + rng.range(-0.01, 0.01)));
            }
        }
        Shape::Duplicates => {
            let bases: Vec<Vec<f64>> = (0..3).map(|_| random(rng)).collect();
            for i in 0..n {
                if i % 2 == 0 {
                    pts.extend_from_slice(&bases[rng.below(3)]);
                } else {
                    pts.extend(random(rng));
                }
            }
        }
        Shape::Collinear => {
            let a = random(rng);
            let dir = random(rng);
            for _ in 0..n {
                let t = rng.range(-1.0, 1.0);
                pts.extend(a.iter().zip(&dir).map(|(x, y)| x + t * y));
            }
        }
        Shape::Identical => {
            let p = random(rng);
            for _ in 0..n {
                pts.extend_from_slice(&p);
            }
        }
    }
    pts
}

/// Radii to try around `q`: 0, the exact distance to a random point (the inclusive boundary),
/// a fraction of it, and one covering everything.
fn radii<T: Scalar>(flat: &[T], d: usize, q: &[T], rng: &mut Rng) -> Vec<T> {
    let n = flat.len() / d;
    let j = rng.below(n);
    let exact = sq_dist(q, &flat[j * d..(j + 1) * d]).to_f64().sqrt();
    vec![
        T::ZERO,
        T::from_f64(exact),
        T::from_f64(exact * 0.37),
        T::from_f64(exact * 1.5 + 1e-3),
        T::from_f64(1e6),
    ]
}

fn neighborhoods<T: Scalar>(n: usize, radii: &[T]) -> Vec<Neighborhood<T>> {
    let mut out = Vec::new();
    for k in [1, 2, 5, n, n + 3] {
        out.push(Neighborhood::Knn { k });
    }
    for &radius in radii {
        out.push(Neighborhood::Radius {
            radius,
            sorted: true,
        });
        out.push(Neighborhood::Radius {
            radius,
            sorted: false,
        });
        for k in [1, 3, n] {
            out.push(Neighborhood::KnnRadius { k, radius });
        }
    }
    out
}

/// Compares PCA sweep and brute force on every neighbourhood kind for a sample of queries.
fn compare<T: Scalar>(
    flat: &[T],
    d: usize,
    max_stored: usize,
    rng: &mut Rng,
) -> std::result::Result<(), String> {
    let n = flat.len() / d;
    let view = PointsView::from_flat(flat, d).map_err(|e| format!("{e:?}"))?;
    let brute = BruteForce::<T>::new(&view, NonFinitePolicy::Reject).unwrap();
    let pca = PcaSweep::<T>::new(&view, NonFinitePolicy::Reject).unwrap();
    let mut queries: Vec<(Vec<T>, Query<'static, T>)> = Vec::new();
    let stored: Vec<usize> = if n <= max_stored {
        (0..n).collect()
    } else {
        (0..max_stored).map(|_| rng.below(n)).collect()
    };
    for &i in &stored {
        let p = flat[i * d..(i + 1) * d].to_vec();
        queries.push((p.clone(), Query::stored(i as u32)));
        queries.push((p, Query::stored_excluding_self(i as u32)));
    }
    let mut points: Vec<(Vec<T>, Option<u32>)> = Vec::new();
    for _ in 0..4 {
        let i = rng.below(n);
        let base = &flat[i * d..(i + 1) * d];
        let jitter: Vec<T> = base
            .iter()
            .map(|&x| T::from_f64(x.to_f64() + rng.range(-0.5, 0.5) * rng.unit()))
            .collect();
        points.push((jitter, None));
        points.push((base.to_vec(), Some(i as u32)));
        points.push((base.to_vec(), Some(rng.below(n) as u32)));
    }
    let (mut a, mut b) = (Vec::new(), Vec::new());
    let mut run = |coords: &[T], query: Query<'_, T>, rng: &mut Rng| {
        for nb in neighborhoods(n, &radii(flat, d, coords, rng)) {
            brute.search(query, nb, &mut a).unwrap();
            pca.search(query, nb, &mut b).unwrap();
            if !nb.is_sorted() {
                a.sort_by(|x, y| x.cmp_by_distance(y));
                b.sort_by(|x, y| x.cmp_by_distance(y));
            }
            if a != b {
                return Err(format!(
                    "{query:?} {nb:?}:\n brute {a:?}\n pca   {b:?}\n axes {:?}",
                    pca.axes()
                ));
            }
        }
        Ok(())
    };
    for (coords, query) in &queries {
        run(coords, *query, rng)?;
    }
    for (coords, exclude) in &points {
        let query = Query::Point {
            coords,
            exclude: *exclude,
        };
        run(coords, query, rng)?;
    }
    Ok(())
}

fn check_shape<T: Scalar>(
    shape: Shape,
    n: usize,
    d: usize,
    max_stored: usize,
    seed: u64,
) -> std::result::Result<(), String> {
    let mut rng = Rng(seed);
    let flat: Vec<T> = make_points(shape, n, d, &mut rng)
        .into_iter()
        .map(T::from_f64)
        .collect();
    compare(&flat, d, max_stored, &mut rng).map_err(|e| format!("{shape:?} n={n} d={d}: {e}"))
}

fn shape() -> impl Strategy<Value = Shape> {
    prop::sample::select(SHAPES.to_vec())
}

fn dimension() -> impl Strategy<Value = usize> {
    prop::sample::select(vec![1usize, 2, 3, 7])
}

proptest! {
    #[test]
    fn same_as_brute_force_f64(shape in shape(), n in 1usize..90, d in dimension(), seed in any::<u64>()) {
        if let Err(e) = check_shape::<f64>(shape, n, d, 24, seed) {
            prop_assert!(false, "{}", e);
        }
    }

    #[test]
    fn same_as_brute_force_f32(shape in shape(), n in 1usize..90, d in dimension(), seed in any::<u64>()) {
        if let Err(e) = check_shape::<f32>(shape, n, d, 24, seed) {
            prop_assert!(false, "{}", e);
        }
    }
}

#[test]
fn larger_sets_every_shape() {
    for (s, shape) in SHAPES.into_iter().enumerate() {
        for d in [1, 2, 3, 7] {
            check_shape::<f32>(shape, 1000, d, 4, 17 + s as u64).unwrap();
            check_shape::<f64>(shape, 1000, d, 4, 91 + s as u64).unwrap();
        }
    }
}

#[test]
fn first_axis_follows_a_line() {
    let pts: Vec<[f64; 3]> = (0..50)
        .map(|i| {
            let t = i as f64;
            [t, t, 0.01 * (i % 3) as f64]
        })
        .collect();
    let view = PointsView::from_rows(&pts).unwrap();
    let pca = PcaSweep::<f64>::new(&view, NonFinitePolicy::Reject).unwrap();
    let a = &pca.axes()[..3];
    let s = std::f64::consts::FRAC_1_SQRT_2;
    assert!((a[0].abs() - s).abs() < 1e-6 && (a[1].abs() - s).abs() < 1e-6);
    assert!(a[2].abs() < 1e-3);
}

#[test]
fn huge_coordinates_scan_everything_and_stay_exact() {
    let pts: Vec<[f64; 2]> = vec![[1e305, 0.0], [-1e305, 1.0], [0.0, 0.0], [1.0, 1.0]];
    let view = PointsView::from_rows(&pts).unwrap();
    let pca = PcaSweep::<f64>::new(&view, NonFinitePolicy::Reject).unwrap();
    let brute = BruteForce::<f64>::new(&view, NonFinitePolicy::Reject).unwrap();
    let (mut a, mut b) = (Vec::new(), Vec::new());
    for nb in [
        Neighborhood::Knn { k: 4 },
        Neighborhood::Radius {
            radius: 2.0,
            sorted: true,
        },
    ] {
        for i in 0..4 {
            brute.search(Query::stored(i), nb, &mut a).unwrap();
            pca.search(Query::stored(i), nb, &mut b).unwrap();
            assert_eq!(a, b);
        }
    }
}

#[test]
fn skipped_points_keep_caller_indices() {
    let pts: Vec<[f32; 2]> = vec![
        [0.0, 0.0],
        [f32::NAN, 1.0],
        [1.0, 0.0],
        [0.0, f32::INFINITY],
        [0.5, 0.5],
    ];
    let view = PointsView::from_rows(&pts).unwrap();
    assert!(matches!(
        PcaSweep::<f32>::new(&view, NonFinitePolicy::Reject),
        Err(NbhdError::NonFinite {
            index: 1,
            coordinate: 0
        })
    ));
    let pca = PcaSweep::<f32>::new(&view, NonFinitePolicy::Skip).unwrap();
    let brute = BruteForce::<f32>::new(&view, NonFinitePolicy::Skip).unwrap();
    assert_eq!(pca.source_len(), 5);
    let (mut a, mut b) = (Vec::new(), Vec::new());
    for i in [0, 2, 4] {
        brute
            .search(Query::stored(i), Neighborhood::Knn { k: 5 }, &mut a)
            .unwrap();
        pca.search(Query::stored(i), Neighborhood::Knn { k: 5 }, &mut b)
            .unwrap();
        assert_eq!(a, b);
        assert_eq!(b.len(), 3);
    }
    assert_eq!(
        pca.search(Query::stored(1), Neighborhood::Knn { k: 1 }, &mut b),
        Err(NbhdError::SkippedPoint { index: 1 })
    );
}

#[test]
fn errors_match_brute_force() {
    let pts: Vec<[f64; 3]> = vec![[0.0, 0.0, 0.0], [1.0, 2.0, 3.0]];
    let view = PointsView::from_rows(&pts).unwrap();
    let pca = PcaSweep::<f64>::new(&view, NonFinitePolicy::Reject).unwrap();
    let brute = BruteForce::<f64>::new(&view, NonFinitePolicy::Reject).unwrap();
    let mut out = Vec::new();
    let cases: Vec<(Query<'_, f64>, Neighborhood<f64>)> = vec![
        (Query::stored(0), Neighborhood::Knn { k: 0 }),
        (
            Query::stored(0),
            Neighborhood::Radius {
                radius: -1.0,
                sorted: true,
            },
        ),
        (
            Query::stored(0),
            Neighborhood::KnnRadius {
                k: 1,
                radius: f64::NAN,
            },
        ),
        (Query::stored(2), Neighborhood::Knn { k: 1 }),
        (Query::point(&[0.0, 0.0]), Neighborhood::Knn { k: 1 }),
        (
            Query::point(&[0.0, f64::NAN, 0.0]),
            Neighborhood::Knn { k: 1 },
        ),
    ];
    for (q, nb) in cases {
        let e1 = brute.search(q, nb, &mut out).unwrap_err();
        let e2 = pca.search(q, nb, &mut out).unwrap_err();
        assert_eq!(format!("{e1:?}"), format!("{e2:?}"));
    }
}
