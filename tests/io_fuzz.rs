//! The readers of `nbhd::io` on hostile bytes, on the stable toolchain: the fuzz seeds
//! (tests/data/fuzz-seeds) and every crash the fuzzer ever found (tests/data/fuzz-regressions),
//! through every reader, then seeded mutations of the seeds (bit flips, cuts, huge numbers in
//! headers). Each read must return a cloud or an error: a panic fails the test, and an abort
//! or a hang takes it down. The coverage-guided runs are scripts/fuzz.sh (cargo-fuzz).
#![cfg(feature = "io")]

use nbhd::io::{read_bytes, Format};
use std::path::{Path, PathBuf};

fn data(sub: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(sub)
}

/// Files under `dir`/<format>/, with the format the folder names.
fn files(dir: &Path) -> Vec<(PathBuf, Format)> {
    let mut v = Vec::new();
    let Ok(entries) = std::fs::read_dir(dir) else {
        return v;
    };
    for e in entries.flatten() {
        let format = match e.file_name().to_str() {
            Some("ply") => Format::Ply,
            Some("pcd" | "pcd_compressed") => Format::Pcd,
            Some("obj") => Format::Obj,
            Some("xyz") => Format::Xyz,
            Some("las") => Format::Las,
            _ => continue,
        };
        let mut fs: Vec<_> = std::fs::read_dir(e.path())
            .unwrap()
            .flatten()
            .map(|f| f.path())
            .collect();
        fs.sort();
        v.extend(fs.into_iter().map(|f| (f, format)));
    }
    v.sort_by(|a, b| a.0.cmp(&b.0));
    v
}

const ALL: [Format; 5] = [
    Format::Ply,
    Format::Pcd,
    Format::Obj,
    Format::Xyz,
    Format::Las,
];

fn read_any(bytes: &[u8], format: Format) {
    if let Ok(c) = read_bytes(bytes, format) {
        c.validate().expect("a cloud read is consistent");
    }
}

#[test]
fn seeds_and_regressions_through_every_reader() {
    let seeds = files(&data("fuzz-seeds"));
    assert!(seeds.len() >= 15, "{} seeds", seeds.len());
    let mut n = 0;
    for (path, own) in seeds.iter().chain(&files(&data("fuzz-regressions"))) {
        let bytes = std::fs::read(path).unwrap();
        for f in ALL {
            read_any(&bytes, f);
            n += 1;
        }
        // The seeds are valid files of their format (but the raw compressed payloads and
        // the ones named bad-*).
        let name = path.file_name().unwrap().to_str().unwrap();
        let raw = path.components().any(|c| c.as_os_str() == "pcd_compressed");
        if path.starts_with(data("fuzz-seeds")) && !raw {
            let ok = read_bytes(&bytes, *own).is_ok();
            assert_eq!(ok, !name.starts_with("bad"), "{}", path.display());
        }
    }
    assert!(n > 0);
}

/// A seeded generator (xorshift).
struct R(u64);

impl R {
    fn below(&mut self, n: usize) -> usize {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 % n.max(1) as u64) as usize
    }
}

/// Replaces a run of digits with a huge or odd number (the counts of headers).
fn swap_number(b: &mut Vec<u8>, rng: &mut R) {
    let digits: Vec<usize> = (0..b.len()).filter(|&i| b[i].is_ascii_digit()).collect();
    if digits.is_empty() {
        return;
    }
    let start = digits[rng.below(digits.len())];
    let end = (start..b.len())
        .find(|&i| !b[i].is_ascii_digit())
        .unwrap_or(b.len());
    let with: &[u8] = match rng.below(6) {
        0 => b"18446744073709551615",
        1 => b"4294967296",
        2 => b"1000000000000",
        3 => b"0",
        4 => b"-1",
        _ => b"357913941",
    };
    b.splice(start..end, with.iter().copied());
}

#[test]
fn mutated_seeds_never_panic() {
    let seeds = files(&data("fuzz-seeds"));
    let mut rng = R(0x5eed_2545_f491_4f6c);
    let start = std::time::Instant::now();
    for (path, format) in &seeds {
        let seed = std::fs::read(path).unwrap();
        for _ in 0..400 {
            let mut b = seed.clone();
            for _ in 0..1 + rng.below(3) {
                match rng.below(5) {
                    0 if !b.is_empty() => {
                        let i = rng.below(b.len());
                        b[i] ^= 1 << rng.below(8);
                    }
                    1 if !b.is_empty() => {
                        let i = rng.below(b.len());
                        b[i] = rng.below(256) as u8;
                    }
                    2 => {
                        let cut = rng.below(b.len() + 1);
                        b.truncate(cut);
                    }
                    3 => swap_number(&mut b, &mut rng),
                    _ => {
                        let i = rng.below(b.len() + 1);
                        b.insert(i, rng.below(256) as u8);
                    }
                }
            }
            if path.components().any(|c| c.as_os_str() == "pcd_compressed") {
                // As the read_pcd_compressed fuzz target builds its files.
                let Some((&n, body)) = b.split_first() else {
                    continue;
                };
                let mut file = format!(
                    "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH {n}\n\
                     HEIGHT 1\nPOINTS {n}\nDATA binary_compressed\n"
                )
                .into_bytes();
                file.extend_from_slice(body);
                read_any(&file, Format::Pcd);
            } else {
                read_any(&b, *format);
            }
        }
    }
    assert!(
        start.elapsed().as_secs() < 60,
        "mutated reads took {:?}",
        start.elapsed()
    );
}
