//! `nbhd bench speed`: nbhd's all-point tables side by side with the Rust peers in one run:
//! kiddo's immutable tree (f32 and f64) and brute force, on generated sets and on
//! point-cloud files, for the build, kNN (k = 10, 30), radius (about 20 neighbours) and ε-k
//! (k = 16 within that radius), on each requested number of threads; and single queries
//! (`single10`, `single30`: one `KdTree::knn` call per point in the caller's order, and the
//! same loop through the C ABI's `nbhd_tree_knn`), as a caller looping over queries gets them.
//!
//! Every point queries the tree built on the same set, itself included (as the peers do), and
//! both sides write the whole table (rows in caller order, indices and squared distances).
//! The table rows also time the floor: a kernel given the exact neighbours of every point,
//! which only reads them, computes their squared distances and writes the table in caller
//! order (what any search must at least do).
//! Each figure is the median of `--reps` runs, nbhd's and its peer's in alternation; ratios are peer / nbhd, so > 1 means nbhd is
//! faster. Neighbour counts are checked against kiddo's and any difference is reported.

use crate::error::{Context, Result};
use crate::output::{num, Output};
use crate::read;
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use nbhd::ffi::{
    nbhd_points, nbhd_scalar_type, nbhd_status, nbhd_tree, nbhd_tree_build, nbhd_tree_free,
    nbhd_tree_knn,
};
use nbhd::shapes::datasets::Dataset;
use nbhd::table::neighborhoods_of_all;
use nbhd::NeighborIndex;
use nbhd::{
    BruteForce, BuildOptions, KdTree, NeighborTable, Neighborhood, NonFinitePolicy, PointsView,
    Query, Scalar, TableOptions,
};
use rayon::prelude::*;
use serde_json::json;
use std::ffi::c_void;
use std::fmt::Write as _;
use std::num::NonZero;
use std::path::Path;
use std::time::Instant;

/// Brute force is quadratic: by default it runs only on sets of at most this many points (and
/// knn10 only), once per thread count.
pub const BRUTE_MAX_POINTS: usize = 150_000;

/// The brute-force limit of `--quick` (77,616² distances take half a minute).
pub const QUICK_BRUTE_MAX_POINTS: usize = 20_000;

/// Sets of at most this many points are "small" (the only ones `--quick` runs).
pub const QUICK_MAX_POINTS: usize = 150_000;

/// Side-by-side speed of nbhd, kiddo's immutable tree and brute force
///
/// For each set, operation, thread count and scalar type: nbhd's median time, kiddo's
/// (ImmutableKdTree, queries in chunks on a pool of that many threads, the table written like
/// nbhd's), brute force (knn10 on sets of at most 150,000 points only, one run: it is quadratic), the
/// ratios peer / nbhd (> 1 means nbhd is faster), nbhd's speed-up over its own 1-thread time,
/// and a check that the neighbour counts agree with kiddo's. Per set: tree bytes per point.
#[derive(clap::Args, Debug)]
pub struct SpeedArgs {
    /// Sets, comma-separated: generated sets (torus-77k, torus-100k, half-duplicates-100k,
    /// cylinder-plane-123k, torus-1M, cube-1M, or `all`) and PCD/PLY/OBJ/XYZ files (points
    /// with NaN coordinates are skipped)
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "torus-77k,cylinder-plane-123k,half-duplicates-100k"
    )]
    pub sets: Vec<String>,

    /// Operations, comma-separated
    #[arg(
        long,
        value_enum,
        value_delimiter = ',',
        default_value = "build,knn10,knn30,radius,epsk,single10,single30"
    )]
    pub ops: Vec<Op>,

    /// Thread counts, comma-separated (each operation runs on each)
    #[arg(long, value_delimiter = ',', default_value = "1,2")]
    pub thread_counts: Vec<usize>,

    /// Runs per figure (the median is reported)
    #[arg(long, default_value_t = 5)]
    pub reps: usize,

    /// Coordinate type of the trees
    #[arg(long, value_enum, default_value = "f32")]
    pub scalar: ScalarArg,

    /// Brute force (knn10 only, one run: it is quadratic) on sets of at most this many points
    /// [default: 150000; 20000 with --quick]
    #[arg(long)]
    pub brute_max_points: Option<usize>,

    /// Small sets only (at most 150,000 points), one run per figure: a smoke test
    #[arg(long)]
    pub quick: bool,
}

