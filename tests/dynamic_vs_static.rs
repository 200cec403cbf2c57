//! Property tests of the dynamic tree: random interleavings of batch insertions, removals and
//! queries, on every kind of point set (duplicates, identical points, grids) with NaN points,
//! in 1, 2, 3 and 5 dimensions, f32 and f64, over every pivot × median combination. After
//! every step every query kind answers exactly what brute force over the live points answers
//! (same indices, squared distances and order), the all-point and batch tables are the bytes
//! of a static tree built over the live points (the others skipped), for 1 and 2 threads, as
//! are the box queries, the tables of listed points, the spacing and the filters, and the
//! index rule holds (removed indices refused, never reused).

mod common;

use common::{points, Kind, Rng, KINDS};
use nbhd::dynamic::DynamicKdTree;
use nbhd::filter::{
    radius_outlier_removal, statistical_outlier_removal, RadiusOutlierOptions,
    StatisticalOutlierOptions,
};
use nbhd::NeighborIndex;
use nbhd::{
    BruteForce, BuildOptions, KdTree, MedianAlgorithm, NbhdError, NeighborSearch, Neighborhood,
    NonFinitePolicy, PivotPolicy, PointsView, Query, Scalar, TableOptions,
};
use proptest::prelude::*;

/// The model: every index given, its coordinates, and whether it is live.
struct Model<T> {
    dim: usize,
    coords: Vec<T>,
    live: Vec<bool>,
    skipped: Vec<bool>,
}

impl<T: Scalar> Model<T> {
    /// The coordinates of every index, NaN for points not live: a static build over them with
    /// non-finite points skipped is the static tree over the live points, under their indices.
    fn masked(&self) -> Vec<T> {
        let nan = T::from_f64(f64::NAN);
        let mut v = self.coords.clone();
        for (i, &l) in self.live.iter().enumerate() {
            if !l {
                v[i * self.dim..(i + 1) * self.dim].fill(nan);
            }
        }
        v
    }
}

fn kinds<T: Scalar>(k: usize, radius: T) -> Vec<Neighborhood<T>> {
    vec![
        Neighborhood::Knn { k: 1 },
        Neighborhood::Knn { k: 6 },
        Neighborhood::Knn { k: k + 3 },
        Neighborhood::Radius {
            radius,
            sorted: true,
        },
        Neighborhood::KnnRadius { k: 4, radius },
    ]
}

