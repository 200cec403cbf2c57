//! How commands print: human text, one JSON document (`--json`), or nothing (`--quiet`).

/// Output mode shared by all commands.
#[derive(Clone, Copy, Debug)]
pub struct Output {
    /// Print one JSON document on stdout.
    pub json: bool,
    /// Print nothing but errors (and JSON if asked for).
    pub quiet: bool,
}

impl Output {
    pub fn new(json: bool, quiet: bool) -> Self {
        Self { json, quiet }
    }

    /// Prints the human-readable text unless `--json` or `--quiet`.
    pub fn text(&self, s: impl AsRef<str>) {
        if !self.json && !self.quiet {
            emit(s.as_ref());
        }
    }

    /// Prints a message on standard error unless `--json` or `--quiet` (for commands whose
    /// result goes to standard output).
    pub fn note(&self, s: impl AsRef<str>) {
        if !self.json && !self.quiet {
            eprintln!("{}", s.as_ref());
        }
    }

    /// Prints the JSON document if `--json`.
    pub fn json(&self, v: &serde_json::Value) {
        if self.json {
            emit(&serde_json::to_string_pretty(v).expect("JSON of plain values"));
        }
    }
}

/// Writes a line to stdout; a closed pipe (`nbhd info --json x | head`) is not an error.
fn emit(s: &str) {
    use std::io::Write;
    let _ = writeln!(std::io::stdout().lock(), "{s}");
}

/// A float for JSON: `null` for NaN and infinities (JSON has no such numbers).
pub fn num(v: f64) -> serde_json::Value {
    serde_json::Number::from_f64(v).map_or(serde_json::Value::Null, serde_json::Value::Number)
}

/// The time since `t` in milliseconds, as the commands report times.
pub fn ms(t: std::time::Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}