/// An operation of the benchmark.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Op {
    /// Building the tree (kiddo's build is single-threaded)
    Build,
    /// The 10 nearest points of every point
    Knn10,
    /// The 30 nearest points of every point
    Knn30,
    /// All points within the radius giving about 20 neighbours on average
    Radius,
    /// The 16 nearest within that radius (ε-k)
    Epsk,
    /// The 10 nearest of every point, one single query per point in the caller's order
    /// (`KdTree::knn`, and `nbhd_tree_knn` through the C ABI)
    Single10,
    /// The 30 nearest, one single query per point as `single10`
    Single30,
}

impl Op {
    fn name(self) -> &'static str {
        match self {
            Op::Build => "build",
            Op::Knn10 => "knn10",
            Op::Knn30 => "knn30",
            Op::Radius => "radius",
            Op::Epsk => "epsk",
            Op::Single10 => "single10",
            Op::Single30 => "single30",
        }
    }

    /// k of the kNN operations.
    fn k(self) -> Option<usize> {
        match self {
            Op::Knn10 | Op::Single10 => Some(10),
            Op::Knn30 | Op::Single30 => Some(30),
            _ => None,
        }
    }

    fn is_single(self) -> bool {
        matches!(self, Op::Single10 | Op::Single30)
    }

    /// Whether the neighbour counts must equal kiddo's exactly (kNN), or may differ by points
    /// exactly on the radius.
    fn counts_exact(self) -> bool {
        self.k().is_some()
    }
}

/// Scalar types to run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum ScalarArg {
    F32,
    F64,
    Both,
}

/// A set of points to run on.
struct BenchSet {
    name: String,
    /// Finite points only.
    points: Vec<[f64; 3]>,
}

/// One measured line of the table.
struct Row {
    set: String,
    scalar: &'static str,
    op: Op,
    threads: usize,
    nbhd_s: f64,
    kiddo_s: f64,
    brute_s: Option<f64>,
    /// The floor kernel (tables): the exact neighbours read, measured and written.
    floor_s: Option<f64>,
    /// The same single queries through the C ABI (`nbhd_tree_knn`).
    c_abi_s: Option<f64>,
    /// nbhd's 1-thread time over this one (when 1 thread was run).
    speedup: Option<f64>,
    /// Neighbour totals of nbhd and kiddo (tables only).
    totals: Option<(usize, usize)>,
}

impl Row {
    /// "ok", or what differs.
    fn check(&self) -> String {
        match self.totals {
            None => "–".into(),
            Some((a, b)) if a == b => "ok".into(),
            Some((a, b)) => format!("differs: nbhd {a}, kiddo {b}"),
        }
    }

    fn agrees(&self) -> bool {
        self.totals.is_none_or(|(a, b)| a == b)
    }
}

/// Per set and scalar: tree memory and the radius used.
struct SetInfo {
    set: String,
    points: usize,
    scalar: &'static str,
    bytes_per_point: f64,
    radius: f64,
}

/// Options resolved from the command line.
struct Plan {
    ops: Vec<Op>,
    threads: Vec<usize>,
    reps: usize,
    brute_max_points: usize,
}

pub fn run(a: SpeedArgs, out: &Output) -> Result<()> {
    let plan = plan(&a)?;
    let sets = load_sets(&a.sets, a.quick)?;
    let (mut rows, mut infos) = (Vec::new(), Vec::new());
    for set in &sets {
        out.note(format!("{}: {} points", set.name, set.points.len()));
        let radius = radius_for_20(&set.points)?;
        if matches!(a.scalar, ScalarArg::F32 | ScalarArg::Both) {
            infos.push(bench_set::<f32>(set, radius, &plan, &mut rows)?);
        }
        if matches!(a.scalar, ScalarArg::F64 | ScalarArg::Both) {
            infos.push(bench_set::<f64>(set, radius, &plan, &mut rows)?);
        }
    }
    fill_speedups(&mut rows);
    out.text(markdown(&rows, &infos, &plan));
    out.json(&to_json(&rows, &infos, &plan));
    Ok(())
}

