//! The C ABI tested from C. Builds the cdylib (`cargo build --lib` with this test's profile and
//! target directory, which reuses the library the tests were built with), compiles the programs in `tests/c/` against it and `include/nbhd.h` with
//! the system C compiler (`cc`, or `$CC`), and runs them: natively, under valgrind memcheck
//! (skipped with a note when valgrind is absent, unless `NBHD_REQUIRE_VALGRIND` is set), and
//! with several threads on one tree. Also checks that the C test calls every export of the
//! header and that the header compiles and links as C++.
#![cfg(unix)]

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::{Mutex, OnceLock};

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

/// Where the cdylib is and where compiled C programs go.
struct Built {
    lib_dir: PathBuf,
    out_dir: PathBuf,
}

/// Prints a note that shows even when the test harness captures output.
fn note(text: &str) {
    let _ = writeln!(std::io::stderr(), "note: {text}");
}

fn describe(what: &str, out: &Output) -> String {
    format!(
        "{what} failed ({}):\n--- stdout\n{}\n--- stderr\n{}",
        out.status,
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    )
}

/// Builds the cdylib once per test process, with the profile this test was built with, into
/// the same target directory (so a clean clone needs nothing but `cargo test`).
fn built() -> &'static Built {
    static BUILT: OnceLock<Result<Built, String>> = OnceLock::new();
    let built = BUILT.get_or_init(|| {
        let exe = std::env::current_exe().map_err(|e| e.to_string())?;
        // The test runs from <target>/<profile dir>/deps/.
        let profile_dir = exe
            .parent()
            .and_then(Path::parent)
            .ok_or("cannot find the profile directory")?
            .to_path_buf();
        let target_dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
            .parent()
            .ok_or("cannot find the target directory")?
            .to_path_buf();
        let profile = profile_dir
            .file_name()
            .and_then(|n| n.to_str())
            .ok_or("profile directory without a name")?
            .to_owned();
        let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
        let mut cmd = Command::new(cargo);
        cmd.args(["build", "--lib", "--quiet", "--manifest-path"])
            .arg(Path::new(ROOT).join("Cargo.toml"))
            .arg("--target-dir")
            .arg(&target_dir);
        // The profile `cargo test` built this test with: `test` for target/debug, `bench` for
        // target/release (`cargo test --release`). The lib unit is then the one already built
        // for the tests, so nothing is compiled twice.
        let cargo_profile = match profile.as_str() {
            "debug" => "test",
            "release" => "bench",
            other => other,
        };
        cmd.args(["--profile", cargo_profile]);
        // With `cargo test --target T` the test runs from <target>/T/<profile dir>/deps/.
        if let Some(triple) = profile_dir
            .parent()
            .filter(|p| *p != target_dir)
            .and_then(Path::file_name)
        {
            cmd.arg("--target").arg(triple);
        }
        let out = cmd.output().map_err(|e| format!("cannot run cargo: {e}"))?;
        if !out.status.success() {
            return Err(describe("cargo build --lib", &out));
        }
        let lib = profile_dir.join(format!(
            "{}nbhd{}",
            std::env::consts::DLL_PREFIX,
            std::env::consts::DLL_SUFFIX
        ));
        if !lib.exists() {
            return Err(format!("the cdylib is not at {}", lib.display()));
        }
        let out_dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
            .join("c_abi")
            .join(&profile);
        std::fs::create_dir_all(&out_dir).map_err(|e| e.to_string())?;
        Ok(Built {
            lib_dir: profile_dir,
            out_dir,
        })
    });
    match built {
        Ok(b) => b,
        Err(e) => panic!("{e}"),
    }
}

/// Compiles `tests/c/<name>.c` once per test process and returns the executable.
fn compiled(name: &str) -> PathBuf {
    static DONE: Mutex<Vec<(String, PathBuf)>> = Mutex::new(Vec::new());
    let mut done = DONE.lock().unwrap_or_else(|e| e.into_inner());
    if let Some((_, exe)) = done.iter().find(|(n, _)| n == name) {
        return exe.clone();
    }
    let b = built();
    let exe = b.out_dir.join(name);
    let cc = std::env::var("CC").unwrap_or_else(|_| "cc".into());
    let out = Command::new(&cc)
        .args(["-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic"])
        // The brute force must round exactly as the library: no fused multiply-adds.
        .args(["-ffp-contract=off", "-g", "-O1", "-pthread"])
        .arg("-I")
        .arg(Path::new(ROOT).join("include"))
        .arg(Path::new(ROOT).join("tests/c").join(format!("{name}.c")))
        .arg("-o")
        .arg(&exe)
        .arg(format!("-L{}", b.lib_dir.display()))
        .arg(format!("-Wl,-rpath,{}", b.lib_dir.display()))
        .args(["-lnbhd", "-lm"])
        .output()
        .unwrap_or_else(|e| panic!("cannot run the C compiler `{cc}`: {e}"));
    assert!(
        out.status.success(),
        "{}",
        describe(&format!("compiling tests/c/{name}.c"), &out)
    );
    done.push((name.to_owned(), exe.clone()));
    exe
}

