//! Criterion statistics of nbhd against kiddo's immutable tree, f32 and f64 side by side in one
//! group per operation: the build and the four all-point tables (kNN k = 10 and 30, radius with
//! about 20 neighbours, the 16 nearest within it) on torus-77k, kNN k = 10 on the
//! duplicate-heavy half-duplicates-100k, and brute force against nbhd for kNN k = 10 on a
//! 20,000-point subsample of the torus (brute force is quadratic). One thread; every point
//! queries its own set, itself included, and both sides write the whole table. Also the build
//! of every pivot policy on two duplicate-heavy sets (half-duplicates-100k, and 100,000 rows
//! of two points), nbhd only.
//!
//! Run: `cargo bench --bench tables` (a few minutes), or one group:
//! `cargo bench --bench tables -- knn10`. Not run in CI. The side-by-side table over many
//! sets and thread counts is `nbhd bench speed` (cli/README.md).

use std::hint::black_box;
use std::num::NonZero;
use std::time::Duration;

use criterion::{criterion_group, criterion_main, BenchmarkGroup, Criterion};
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use nbhd::shapes::datasets::Dataset;
use nbhd::table::neighborhoods_of_all;
use nbhd::NeighborIndex;
use nbhd::{
    BruteForce, BuildOptions, KdTree, Neighborhood, NonFinitePolicy, PivotPolicy, PointsView,
    Query, QueryOptions, Scalar, TableOptions,
};

/// One thread for both sides.
const ONE: TableOptions = TableOptions {
    exclude_self: false,
    threads: 1,
    query: QueryOptions::DEFAULT,
};

/// A table operation, in the terms of both libraries.
#[derive(Clone, Copy)]
enum Op {
    Knn(usize),
    Radius(f64),
    EpsK(usize, f64),
}

impl Op {
    fn nbhd<T: Scalar>(self) -> Neighborhood<T> {
        match self {
            Op::Knn(k) => Neighborhood::Knn { k },
            Op::Radius(r) => Neighborhood::Radius {
                radius: T::from_f64(r),
                sorted: true,
            },
            Op::EpsK(k, r) => Neighborhood::KnnRadius {
                k,
                radius: T::from_f64(r),
            },
        }
    }
}

/// kiddo over one coordinate type: build, and the all-point table written like nbhd's (row
/// lengths, indices, squared distances; rows in caller order) on the current thread.
trait Peer: Scalar {
    type Tree;
    fn build(points: &[[Self; 3]]) -> Self::Tree;
    fn table(tree: &Self::Tree, points: &[[Self; 3]], op: Op) -> usize;
}

macro_rules! peer {
    ($t:ty) => {
        impl Peer for $t {
            type Tree = ImmutableKdTree<$t, 3>;

            fn build(points: &[[$t; 3]]) -> Self::Tree {
                ImmutableKdTree::new_from_slice(points).unwrap()
            }

            fn table(tree: &Self::Tree, points: &[[$t; 3]], op: Op) -> usize {
                let (mut lens, mut ids, mut dists) = (Vec::new(), Vec::new(), Vec::new());
                for p in points {
                    let q = tree.query(p);
                    let res = match op {
                        Op::Knn(k) => q
                            .nearest_n::<SquaredEuclidean<$t>>(NonZero::new(k).unwrap())
                            .execute(),
                        Op::Radius(r) => q.within::<SquaredEuclidean<$t>>((r * r) as $t).execute(),
                        Op::EpsK(k, r) => q
                            .nearest_n::<SquaredEuclidean<$t>>(NonZero::new(k).unwrap())
                            .within((r * r) as $t)
                            .execute(),
                    };
                    lens.push(res.len());
                    for item in res {
                        ids.push(item.item);
                        dists.push(item.distance);
                    }
                }
                black_box((&lens, &dists));
                ids.len()
            }
        }
    };
}

peer!(f32);
peer!(f64);

/// A set in both coordinate types.
struct Set {
    f32: Vec<[f32; 3]>,
    f64: Vec<[f64; 3]>,
}

impl Set {
    fn new(points: Vec<[f64; 3]>) -> Self {
        Self {
            f32: points.iter().map(|p| p.map(|c| c as f32)).collect(),
            f64: points,
        }
    }
}

fn tree<T: Scalar>(points: &[[T; 3]]) -> KdTree<T> {
    let view = PointsView::from_rows(points).unwrap();
    KdTree::build(&view, &BuildOptions::default()).unwrap()
}

/// The radius giving about 20 neighbours (self included): the median distance to the 21st
/// nearest point over about 2,000 points.
fn radius_for_20(points: &[[f64; 3]]) -> f64 {
    let t = tree(points);
    let mut out = Vec::new();
    let mut d: Vec<f64> = (0..points.len())
        .step_by((points.len() / 2000).max(1))
        .map(|i| {
            t.knn(Query::stored(i as u32), 21, &mut out).unwrap();
            out.last().unwrap().sq_dist.sqrt()
        })
        .collect();
    d.sort_by(f64::total_cmp);
    d[d.len() / 2]
}

