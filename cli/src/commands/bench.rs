//! `nbhd bench thesis`: the computational results of the thesis' Chapter 8, reproduced on
//! generated samples of its three geometries at its sizes (Fig. 8.2), with a markdown report and
//! SVG plots.
//!
//! The thesis' Costa surface is replaced by a catenoid (`nbhd::shapes::Catenoid`), its cylinder
//! by the open cylinder with a plane segment through its axis, and its Catmull–Clark
//! subdivisions by uniform random samples of the same point counts. Times are single-threaded,
//! as the thesis' Java program was, and trees have one point per leaf (the thesis' shape).

use crate::commands::ms;
use crate::output::{num, Output};
use crate::progress::Progress;
use nbhd::shapes::{
    sample, Catenoid, CylinderPlane, Shape, Torus, COSTA_SIZES, CYLINDER_SIZES, TORUS_SIZES,
};
use nbhd::table::neighborhoods_of_all;
use nbhd::{
    BruteForce, BuildOptions, KdTree, MedianAlgorithm, NeighborSearch, Neighborhood,
    NonFinitePolicy, PcaSweep, PivotPolicy, PointsView, TableOptions,
};
use serde_json::json;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Benchmarks
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(subcommand)]
    pub which: Which,
}

#[derive(clap::Subcommand, Debug)]
pub enum Which {
    Thesis(ThesisArgs),
    Speed(crate::commands::bench_speed::SpeedArgs),
}

/// Reproduce Chapter 8 of the thesis: build times and depths of every tree variant, k-d tree
/// vs PCA sweep vs brute force, closest-to-middle vs median trees
///
/// Writes report.md, results.json and SVG plots into the output folder. The full run takes a
/// few minutes on 2 cores; --quick uses the original sizes only (seconds).
#[derive(clap::Args, Debug)]
pub struct ThesisArgs {
    /// Results folder (created if missing)
    #[arg(long, short, default_value = "nbhd-bench")]
    pub out: PathBuf,

    /// Builds per variant and size (the median is reported; the thesis built 1000 times)
    #[arg(long, default_value_t = 5)]
    pub repeats: usize,

    /// Only the original sizes (4,918 / 5,249 / 4,851 points) and fewer k and ε values
    #[arg(long)]
    pub quick: bool,
}

pub fn run(a: Args, out: &Output) -> Result<(), String> {
    match a.which {
        Which::Thesis(t) => thesis(t, out),
        Which::Speed(s) => crate::commands::bench_speed::run(s, out),
    }
}

/// A geometry of Fig. 8.1 at its three sizes.
struct Geometry {
    name: &'static str,
    shape: Box<dyn Shape>,
    sizes: [usize; 3],
}

fn geometries() -> Vec<Geometry> {
    vec![
        Geometry {
            name: "Costa (catenoid)",
            shape: Box::new(Catenoid::new(1.0, 1.2)),
            sizes: COSTA_SIZES,
        },
        Geometry {
            name: "Cylinder",
            shape: Box::new(CylinderPlane::new(0.5, 2.0)),
            sizes: CYLINDER_SIZES,
        },
        Geometry {
            name: "Torus",
            shape: Box::new(Torus::new(1.0, 0.35)),
            sizes: TORUS_SIZES,
        },
    ]
}

/// The build variants of Fig. 8.8 (first five) and the other policies.
const VARIANTS: [(&str, PivotPolicy, MedianAlgorithm); 8] = [
    (
        "Sorting",
        PivotPolicy::CyclicMedian,
        MedianAlgorithm::Presorted,
    ),
    (
        "Median (Sorting)",
        PivotPolicy::CyclicMedian,
        MedianAlgorithm::Sort,
    ),
    (
        "Median (Linear Det.)",
        PivotPolicy::CyclicMedian,
        MedianAlgorithm::MedianOfMedians,
    ),
    (
        "Median (Floyd-Rivest)",
        PivotPolicy::CyclicMedian,
        MedianAlgorithm::FloydRivest,
    ),
    (
        "Closest to Middle",
        PivotPolicy::ClosestToMiddle,
        MedianAlgorithm::FloydRivest,
    ),
    (
        "Median (Quickselect)",
        PivotPolicy::CyclicMedian,
        MedianAlgorithm::Quickselect,
    ),
    (
        "Spread median",
        PivotPolicy::SpreadMedian,
        MedianAlgorithm::FloydRivest,
    ),
    (
        "Sliding midpoint",
        PivotPolicy::SlidingMidpoint,
        MedianAlgorithm::FloydRivest,
    ),
];

