//! The report of `nbhd bench thesis`: markdown text, the JSON results, the claims of the
//! thesis checked on this run, and the tables and SVG plots of measured curves.

use crate::error::{Error, Result};
use crate::output::num;
use serde_json::json;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// A curve: label and (x, y) points.
pub(super) type Series = (String, Vec<(f64, f64)>);

/// What a run writes: `report.md`, `results.json` and the plots, all in one folder.
pub(super) struct Report {
    /// The markdown text.
    pub md: String,
    /// The JSON results.
    pub results: serde_json::Value,
    /// Each claim of the thesis and whether it holds on this run.
    pub checks: Vec<(String, bool)>,
    /// The results folder.
    dir: PathBuf,
}

impl Report {
    /// An empty report into the folder `dir`.
    pub fn new(dir: &Path) -> Self {
        Self {
            md: String::new(),
            results: json!({}),
            checks: Vec::new(),
            dir: dir.to_path_buf(),
        }
    }

    /// Adds a line (and a newline) to the markdown text.
    pub fn line(&mut self, text: impl std::fmt::Display) {
        let _ = writeln!(self.md, "{text}");
    }

    /// Records whether a claim of the thesis holds.
    pub fn check(&mut self, claim: impl Into<String>, holds: bool) {
        self.checks.push((claim.into(), holds));
    }

    /// Adds a markdown table of `series`, one row per x.
    pub fn table(&mut self, x: &str, series: &[Series]) {
        table_md(&mut self.md, x, series);
    }

    /// Draws `series` into the SVG file `file` of the results folder.
    pub fn plot(&self, file: &str, title: &str, x: &str, y: &str, series: &[Series]) -> Result<()> {
        plot(&self.dir.join(file), title, x, y, series)
    }
}

/// The first word of a name, in lower case, for file names.
pub(super) fn slug(s: &str) -> String {
    s.split_whitespace()
        .next()
        .unwrap_or(s)
        .to_ascii_lowercase()
}

/// The curves as JSON: label, x values and times.
pub(super) fn series_json(series: &[Series]) -> serde_json::Value {
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
fn plot(path: &Path, title: &str, x: &str, y: &str, series: &[Series]) -> Result<()> {
    use plotters::prelude::*;
    let err = |e: &dyn std::fmt::Display| Error::about(path.display(), e);
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
