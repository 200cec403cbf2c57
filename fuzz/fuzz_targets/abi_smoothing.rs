//! The C ABI's smoothing, curvatures and normals on arbitrary arguments (see fuzz/abi_bodies.rs).
#![no_main]

use libfuzzer_sys::fuzz_target;

#[allow(dead_code)]
#[path = "../abi_bodies.rs"]
mod abi_bodies;

fuzz_target!(|data: &[u8]| abi_bodies::smoothing(data));
