//! The command line of README.md, run as the README shows it. Its blocks marked
//! `<!-- snippet: cli-quickstart -->` and `<!-- snippet: cli-install -->` (taken out by
//! `scripts/readme-snippet.sh`, which every README test uses) run in bash, stopping at the
//! first failing line:
//!
//! - the quick start from a directory whose `tests/` is the repository's (the README runs it
//!   from the clone's root), with the `nbhd` of this build first on `PATH`; every file it names
//!   outside `tests/` must then exist and not be empty;
//! - the install line in the clone's root with `CARGO_INSTALL_ROOT` in a temporary directory,
//!   whose `bin/` is first on `PATH`: the `nbhd` it installs must be there and print this
//!   version. That is a `dist` build of the tool (minutes when it is not up to date), so it runs
//!   only with `NBHD_TEST_INSTALL=1`, which `scripts/test.sh` sets (its C++ stage reuses the
//!   build).
#![cfg(unix)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("cli/ lies in the repository")
        .to_path_buf()
}

/// The README's block `name`.
fn snippet(name: &str) -> String {
    let out = Command::new("sh")
        .arg(repo().join("scripts/readme-snippet.sh"))
        .arg(repo().join("README.md"))
        .arg(name)
        .output()
        .expect("cannot run sh");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).expect("README.md is UTF-8")
}

/// `PATH` with `first` in front.
fn path_with(first: &Path) -> String {
    let rest = std::env::var("PATH").unwrap_or_default();
    format!("{}:{rest}", first.display())
}

/// Runs `block` with `bash -euo pipefail` and fails the test with its output if it fails.
fn run_block(name: &str, block: &str, cmd: &mut Command) -> Output {
    let out = cmd
        .args(["-euo", "pipefail", "-c", block])
        .output()
        .expect("cannot run bash");
    assert!(
        out.status.success(),
        "README.md's block {name} failed ({}):\n{block}\n--- stdout\n{}\n--- stderr\n{}",
        out.status,
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// A fresh directory under the target's temporary directory.
fn fresh_dir(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    if dir.exists() {
        std::fs::remove_dir_all(&dir).expect("cannot empty the test directory");
    }
    std::fs::create_dir_all(&dir).expect("cannot make the test directory");
    dir
}

/// The words of `block` that name a file the commands write: a point file, a picture or a
/// table outside `tests/`.
fn written_files(block: &str) -> Vec<&str> {
    const WRITTEN: [&str; 7] = [".ply", ".pcd", ".las", ".laz", ".xyz", ".csv", ".png"];
    block
        .lines()
        .map(|line| line.split('#').next().unwrap_or(""))
        .flat_map(str::split_whitespace)
        .filter(|w| !w.starts_with("tests/") && !w.starts_with('-'))
        .filter(|w| WRITTEN.iter().any(|ext| w.ends_with(ext)))
        .collect()
}

#[test]
fn readme_cli_quick_start_runs_as_written() {
    let block = snippet("cli-quickstart");
    let dir = fresh_dir("readme_cli_quickstart");
    std::os::unix::fs::symlink(repo().join("tests"), dir.join("tests"))
        .expect("cannot link tests/");
    let bin = Path::new(env!("CARGO_BIN_EXE_nbhd"))
        .parent()
        .expect("the binary lies in a directory");
    run_block(
        "cli-quickstart",
        &block,
        Command::new("bash")
            .current_dir(&dir)
            .env("PATH", path_with(bin)),
    );
    let files = written_files(&block);
    assert!(
        !files.is_empty(),
        "the quick start writes no file:\n{block}"
    );
    for f in files {
        let len = std::fs::metadata(dir.join(f)).map(|m| m.len()).unwrap_or(0);
        assert!(len > 0, "the quick start did not write {f}:\n{block}");
    }
}

#[test]
fn readme_install_puts_this_nbhd_on_the_path() {
    if std::env::var_os("NBHD_TEST_INSTALL").is_none_or(|v| v != "1") {
        eprintln!(
            "skipped: the README's `cargo install` is a dist build of the tool; \
             NBHD_TEST_INSTALL=1 runs it (scripts/test.sh sets it)"
        );
        return;
    }
    let block = snippet("cli-install");
    let root = fresh_dir("readme_install_root");
    let out = run_block(
        "cli-install",
        &block,
        Command::new("bash")
            .current_dir(repo())
            .env("CARGO_INSTALL_ROOT", &root)
            .env("PATH", path_with(&root.join("bin"))),
    );
    assert!(
        root.join("bin/nbhd").is_file(),
        "the README's install block put no nbhd into {}/bin",
        root.display()
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    let version = format!("nbhd {}", env!("CARGO_PKG_VERSION"));
    assert!(
        stdout.lines().any(|l| l.trim() == version),
        "the installed tool did not print `{version}`:\n{stdout}"
    );
}