/// Thesis' Fig. 8.8 medians in ms (Sorting, Median (Sorting), Median (Linear Det.),
/// Median (Floyd-Rivest), Closest to Middle) per geometry and size.
const THESIS_BUILD_MS: [[[f64; 3]; 5]; 3] = [
    [
        [8.0, 61.0, 326.0],
        [11.0, 89.0, 496.0],
        [15.0, 119.0, 629.0],
        [5.0, 37.0, 198.0],
        [5.0, 110.0, 2046.0],
    ],
    [
        [10.0, 76.0, 353.0],
        [13.0, 122.0, 586.0],
        [19.0, 155.0, 733.0],
        [6.0, 46.0, 201.0],
        [12.0, 108.0, 498.0],
    ],
    [
        [6.0, 32.0, 160.0],
        [8.0, 50.0, 261.0],
        [14.0, 76.0, 377.0],
        [5.0, 23.0, 106.0],
        [4.0, 70.0, 1089.0],
    ],
];

/// Thesis' Fig. 8.7 depths (balanced, closest to middle) of Cylinder and Torus.
const THESIS_DEPTH: [Option<[[usize; 3]; 2]>; 3] = [
    None,
    Some([[12, 14, 16], [287, 694, 2162]]),
    Some([[12, 14, 16], [238, 1373, 5453]]),
];

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn flat(points: &[glam::DVec3]) -> Vec<f64> {
    points.iter().flat_map(|p| p.to_array()).collect()
}

fn diameter(points: &[glam::DVec3]) -> f64 {
    let (lo, hi) = points.iter().fold(
        (
            glam::DVec3::splat(f64::INFINITY),
            glam::DVec3::splat(f64::NEG_INFINITY),
        ),
        |(lo, hi), &p| (lo.min(p), hi.max(p)),
    );
    (hi - lo).length()
}

fn thesis_options(pivot: PivotPolicy, median: MedianAlgorithm) -> BuildOptions {
    BuildOptions {
        leaf_size: 1,
        threads: 1,
        ..BuildOptions::with(pivot, median)
    }
}

/// Milliseconds of the all-point table of `searcher` for `nbhd` (self excluded): the
/// faster of two runs, so that the first run's page faults do not count.
fn table_ms(searcher: &dyn Searcher, nbhd: Neighborhood<f64>) -> Result<(f64, usize), String> {
    let mut best = f64::INFINITY;
    let mut total = 0;
    for _ in 0..2 {
        let t = Instant::now();
        total = searcher.table(nbhd)?;
        best = best.min(ms(t));
    }
    Ok((best, total))
}

/// The three searchers behind one call.
trait Searcher {
    fn table(&self, nbhd: Neighborhood<f64>) -> Result<usize, String>;
}

impl Searcher for KdTree<f64> {
    fn table(&self, nbhd: Neighborhood<f64>) -> Result<usize, String> {
        let opts = TableOptions {
            exclude_self: true,
            threads: 1,
        };
        self.neighborhoods(nbhd, &opts)
            .map(|t| t.total())
            .map_err(|e| e.to_string())
    }
}

struct Baseline<S>(S);

impl<S: NeighborSearch<f64>> Searcher for Baseline<S> {
    fn table(&self, nbhd: Neighborhood<f64>) -> Result<usize, String> {
        neighborhoods_of_all(&self.0, nbhd, true)
            .map(|t| t.total())
            .map_err(|e| e.to_string())
    }
}

/// A curve: label and (x, y) points.
type Series = (String, Vec<(f64, f64)>);

fn thesis(a: ThesisArgs, out: &Output) -> Result<(), String> {
    if a.repeats == 0 {
        return Err("--repeats must be at least 1".into());
    }
    std::fs::create_dir_all(&a.out).map_err(|e| format!("{}: {e}", a.out.display()))?;
    // Every timing on one thread, as in the thesis.
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .map_err(|e| e.to_string())?;
    pool.install(|| thesis_run(&a, out))
}