/// Small samples and short measurements: the whole bench runs in a few minutes.
fn quick_group<'a>(
    c: &'a mut Criterion,
    name: &str,
) -> BenchmarkGroup<'a, criterion::measurement::WallTime> {
    let mut g = c.benchmark_group(name);
    g.sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(3));
    g
}

/// nbhd and kiddo, f32 and f64, on one table operation.
fn table_group(c: &mut Criterion, name: &str, set: &Set, op: Op) {
    let (t32, t64) = (tree(&set.f32), tree(&set.f64));
    let (k32, k64) = (f32::build(&set.f32), f64::build(&set.f64));
    let mut g = quick_group(c, name);
    g.bench_function("nbhd f32", |b| {
        b.iter(|| t32.neighborhoods(op.nbhd(), &ONE).unwrap().total())
    });
    g.bench_function("nbhd f64", |b| {
        b.iter(|| t64.neighborhoods(op.nbhd(), &ONE).unwrap().total())
    });
    g.bench_function("kiddo f32", |b| b.iter(|| f32::table(&k32, &set.f32, op)));
    g.bench_function("kiddo f64", |b| b.iter(|| f64::table(&k64, &set.f64, op)));
    g.finish();
}

fn build_group(c: &mut Criterion, set: &Set) {
    let one = BuildOptions {
        threads: 1,
        ..BuildOptions::default()
    };
    let (v32, v64) = (
        PointsView::from_rows(&set.f32).unwrap(),
        PointsView::from_rows(&set.f64).unwrap(),
    );
    let mut g = quick_group(c, "build/torus-77k");
    g.bench_function("nbhd f32", |b| {
        b.iter(|| KdTree::<f32>::build(&v32, &one).unwrap())
    });
    g.bench_function("nbhd f64", |b| {
        b.iter(|| KdTree::<f64>::build(&v64, &one).unwrap())
    });
    g.bench_function("kiddo f32", |b| b.iter(|| f32::build(&set.f32)));
    g.bench_function("kiddo f64", |b| b.iter(|| f64::build(&set.f64)));
    g.finish();
}

/// The build of every pivot policy (f32, one thread, the default median algorithm) on a
/// duplicate-heavy set: where a policy's tie handling degenerates, its build goes quadratic
/// (closest to middle took 27 s and depth 50,385 on the two-point set before its ties split
/// the copies of the smallest coordinate off together; tests/tree_degenerate.rs).
fn policy_build_group(c: &mut Criterion, name: &str, points: &[[f32; 3]]) {
    let view = PointsView::from_rows(points).unwrap();
    let mut g = quick_group(c, name);
    for pivot in PivotPolicy::ALL {
        let opts = BuildOptions {
            pivot,
            threads: 1,
            ..BuildOptions::default()
        };
        g.bench_function(pivot.name(), |b| {
            b.iter(|| KdTree::<f32>::build(&view, &opts).unwrap())
        });
    }
    g.finish();
}

/// `n` rows holding one of two points (the case of a build of depth n/2 before the fix).
fn two_points(n: usize) -> Vec<[f32; 3]> {
    let mut rng = nbhd::shapes::Rng::new(37);
    (0..n)
        .map(|_| [if rng.below(2) == 0 { 0.0 } else { 1.0 }; 3])
        .collect()
}

/// Brute force against nbhd, kNN k = 10, f32, on an evenly strided 20,000-point subsample.
fn brute_group(c: &mut Criterion, torus: &Set) {
    let step = torus.f32.len() / 20_000;
    let sub: Vec<[f32; 3]> = torus
        .f32
        .iter()
        .step_by(step)
        .take(20_000)
        .copied()
        .collect();
    let view = PointsView::from_rows(&sub).unwrap();
    let brute = BruteForce::<f32>::new(&view, NonFinitePolicy::Reject).unwrap();
    let t = tree(&sub);
    let nbhd = Neighborhood::Knn { k: 10 };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let mut g = quick_group(c, "knn10/torus-20k-subsample");
    g.bench_function("nbhd f32", |b| {
        b.iter(|| t.neighborhoods(nbhd, &ONE).unwrap().total())
    });
    g.bench_function("brute force f32", |b| {
        b.iter(|| {
            pool.install(|| neighborhoods_of_all(&brute, nbhd, false))
                .unwrap()
                .total()
        })
    });
    g.finish();
}

fn benches(c: &mut Criterion) {
    let torus = Set::new(Dataset::Torus77k.points());
    let r = radius_for_20(&torus.f64);
    build_group(c, &torus);
    table_group(c, "knn10/torus-77k", &torus, Op::Knn(10));
    table_group(c, "knn30/torus-77k", &torus, Op::Knn(30));
    table_group(c, "radius/torus-77k", &torus, Op::Radius(r));
    table_group(c, "epsk/torus-77k", &torus, Op::EpsK(16, r));
    let dup = Set::new(Dataset::HalfDuplicates100k.points());
    table_group(c, "knn10/half-duplicates-100k", &dup, Op::Knn(10));
    policy_build_group(c, "build-policies/half-duplicates-100k", &dup.f32);
    policy_build_group(c, "build-policies/two-points-100k", &two_points(100_000));
    brute_group(c, &torus);
}

criterion_group!(tables, benches);
criterion_main!(tables);
