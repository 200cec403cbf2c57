//! The C ABI: `nbhd_*` functions over opaque handles and plain structs, a thin, mechanical
//! layer over the safe API of this crate. No logic lives only here: every export checks its
//! pointers, converts C values to the core's types, calls the core and converts back.
//!
//! `include/nbhd.h` is generated from this module by cbindgen (`scripts/gen-header.sh`, with
//! `cbindgen.toml` at the crate root); a test fails when the committed header is stale. The
//! overview C users read first (ownership, units, index limits, thread safety, errors) is the
//! header's preamble, kept in `cbindgen.toml`.
//!
//! Rules of this layer:
//! - every export runs inside a panic guard ([`status`]): a Rust panic becomes
//!   `NBHD_STATUS_INTERNAL` with its message, and no unwinding ever reaches C;
//! - every pointer is checked for NULL and for the alignment of the type it is read or
//!   written as, before anything is read; structs from C are read field by field (`fields.rs`),
//!   C enum values as integers checked against [`enums`], so an out-of-range value is an
//!   error (one rule for which status, in `fields.rs`), never undefined behaviour;
//! - the C options structs carry nothing the core's options do not: each reader converts
//!   field by field into the core's options (threads included) and calls the core;
//! - `unsafe` is this module's tool for reading and writing C memory, each block with a
//!   `// SAFETY:` comment; elsewhere the crate has it only in a measured hot loop
//!   (`tree/group_search.rs`), the byte view of a point buffer (`points.rs`) and the memory
//!   query of `table.rs`. `clippy::undocumented_unsafe_blocks` holds crate-wide (`lib.rs`).
#![allow(non_camel_case_types)]
#![deny(unsafe_op_in_unsafe_fn)]
#![warn(clippy::undocumented_unsafe_blocks)]

// The header follows the order of these modules (cbindgen reads them in turn): errors first,
// then every enum, the plain types, the tree and its nodes, single queries, tables, and normals, curvatures
// and smoothing (their shared outputs and callback first). Blank lines keep rustfmt from
// sorting them.
pub mod status;

pub mod enums;

pub mod types;

pub mod tree;

pub mod nodes;

pub mod persist;

pub mod query;

pub mod in_box;

pub mod filter;

pub mod table;

pub mod dynamic;

pub mod periodic;

pub mod pairs;

pub mod smoothing_io;

pub mod smooth;

pub mod normals;

pub mod robust;

pub mod prepared;

mod args;

mod fields;

pub use dynamic::*;
pub use enums::*;
pub use filter::*;
pub use in_box::*;
pub use nodes::*;
pub use normals::*;
pub use periodic::*;
pub use persist::*;
pub use prepared::*;
pub use query::*;
pub use robust::*;
pub use smooth::*;
pub use smoothing_io::*;
pub use status::*;
pub use table::*;
pub use tree::*;
pub use types::*;

/// Major version of the nbhd library this header belongs to.
pub const NBHD_VERSION_MAJOR: u32 = 0;
/// Minor version of the nbhd library this header belongs to.
pub const NBHD_VERSION_MINOR: u32 = 1;
/// Patch version of the nbhd library this header belongs to.
pub const NBHD_VERSION_PATCH: u32 = 0;
/// The version of this header as one number, `MAJOR * 1000000 + MINOR * 1000 + PATCH`;
/// compare it with `nbhd_version()` to detect a header/library mismatch at run time.
pub const NBHD_VERSION: u32 =
    NBHD_VERSION_MAJOR * 1_000_000 + NBHD_VERSION_MINOR * 1_000 + NBHD_VERSION_PATCH;

/// The largest `threads` option a call accepts. A larger value fails with
/// NBHD_STATUS_INVALID_OPTION, naming the value, before any thread is started. (0, a thread
/// per core, is always accepted.)
pub const NBHD_MAX_THREADS: usize = 1024;

/// The version of the library that is linked, as `MAJOR * 1000000 + MINOR * 1000 + PATCH`
/// (compare with `NBHD_VERSION` from the header you compiled against).
#[no_mangle]
pub extern "C" fn nbhd_version() -> u32 {
    NBHD_VERSION
}

/// The version of the library that is linked, as a string such as "0.1.0". The string is
/// static: never free it.
#[no_mangle]
pub extern "C" fn nbhd_version_string() -> *const std::ffi::c_char {
    concat!(env!("CARGO_PKG_VERSION"), "\0").as_ptr().cast()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn version_constants_follow_cargo_toml() {
        let parse = |s: &str| s.parse::<u32>().unwrap();
        assert_eq!(NBHD_VERSION_MAJOR, parse(env!("CARGO_PKG_VERSION_MAJOR")));
        assert_eq!(NBHD_VERSION_MINOR, parse(env!("CARGO_PKG_VERSION_MINOR")));
        assert_eq!(NBHD_VERSION_PATCH, parse(env!("CARGO_PKG_VERSION_PATCH")));
        assert_eq!(nbhd_version(), NBHD_VERSION);
        // SAFETY: nbhd_version_string returns a static NUL-terminated string.
        let s = unsafe { std::ffi::CStr::from_ptr(nbhd_version_string()) };
        assert_eq!(s.to_str().unwrap(), env!("CARGO_PKG_VERSION"));
    }

    #[test]
    fn the_thread_limit_is_the_core_s() {
        assert_eq!(NBHD_MAX_THREADS, crate::parallel::MAX_THREADS);
    }
}
