//! Side-by-side speed of nbhd, kiddo's immutable tree and brute force: a thin wrapper around
//! the CLI's `nbhd bench speed` (cli/src/commands/bench/speed.rs), which is the one home of the
//! side-by-side table (see `nbhd bench speed --help` and cli/README.md).
//!
//! Run: `cargo bench --bench compare -- --sets torus-77k,cylinder-plane-123k --ops knn10`:
//! every argument after `--` goes to `nbhd bench speed`. Without `--sets` every generated set
//! runs (`--sets all`). The old variables still work: `NBHD_BENCH_SETS`, `NBHD_BENCH_OPS`
//! (comma lists) and `NBHD_BENCH_REPS` become `--sets`, `--ops` and `--reps`.
//!
//! For statistics per function (criterion), see benches/tables.rs.

use std::process::{Command, ExitCode};

/// The arguments of `nbhd bench speed`: the old variables first, then the command line's
/// (cargo bench adds `--bench`, which is dropped).
fn speed_args() -> Vec<String> {
    let mut args: Vec<String> = vec!["bench".into(), "speed".into()];
    for (var, flag) in [
        ("NBHD_BENCH_SETS", "--sets"),
        ("NBHD_BENCH_OPS", "--ops"),
        ("NBHD_BENCH_REPS", "--reps"),
    ] {
        if let Ok(v) = std::env::var(var) {
            args.extend([flag.to_string(), v]);
        }
    }
    let given: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| a != "--bench")
        .collect();
    if !args.iter().chain(&given).any(|a| a.starts_with("--sets")) {
        args.extend(["--sets".into(), "all".into()]);
    }
    args.extend(given);
    args
}

fn main() -> ExitCode {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| env!("CARGO").to_string());
    let status = Command::new(cargo)
        .args(["run", "--quiet", "--release", "-p", "nbhd-cli", "--"])
        .args(speed_args())
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .status();
    match status {
        Ok(s) if s.success() => ExitCode::SUCCESS,
        Ok(s) => {
            eprintln!("compare: nbhd bench speed failed ({s})");
            ExitCode::FAILURE
        }
        Err(e) => {
            eprintln!("compare: could not run cargo: {e}");
            ExitCode::FAILURE
        }
    }
}