/// Compares the dynamic tree with brute force and a static tree over the model's live points.
fn check<T: Scalar>(tree: &DynamicKdTree<T>, model: &Model<T>, rng: &mut Rng) {
    let d = model.dim;
    let n = model.live.len();
    let live: Vec<u32> = (0..n as u32).filter(|&i| model.live[i as usize]).collect();
    assert_eq!(tree.len(), live.len());
    assert_eq!(tree.next_index() as usize, n);
    let mut got = Vec::new();
    let mut want = Vec::new();
    // Index rule: removed and skipped indices are refused, unknown ones are out of range.
    for i in 0..n as u32 {
        let r = tree.knn(Query::stored(i), 1, &mut got);
        if model.live[i as usize] {
            assert!(r.is_ok());
            assert_eq!(tree.point(i).unwrap(), &model.coords[i as usize * d..][..d]);
        } else if model.skipped[i as usize] {
            assert_eq!(r, Err(NbhdError::SkippedPoint { index: i as usize }));
        } else {
            assert_eq!(r, Err(NbhdError::RemovedPoint { index: i as usize }));
        }
    }
    assert!(matches!(
        tree.knn(Query::stored(n as u32), 1, &mut got),
        Err(NbhdError::IndexOutOfRange { .. })
    ));
    let free: Vec<Vec<T>> = (0..3)
        .map(|_| {
            (0..d)
                .map(|_| T::from_f64(rng.unit() * 2.0 - 0.5))
                .collect()
        })
        .collect();
    if live.is_empty() {
        for q in &free {
            tree.knn(Query::point(q), 3, &mut got).unwrap();
            assert!(got.is_empty());
        }
        let t = tree
            .neighborhoods(Neighborhood::Knn { k: 2 }, &TableOptions::default())
            .unwrap();
        assert_eq!((t.len(), t.total()), (n, 0));
        return;
    }
    let masked = model.masked();
    let view = PointsView::from_flat(&masked, d).unwrap();
    let brute = BruteForce::<T>::new(&view, NonFinitePolicy::Skip).unwrap();
    // A radius through a real neighbour distance, so boundary points exist.
    brute
        .search(
            Query::point(&free[0]),
            Neighborhood::Knn { k: 5 },
            &mut want,
        )
        .unwrap();
    let radius = T::from_f64(want.last().unwrap().sq_dist.to_f64().sqrt());
    let some_live = live[rng.below(live.len())];
    let other_live = live[rng.below(live.len())];
    let mut queries: Vec<Query<'_, T>> = vec![
        Query::stored(some_live),
        Query::stored_excluding_self(some_live),
        Query::stored_excluding_self(other_live),
    ];
    for q in &free {
        queries.push(Query::point(q));
    }
    queries.push(Query::Point {
        coords: &free[1],
        exclude: Some(other_live),
    });
    for nbhd in kinds(live.len(), radius) {
        for &q in &queries {
            tree.search(q, nbhd, &mut got).unwrap();
            brute.search(q, nbhd, &mut want).unwrap();
            assert_eq!(got, want, "{nbhd:?} {q:?}");
        }
    }
    // The unsorted radius query: the same set.
    let unsorted = Neighborhood::Radius {
        radius,
        sorted: false,
    };
    let sorted = Neighborhood::Radius {
        radius,
        sorted: true,
    };
    tree.search(queries[3], unsorted, &mut got).unwrap();
    brute.search(queries[3], sorted, &mut want).unwrap();
    got.sort_by(|a, b| a.cmp_by_distance(b));
    assert_eq!(got, want);
    // Tables: the static tree's bytes, for 1 and 2 threads.
    let stat = KdTree::<T>::build(
        &view,
        &BuildOptions {
            non_finite: NonFinitePolicy::Skip,
            ..*tree.options()
        },
    )
    .unwrap();
    // The batch: the free points, live points (copies among the stored points), a query
    // twice, and points around the live ones, so groups of nearby queries form.
    let mut batch: Vec<Vec<T>> = free.clone();
    for _ in 0..40 {
        let p = live[rng.below(live.len())] as usize;
        let c = &model.coords[p * d..(p + 1) * d];
        batch.push(c.to_vec());
        batch.push(
            c.iter()
                .map(|&x| x + T::from_f64((rng.unit() - 0.5) * 0.05))
                .collect(),
        );
    }
    batch.push(free[1].clone());
    // every live point: a batch dense enough to be answered in groups (`src/dynamic/batch.rs`)
    for &p in &live {
        batch.push(model.coords[p as usize * d..(p as usize + 1) * d].to_vec());
    }
    let flat_free: Vec<T> = batch.concat();
    let qview = PointsView::from_flat(&flat_free, d).unwrap();
    for nbhd in [
        Neighborhood::Knn { k: 4 },
        Neighborhood::KnnRadius { k: 3, radius },
        Neighborhood::Radius {
            radius,
            sorted: true,
        },
    ] {
        for exclude_self in [true, false] {
            let want = stat
                .neighborhoods(
                    nbhd,
                    &TableOptions {
                        exclude_self,
                        threads: 1,
                        ..Default::default()
                    },
                )
                .unwrap();
            for threads in [1, 2] {
                let opts = TableOptions {
                    exclude_self,
                    threads,
                    ..Default::default()
                };
                assert_eq!(tree.neighborhoods(nbhd, &opts).unwrap(), want);
            }
        }
        let want = stat
            .neighborhoods_of(&qview, nbhd, &TableOptions::default())
            .unwrap();
        // every row of the batch is brute force's over the live points
        let mut row = Vec::new();
        for (i, q) in batch.iter().enumerate() {
            brute.search(Query::point(q), nbhd, &mut row).unwrap();
            assert_eq!(
                want.indices_of(i),
                row.iter().map(|n| n.index).collect::<Vec<_>>()
            );
            assert_eq!(
                want.sq_dists_of(i),
                row.iter().map(|n| n.sq_dist).collect::<Vec<_>>()
            );
        }
        for threads in [1, 2] {
            let opts = TableOptions {
                exclude_self: false,
                threads,
                ..Default::default()
            };
            assert_eq!(tree.neighborhoods_of(&qview, nbhd, &opts).unwrap(), want);
        }
    }
    the_rest_of_the_family_matches(tree, &stat, &live, &batch, rng);
}

