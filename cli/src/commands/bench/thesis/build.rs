//! Section 8.1: build times (Fig. 8.4–8.6, 8.8) and depths (Fig. 8.7) of every tree variant on
//! the three geometries, beside the thesis' figures.

use super::measure::{median, thesis_options, Sample};
use super::report::{slug, Report, Series};
use super::setup::{Geometry, THESIS_BUILD_MS, THESIS_DEPTH, VARIANTS};
use super::Bench;
use crate::error::Result;
use crate::output::{ms, num};
use crate::progress::Progress;
use nbhd::{KdTree, PivotPolicy};
use serde_json::json;
use std::time::Instant;

/// One build variant on one geometry: the median build time and the depth at each size.
struct VariantRow {
    label: String,
    ms: Vec<f64>,
    depths: Vec<usize>,
}

/// Measures, reports and plots the builds of every variant on every geometry.
pub(super) fn build_times(b: &mut Bench) -> Result<()> {
    let nsizes = b.nsizes;
    let report = &mut b.report;
    let steps = (b.geos.len() * nsizes * VARIANTS.len()) as u64;
    let bar = Progress::bar(b.out, steps, "building trees");
    let mut build = Vec::new();
    report.line("## Build times (Fig. 8.8) and depths (Fig. 8.7)\n");
    for (gi, g) in b.geos.iter().enumerate() {
        let sizes = &g.sizes[..nsizes];
        let (rows, identical) = measure_builds(g, sizes, b.args.repeats, &bar)?;
        report.check(
            format!(
                "{}: every median algorithm and the presorted build give the identical tree (8.1)",
                g.name
            ),
            identical,
        );
        build_table(report, nsizes, gi, g, &rows);
        check_build_claims(report, nsizes, g, &rows);
        let series: Vec<Series> = rows
            .iter()
            .map(|r| {
                let points = sizes.iter().zip(&r.ms).map(|(&n, &t)| (n as f64, t));
                (r.label.clone(), points.collect())
            })
            .collect();
        let file = format!("build-{}.svg", slug(g.name));
        report.plot(
            &file,
            &format!("Build times, {} (Fig. 8.4-8.6)", g.name),
            "points",
            "ms (median)",
            &series,
        )?;
        report.line(format!("![build times]({file})\n"));
        build.push(json!({
            "geometry": g.name,
            "sizes": sizes,
            "variants": rows.iter().map(|r| json!({"variant": r.label, "ms": r.ms.iter().map(|&x| num(x)).collect::<Vec<_>>(), "depth": r.depths})).collect::<Vec<_>>(),
        }));
    }
    report.results["build"] = json!(build);
    Ok(())
}

/// Builds every variant `repeats` times at each size (after one untimed build); returns a row
/// per variant and whether every cyclic-median variant built the identical tree.
fn measure_builds(
    g: &Geometry,
    sizes: &[usize],
    repeats: usize,
    bar: &Progress,
) -> Result<(Vec<VariantRow>, bool)> {
    let mut rows: Vec<VariantRow> = VARIANTS
        .iter()
        .map(|v| VariantRow {
            label: v.0.to_string(),
            ms: Vec::new(),
            depths: Vec::new(),
        })
        .collect();
    let mut identical = true;
    for &n in sizes {
        let sample = Sample::new(g, n);
        let view = sample.view()?;
        let mut reference: Option<KdTree<f64>> = None;
        for (row, &(label, pivot, med)) in rows.iter_mut().zip(VARIANTS.iter()) {
            bar.message(format!("{} {n}: {label}", g.name));
            let opts = thesis_options(pivot, med);
            let mut times = Vec::new();
            // One untimed build first: page faults and caches are not the variant's.
            let mut tree = KdTree::<f64>::build(&view, &opts)?;
            for _ in 0..repeats {
                let t = Instant::now();
                tree = KdTree::<f64>::build(&view, &opts)?;
                times.push(ms(t));
            }
            row.ms.push(median(times));
            row.depths.push(tree.stats().depth);
            if pivot == PivotPolicy::CyclicMedian {
                match &reference {
                    None => reference = Some(tree),
                    Some(r) => identical &= r.same_structure(&tree),
                }
            }
            bar.inc(1);
        }
    }
    Ok((rows, identical))
}

/// `a / b / c`.
fn joined<T: ToString>(values: &[T]) -> String {
    values
        .iter()
        .map(|v| v.to_string())
        .collect::<Vec<_>>()
        .join(" / ")
}

/// The markdown table of one geometry: our times and depths next to the thesis'.
fn build_table(report: &mut Report, nsizes: usize, gi: usize, g: &Geometry, rows: &[VariantRow]) {
    let sizes: Vec<String> = g.sizes[..nsizes].iter().map(|n| n.to_string()).collect();
    report.line(format!("### {}\n", g.name));
    report.line(format!(
        "| variant | {} | depth | thesis ms | thesis depth |\n|---|{}---|---|---|",
        sizes.join(" | "),
        "---|".repeat(nsizes)
    ));
    for (vi, row) in rows.iter().enumerate() {
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
                joined(&d[which][..nsizes])
            } else {
                "-".into()
            }
        });
        report.line(format!(
            "| {} | {} | {} | {} | {} |",
            row.label,
            row.ms
                .iter()
                .map(|t| format!("{t:.2}"))
                .collect::<Vec<_>>()
                .join(" | "),
            joined(&row.depths),
            thesis_ms.unwrap_or_else(|| "-".into()),
            thesis_depth.unwrap_or_else(|| "-".into()),
        ));
    }
    report.line("");
}

/// The thesis' claims on builds: Floyd-Rivest is the fastest balanced build, and
/// closest-to-middle trees are far deeper than balanced ones.
fn check_build_claims(report: &mut Report, nsizes: usize, g: &Geometry, rows: &[VariantRow]) {
    let fr = &rows[3].ms;
    let fastest = (0..nsizes).all(|s| (0..3).all(|v| fr[s] <= rows[v].ms[s]));
    report.check(
        format!(
            "{}: Median (Floyd-Rivest) builds faster than Sorting, Median (Sorting) and Median (Linear Det.) at every size",
            g.name
        ),
        fastest,
    );
    let deeper = (0..nsizes).all(|s| rows[4].depths[s] > 2 * rows[0].depths[s]);
    report.check(
        format!(
            "{}: closest-to-middle trees are far deeper than balanced ones, more than twice \
             (Fig. 8.7; depths here {} vs {})",
            g.name,
            joined(&rows[4].depths),
            joined(&rows[0].depths),
        ),
        deeper,
    );
}