fn thesis_run(a: &ThesisArgs, out: &Output) -> Result<(), String> {
    let started = Instant::now();
    let geos = geometries();
    let nsizes = if a.quick { 1 } else { 3 };
    let mut report = String::new();
    let _ = writeln!(
        report,
        "# Chapter 8 of the thesis, reproduced with nbhd\n\n\
         Generated samples at the sizes of Fig. 8.2 (Costa is a catenoid here, the cylinder the open \
         cylinder with a plane segment through its axis; uniform random samples instead of \
         Catmull-Clark subdivisions). Single-threaded, one point per leaf, times in ms; builds \
         are the median of {} runs after one untimed build, query times the faster of two runs \
         of the all-point table.{}\n",
        a.repeats,
        if a.quick { " Quick run: original sizes only." } else { "" }
    );
    let mut results = json!({});
    let mut checks: Vec<(String, bool)> = Vec::new();

    // ---- 8.1: build times and depths ----
    let steps = (geos.len() * nsizes * VARIANTS.len()) as u64;
    let bar = Progress::bar(out, steps, "building trees");
    let mut build = Vec::new();
    let _ = writeln!(report, "## Build times (Fig. 8.8) and depths (Fig. 8.7)\n");
    for (gi, g) in geos.iter().enumerate() {
        let mut rows: Vec<(String, Vec<f64>, Vec<usize>)> = VARIANTS
            .iter()
            .map(|v| (v.0.to_string(), Vec::new(), Vec::new()))
            .collect();
        let mut identical = true;
        for &n in &g.sizes[..nsizes] {
            let pts = sample(g.shape.as_ref(), n, 2024).points;
            let coords = flat(&pts);
            let view = PointsView::from_flat(&coords, 3).map_err(|e| e.to_string())?;
            let mut reference: Option<KdTree<f64>> = None;
            for (vi, &(label, pivot, med)) in VARIANTS.iter().enumerate() {
                bar.message(format!("{} {n}: {label}", g.name));
                let opts = thesis_options(pivot, med);
                let mut times = Vec::new();
                // One untimed build first: page faults and caches are not the variant's.
                let mut tree = Some(KdTree::<f64>::build(&view, &opts).map_err(|e| e.to_string())?);
                for _ in 0..a.repeats {
                    let t = Instant::now();
                    tree = Some(KdTree::<f64>::build(&view, &opts).map_err(|e| e.to_string())?);
                    times.push(ms(t));
                }
                let tree = tree.expect("repeats >= 1");
                rows[vi].1.push(median(times));
                rows[vi].2.push(tree.stats().depth);
                if pivot == PivotPolicy::CyclicMedian {
                    match &reference {
                        None => reference = Some(tree),
                        Some(r) => identical &= r.same_structure(&tree),
                    }
                }
                bar.inc(1);
            }
        }
        checks.push((
            format!(
                "{}: every median algorithm and the presorted build give the identical tree (8.1)",
                g.name
            ),
            identical,
        ));
        // The table: ours next to the thesis'.
        let sizes: Vec<String> = g.sizes[..nsizes].iter().map(|n| n.to_string()).collect();
        let _ = writeln!(report, "### {}\n", g.name);
        let _ = writeln!(
            report,
            "| variant | {} | depth | thesis ms | thesis depth |\n|---|{}---|---|---|",
            sizes.join(" | "),
            "---|".repeat(nsizes)
        );
        for (vi, (label, times, depths)) in rows.iter().enumerate() {
            let thesis_ms = (vi < 5).then(|| {
                THESIS_BUILD_MS[gi][vi][..nsizes]
                    .iter()
                    .map(|v| format!("{v}"))
                    .collect::<Vec<_>>()
                    .join(" / ")
            });
            let thesis_depth = THESIS_DEPTH[gi].map(|d| {
                let which = usize::from(VARIANTS[vi].1 == PivotPolicy::ClosestToMiddle);
                if VARIANTS[vi].1.is_balanced() || which == 1 {
                    d[which][..nsizes]
                        .iter()
                        .map(|v| v.to_string())
                        .collect::<Vec<_>>()
                        .join(" / ")
                } else {
                    "-".into()
                }
            });
            let _ = writeln!(
                report,
                "| {label} | {} | {} | {} | {} |",
                times
                    .iter()
                    .map(|t| format!("{t:.2}"))
                    .collect::<Vec<_>>()
                    .join(" | "),
                depths
                    .iter()
                    .map(|d| d.to_string())
                    .collect::<Vec<_>>()
                    .join(" / "),
                thesis_ms.unwrap_or_else(|| "-".into()),
                thesis_depth.unwrap_or_else(|| "-".into()),
            );
        }
        let _ = writeln!(report);
        // Floyd-Rivest fastest of the thesis' balanced builds?
        let fr = &rows[3].1;
        let fastest = (0..nsizes).all(|s| (0..3).all(|v| fr[s] <= rows[v].1[s]));
        checks.push((
            format!(
                "{}: Median (Floyd-Rivest) builds faster than Sorting, Median (Sorting) and Median (Linear Det.) at every size",
                g.name
            ),
            fastest,
        ));
        let deeper = (0..nsizes).all(|s| rows[4].2[s] > 2 * rows[0].2[s]);
        checks.push((
            format!(
                "{}: closest-to-middle trees are far deeper than balanced ones, more than twice \
                 (Fig. 8.7; depths here {} vs {})",
                g.name,
                rows[4]
                    .2
                    .iter()
                    .map(|d| d.to_string())
                    .collect::<Vec<_>>()
                    .join(" / "),
                rows[0]
                    .2
                    .iter()
                    .map(|d| d.to_string())
                    .collect::<Vec<_>>()
                    .join(" / "),
            ),
            deeper,
        ));
        let series: Vec<Series> = rows
            .iter()
            .map(|(l, t, _)| {
                (
                    l.clone(),
                    g.sizes[..nsizes]
                        .iter()
                        .zip(t)
                        .map(|(&n, &t)| (n as f64, t))
                        .collect(),
                )
            })
            .collect();
        let file = format!("build-{}.svg", slug(g.name));
        plot(
            &a.out.join(&file),
            &format!("Build times, {} (Fig. 8.4-8.6)", g.name),
            "points",
            "ms (median)",
            &series,
        )?;
        let _ = writeln!(report, "![build times]({file})\n");
        build.push(json!({
            "geometry": g.name,
            "sizes": &g.sizes[..nsizes],
            "variants": rows.iter().map(|(l, t, d)| json!({"variant": l, "ms": t.iter().map(|&x| num(x)).collect::<Vec<_>>(), "depth": d})).collect::<Vec<_>>(),
        }));
    }
    results["build"] = json!(build);
    drop(bar);

    // ---- 8.2: kd-tree vs PCA sweep vs brute force on the original cylinder ----
    let cyl = &geos[1];
    let pts = sample(cyl.shape.as_ref(), cyl.sizes[0], 2024).points;
    let coords = flat(&pts);
    let view = PointsView::from_flat(&coords, 3).map_err(|e| e.to_string())?;
    let diam = diameter(&pts);
    let sorting = |view: &PointsView<'_>| {
        KdTree::<f64>::build(
            view,
            &thesis_options(PivotPolicy::CyclicMedian, MedianAlgorithm::Presorted),
        )
        .map_err(|e| e.to_string())
    };
    let ctm = |view: &PointsView<'_>| {
        KdTree::<f64>::build(
            view,
            &thesis_options(PivotPolicy::ClosestToMiddle, MedianAlgorithm::FloydRivest),
        )
        .map_err(|e| e.to_string())
    };
    let kd = sorting(&view)?;
    let pca =
        Baseline(PcaSweep::<f64>::new(&view, NonFinitePolicy::Reject).map_err(|e| e.to_string())?);
    let brute = Baseline(
        BruteForce::<f64>::new(&view, NonFinitePolicy::Reject).map_err(|e| e.to_string())?,
    );
    let searchers: [(&str, &dyn Searcher); 3] = [
        ("kd-tree (Sorting)", &kd),
        ("PCA sweep", &pca),
        ("brute force", &brute),
    ];
    let ks: Vec<usize> = if a.quick {
        vec![1, 10, 50, 100, 200, 400]
    } else {
        vec![1, 5, 10, 25, 50, 75, 100, 150, 200, 250, 300, 350, 400]
    };
    let fracs: Vec<f64> = if a.quick {
        vec![0.001, 0.02, 0.05, 0.1, 0.15]
    } else {
        vec![0.001, 0.01, 0.02, 0.03, 0.05, 0.075, 0.1, 0.125, 0.15]
    };
    let bar = Progress::bar(
        out,
        (3 * (ks.len() + fracs.len())) as u64,
        "kd-tree vs PCA vs brute force",
    );
    let mut knn_series: Vec<Series> = Vec::new();
    let mut rad_series: Vec<Series> = Vec::new();
    for (label, s) in searchers {
        let mut k_pts = Vec::new();
        for &k in &ks {
            let (t, _) = table_ms(s, Neighborhood::KnnRadius { k, radius: diam })?;
            k_pts.push((k as f64, t));
            bar.inc(1);
        }
        knn_series.push((label.to_string(), k_pts));
        let mut r_pts = Vec::new();
        for &f in &fracs {
            let (t, _) = table_ms(
                s,
                Neighborhood::Radius {
                    radius: f * diam,
                    sorted: true,
                },
            )?;
            r_pts.push((100.0 * f, t));
            bar.inc(1);
        }
        rad_series.push((label.to_string(), r_pts));
    }
    drop(bar);
    let _ = writeln!(
        report,
        "## k-d tree vs PCA sweep vs brute force (Fig. 8.9, 8.10)\n\nCylinder, {} points, \
         diameter {diam:.3}; all-point tables, self excluded.\n",
        cyl.sizes[0]
    );
    table_md(&mut report, "k (ε = diameter)", &knn_series);
    table_md(
        &mut report,
        "ε in % of the diameter (no k limit)",
        &rad_series,
    );
    plot(
        &a.out.join("fig8.9-knn.svg"),
        "All k nearest (large ε), Cylinder (Fig. 8.9)",
        "k",
        "ms",
        &knn_series,
    )?;
    plot(
        &a.out.join("fig8.10-radius.svg"),
        "All within ε (no k limit), Cylinder (Fig. 8.10)",
        "ε [% of diameter]",
        "ms",
        &rad_series,
    )?;
    let _ = writeln!(
        report,
        "![k](fig8.9-knn.svg)\n![radius](fig8.10-radius.svg)\n"
    );
    let faster =
        |series: &[Series]| (0..series[0].1.len()).all(|i| series[0].1[i].1 < series[1].1[i].1);
    checks.push((
        "Cylinder: the k-d tree is faster than the PCA sweep for every k up to 400 (8.2)".into(),
        faster(&knn_series),
    ));
    checks.push((
        "Cylinder: the k-d tree is faster than the PCA sweep for every ε up to 15% of the diameter (8.2)"
            .into(),
        faster(&rad_series),
    ));
    results["kd_vs_pca_knn"] = series_json(&knn_series);
    results["kd_vs_pca_radius"] = series_json(&rad_series);

    // ---- 8.3: closest to middle vs median ----
    let _ = writeln!(
        report,
        "## Closest to middle vs median trees (Fig. 8.11-8.13)\n"
    );
    let ks: Vec<usize> = if a.quick {
        vec![1, 25, 50, 100]
    } else {
        vec![1, 10, 25, 50, 75, 100]
    };
    let mut ctm_series: Vec<Series> = Vec::new();
    let mut ctm_slower = true;
    let bar = Progress::bar(
        out,
        (2 * nsizes * ks.len()) as u64,
        "closest to middle vs median",
    );
    for &n in &cyl.sizes[..nsizes] {
        let pts = sample(cyl.shape.as_ref(), n, 2024).points;
        let coords = flat(&pts);
        let view = PointsView::from_flat(&coords, 3).map_err(|e| e.to_string())?;
        let diam = diameter(&pts);
        let mut sums = [0.0; 2];
        for (ti, (label, tree)) in [
            ("Sorting", sorting(&view)?),
            ("Closest to Middle", ctm(&view)?),
        ]
        .iter()
        .enumerate()
        {
            let mut p = Vec::new();
            for &k in &ks {
                let (t, _) = table_ms(tree, Neighborhood::KnnRadius { k, radius: diam })?;
                p.push((k as f64, t));
                sums[ti] += t;
                bar.inc(1);
            }
            ctm_series.push((format!("{label}, {n}"), p));
        }
        ctm_slower &= sums[1] >= 0.9 * sums[0];
    }
    drop(bar);
    let _ = writeln!(
        report,
        "Cylinder, all k nearest with a large ε (Fig. 8.11):\n"
    );
    table_md(&mut report, "k", &ctm_series);
    plot(
        &a.out.join("fig8.11-cylinder-knn.svg"),
        "Sorting vs Closest to Middle, Cylinder (Fig. 8.11)",
        "k",
        "ms",
        &ctm_series,
    )?;
    let _ = writeln!(report, "![ctm cylinder](fig8.11-cylinder-knn.svg)\n");

    // Fig. 8.12: original Costa, repeated, median.
    let costa = &geos[0];
    let pts = sample(costa.shape.as_ref(), costa.sizes[0], 2024).points;
    let coords = flat(&pts);
    let view = PointsView::from_flat(&coords, 3).map_err(|e| e.to_string())?;
    let diam = diameter(&pts);
    let mut costa_series: Vec<Series> = Vec::new();
    let mut sums = [0.0; 2];
    for (ti, (label, tree)) in [
        ("Sorting", sorting(&view)?),
        ("Closest to Middle", ctm(&view)?),
    ]
    .iter()
    .enumerate()
    {
        let mut p = Vec::new();
        for &k in &ks {
            let mut times = Vec::new();
            for _ in 0..a.repeats {
                times.push(table_ms(tree, Neighborhood::KnnRadius { k, radius: diam })?.0);
            }
            let t = median(times);
            sums[ti] += t;
            p.push((k as f64, t));
        }
        costa_series.push((label.to_string(), p));
    }
    ctm_slower &= sums[1] >= 0.9 * sums[0];
    let _ = writeln!(
        report,
        "{}, {} points, median of {} runs (Fig. 8.12):\n",
        costa.name, costa.sizes[0], a.repeats
    );
    table_md(&mut report, "k", &costa_series);
    plot(
        &a.out.join("fig8.12-costa-knn.svg"),
        "Sorting vs Closest to Middle, Costa (Fig. 8.12)",
        "k",
        "ms (median)",
        &costa_series,
    )?;
    let _ = writeln!(report, "![ctm costa](fig8.12-costa-knn.svg)\n");

    // Fig. 8.13: torus, original and once subdivided, ε from 0.1% to 10% of the diameter.
    let torus = &geos[2];
    let fracs: Vec<f64> = if a.quick {
        vec![0.001, 0.025, 0.05, 0.1]
    } else {
        vec![
            0.001, 0.01, 0.02, 0.03, 0.04, 0.05, 0.06, 0.07, 0.08, 0.09, 0.1,
        ]
    };
    let mut torus_series: Vec<Series> = Vec::new();
    for &n in &torus.sizes[..nsizes.min(2)] {
        let pts = sample(torus.shape.as_ref(), n, 2024).points;
        let coords = flat(&pts);
        let view = PointsView::from_flat(&coords, 3).map_err(|e| e.to_string())?;
        let diam = diameter(&pts);
        let mut sums = [0.0; 2];
        for (ti, (label, tree)) in [
            ("Sorting", sorting(&view)?),
            ("Closest to Middle", ctm(&view)?),
        ]
        .iter()
        .enumerate()
        {
            let mut p = Vec::new();
            for &f in &fracs {
                let nb = Neighborhood::Radius {
                    radius: f * diam,
                    sorted: true,
                };
                let (t, _) = table_ms(tree, nb)?;
                sums[ti] += t;
                p.push((100.0 * f, t));
            }
            torus_series.push((format!("{label}, {n}"), p));
        }
        ctm_slower &= sums[1] >= 0.9 * sums[0];
    }
    let _ = writeln!(report, "Torus, all within ε, no k limit (Fig. 8.13):\n");
    table_md(&mut report, "ε in % of the diameter", &torus_series);
    plot(
        &a.out.join("fig8.13-torus-radius.svg"),
        "Sorting vs Closest to Middle, Torus (Fig. 8.13)",
        "ε [% of diameter]",
        "ms",
        &torus_series,
    )?;
    let _ = writeln!(report, "![ctm torus](fig8.13-torus-radius.svg)\n");
    checks.push((
        "Closest-to-middle trees answer queries no faster than balanced trees (within 10%) on \
         every geometry tried (8.3, 8.4: Moore's result not reproduced)"
            .into(),
        ctm_slower,
    ));
    results["ctm_cylinder"] = series_json(&ctm_series);
    results["ctm_costa"] = series_json(&costa_series);
    results["ctm_torus"] = series_json(&torus_series);

    // ---- conclusions ----
    let _ = writeln!(
        report,
        "## The thesis' conclusions on this implementation\n"
    );
    for (c, ok) in &checks {
        let _ = writeln!(
            report,
            "- {}: {c}",
            if *ok { "holds" } else { "does NOT hold" }
        );
    }
    let secs = started.elapsed().as_secs_f64();
    let _ = writeln!(report, "\nTotal run time {secs:.1} s.");
    results["checks"] = checks
        .iter()
        .map(|(c, ok)| json!({"claim": c, "holds": ok}))
        .collect();
    results["seconds"] = num(secs);
    let md = a.out.join("report.md");
    std::fs::write(&md, &report).map_err(|e| format!("{}: {e}", md.display()))?;
    let js = a.out.join("results.json");
    std::fs::write(
        &js,
        serde_json::to_string_pretty(&results).expect("plain values"),
    )
    .map_err(|e| format!("{}: {e}", js.display()))?;
    results["report"] = json!(md.display().to_string());
    out.json(&results);
    out.text(format!(
        "{report}\nwrote {} (with SVG plots and results.json)",
        md.display()
    ));
    Ok(())
}

