//! The C ABI tested from C. Builds the cdylib (`cargo build --lib` with this test's profile and
//! target directory, which reuses the library the tests were built with), compiles the programs in `tests/c/` against it and `include/nbhd.h` with
//! the system C compiler (`cc`, or `$CC`), and runs them: natively, under valgrind memcheck
//! (skipped with a note when valgrind is absent, unless `NBHD_REQUIRE_VALGRIND` is set), and
//! with several threads on one tree. Also checks that the C test calls every export of the
//! header and that the header compiles and links as C++.
//!
//! On Linux the cdylib carries a SONAME (`libnbhd.so.0.<MINOR>` for 0.x, `libnbhd.so.<MAJOR>`
//! from 1.0; set by `build.rs`), and programs linked against it ask the loader for that name. The
//! programs are therefore linked and run through a directory this test owns
//! (`<target tmp>/c_abi/<profile>/lib`) that holds `libnbhd.so` and the SONAME as symbolic links
//! to the built library, as an installation would; nothing of the system is used. The SONAME
//! itself, and that the programs record it, are checked by reading the ELF dynamic sections.
#![cfg(unix)]

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::{Mutex, OnceLock};

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

/// Where the cdylib is and where compiled C programs go.
struct Built {
    /// The cdylib cargo built, `<target>/<profile>/libnbhd.so`.
    lib: PathBuf,
    /// The directory the programs are linked and run with: `libnbhd.so` and the SONAME, both
    /// symbolic links to `lib`.
    lib_dir: PathBuf,
    out_dir: PathBuf,
}

/// The SONAME `build.rs` must give the cdylib, from this package's version (the rule is stated
/// there): `None` where the target has no SONAMEs.
fn expected_soname() -> Option<String> {
    if !cfg!(target_os = "linux") {
        return None;
    }
    let major = env!("CARGO_PKG_VERSION_MAJOR");
    let minor = env!("CARGO_PKG_VERSION_MINOR");
    Some(if major == "0" {
        format!("libnbhd.so.0.{minor}")
    } else {
        format!("libnbhd.so.{major}")
    })
}

/// The names an ELF file's dynamic section gives: its own SONAME and the libraries it needs.
#[derive(Debug, Default)]
struct Dynamic {
    soname: Option<String>,
    needed: Vec<String>,
}