/// Checks the options; `--quick` means one run per figure.
fn plan(a: &SpeedArgs) -> Result<Plan> {
    if a.reps == 0 {
        return Err("--reps must be at least 1".into());
    }
    if a.thread_counts.contains(&0) {
        return Err("--thread-counts must be at least 1 each".into());
    }
    if let Some(t) = a.thread_counts.iter().find(|&&t| t > nbhd::MAX_THREADS) {
        return Err(format!(
            "--thread-counts {t} is above the maximum of {} worker threads",
            nbhd::MAX_THREADS
        )
        .into());
    }
    let mut ops = a.ops.clone();
    ops.dedup();
    let mut threads = a.thread_counts.clone();
    threads.dedup();
    Ok(Plan {
        ops,
        threads,
        reps: if a.quick { 1 } else { a.reps },
        brute_max_points: a.brute_max_points.unwrap_or(if a.quick {
            QUICK_BRUTE_MAX_POINTS
        } else {
            BRUTE_MAX_POINTS
        }),
    })
}

/// Generated sets by name (`all` for every one) and files by path, finite points only.
fn load_sets(names: &[String], quick: bool) -> Result<Vec<BenchSet>> {
    let mut sets = Vec::new();
    for name in names.iter().map(|n| n.trim()).filter(|n| !n.is_empty()) {
        if name == "all" {
            for d in Dataset::ALL {
                if !quick || d.len_hint() <= QUICK_MAX_POINTS {
                    sets.push(generated(d));
                }
            }
        } else if let Some(d) = Dataset::from_name(name) {
            if quick && d.len_hint() > QUICK_MAX_POINTS {
                return Err(format!(
                    "--quick runs small sets only (at most {QUICK_MAX_POINTS} points); {name} is not"
                ).into());
            }
            sets.push(generated(d));
        } else if Path::new(name).exists() {
            sets.push(from_file(name, quick)?);
        } else {
            let known: Vec<&str> = Dataset::ALL.iter().map(|d| d.name()).collect();
            return Err(format!(
                "'{name}' is neither a generated set ({}, all) nor an existing file",
                known.join(", ")
            )
            .into());
        }
    }
    if sets.is_empty() {
        return Err("no sets to run (--sets is empty)".into());
    }
    Ok(sets)
}

/// Point counts of the generated sets, known without generating them.
trait LenHint {
    fn len_hint(self) -> usize;
}

impl LenHint for Dataset {
    fn len_hint(self) -> usize {
        match self {
            Dataset::Torus77k => 77_616,
            Dataset::Torus100k | Dataset::HalfDuplicates100k => 100_000,
            Dataset::CylinderPlane123k => 123_393,
            Dataset::Torus1M | Dataset::Cube1M => 1_000_000,
        }
    }
}

fn generated(d: Dataset) -> BenchSet {
    BenchSet {
        name: d.name().into(),
        points: d.points(),
    }
}

/// A point-cloud file (format from the extension); points with NaN coordinates are skipped.
fn from_file(path: &str, quick: bool) -> Result<BenchSet> {
    let cloud = read::cloud(Path::new(path), None).context(path)?;
    let points: Vec<[f64; 3]> = read::finite_points(&cloud)
        .0
        .iter()
        .map(|p| p.to_array())
        .collect();
    if points.len() < 31 {
        return Err(format!(
            "{path}: {} finite points; the benchmark needs at least 31",
            points.len()
        )
        .into());
    }
    if quick && points.len() > QUICK_MAX_POINTS {
        return Err(format!(
            "--quick runs small sets only (at most {QUICK_MAX_POINTS} points); {path} has {}",
            points.len()
        )
        .into());
    }
    let name = Path::new(path)
        .file_name()
        .map_or(path.into(), |f| f.to_string_lossy().into_owned());
    Ok(BenchSet { name, points })
}

/// The radius giving about 20 neighbours (self included, so the 21st nearest) on average: the
/// median distance to the 21st nearest point over a sample of about 2,000 points, computed in
/// f64 so that f32 and f64 runs use the same radius.
fn radius_for_20(points: &[[f64; 3]]) -> Result<f64> {
    let view = PointsView::from_rows(points)?;
    let tree = KdTree::<f64>::build(&view, &BuildOptions::default())?;
    let mut out = Vec::new();
    let mut d: Vec<f64> = Vec::new();
    for i in (0..points.len()).step_by((points.len() / 2000).max(1)) {
        tree.knn(Query::stored(i as u32), 21, &mut out)?;
        d.push(out.last().map_or(0.0, |n| n.sq_dist.sqrt()));
    }
    d.sort_by(f64::total_cmp);
    Ok(d[d.len() / 2])
}