fn slug(s: &str) -> String {
    s.split_whitespace()
        .next()
        .unwrap_or(s)
        .to_ascii_lowercase()
}

fn series_json(series: &[Series]) -> serde_json::Value {
    series
        .iter()
        .map(|(l, p)| {
            json!({
                "label": l,
                "x": p.iter().map(|q| num(q.0)).collect::<Vec<_>>(),
                "ms": p.iter().map(|q| num(q.1)).collect::<Vec<_>>(),
            })
        })
        .collect()
}

/// A markdown table: one column per series, one row per x.
fn table_md(report: &mut String, x: &str, series: &[Series]) {
    let _ = writeln!(
        report,
        "| {x} | {} |\n|---|{}",
        series
            .iter()
            .map(|s| s.0.as_str())
            .collect::<Vec<_>>()
            .join(" | "),
        "---|".repeat(series.len())
    );
    let Some(first) = series.first() else {
        return;
    };
    for (i, &(xv, _)) in first.1.iter().enumerate() {
        let _ = writeln!(
            report,
            "| {} | {} |",
            (xv * 1e6).round() / 1e6,
            series
                .iter()
                .map(|s| s.1.get(i).map_or("-".into(), |p| format!("{:.2}", p.1)))
                .collect::<Vec<_>>()
                .join(" | ")
        );
    }
    let _ = writeln!(report);
}