/// Box queries, tables of listed points, the spacing and the filters of the growing tree: the
/// static tree's answers over the live points, byte for byte (every query of the one index
/// family, `src/index/`, exists for both flavours).
fn the_rest_of_the_family_matches<T: Scalar>(
    tree: &DynamicKdTree<T>,
    stat: &KdTree<T>,
    live: &[u32],
    batch: &[Vec<T>],
    rng: &mut Rng,
) {
    let d = tree.dim();
    // boxes around points of the batch, of random extents, a half-space and a plane
    let mut boxes: Vec<T> = Vec::new();
    for q in batch.iter().take(12) {
        let r = T::from_f64(rng.unit() * 0.3);
        boxes.extend(q.iter().map(|&c| c - r));
        boxes.extend(q.iter().map(|&c| c + r));
    }
    let inf = T::from_f64(f64::INFINITY);
    boxes.extend((0..d).map(|_| T::ZERO - inf));
    boxes.extend((0..d).map(|j| if j == 0 { T::from_f64(0.5) } else { inf }));
    boxes.extend(batch[3].iter().copied());
    boxes.extend(batch[3].iter().copied());
    let (mut got, mut want) = (Vec::new(), Vec::new());
    for b in boxes.chunks_exact(2 * d) {
        let (min, max) = b.split_at(d);
        tree.in_box(min, max, &mut got).unwrap();
        stat.in_box(min, max, &mut want).unwrap();
        assert_eq!(got, want, "box {min:?} {max:?}");
    }
    for threads in [1, 2] {
        assert_eq!(
            tree.in_boxes(&boxes, threads).unwrap(),
            stat.in_boxes(&boxes, 1).unwrap()
        );
    }
    assert_eq!(tree.indices(), live);
    // tables of listed points: some live points, in any order, one twice
    let listed: Vec<u32> = (0..8).map(|_| live[rng.below(live.len())]).collect();
    for nbhd in [
        Neighborhood::Knn { k: 3 },
        Neighborhood::Radius {
            radius: T::from_f64(0.2),
            sorted: true,
        },
    ] {
        let opts = TableOptions::default();
        assert_eq!(
            tree.neighborhoods_at(&listed, nbhd, &opts).unwrap(),
            stat.neighborhoods_at(&listed, nbhd, &opts).unwrap()
        );
    }
    // the spacing and the filters
    assert_eq!(tree.spacing(2), stat.spacing(1));
    let sor = StatisticalOutlierOptions {
        k: 3,
        std_ratio: 0.5,
        threads: 2,
    };
    assert_eq!(
        statistical_outlier_removal(tree, &sor),
        statistical_outlier_removal(stat, &sor)
    );
    for min_neighbors in [0, 2] {
        let ror = RadiusOutlierOptions {
            radius: 0.15,
            min_neighbors,
            threads: 1,
        };
        assert_eq!(
            radius_outlier_removal(tree, &ror).unwrap(),
            radius_outlier_removal(stat, &ror).unwrap()
        );
    }
}

