//! Any bytes given to the PCD reader: an error or a cloud, never a panic, abort or hang.
#![no_main]

use libfuzzer_sys::fuzz_target;
use nbhd::io::{read_bytes, Format};

fuzz_target!(|data: &[u8]| {
    if let Ok(cloud) = read_bytes(data, Format::Pcd) {
        // What was read is consistent.
        assert!(cloud.validate().is_ok());
    }
});
