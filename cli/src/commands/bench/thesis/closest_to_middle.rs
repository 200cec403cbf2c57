//! Sections 8.3 and 8.4: queries on closest-to-middle trees (Moore) against the balanced
//! "Sorting" tree: the cylinder at each size (Fig. 8.11), the original Costa surface with
//! repeated runs (Fig. 8.12), and the torus with radius queries (Fig. 8.13).

use super::measure::{median, sorting_and_closest_to_middle, table_ms, Sample};
use super::report::{series_json, Series};
use super::Bench;
use crate::error::Result;
use crate::progress::Progress;
use nbhd::{KdTree, Neighborhood};

/// Measures, reports and plots the three comparisons, and checks Moore's claim on them.
pub(super) fn closest_to_middle_vs_median(b: &mut Bench) -> Result<()> {
    b.report
        .line("## Closest to middle vs median trees (Fig. 8.11-8.13)\n");
    let ks: Vec<usize> = if b.args.quick {
        vec![1, 25, 50, 100]
    } else {
        vec![1, 10, 25, 50, 75, 100]
    };
    let (ctm_series, cylinder_slower) = cylinder(b, &ks)?;
    let (costa_series, costa_slower) = costa(b, &ks)?;
    let (torus_series, torus_slower) = torus(b)?;
    b.report.check(
        "Closest-to-middle trees answer queries no faster than balanced trees (within 10%) on \
         every geometry tried (8.3, 8.4: Moore's result not reproduced)",
        cylinder_slower && costa_slower && torus_slower,
    );
    b.report.results["ctm_cylinder"] = series_json(&ctm_series);
    b.report.results["ctm_costa"] = series_json(&costa_series);
    b.report.results["ctm_torus"] = series_json(&torus_series);
    Ok(())
}

/// How one comparison times a tree on a neighbourhood, in milliseconds.
type Timer<'a> = dyn FnMut(&KdTree<f64>, Neighborhood<f64>) -> Result<f64> + 'a;

/// The two trees of `sample` on the neighbourhoods `xs` (x value and neighbourhood), each
/// timed by `time`; returns their curves, labelled by `label`, and whether the
/// closest-to-middle tree took at least 90% of the Sorting tree's total time.
fn race(
    sample: &Sample,
    xs: &[(f64, Neighborhood<f64>)],
    time: &mut Timer<'_>,
    label: &dyn Fn(&str) -> String,
) -> Result<(Vec<Series>, bool)> {
    let view = sample.view()?;
    let mut series = Vec::new();
    let mut sums = [0.0; 2];
    for (ti, (name, tree)) in sorting_and_closest_to_middle(&view)?.iter().enumerate() {
        let mut p = Vec::new();
        for &(x, nbhd) in xs {
            let t = time(tree, nbhd)?;
            sums[ti] += t;
            p.push((x, t));
        }
        series.push((label(name), p));
    }
    Ok((series, sums[1] >= 0.9 * sums[0]))
}

/// All k nearest with a large ε on the cylinder at each size (Fig. 8.11).
fn cylinder(b: &mut Bench, ks: &[usize]) -> Result<(Vec<Series>, bool)> {
    let cyl = &b.geos[1];
    let sizes = &cyl.sizes[..b.nsizes];
    let bar = Progress::bar(
        b.out,
        (2 * sizes.len() * ks.len()) as u64,
        "closest to middle vs median",
    );
    let mut all = Vec::new();
    let mut slower = true;
    for &n in sizes {
        let sample = Sample::new(cyl, n);
        let radius = sample.diameter;
        let xs: Vec<_> = ks
            .iter()
            .map(|&k| (k as f64, Neighborhood::KnnRadius { k, radius }))
            .collect();
        let mut time = |tree: &KdTree<f64>, nbhd| {
            let (t, _) = table_ms(tree, nbhd)?;
            bar.inc(1);
            Ok(t)
        };
        let (series, s) = race(&sample, &xs, &mut time, &|name| format!("{name}, {n}"))?;
        all.extend(series);
        slower &= s;
    }
    drop(bar);
    let report = &mut b.report;
    report.line("Cylinder, all k nearest with a large ε (Fig. 8.11):\n");
    report.table("k", &all);
    report.plot(
        "fig8.11-cylinder-knn.svg",
        "Sorting vs Closest to Middle, Cylinder (Fig. 8.11)",
        "k",
        "ms",
        &all,
    )?;
    report.line("![ctm cylinder](fig8.11-cylinder-knn.svg)\n");
    Ok((all, slower))
}

/// All k nearest with a large ε on the original Costa surface, the median of repeated runs
/// (Fig. 8.12).
fn costa(b: &mut Bench, ks: &[usize]) -> Result<(Vec<Series>, bool)> {
    let costa = &b.geos[0];
    let repeats = b.args.repeats;
    let sample = Sample::new(costa, costa.sizes[0]);
    let radius = sample.diameter;
    let xs: Vec<_> = ks
        .iter()
        .map(|&k| (k as f64, Neighborhood::KnnRadius { k, radius }))
        .collect();
    let mut time = |tree: &KdTree<f64>, nbhd| {
        let mut times = Vec::new();
        for _ in 0..repeats {
            times.push(table_ms(tree, nbhd)?.0);
        }
        Ok(median(times))
    };
    let (series, slower) = race(&sample, &xs, &mut time, &|name| name.to_string())?;
    let report = &mut b.report;
    report.line(format!(
        "{}, {} points, median of {repeats} runs (Fig. 8.12):\n",
        costa.name, costa.sizes[0]
    ));
    report.table("k", &series);
    report.plot(
        "fig8.12-costa-knn.svg",
        "Sorting vs Closest to Middle, Costa (Fig. 8.12)",
        "k",
        "ms (median)",
        &series,
    )?;
    report.line("![ctm costa](fig8.12-costa-knn.svg)\n");
    Ok((series, slower))
}

/// All within ε, no k limit, on the torus, original and once subdivided, ε from 0.1% to 10%
/// of the diameter (Fig. 8.13).
fn torus(b: &mut Bench) -> Result<(Vec<Series>, bool)> {
    let torus = &b.geos[2];
    let fracs: Vec<f64> = if b.args.quick {
        vec![0.001, 0.025, 0.05, 0.1]
    } else {
        vec![
            0.001, 0.01, 0.02, 0.03, 0.04, 0.05, 0.06, 0.07, 0.08, 0.09, 0.1,
        ]
    };
    let mut all = Vec::new();
    let mut slower = true;
    for &n in &torus.sizes[..b.nsizes.min(2)] {
        let sample = Sample::new(torus, n);
        let diam = sample.diameter;
        let xs: Vec<_> = fracs
            .iter()
            .map(|&f| {
                let nbhd = Neighborhood::Radius {
                    radius: f * diam,
                    sorted: true,
                };
                (100.0 * f, nbhd)
            })
            .collect();
        let mut time = |tree: &KdTree<f64>, nbhd| Ok(table_ms(tree, nbhd)?.0);
        let (series, s) = race(&sample, &xs, &mut time, &|name| format!("{name}, {n}"))?;
        all.extend(series);
        slower &= s;
    }
    let report = &mut b.report;
    report.line("Torus, all within ε, no k limit (Fig. 8.13):\n");
    report.table("ε in % of the diameter", &all);
    report.plot(
        "fig8.13-torus-radius.svg",
        "Sorting vs Closest to Middle, Torus (Fig. 8.13)",
        "ε [% of diameter]",
        "ms",
        &all,
    )?;
    report.line("![ctm torus](fig8.13-torus-radius.svg)\n");
    Ok((all, slower))
}