/// The median wall times, in seconds, of `reps` rounds that each run every one of `runs` once,
/// in turn: the runs compared share whatever load passes over the shared machine, so their
/// ratios are steadier than those of medians taken one after the other (on the 1M cube, single
/// queries' kiddo / nbhd came out 1.81 and 1.33 in two runs of that kind, 6 minutes apart).
fn interleaved_medians<const N: usize>(reps: usize, mut runs: [&mut dyn FnMut(); N]) -> [f64; N] {
    let mut t = vec![Vec::with_capacity(reps); N];
    for _ in 0..reps {
        for (f, t) in runs.iter_mut().zip(&mut t) {
            let s = Instant::now();
            f();
            t.push(s.elapsed().as_secs_f64());
        }
    }
    std::array::from_fn(|i| {
        t[i].sort_by(f64::total_cmp);
        t[i][reps / 2]
    })
}

/// The median wall time of `reps` runs of `f`, in seconds.
fn median_secs(reps: usize, mut f: impl FnMut()) -> f64 {
    let mut t: Vec<f64> = (0..reps)
        .map(|_| {
            let s = Instant::now();
            f();
            s.elapsed().as_secs_f64()
        })
        .collect();
    t.sort_by(f64::total_cmp);
    t[reps / 2]
}

fn pool(threads: usize) -> Result<rayon::ThreadPool> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .context(format!("could not create {threads} threads"))
}

/// A coordinate type run by both nbhd and kiddo.
trait Float: Scalar {
    const NAME: &'static str;
    /// The C ABI's name of this type.
    const C_TYPE: nbhd_scalar_type;
    /// kiddo's immutable tree over this type.
    type Peer: Sync;
    fn peer_build(points: &[[Self; 3]]) -> Self::Peer;
    /// kiddo's all-point table in the current pool; returns the neighbour total.
    fn peer_table(tree: &Self::Peer, points: &[[Self; 3]], op: Op, sq_radius: Self) -> usize;
}

/// kiddo's all-point table: rows in caller order, written like nbhd's (row lengths, indices,
/// squared distances), queries in chunks of 1,024 on the current rayon pool.
macro_rules! kiddo_float {
    ($t:ty, $name:literal, $c:ident) => {
        impl Float for $t {
            const NAME: &'static str = $name;
            const C_TYPE: nbhd_scalar_type = nbhd_scalar_type::$c;
            type Peer = ImmutableKdTree<$t, 3>;

            fn peer_build(points: &[[$t; 3]]) -> Self::Peer {
                ImmutableKdTree::new_from_slice(points).expect("kiddo builds any finite set")
            }

            fn peer_table(tree: &Self::Peer, points: &[[$t; 3]], op: Op, r2: $t) -> usize {
                let chunks: Vec<(Vec<usize>, Vec<u32>, Vec<$t>)> = points
                    .par_chunks(1024)
                    .map(|chunk| {
                        let (mut lens, mut ids, mut dists) = (Vec::new(), Vec::new(), Vec::new());
                        for p in chunk {
                            let q = tree.query(p);
                            let nearest =
                                |k: usize| NonZero::new(k).expect("k of the benchmark is > 0");
                            let res = match op {
                                Op::Knn10 | Op::Single10 | Op::Build => {
                                    q.nearest_n::<SquaredEuclidean<$t>>(nearest(10)).execute()
                                }
                                Op::Knn30 | Op::Single30 => {
                                    q.nearest_n::<SquaredEuclidean<$t>>(nearest(30)).execute()
                                }
                                Op::Radius => q.within::<SquaredEuclidean<$t>>(r2).execute(),
                                Op::Epsk => q
                                    .nearest_n::<SquaredEuclidean<$t>>(nearest(16))
                                    .within(r2)
                                    .execute(),
                            };
                            lens.push(res.len());
                            for item in res {
                                ids.push(item.item);
                                dists.push(item.distance);
                            }
                        }
                        (lens, ids, dists)
                    })
                    .collect();
                chunks.iter().map(|c| c.1.len()).sum()
            }
        }
    };
}

kiddo_float!(f32, "f32", F32);
kiddo_float!(f64, "f64", F64);