/// Reads the dynamic section of an ELF file (32 or 64 bit, either byte order) through the
/// section headers: the `SHT_DYNAMIC` section's `DT_SONAME` and `DT_NEEDED` entries are offsets
/// into the string table its `sh_link` names.
fn elf_dynamic(path: &Path) -> Result<Dynamic, String> {
    let data = std::fs::read(path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    let bad = |what: &str| format!("{}: not a valid ELF file ({what})", path.display());
    if data.len() < 64 || data[..4] != *b"\x7fELF" {
        return Err(bad("no ELF header"));
    }
    let wide = match data[4] {
        1 => false,
        2 => true,
        _ => return Err(bad("unknown class")),
    };
    let little = match data[5] {
        1 => true,
        2 => false,
        _ => return Err(bad("unknown byte order")),
    };
    let uint = |at: usize, len: usize| -> Result<u64, String> {
        let bytes = data.get(at..at + len).ok_or_else(|| bad("truncated"))?;
        let fold = |v: u64, b: &u8| (v << 8) | u64::from(*b);
        Ok(if little {
            bytes.iter().rev().fold(0, fold)
        } else {
            bytes.iter().fold(0, fold)
        })
    };
    let word = if wide { 8 } else { 4 };
    let at = |v: u64| usize::try_from(v).map_err(|_| bad("offset out of range"));
    // e_shoff, e_shentsize, e_shnum.
    let (sh_off, sh_size, sh_num) = if wide {
        (uint(0x28, 8)?, uint(0x3a, 2)?, uint(0x3c, 2)?)
    } else {
        (uint(0x20, 4)?, uint(0x2e, 2)?, uint(0x30, 2)?)
    };
    if sh_num == 0 {
        return Err(bad("no section headers"));
    }
    // (sh_type, sh_offset, sh_size, sh_link) of section i.
    let section = |i: u64| -> Result<(u64, u64, u64, u64), String> {
        let base = at(sh_off + i * sh_size)?;
        Ok((
            uint(base + 4, 4)?,
            uint(base + 8 + 2 * word, word)?,
            uint(base + 8 + 3 * word, word)?,
            uint(base + 8 + 4 * word, 4)?,
        ))
    };
    let mut dynamic = Dynamic::default();
    for i in 0..sh_num {
        let (kind, offset, size, link) = section(i)?;
        const SHT_DYNAMIC: u64 = 6;
        if kind != SHT_DYNAMIC {
            continue;
        }
        let (_, str_offset, str_size, _) = section(link)?;
        let strings = data
            .get(at(str_offset)?..at(str_offset + str_size)?)
            .ok_or_else(|| bad("string table out of the file"))?;
        let string = |v: u64| -> Result<String, String> {
            let s = strings
                .get(at(v)?..)
                .ok_or_else(|| bad("string out of its table"))?;
            let end = s
                .iter()
                .position(|&b| b == 0)
                .ok_or_else(|| bad("unterminated string"))?;
            Ok(String::from_utf8_lossy(&s[..end]).into_owned())
        };
        for entry in (offset..offset + size).step_by(2 * word) {
            let (tag, value) = (uint(at(entry)?, word)?, uint(at(entry)? + word, word)?);
            const DT_NULL: u64 = 0;
            const DT_NEEDED: u64 = 1;
            const DT_SONAME: u64 = 14;
            match tag {
                DT_NULL => break,
                DT_NEEDED => dynamic.needed.push(string(value)?),
                DT_SONAME => dynamic.soname = Some(string(value)?),
                _ => {}
            }
        }
        return Ok(dynamic);
    }
    Err(bad("no dynamic section"))
}

/// Makes `dir/name` a symbolic link to `target`, replacing whatever is there atomically (test
/// processes of the same profile may do this at the same time).
fn symlink_into(dir: &Path, name: &str, target: &Path) -> Result<(), String> {
    let tmp = dir.join(format!(".{name}.{}", std::process::id()));
    let _ = std::fs::remove_file(&tmp);
    std::os::unix::fs::symlink(target, &tmp)
        .and_then(|()| std::fs::rename(&tmp, dir.join(name)))
        .map_err(|e| {
            format!(
                "cannot link {} to {}: {e}",
                dir.join(name).display(),
                target.display()
            )
        })
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
        // The link name and, where the library has one, its SONAME (the name the loader looks
        // for), both pointing at the library cargo just built.
        let lib_dir = out_dir.join("lib");
        std::fs::create_dir_all(&lib_dir).map_err(|e| e.to_string())?;
        let file_name = lib
            .file_name()
            .and_then(|n| n.to_str())
            .ok_or("bad library name")?;
        symlink_into(&lib_dir, file_name, &lib)?;
        if cfg!(target_os = "linux") {
            if let Some(soname) = elf_dynamic(&lib)?.soname {
                symlink_into(&lib_dir, &soname, &lib)?;
            }
        }
        Ok(Built {
            lib,
            lib_dir,
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
fn c_dynamic_tree_answers_as_the_static_tree() {
    let mut cmd = Command::new(compiled("dynamic_test"));
    cmd.arg(scratch("dynamic"));
    run(cmd, "tests/c/dynamic_test");
}

#[test]
fn c_dynamic_tree_is_clean_under_valgrind() {
    let exe = compiled("dynamic_test");
    if let Some(mut cmd) = valgrind() {
        cmd.arg(exe).arg(scratch("dynamic-valgrind"));
        run(cmd, "valgrind tests/c/dynamic_test");
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

/// Thread counts bounded, a call's own pool gone when it returns, and nbhd usable in a child
/// forked after parallel calls (a hang is an alarm() in the child, reported by the parent).
/// Natively only: valgrind runs threads one at a time, and the test counts them.
#[cfg(target_os = "linux")]
#[test]
fn c_pools_are_bounded_and_survive_fork() {
    run(Command::new(compiled("fork_test")), "tests/c/fork_test");
}

#[test]
fn c_boxes_spacing_and_filters_match_brute_force() {
    run(
        Command::new(compiled("features_test")),
        "tests/c/features_test",
    );
}

#[test]
fn c_features_are_clean_under_valgrind() {
    if let Some(mut cmd) = valgrind() {
        cmd.arg(compiled("features_test"));
        run(cmd, "valgrind tests/c/features_test");
    }
}

#[test]
fn c_metric_queries_match_brute_force() {
    run(Command::new(compiled("metric_test")), "tests/c/metric_test");
}

#[test]
fn c_metric_queries_are_clean_under_valgrind() {
    if let Some(mut cmd) = valgrind() {
        cmd.arg(compiled("metric_test"));
        run(cmd, "valgrind tests/c/metric_test");
    }
}

#[test]
fn c_periodic_queries_match_brute_force() {
    run(
        Command::new(compiled("periodic_test")),
        "tests/c/periodic_test",
    );
}

#[test]
fn c_periodic_queries_are_clean_under_valgrind() {
    if let Some(mut cmd) = valgrind() {
        cmd.arg(compiled("periodic_test"));
        run(cmd, "valgrind tests/c/periodic_test");
    }
}

#[test]
fn c_pair_queries_match_brute_force() {
    run(Command::new(compiled("pairs_test")), "tests/c/pairs_test");
}

#[test]
fn c_pair_queries_are_clean_under_valgrind() {
    if let Some(mut cmd) = valgrind() {
        cmd.arg(compiled("pairs_test"));
        run(cmd, "valgrind tests/c/pairs_test");
    }
}

#[test]
fn c_tree_nodes_match_the_points() {
    run(Command::new(compiled("nodes_test")), "tests/c/nodes_test");
}

#[test]
fn c_tree_nodes_are_clean_under_valgrind() {
    if let Some(mut cmd) = valgrind() {
        cmd.arg(compiled("nodes_test"));
        run(cmd, "valgrind tests/c/nodes_test");
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

#[test]
fn c_subset_trees_answer_as_brute_force() {
    run(Command::new(compiled("subset_test")), "tests/c/subset_test");
}

#[test]
fn c_subset_trees_are_clean_under_valgrind() {
    let exe = compiled("subset_test");
    if let Some(mut cmd) = valgrind() {
        cmd.arg(exe);
        run(cmd, "valgrind tests/c/subset_test");
    }
}

/// A scratch directory for a C test's files, emptied first.
#[test]
fn c_buffers_changed_between_calls_and_threads_interleaved() {
    run(Command::new(compiled("mutate_test")), "tests/c/mutate_test");
}

#[test]
fn c_buffers_changed_between_calls_are_clean_under_valgrind() {
    let exe = compiled("mutate_test");
    if let Some(mut cmd) = valgrind() {
        cmd.arg(exe);
        run(cmd, "valgrind tests/c/mutate_test");
    }
}

fn scratch(name: &str) -> PathBuf {
    let dir = built().out_dir.join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn c_saved_trees_load_back() {
    let mut cmd = Command::new(compiled("persist_test"));
    cmd.arg(scratch("persist"));
    run(cmd, "tests/c/persist_test");
}

#[test]
fn c_saved_trees_are_clean_under_valgrind() {
    let exe = compiled("persist_test");
    if let Some(mut cmd) = valgrind() {
        cmd.arg(exe).arg(scratch("persist-valgrind"));
        run(cmd, "valgrind tests/c/persist_test");
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
        // the programs and the headers they share (tests/c/brute.h calls the searches)
        if path.extension().is_some_and(|e| e == "c" || e == "h") {
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

/// `readelf -d` output for `path`, or `None` (with a note) when readelf is not installed.
fn readelf_dynamic(path: &Path) -> Option<String> {
    match Command::new("readelf").arg("-d").arg(path).output() {
        Ok(out) if out.status.success() => Some(String::from_utf8_lossy(&out.stdout).into_owned()),
        Ok(out) => panic!("{}", describe("readelf -d", &out)),
        Err(_) => {
            note("readelf is not installed: the SONAME is checked by this test's ELF reader only");
            None
        }
    }
}

#[test]
fn cdylib_has_the_versioned_soname() {
    let Some(expected) = expected_soname() else {
        note("not Linux: the cdylib has no SONAME to check; the SONAME test is SKIPPED");
        return;
    };
    let lib = &built().lib;
    let dynamic = elf_dynamic(lib).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        dynamic.soname.as_deref(),
        Some(expected.as_str()),
        "{} has the wrong SONAME (build.rs should set it from the version {})",
        lib.display(),
        env!("CARGO_PKG_VERSION")
    );
    // readelf, where present, must agree with the reader above.
    if let Some(text) = readelf_dynamic(lib) {
        assert!(
            text.contains(&format!("Library soname: [{expected}]")),
            "readelf -d {} shows no SONAME {expected}:\n{text}",
            lib.display()
        );
    }
}

#[test]
fn c_programs_record_the_soname() {
    let Some(expected) = expected_soname() else {
        note("not Linux: no SONAME for the C programs to record; the check is SKIPPED");
        return;
    };
    let exe = compiled("abi_test");
    let dynamic = elf_dynamic(&exe).unwrap_or_else(|e| panic!("{e}"));
    let ours: Vec<_> = dynamic
        .needed
        .iter()
        .filter(|n| n.starts_with("libnbhd"))
        .collect();
    assert_eq!(
        ours,
        [&expected],
        "{} should need nbhd by its SONAME; it needs {:?}",
        exe.display(),
        dynamic.needed
    );
}
