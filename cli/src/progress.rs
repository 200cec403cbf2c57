//! Progress bars and spinners on standard error (indicatif), hidden with `--quiet` or
//! `--json` and whenever standard error is not a terminal.

use crate::output::Output;
use indicatif::{ProgressBar, ProgressStyle};
use std::time::Duration;

/// A progress bar, a spinner, or nothing.
pub struct Progress {
    bar: ProgressBar,
}

impl Progress {
    /// A bar of `len` steps labelled `msg`.
    pub fn bar(out: &Output, len: u64, msg: impl Into<String>) -> Self {
        let bar = if out.json || out.quiet {
            ProgressBar::hidden()
        } else {
            ProgressBar::new(len)
        };
        bar.set_style(
            ProgressStyle::with_template(
                "{spinner:.green} {msg:28} [{bar:32.cyan/blue}] {percent:>3}% {elapsed:>4}",
            )
            .expect("valid template")
            .progress_chars("=> "),
        );
        bar.set_message(msg.into());
        bar.enable_steady_tick(Duration::from_millis(120));
        Self { bar }
    }

    /// A spinner labelled `msg`, for a step whose length is unknown.
    pub fn spinner(out: &Output, msg: impl Into<String>) -> Self {
        let bar = if out.json || out.quiet {
            ProgressBar::hidden()
        } else {
            ProgressBar::new_spinner()
        };
        bar.set_style(
            ProgressStyle::with_template("{spinner:.green} {msg} {elapsed}")
                .expect("valid template"),
        );
        bar.set_message(msg.into());
        bar.enable_steady_tick(Duration::from_millis(120));
        Self { bar }
    }

    /// Nothing on screen.
    pub fn hidden() -> Self {
        Self {
            bar: ProgressBar::hidden(),
        }
    }

    /// Sets the label.
    pub fn message(&self, msg: impl Into<String>) {
        self.bar.set_message(msg.into());
    }

    /// Sets the position.
    pub fn set(&self, pos: u64) {
        self.bar.set_position(pos);
    }

    /// Advances by `n` steps.
    pub fn inc(&self, n: u64) {
        self.bar.inc(n);
    }

    /// Runs `f` with the bar taken off the screen, so that `f` can print.
    pub fn suspend<R>(&self, f: impl FnOnce() -> R) -> R {
        self.bar.suspend(f)
    }

    /// A callback for `nbhd::smooth::smooth_with_progress` that moves this bar (of any
    /// length) from 0 to its end and names the stage.
    pub fn smoothing_callback(
        &self,
        label: &str,
    ) -> impl FnMut(f64, nbhd::smooth::Stage) -> bool + '_ {
        let label = label.to_string();
        let len = self.bar.length().unwrap_or(1000);
        self.bar.set_length(len);
        move |f, stage| {
            use nbhd::smooth::Stage;
            let what = match stage {
                Stage::Neighbors => "neighbourhoods",
                Stage::Geometry => "normals, curvatures",
                Stage::Step => "moving points",
                Stage::Outputs => "outputs",
                Stage::Done => "done",
            };
            self.bar.set_message(format!("{label}: {what}"));
            self.bar.set_position((f * len as f64).round() as u64);
            true
        }
    }
}

impl Drop for Progress {
    fn drop(&mut self) {
        self.bar.finish_and_clear();
    }
}
