//! The SIMD and portable forms of nbhd's dispatched loops against each other and brute force
//! (see fuzz/simd_bodies.rs).
#![no_main]

use libfuzzer_sys::fuzz_target;

#[allow(dead_code)]
#[path = "../simd_bodies.rs"]
mod simd_bodies;

fuzz_target!(|data: &[u8]| simd_bodies::search(data));