/// Single queries: one `KdTree::knn` call per point, in the caller's order (in chunks of 1,024
/// on the current pool, as kiddo's table), the rows written like the table's. Returns the
/// neighbour total.
fn single_table<T: Scalar>(tree: &KdTree<T>, points: &[[T; 3]], k: usize) -> usize {
    let chunks: Vec<(Vec<usize>, Vec<u32>, Vec<T>)> = points
        .par_chunks(1024)
        .map(|chunk| {
            let (mut lens, mut ids, mut dists) = (Vec::new(), Vec::new(), Vec::new());
            let mut out = Vec::with_capacity(k);
            for p in chunk {
                tree.knn(Query::point(p), k, &mut out)
                    .expect("finite queries of the tree's dimension");
                lens.push(out.len());
                for n in &out {
                    ids.push(n.index);
                    dists.push(n.sq_dist);
                }
            }
            (lens, ids, dists)
        })
        .collect();
    chunks.iter().map(|c| c.1.len()).sum()
}

/// A tree made and queried through the C ABI (`nbhd_tree_build`, `nbhd_tree_knn`), as a C
/// caller holds it.
struct CTree(*mut nbhd_tree);

// SAFETY: an nbhd_tree is immutable once built and documented as queryable from any number of
// threads at once (src/ffi/query.rs); the handle is freed only by `Drop`, with `&mut self`.
unsafe impl Sync for CTree {}

impl CTree {
    fn build<T: Float>(points: &[[T; 3]]) -> Result<Self> {
        let desc = nbhd_points {
            data: points.as_ptr().cast::<c_void>(),
            count: points.len(),
            dim: 3,
            stride: 0,
            scalar_type: T::C_TYPE,
        };
        let mut tree = std::ptr::null_mut();
        // SAFETY: `desc` describes `points`, packed and alive for the call; NULL options are
        // the defaults; `tree` is writable.
        let status = unsafe { nbhd_tree_build(&desc, std::ptr::null(), &mut tree) };
        if status != nbhd_status::Ok {
            return Err(format!("nbhd_tree_build: status {status:?}").into());
        }
        Ok(Self(tree))
    }

    /// The single-query loop of [`single_table`] through `nbhd_tree_knn`; returns the total.
    fn table<T: Float>(&self, points: &[[T; 3]], k: usize) -> usize {
        let chunks: Vec<(Vec<usize>, Vec<u32>, Vec<T>)> = points
            .par_chunks(1024)
            .map(|chunk| {
                let mut lens = Vec::with_capacity(chunk.len());
                let mut ids = vec![0u32; chunk.len() * k];
                let mut dists = vec![T::ZERO; chunk.len() * k];
                let mut total = 0;
                for p in chunk {
                    let mut count = 0usize;
                    // SAFETY: a live handle of a tree of `T` and dimension 3; `p` holds 3 `T`;
                    // the buffers have room for `k` results from `total` on (each row adds at
                    // most k); `count` is writable.
                    let status = unsafe {
                        nbhd_tree_knn(
                            self.0,
                            p.as_ptr().cast::<c_void>(),
                            k,
                            ids.as_mut_ptr().add(total),
                            dists.as_mut_ptr().add(total).cast::<c_void>(),
                            k,
                            &mut count,
                        )
                    };
                    assert_eq!(status, nbhd_status::Ok, "nbhd_tree_knn on a finite query");
                    lens.push(count);
                    total += count;
                }
                ids.truncate(total);
                dists.truncate(total);
                (lens, ids, dists)
            })
            .collect();
        chunks.iter().map(|c| c.1.len()).sum()
    }
}

impl Drop for CTree {
    fn drop(&mut self) {
        // SAFETY: the handle came from nbhd_tree_build and is freed once, here.
        unsafe { nbhd_tree_free(self.0) };
    }
}

