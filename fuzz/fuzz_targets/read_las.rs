//! Any bytes given to the LAS/LAZ reader: an error or a cloud, never a panic, abort or hang.
//!
//! The LAS and LAZ decoding is the `las` and `laz` crates'. nbhd checks the counts they would
//! allocate by before handing them a file, and turns a panic inside them into an error
//! (`catch_unwind` in src/io/las.rs). This target checks that contract: libFuzzer's panic hook
//! (which aborts at the panic, before any unwinding) is replaced by a silent one, so a panic the
//! reader catches is not a crash, while one that escapes `read_bytes` still aborts
//! (libfuzzer-sys aborts on a panic out of the target), and allocation failures and hangs are
//! found as everywhere.
#![no_main]

use libfuzzer_sys::fuzz_target;
use nbhd::io::{read_bytes, Format};

fuzz_target!(|data: &[u8]| {
    static HOOK: std::sync::Once = std::sync::Once::new();
    HOOK.call_once(|| std::panic::set_hook(Box::new(|_| {})));
    if let Ok(cloud) = read_bytes(data, Format::Las) {
        // What was read is consistent.
        assert!(cloud.validate().is_ok(), "inconsistent cloud");
    }
});
