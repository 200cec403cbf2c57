//! `include/nbhd.h` is what cbindgen makes of `src/ffi/mod.rs` (and the modules it declares)
//! with `cbindgen.toml`: this test regenerates it with the cbindgen library and fails if the
//! committed file differs. Generating from the ffi module alone, not the whole crate, keeps
//! the core's public items out of the C API; a second test checks every name is `nbhd_`/`NBHD_`.
//! `NBHD_BLESS_HEADER=1` writes the new header instead (what `scripts/gen-header.sh` does).

use std::path::Path;

fn generate() -> Vec<u8> {
    let root = env!("CARGO_MANIFEST_DIR");
    let config = cbindgen::Config::from_root_or_default(root);
    let bindings = cbindgen::Builder::new()
        .with_src(Path::new(root).join("src/ffi/mod.rs"))
        .with_config(config)
        .generate()
        .expect("cbindgen could not generate the header");
    let mut out = Vec::new();
    bindings.write(&mut out);
    out
}

#[test]
fn header_is_current() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("include/nbhd.h");
    let fresh = generate();
    if std::env::var_os("NBHD_BLESS_HEADER").is_some() {
        std::fs::write(&path, &fresh).expect("cannot write include/nbhd.h");
        return;
    }
    let committed = std::fs::read(&path).unwrap_or_default();
    if committed != fresh {
        let new = Path::new(env!("CARGO_TARGET_TMPDIR")).join("nbhd.h.new");
        let _ = std::fs::write(&new, &fresh);
        let first_diff = committed
            .split(|&b| b == b'\n')
            .zip(fresh.split(|&b| b == b'\n'))
            .position(|(a, b)| a != b)
            .map_or_else(|| "at the end".to_owned(), |l| format!("at line {}", l + 1));
        panic!(
            "include/nbhd.h is stale (it differs from what cbindgen makes of src/ffi, first {first_diff}; \
             the fresh header is in {}).\nRegenerate it with scripts/gen-header.sh and commit it.",
            new.display()
        );
    }
}

#[test]
fn header_has_the_crate_version() {
    let header =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("include/nbhd.h"))
            .expect("include/nbhd.h is missing: run scripts/gen-header.sh");
    for (name, value) in [
        ("MAJOR", env!("CARGO_PKG_VERSION_MAJOR")),
        ("MINOR", env!("CARGO_PKG_VERSION_MINOR")),
        ("PATCH", env!("CARGO_PKG_VERSION_PATCH")),
    ] {
        let line = format!("#define NBHD_VERSION_{name} {value}\n");
        assert!(
            header.contains(&line),
            "the header lacks `{}`: update NBHD_VERSION_* in src/ffi/mod.rs to Cargo.toml's version and run scripts/gen-header.sh",
            line.trim_end()
        );
    }
}

#[test]
fn header_declares_only_nbhd_names() {
    let header =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("include/nbhd.h"))
            .expect("include/nbhd.h is missing: run scripts/gen-header.sh");
    let mut names = Vec::new();
    for line in header.lines() {
        let words: Vec<&str> = line.split_whitespace().collect();
        // A function-pointer type: `typedef ret (*name)(args);`.
        if let Some((_, rest)) = line
            .split_once("(*")
            .filter(|_| line.starts_with("typedef"))
        {
            names.push(rest.split(')').next().unwrap_or(""));
            continue;
        }
        match words.as_slice() {
            ["#define", name, ..] if *name != "NBHD_H" => names.push(*name),
            // `typedef struct {` / `typedef enum {`: the name follows on the closing line.
            ["typedef", .., "{"] => {}
            ["typedef", .., last] => names.push(last.trim_end_matches(';')),
            ["}", name] => names.push(name.trim_end_matches(';')),
            _ => {}
        }
        // Functions: the identifier just before the parenthesis of a top-level declaration.
        if !line.starts_with([' ', '*', '/', '#', '}']) {
            if let Some((before, _)) = line.split_once('(') {
                names.push(before.rsplit([' ', '*']).next().unwrap_or(""));
            }
        }
    }
    assert!(names.len() > 30, "too few names found: {names:?}");
    let foreign: Vec<_> = names
        .iter()
        .filter(|n| !(n.starts_with("nbhd_") || n.starts_with("NBHD_")))
        .collect();
    assert!(
        foreign.is_empty(),
        "the header declares names outside the nbhd_/NBHD_ namespace: {foreign:?}"
    );
}