/// The floor of a table: given the exact neighbours (`exact`), read each neighbour's
/// point, compute its squared distance and write index and distance into a new table in the
/// caller's order, rows in chunks of 1,024 on the current pool. No search, no ordering: what
/// every table must at least do.
fn floor_kernel<T: Scalar>(points: &[[T; 3]], exact: &NeighborTable<T>) -> NeighborTable<T> {
    let offsets = exact.offsets().to_vec();
    let total = exact.total();
    let (mut ids, mut dists) = (vec![0u32; total], vec![T::ZERO; total]);
    let mut pieces = Vec::new();
    let (mut rest_i, mut rest_d) = (&mut ids[..], &mut dists[..]);
    for first in (0..points.len()).step_by(1024) {
        let last = (first + 1024).min(points.len());
        let len = offsets[last] - offsets[first];
        let (a, b) = std::mem::take(&mut rest_i).split_at_mut(len);
        let (c, d) = std::mem::take(&mut rest_d).split_at_mut(len);
        pieces.push((first..last, a, c));
        (rest_i, rest_d) = (b, d);
    }
    pieces.into_par_iter().for_each(|(rows, out_i, out_d)| {
        let base = offsets[rows.start];
        for i in rows {
            let q = &points[i];
            for at in offsets[i]..offsets[i + 1] {
                let j = exact.indices()[at];
                let p = &points[j as usize];
                let mut s = T::ZERO;
                for (&a, &b) in q.iter().zip(p) {
                    let t = a - b;
                    s = s + t * t;
                }
                out_i[at - base] = j;
                out_d[at - base] = s;
            }
        }
    });
    NeighborTable::from_parts(offsets, ids, dists).expect("the exact table's shape")
}

/// nbhd's neighbourhood for an operation (tables only).
fn neighborhood<T: Scalar>(op: Op, radius: T) -> Neighborhood<T> {
    match op {
        Op::Build | Op::Knn10 | Op::Single10 => Neighborhood::Knn { k: 10 },
        Op::Knn30 | Op::Single30 => Neighborhood::Knn { k: 30 },
        Op::Radius => Neighborhood::Radius {
            radius,
            sorted: true,
        },
        Op::Epsk => Neighborhood::KnnRadius { k: 16, radius },
    }
}

/// What one set is timed on: its points in one scalar type, nbhd's tree, kiddo's tree, brute
/// force (on small sets) and the radius of the radius tables.
struct Subjects<'a, T: Float> {
    set: &'a str,
    pts: &'a [[T; 3]],
    tree: &'a KdTree<T>,
    peer: &'a T::Peer,
    brute: Option<&'a BruteForce<T>>,
    radius: T,
    reps: usize,
}

/// Every operation and thread count on one set in one scalar type; returns the tree memory.
fn bench_set<T: Float>(
    set: &BenchSet,
    radius: f64,
    plan: &Plan,
    rows: &mut Vec<Row>,
) -> Result<SetInfo> {
    let pts: Vec<[T; 3]> = set
        .points
        .iter()
        .map(|p| p.map(|c| T::from_f64(c)))
        .collect();
    let view = PointsView::from_rows(&pts)?;
    let options = BuildOptions {
        non_finite: NonFinitePolicy::Reject,
        ..BuildOptions::default()
    };
    let tree = KdTree::<T>::build(&view, &options)?;
    let peer = T::peer_build(&pts);
    let brute = (set.points.len() <= plan.brute_max_points && plan.ops.contains(&Op::Knn10))
        .then(|| BruteForce::<T>::new(&view, NonFinitePolicy::Reject))
        .transpose()?;
    let subjects = Subjects {
        set: &set.name,
        pts: &pts,
        tree: &tree,
        peer: &peer,
        brute: brute.as_ref(),
        radius: T::from_f64(radius),
        reps: plan.reps,
    };
    for &op in &plan.ops {
        for &threads in &plan.threads {
            let p = pool(threads)?;
            let mut row = Row {
                set: set.name.clone(),
                scalar: T::NAME,
                op,
                threads,
                nbhd_s: 0.0,
                kiddo_s: 0.0,
                brute_s: None,
                floor_s: None,
                c_abi_s: None,
                speedup: None,
                totals: None,
            };
            if op == Op::Build {
                let opts = BuildOptions { threads, ..options };
                [row.nbhd_s, row.kiddo_s] = interleaved_medians(
                    plan.reps,
                    [
                        &mut || {
                            KdTree::<T>::build(&view, &opts).expect("built once already");
                        },
                        &mut || {
                            T::peer_build(&pts);
                        },
                    ],
                );
            } else if op.is_single() {
                time_single_knn(&subjects, &p, &mut row)?;
            } else {
                time_table(&subjects, &p, &mut row);
            }
            rows.push(row);
        }
    }
    let s = tree.stats();
    Ok(SetInfo {
        set: set.name.clone(),
        points: set.points.len(),
        scalar: T::NAME,
        bytes_per_point: s.bytes as f64 / s.points as f64,
        radius,
    })
}

