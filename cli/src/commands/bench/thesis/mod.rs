//! `nbhd bench thesis`: the computational results of the thesis' Chapter 8, reproduced on
//! generated samples of its three geometries at its sizes (Fig. 8.2), with a markdown report and
//! SVG plots.
//!
//! The thesis' Costa surface is replaced by a catenoid (`nbhd::shapes::Catenoid`), its cylinder
//! by the open cylinder with a plane segment through its axis, and its Catmull–Clark
//! subdivisions by uniform random samples of the same point counts. Times are single-threaded,
//! as the thesis' Java program was, and trees have one point per leaf (the thesis' shape).

//!
//! The run follows the chapter: `build` (8.1), `baselines` (8.2), `closest_to_middle`
//! (8.3, 8.4), then the list of the thesis' claims and whether each holds here; `setup` holds
//! the geometries, variants and the thesis' own figures, `measure` the samples, trees and
//! timed tables, `report` the markdown, JSON and plots.

mod baselines;
mod build;
mod closest_to_middle;
mod measure;
mod report;
mod setup;

use crate::error::{Context, Result};
use crate::output::{num, Output};
use report::Report;
use serde_json::json;
use setup::Geometry;
use std::path::PathBuf;
use std::time::Instant;

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

/// Runs the benchmark on one thread, as the thesis did.
pub fn run(a: ThesisArgs, out: &Output) -> Result<()> {
    if a.repeats == 0 {
        return Err("--repeats must be at least 1".into());
    }
    std::fs::create_dir_all(&a.out).context(a.out.display())?;
    // Every timing on one thread, as in the thesis.
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build()?;
    pool.install(|| run_chapter(&a, out))
}

/// What every section reads and the report it adds to.
struct Bench<'a> {
    args: &'a ThesisArgs,
    out: &'a Output,
    /// Sizes per geometry: 3, or 1 with --quick.
    nsizes: usize,
    /// Costa (a catenoid), Cylinder, Torus.
    geos: Vec<Geometry>,
    report: Report,
}

/// The sections in turn, then the conclusions and the files.
fn run_chapter(a: &ThesisArgs, out: &Output) -> Result<()> {
    let started = Instant::now();
    let mut b = Bench {
        args: a,
        out,
        nsizes: if a.quick { 1 } else { 3 },
        geos: setup::geometries(),
        report: Report::new(&a.out),
    };
    b.report.line(format!(
        "# Chapter 8 of the thesis, reproduced with nbhd\n\n\
         Generated samples at the sizes of Fig. 8.2 (Costa is a catenoid here, the cylinder the open \
         cylinder with a plane segment through its axis; uniform random samples instead of \
         Catmull-Clark subdivisions). Single-threaded, one point per leaf, times in ms; builds \
         are the median of {} runs after one untimed build, query times the faster of two runs \
         of the all-point table.{}\n",
        a.repeats,
        if a.quick { " Quick run: original sizes only." } else { "" }
    ));
    build::build_times(&mut b)?;
    baselines::kd_tree_vs_pca_vs_brute(&mut b)?;
    closest_to_middle::closest_to_middle_vs_median(&mut b)?;
    conclusions(&mut b.report, started);
    write_files(b.report, &a.out, out)
}

/// The claims of the thesis and whether each holds, and the total run time.
fn conclusions(report: &mut Report, started: Instant) {
    report.line("## The thesis' conclusions on this implementation\n");
    let lines: Vec<String> = report
        .checks
        .iter()
        .map(|(c, ok)| format!("- {}: {c}", if *ok { "holds" } else { "does NOT hold" }))
        .collect();
    for l in lines {
        report.line(l);
    }
    let secs = started.elapsed().as_secs_f64();
    report.line(format!("\nTotal run time {secs:.1} s."));
    report.results["checks"] = report
        .checks
        .iter()
        .map(|(c, ok)| json!({"claim": c, "holds": ok}))
        .collect();
    report.results["seconds"] = num(secs);
}

/// Writes report.md and results.json, and prints the report (or the JSON results).
fn write_files(mut report: Report, dir: &std::path::Path, out: &Output) -> Result<()> {
    let md = dir.join("report.md");
    std::fs::write(&md, &report.md).context(md.display())?;
    let js = dir.join("results.json");
    std::fs::write(
        &js,
        serde_json::to_string_pretty(&report.results).expect("plain values"),
    )
    .context(js.display())?;
    report.results["report"] = json!(md.display().to_string());
    out.json(&report.results);
    out.text(format!(
        "{}\nwrote {} (with SVG plots and results.json)",
        report.md,
        md.display()
    ));
    Ok(())
}