fn run(mut cmd: Command, what: &str) {
    let out = cmd
        .env("LD_LIBRARY_PATH", &built().lib_dir)
        .output()
        .unwrap_or_else(|e| panic!("cannot run {what}: {e}"));
    print!("{}", String::from_utf8_lossy(&out.stdout));
    assert!(out.status.success(), "{}", describe(what, &out));
}

/// `valgrind` if it is installed; otherwise a note and `None` (or a failure when
/// `NBHD_REQUIRE_VALGRIND` is set, as in CI).
fn valgrind() -> Option<Command> {
    let found = Command::new("valgrind")
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success());
    if !found {
        assert!(
            std::env::var_os("NBHD_REQUIRE_VALGRIND").is_none(),
            "valgrind is required (NBHD_REQUIRE_VALGRIND is set) but not installed"
        );
        note("valgrind is not installed: the memcheck run of the C tests is SKIPPED (install valgrind to run it)");
        return None;
    }
    let mut cmd = Command::new("valgrind");
    cmd.args([
        "--error-exitcode=1",
        "--leak-check=full",
        "--errors-for-leak-kinds=definite,indirect",
        "--show-leak-kinds=definite,indirect",
        "--track-origins=yes",
        "--quiet",
    ]);
    Some(cmd)
}

#[test]
fn c_program_checks_every_export_and_error_path() {
    run(Command::new(compiled("abi_test")), "tests/c/abi_test");
}

#[test]
fn c_program_is_clean_under_valgrind() {
    let exe = compiled("abi_test");
    if let Some(mut cmd) = valgrind() {
        cmd.arg(exe);
        run(cmd, "valgrind tests/c/abi_test");
    }
}

#[test]
fn c_threads_share_one_tree() {
    run(
        Command::new(compiled("threads_test")),
        "tests/c/threads_test",
    );
}

#[test]
fn c_threads_are_clean_under_valgrind() {
    let exe = compiled("threads_test");
    if let Some(mut cmd) = valgrind() {
        // Fewer points: valgrind runs the threads one at a time, some 30 times slower.
        cmd.arg(exe).arg("600");
        run(cmd, "valgrind tests/c/threads_test");
    }
}

#[test]
fn c_smoothing_checks_against_a_sphere() {
    run(Command::new(compiled("smooth_test")), "tests/c/smooth_test");
}

#[test]
fn c_smoothing_is_clean_under_valgrind() {
    let exe = compiled("smooth_test");
    if let Some(mut cmd) = valgrind() {
        // Fewer points: valgrind is some 30 times slower.
        cmd.arg(exe).arg("400");
        run(cmd, "valgrind tests/c/smooth_test");
    }
}

/// Names of the functions the header declares.
fn header_functions() -> Vec<String> {
    let header = std::fs::read_to_string(Path::new(ROOT).join("include/nbhd.h")).unwrap();
    let mut names = Vec::new();
    for line in header
        .lines()
        .filter(|l| !l.starts_with([' ', '*', '/', '#']))
    {
        // `ret_type *name(args` : the identifier just before the parenthesis.
        if let Some((before, _)) = line.split_once('(') {
            let name = before.rsplit([' ', '*']).next().unwrap_or("");
            if name.starts_with("nbhd_") {
                names.push(name.to_owned());
            }
        }
    }
    names
}

#[test]
fn c_tests_call_every_export() {
    let names = header_functions();
    assert!(names.len() >= 20, "too few functions found: {names:?}");
    let mut source = String::new();
    for entry in std::fs::read_dir(Path::new(ROOT).join("tests/c")).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "c") {
            source += &std::fs::read_to_string(path).unwrap();
        }
    }
    let missing: Vec<_> = names
        .iter()
        .filter(|n| !source.contains(&format!("{n}(")))
        .collect();
    assert!(
        missing.is_empty(),
        "no C test in tests/c/ calls {missing:?}"
    );
}

#[test]
fn header_compiles_and_links_as_cpp() {
    let cxx = std::env::var("CXX").unwrap_or_else(|_| "c++".into());
    if Command::new(&cxx).arg("--version").output().is_err() {
        note(&format!(
            "no C++ compiler `{cxx}`: the C++ check of nbhd.h is SKIPPED"
        ));
        return;
    }
    let b = built();
    let src = b.out_dir.join("cpp_check.cpp");
    let exe = b.out_dir.join("cpp_check");
    std::fs::write(
        &src,
        "#include \"nbhd.h\"\n\
         int main() {\n\
             nbhd_build_options o = nbhd_build_options_default();\n\
             nbhd_tree *t = nullptr;\n\
             nbhd_status s = nbhd_tree_build(nullptr, &o, &t);\n\
             nbhd_tree_free(t);\n\
             return (nbhd_version() == NBHD_VERSION && s == NBHD_STATUS_NULL_POINTER) ? 0 : 1;\n\
         }\n",
    )
    .unwrap();
    let out = Command::new(&cxx)
        .args(["-std=c++11", "-Wall", "-Wextra", "-Werror", "-pedantic"])
        .arg("-I")
        .arg(Path::new(ROOT).join("include"))
        .arg(&src)
        .arg("-o")
        .arg(&exe)
        .arg(format!("-L{}", b.lib_dir.display()))
        .arg(format!("-Wl,-rpath,{}", b.lib_dir.display()))
        .arg("-lnbhd")
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        describe("compiling nbhd.h as C++", &out)
    );
    run(Command::new(exe), "the C++ check");
}