/// Times the single-query kNN operation `row.op` in the pool `p`: nbhd in Rust, nbhd through
/// the C ABI and kiddo, alternating; the Rust and C answers must agree.
fn time_single_knn<T: Float>(
    s: &Subjects<'_, T>,
    p: &rayon::ThreadPool,
    row: &mut Row,
) -> Result<()> {
    let (op, r) = (row.op, s.radius);
    let k = op.k().expect("single ops are kNN");
    let (mut ours, mut theirs, mut via_c) = (0, 0, 0);
    let c_tree = CTree::build(s.pts)?;
    let [nbhd_s, c_abi_s, kiddo_s] = interleaved_medians(
        s.reps,
        [
            &mut || ours = p.install(|| single_table(s.tree, s.pts, k)),
            &mut || via_c = p.install(|| c_tree.table(s.pts, k)),
            &mut || theirs = p.install(|| T::peer_table(s.peer, s.pts, op, r * r)),
        ],
    );
    (row.nbhd_s, row.c_abi_s, row.kiddo_s) = (nbhd_s, Some(c_abi_s), kiddo_s);
    if via_c != ours {
        return Err(format!(
            "{}: the C ABI found {via_c} neighbours, KdTree::knn {ours}",
            s.set
        )
        .into());
    }
    row.totals = Some((ours, theirs));
    Ok(())
}

/// Times the all-point table `row.op` with `row.threads` threads (pool `p`): nbhd and kiddo
/// alternating, then the floor kernel over nbhd's exact table and, for kNN-10 on small sets,
/// brute force.
fn time_table<T: Float>(s: &Subjects<'_, T>, p: &rayon::ThreadPool, row: &mut Row) {
    let (op, r) = (row.op, s.radius);
    let nbhd = neighborhood(op, r);
    let opts = TableOptions {
        exclude_self: false,
        threads: row.threads,
        ..Default::default()
    };
    let (mut ours, mut theirs) = (0, 0);
    [row.nbhd_s, row.kiddo_s] = interleaved_medians(
        s.reps,
        [
            &mut || {
                ours = s
                    .tree
                    .neighborhoods(nbhd, &opts)
                    .expect("valid options")
                    .total();
            },
            &mut || theirs = p.install(|| T::peer_table(s.peer, s.pts, op, r * r)),
        ],
    );
    row.totals = Some((ours, theirs));
    {
        let exact = s.tree.neighborhoods(nbhd, &opts).expect("valid options");
        row.floor_s = Some(median_secs(s.reps, || {
            p.install(|| floor_kernel(s.pts, &exact));
        }));
    }
    if let (Some(b), Op::Knn10) = (s.brute, op) {
        row.brute_s = Some(median_secs(1, || {
            p.install(|| neighborhoods_of_all(b, nbhd, false))
                .expect("valid options");
        }));
    }
}

/// Mean row length of the radius table (self included), if it was run: about 20 unless the
/// set has many copies of a point (then no radius gives 20).
fn mean_in_radius(rows: &[Row], i: &SetInfo) -> Option<f64> {
    rows.iter()
        .find(|r| r.set == i.set && r.scalar == i.scalar && r.op == Op::Radius)
        .and_then(|r| r.totals)
        .map(|t| t.0 as f64 / i.points as f64)
}