/// Runs `steps` random operations on a tree of dimension `d` over a pool of `kind` points.
fn run<T: Scalar>(kind: Kind, d: usize, options: BuildOptions, seed: u64, steps: usize) {
    let mut rng = Rng::new(seed);
    let mut pool: Vec<T> = points(kind, 600, d, seed)
        .iter()
        .map(|&c| T::from_f64(c))
        .collect();
    // A few NaN and infinite points.
    for _ in 0..8 {
        let i = rng.below(600);
        pool[i * d + rng.below(d)] = T::from_f64(if rng.unit() < 0.5 {
            f64::NAN
        } else {
            f64::INFINITY
        });
    }
    let mut tree = DynamicKdTree::<T>::new(d, &options).unwrap();
    // growth factors 2 to 5: other forests, the same answers
    tree.set_growth(2 + (seed % 4) as usize).unwrap();
    assert!(tree.set_growth(1).is_err());
    let mut model = Model {
        dim: d,
        coords: Vec::new(),
        live: Vec::new(),
        skipped: Vec::new(),
    };
    let mut used = 0;
    for _ in 0..steps {
        let r = rng.unit();
        if r < 0.5 && used < 600 {
            let m = (1 + rng.below(80)).min(600 - used);
            let batch = &pool[used * d..(used + m) * d];
            used += m;
            let first_bad = batch
                .chunks_exact(d)
                .position(|p| p.iter().any(|c| !c.is_finite()));
            let before = tree.next_index();
            let res = tree.insert_flat(batch);
            if options.non_finite == NonFinitePolicy::Reject && first_bad.is_some() {
                assert!(matches!(res, Err(NbhdError::NonFinite { index, .. })
                    if Some(index) == first_bad));
                assert_eq!(tree.next_index(), before);
                continue;
            }
            assert_eq!(res, Ok(before));
            for p in batch.chunks_exact(d) {
                let ok = p.iter().all(|c| c.is_finite());
                model.coords.extend_from_slice(p);
                model.live.push(ok);
                model.skipped.push(!ok);
            }
        } else if r < 0.85 {
            let live: Vec<u32> = (0..model.live.len() as u32)
                .filter(|&i| model.live[i as usize])
                .collect();
            if live.is_empty() {
                continue;
            }
            let victims: Vec<u32> = if rng.unit() < 0.3 {
                // the oldest points, as a sliding window drops them
                live[..1 + rng.below(live.len())].to_vec()
            } else {
                let m = 1 + rng.below(live.len().min(40));
                let mut v: Vec<u32> = (0..m).map(|_| live[rng.below(live.len())]).collect();
                v.sort_unstable();
                v.dedup();
                v.reverse();
                v
            };
            // A removal naming a removed index changes nothing.
            if let Some(dead) = (0..model.live.len()).find(|&i| !model.live[i] && !model.skipped[i])
            {
                let mut bad = victims.clone();
                bad.push(dead as u32);
                assert_eq!(
                    tree.remove(&bad),
                    Err(NbhdError::RemovedPoint { index: dead })
                );
                assert_eq!(tree.len(), live.len());
            }
            tree.remove(&victims).unwrap();
            for &v in &victims {
                model.live[v as usize] = false;
            }
        }
        check(&tree, &model, &mut rng);
    }
    // Named twice in one call: refused, nothing removed.
    if let Some(i) = (0..model.live.len()).find(|&i| model.live[i]) {
        assert_eq!(
            tree.remove(&[i as u32, i as u32]),
            Err(NbhdError::RemovedPoint { index: i })
        );
        assert!(tree.is_live(i as u32));
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(40))]

    #[test]
    fn dynamic_tree_answers_as_the_static_tree_over_the_live_points(
        seed in any::<u64>(),
        kind in 0..KINDS.len(),
        d in prop::sample::select(vec![1usize, 2, 3, 5]),
        pivot in 0..PivotPolicy::ALL.len(),
        median in 0..MedianAlgorithm::ALL.len(),
        leaf_size in prop::sample::select(vec![1usize, 3, 12]),
        skip in any::<bool>(),
        double in any::<bool>(),
    ) {
        let options = BuildOptions {
            pivot: PivotPolicy::ALL[pivot],
            median: MedianAlgorithm::ALL[median],
            leaf_size,
            non_finite: if skip { NonFinitePolicy::Skip } else { NonFinitePolicy::Reject },
            threads: 1,
        };
        if double {
            run::<f64>(KINDS[kind], d, options, seed, 14);
        } else {
            run::<f32>(KINDS[kind], d, options, seed, 14);
        }
    }
}

/// A long sliding window (insert a frame, drop the oldest frame) and a growing cloud, checked
/// against brute force and the static tree at every step: exercises merges, rebuilds after
/// removals, dropped trees and the freeing of old coordinates.
#[test]
fn sliding_window_and_accumulation() {
    for (pivot, median) in [
        (PivotPolicy::SlidingMidpoint, MedianAlgorithm::FloydRivest),
        (PivotPolicy::CyclicMedian, MedianAlgorithm::Presorted),
    ] {
        let options = BuildOptions {
            threads: 2,
            ..BuildOptions::with(pivot, median)
        };
        let d = 3;
        let pool: Vec<f32> = points(Kind::Clustered, 3000, d, 7)
            .iter()
            .map(|&c| c as f32)
            .collect();
        let mut tree = DynamicKdTree::<f32>::new(d, &options).unwrap();
        let mut model = Model {
            dim: d,
            coords: Vec::new(),
            live: Vec::new(),
            skipped: Vec::new(),
        };
        let mut rng = Rng::new(3);
        let frame = 100;
        for f in 0..30 {
            let batch = &pool[f * frame * d..(f + 1) * frame * d];
            assert_eq!(tree.insert_flat(batch), Ok((f * frame) as u32));
            model.coords.extend_from_slice(batch);
            model.live.extend(std::iter::repeat_n(true, frame));
            model.skipped.extend(std::iter::repeat_n(false, frame));
            if f >= 6 {
                let old: Vec<u32> = ((f - 6) * frame..(f - 5) * frame)
                    .map(|i| i as u32)
                    .collect();
                tree.remove(&old).unwrap();
                for &i in &old {
                    model.live[i as usize] = false;
                }
            }
            let stats = tree.stats();
            assert_eq!(stats.trees.iter().map(|t| t.0).sum::<usize>(), tree.len());
            for w in stats.trees.windows(2) {
                assert!(w[0].0 >= 2 * w[1].0, "sizes {:?}", stats.trees);
            }
            for t in &stats.trees {
                assert!(
                    t.1 <= t.0,
                    "a tree with more removed than live {:?}",
                    stats.trees
                );
            }
            check(&tree, &model, &mut rng);
        }
    }
}

