//! Gives the C library (the cdylib) a SONAME on Linux, so that programs linked against it record
//! an ABI version instead of a bare `libnbhd.so`.
//!
//! The SONAME rule (also in `scripts/install.sh` and checked by `tests/c_abi.rs`):
//!
//! - version 1.0 and later: `libnbhd.so.<MAJOR>` — a new major version is the only ABI break;
//! - version 0.x: `libnbhd.so.0.<MINOR>` — as in Cargo's semver rules, a 0.x minor release may
//!   break the ABI, so it gets a new SONAME; patch releases keep it.
//!
//! The file itself is installed as `libnbhd.so.<MAJOR>.<MINOR>.<PATCH>` with the SONAME and
//! `libnbhd.so` as symbolic links to it (`scripts/install.sh`). The rlib, the staticlib and other
//! targets are untouched: `rustc-cdylib-link-arg` reaches the cdylib's link only.
//!
//! It also tells the crate whether the compiler is Rust 1.89 or later (`cfg(rustc_1_89)`),
//! where the AVX-512 intrinsics are stable: the tables' AVX-512 loops
//! (`src/tree/group_search/avx512.rs`) are built there; older compilers, down to the crate's
//! `rust-version`, build the portable loops alone.

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    autocfg::new().emit_rustc_version(1, 89);
    // The target's OS, not the host's (this script runs on the host).
    if std::env::var("CARGO_CFG_TARGET_OS").as_deref() != Ok("linux") {
        return;
    }
    let major = env!("CARGO_PKG_VERSION_MAJOR");
    let minor = env!("CARGO_PKG_VERSION_MINOR");
    let soname = if major == "0" {
        format!("libnbhd.so.0.{minor}")
    } else {
        format!("libnbhd.so.{major}")
    };
    println!("cargo:rustc-cdylib-link-arg=-Wl,-soname,{soname}");
}