/// nbhd's speed-up over its own 1-thread time, for every row whose 1-thread twin was run.
fn fill_speedups(rows: &mut [Row]) {
    let ones: Vec<(String, &'static str, Op, f64)> = rows
        .iter()
        .filter(|r| r.threads == 1)
        .map(|r| (r.set.clone(), r.scalar, r.op, r.nbhd_s))
        .collect();
    for r in rows.iter_mut() {
        if let Some(one) = ones
            .iter()
            .find(|o| o.0 == r.set && o.1 == r.scalar && o.2 == r.op)
        {
            r.speedup = Some(one.3 / r.nbhd_s);
        }
    }
}

fn ms(s: Option<f64>) -> String {
    s.map_or("–".into(), |s| format!("{:.1}", s * 1e3))
}

fn ratio(peer: Option<f64>, ours: f64) -> String {
    peer.map_or("–".into(), |p| format!("{:.2}", p / ours))
}

/// The Markdown report: one table of times and ratios, one of memory and radii, and notes.
fn markdown(rows: &[Row], infos: &[SetInfo], plan: &Plan) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "| set | scalar | operation | threads | nbhd [ms] | kiddo [ms] | kiddo / nbhd | brute [ms] | brute / nbhd | nbhd speed-up vs 1 thread | C ABI [ms] | kiddo / C ABI | floor [ms] | nbhd / floor | counts vs kiddo |"
    );
    let _ = writeln!(
        s,
        "|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|"
    );
    for r in rows {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            r.set,
            r.scalar,
            r.op.name(),
            r.threads,
            ms(Some(r.nbhd_s)),
            ms(Some(r.kiddo_s)),
            ratio(Some(r.kiddo_s), r.nbhd_s),
            ms(r.brute_s),
            ratio(r.brute_s, r.nbhd_s),
            r.speedup.map_or("–".into(), |x| format!("{x:.2}")),
            ms(r.c_abi_s),
            r.c_abi_s.map_or("–".into(), |c| ratio(Some(r.kiddo_s), c)),
            ms(r.floor_s),
            r.floor_s
                .map_or("–".into(), |f| format!("{:.1}", r.nbhd_s / f)),
            r.check(),
        );
    }
    let _ = writeln!(
        s,
        "\n| set | points | scalar | tree bytes/point | radius (~20 neighbours) | mean neighbours within it |"
    );
    let _ = writeln!(s, "|---|---:|---|---:|---:|---:|");
    for i in infos {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {:.1} | {:.6} | {} |",
            i.set,
            i.points,
            i.scalar,
            i.bytes_per_point,
            i.radius,
            mean_in_radius(rows, i).map_or("–".into(), |m| format!("{m:.1}"))
        );
    }
    let bad = rows.iter().filter(|r| !r.agrees()).count();
    let _ = write!(
        s,
        "\nMedian of {} run(s) per figure, nbhd and its peers in alternation; ratios are peer / nbhd (> 1: nbhd is faster). Every \
         point queries its own set, itself included; both write the whole table. Brute force: \
         knn10 on sets of at most {} points only, one run (it is quadratic). kiddo's \
         build is single-threaded. single10/single30: one query per point in the caller's \
         order (KdTree::knn; C ABI: nbhd_tree_knn), against kiddo called the same way. Floor: \
         the exact rows read, their squared distances computed and the table written in \
         caller order (no search); nbhd / floor is the table's time over it. Count check: {}.",
        plan.reps,
        plan.brute_max_points,
        if bad == 0 {
            "all agree with kiddo".to_string()
        } else {
            format!("{bad} row(s) differ from kiddo")
        }
    );
    s
}

fn to_json(measured: &[Row], infos: &[SetInfo], plan: &Plan) -> serde_json::Value {
    let rows: Vec<_> = measured
        .iter()
        .map(|r| {
            json!({
                "set": r.set,
                "scalar": r.scalar,
                "op": r.op.name(),
                "threads": r.threads,
                "nbhd_ms": num(r.nbhd_s * 1e3),
                "kiddo_ms": num(r.kiddo_s * 1e3),
                "kiddo_ratio": num(r.kiddo_s / r.nbhd_s),
                "brute_ms": r.brute_s.map(|b| num(b * 1e3)),
                "c_abi_ms": r.c_abi_s.map(|c| num(c * 1e3)),
                "floor_ms": r.floor_s.map(|f| num(f * 1e3)),
                "floor_ratio": r.floor_s.map(|f| num(r.nbhd_s / f)),
                "brute_ratio": r.brute_s.map(|b| num(b / r.nbhd_s)),
                "speedup_vs_1_thread": r.speedup.map(num),
                "nbhd_total": r.totals.map(|t| t.0),
                "kiddo_total": r.totals.map(|t| t.1),
                "counts_agree": r.agrees(),
                "counts_must_be_equal": r.op.counts_exact(),
            })
        })
        .collect();
    let sets: Vec<_> = infos
        .iter()
        .map(|i| {
            json!({
                "set": i.set,
                "points": i.points,
                "scalar": i.scalar,
                "tree_bytes_per_point": num(i.bytes_per_point),
                "radius": num(i.radius),
                "mean_in_radius": mean_in_radius(measured, i).map(num),
            })
        })
        .collect();
    json!({
        "reps": plan.reps,
        "brute_max_points": plan.brute_max_points,
        "counts_agree": rows.iter().all(|r| r["counts_agree"] == true),
        "sets": sets,
        "rows": rows,
    })
}
