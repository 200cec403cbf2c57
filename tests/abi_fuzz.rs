//! The C ABI fuzz targets' bodies on the stable toolchain: each target's seeds
//! (tests/data/fuzz-seeds/abi_*) and every input it ever crashed on
//! (tests/data/fuzz-regressions/abi_*), then seeded pseudo-random inputs. The bodies are
//! fuzz/abi_bodies.rs, shared with the cargo-fuzz targets (scripts/fuzz.sh): every export must
//! return a documented status with a message, never panic, abort or hang.

#[path = "../fuzz/abi_bodies.rs"]
mod abi_bodies;

use std::path::PathBuf;

type Body = fn(&[u8]);

const TARGETS: [(&str, Body); 3] = [
    ("abi_build_query", abi_bodies::build_query),
    ("abi_tables", abi_bodies::tables),
    ("abi_smoothing", abi_bodies::smoothing),
];

/// The files of tests/data/`dir`/`target`, sorted (none if the folder does not exist).
fn inputs(dir: &str, target: &str) -> Vec<PathBuf> {
    let d = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(dir)
        .join(target);
    let mut v: Vec<PathBuf> = std::fs::read_dir(d)
        .map(|es| es.flatten().map(|e| e.path()).collect())
        .unwrap_or_default();
    v.sort();
    v
}

#[test]
fn seeds_and_regressions_through_each_target() {
    for (target, body) in TARGETS {
        let seeds = inputs("fuzz-seeds", target);
        assert!(seeds.len() >= 3, "{target}: {} seeds", seeds.len());
        for path in seeds.iter().chain(&inputs("fuzz-regressions", target)) {
            let bytes = std::fs::read(path).unwrap();
            body(&bytes);
        }
    }
}

/// A seeded generator (xorshift).
struct R(u64);

impl R {
    fn next(&mut self) -> u8 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 24) as u8
    }
}

#[test]
fn pseudo_random_inputs_through_each_target() {
    let mut rng = R(0x9e37_79b9_7f4a_7c15);
    for (target, body) in TARGETS {
        let start = std::time::Instant::now();
        for i in 0..300 {
            let len = 16 + usize::from(rng.next()) * 4;
            let mut bytes: Vec<u8> = (0..len).map(|_| rng.next()).collect();
            if target == "abi_tables" && bytes[0] == 0xB1 {
                // the big table has its own seed; keep this test quick
                bytes[0] = 0;
            }
            body(&bytes);
            assert!(
                start.elapsed().as_secs() < 60,
                "{target}: {i} inputs took {:?}",
                start.elapsed()
            );
        }
    }
}
