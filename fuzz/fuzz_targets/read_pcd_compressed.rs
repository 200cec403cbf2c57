//! binary_compressed PCD data behind a valid header: the first byte chooses the point count
//! (0..=255 points of x y z float), the rest is the two sizes and the LZF stream. An error
//! or a cloud, never a panic, abort or hang.
#![no_main]

use libfuzzer_sys::fuzz_target;
use nbhd::io::{read_bytes, Format};

fuzz_target!(|data: &[u8]| {
    let Some((&n, body)) = data.split_first() else {
        return;
    };
    let mut file = format!(
        "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH {n}\nHEIGHT 1\n\
         POINTS {n}\nDATA binary_compressed\n"
    )
    .into_bytes();
    file.extend_from_slice(body);
    if let Ok(cloud) = read_bytes(&file, Format::Pcd) {
        assert_eq!(cloud.len(), n as usize);
    }
});