/// A line plot of the series as SVG.
fn plot(path: &Path, title: &str, x: &str, y: &str, series: &[Series]) -> Result<(), String> {
    use plotters::prelude::*;
    let err = |e: &dyn std::fmt::Display| format!("{}: {e}", path.display());
    let all = series.iter().flat_map(|s| s.1.iter());
    let (x0, x1, y1) = all.fold(
        (f64::INFINITY, f64::NEG_INFINITY, 0.0f64),
        |(a, b, c), p| (a.min(p.0), b.max(p.0), c.max(p.1)),
    );
    let (x0, x1) = if x0 < x1 { (x0, x1) } else { (0.0, 1.0) };
    let y1 = if y1 > 0.0 { y1 * 1.05 } else { 1.0 };
    let root = SVGBackend::new(path, (800, 500)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(x0..x1, 0.0..y1)
        .map_err(|e| err(&e))?;
    chart
        .configure_mesh()
        .x_desc(x)
        .y_desc(y)
        .draw()
        .map_err(|e| err(&e))?;
    for (i, (label, pts)) in series.iter().enumerate() {
        let color = Palette99::pick(i).to_rgba();
        chart
            .draw_series(LineSeries::new(pts.iter().copied(), color.stroke_width(2)))
            .map_err(|e| err(&e))?
            .label(label.as_str())
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2))
            });
        chart
            .draw_series(pts.iter().map(|&p| Circle::new(p, 3, color.filled())))
            .map_err(|e| err(&e))?;
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperLeft)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()
        .map_err(|e| err(&e))?;
    root.present().map_err(|e| err(&e))
}