/// Bad input is refused with nothing changed.
#[test]
fn bad_input() {
    assert_eq!(
        DynamicKdTree::<f32>::new(0, &BuildOptions::default()).err(),
        Some(NbhdError::ZeroDimension)
    );
    let mut tree = DynamicKdTree::<f64>::new(2, &BuildOptions::default()).unwrap();
    assert!(matches!(
        tree.insert_flat(&[1.0, 2.0, 3.0]),
        Err(NbhdError::BufferTooSmall { .. })
    ));
    let p3 = PointsView::from_flat(&[1.0f64, 2.0, 3.0], 3).unwrap();
    assert!(matches!(
        tree.insert(&p3),
        Err(NbhdError::DimensionMismatch {
            expected: 2,
            got: 3
        })
    ));
    assert!(matches!(
        tree.insert_flat(&[0.0, 0.0, 1.0, f64::NAN]),
        Err(NbhdError::NonFinite {
            index: 1,
            coordinate: 1
        })
    ));
    // f64 values beyond f32 are not finite in an f32 tree
    let mut t32 = DynamicKdTree::<f32>::new(1, &BuildOptions::default()).unwrap();
    assert!(matches!(
        t32.insert(&PointsView::from_flat(&[1.0f64, 1e300], 1).unwrap()),
        Err(NbhdError::NonFinite { index: 1, .. })
    ));
    assert_eq!(tree.next_index(), 0);
    assert_eq!(tree.insert_flat(&[0.0, 0.0, 1.0, 0.0]), Ok(0));
    assert_eq!(tree.insert_flat(&[2.0, 0.0]), Ok(2));
    assert!(matches!(
        tree.remove(&[3]),
        Err(NbhdError::IndexOutOfRange { index: 3, count: 3 })
    ));
    tree.remove(&[1]).unwrap();
    assert_eq!(tree.remove(&[1]), Err(NbhdError::RemovedPoint { index: 1 }));
    assert_eq!(
        tree.remove(&[0, 2, 1]),
        Err(NbhdError::RemovedPoint { index: 1 })
    );
    assert_eq!(tree.len(), 2);
    let mut out = Vec::new();
    assert!(tree
        .knn(Query::point(&[0.0, f64::NAN]), 1, &mut out)
        .is_err());
    // a batch with NaN queries: the first by position is named, nothing else happens
    let batch = [0.0, 0.0, 1.0, f64::NAN, f64::INFINITY, 0.0, 2.0, 2.0];
    let qv = PointsView::from_flat(&batch, 2).unwrap();
    for threads in [1, 2] {
        let opts = TableOptions {
            exclude_self: false,
            threads,
            ..Default::default()
        };
        assert_eq!(
            tree.neighborhoods_of(&qv, Neighborhood::Knn { k: 1 }, &opts),
            Err(NbhdError::NonFiniteQuery {
                query: Some(1),
                coordinate: 1
            })
        );
    }
    assert_eq!(tree.len(), 2);
    assert_eq!(
        tree.knn(Query::point(&[0.0, 0.0]), 0, &mut out),
        Err(NbhdError::ZeroK)
    );
    // a removed index is never given again
    assert_eq!(tree.insert_flat(&[1.0, 0.0]), Ok(3));
    tree.knn(Query::point(&[1.0, 0.0]), 3, &mut out).unwrap();
    let ids: Vec<u32> = out.iter().map(|n| n.index).collect();
    assert_eq!(ids, vec![3, 0, 2]);
    // everything removed: empty answers, then growing again
    tree.remove(&[0, 2, 3]).unwrap();
    assert!(tree.is_empty() && tree.stats().trees.is_empty());
    tree.knn(Query::point(&[1.0, 0.0]), 3, &mut out).unwrap();
    assert!(out.is_empty());
    assert_eq!(tree.insert_flat(&[5.0, 5.0]), Ok(4));
    tree.knn(Query::point(&[1.0, 0.0]), 3, &mut out).unwrap();
    assert_eq!(out.len(), 1);
    assert_eq!(out[0].index, 4);
}
