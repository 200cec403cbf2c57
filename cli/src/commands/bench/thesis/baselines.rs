//! Section 8.2: the k-d tree against the PCA sweep and brute force on the original cylinder,
//! all k nearest (Fig. 8.9) and all within ε (Fig. 8.10).

use super::measure::{sorting_tree, table_ms, Baseline, Sample, Searcher};
use super::report::{series_json, Report, Series};
use super::Bench;
use crate::error::Result;
use crate::progress::Progress;
use nbhd::{BruteForce, Neighborhood, NonFinitePolicy, PcaSweep};

/// Measures, reports and plots the three searchers, and checks that the tree is the fastest.
pub(super) fn kd_tree_vs_pca_vs_brute(b: &mut Bench) -> Result<()> {
    let cyl = &b.geos[1];
    let sample = Sample::new(cyl, cyl.sizes[0]);
    let view = sample.view()?;
    let diam = sample.diameter;
    let kd = sorting_tree(&view)?;
    let pca = Baseline(PcaSweep::<f64>::new(&view, NonFinitePolicy::Reject)?);
    let brute = Baseline(BruteForce::<f64>::new(&view, NonFinitePolicy::Reject)?);
    let searchers: [(&str, &dyn Searcher); 3] = [
        ("kd-tree (Sorting)", &kd),
        ("PCA sweep", &pca),
        ("brute force", &brute),
    ];
    let ks: Vec<usize> = if b.args.quick {
        vec![1, 10, 50, 100, 200, 400]
    } else {
        vec![1, 5, 10, 25, 50, 75, 100, 150, 200, 250, 300, 350, 400]
    };
    let fracs: Vec<f64> = if b.args.quick {
        vec![0.001, 0.02, 0.05, 0.1, 0.15]
    } else {
        vec![0.001, 0.01, 0.02, 0.03, 0.05, 0.075, 0.1, 0.125, 0.15]
    };
    let bar = Progress::bar(
        b.out,
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
            let nbhd = Neighborhood::Radius {
                radius: f * diam,
                sorted: true,
            };
            let (t, _) = table_ms(s, nbhd)?;
            r_pts.push((100.0 * f, t));
            bar.inc(1);
        }
        rad_series.push((label.to_string(), r_pts));
    }
    drop(bar);
    write_report(&mut b.report, cyl.sizes[0], diam, &knn_series, &rad_series)
}

/// The tables, plots and checks of Section 8.2.
fn write_report(
    report: &mut Report,
    points: usize,
    diam: f64,
    knn_series: &[Series],
    rad_series: &[Series],
) -> Result<()> {
    report.line(format!(
        "## k-d tree vs PCA sweep vs brute force (Fig. 8.9, 8.10)\n\nCylinder, {points} points, \
         diameter {diam:.3}; all-point tables, self excluded.\n",
    ));
    report.table("k (ε = diameter)", knn_series);
    report.table("ε in % of the diameter (no k limit)", rad_series);
    report.plot(
        "fig8.9-knn.svg",
        "All k nearest (large ε), Cylinder (Fig. 8.9)",
        "k",
        "ms",
        knn_series,
    )?;
    report.plot(
        "fig8.10-radius.svg",
        "All within ε (no k limit), Cylinder (Fig. 8.10)",
        "ε [% of diameter]",
        "ms",
        rad_series,
    )?;
    report.line("![k](fig8.9-knn.svg)\n![radius](fig8.10-radius.svg)\n");
    // The tree (first series) against the PCA sweep (second) at every x.
    let faster =
        |series: &[Series]| (0..series[0].1.len()).all(|i| series[0].1[i].1 < series[1].1[i].1);
    report.check(
        "Cylinder: the k-d tree is faster than the PCA sweep for every k up to 400 (8.2)",
        faster(knn_series),
    );
    report.check(
        "Cylinder: the k-d tree is faster than the PCA sweep for every ε up to 15% of the diameter (8.2)",
        faster(rad_series),
    );
    report.results["kd_vs_pca_knn"] = series_json(knn_series);
    report.results["kd_vs_pca_radius"] = series_json(rad_series);
    Ok(())
}
