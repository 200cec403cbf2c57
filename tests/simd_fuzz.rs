//! The SIMD differential fuzz targets' bodies on the stable toolchain: each target's seeds
//! (tests/data/fuzz-seeds/simd_*) and every input it ever failed on
//! (tests/data/fuzz-regressions/simd_*), then seeded pseudo-random inputs. The bodies are
//! fuzz/simd_bodies.rs, shared with the cargo-fuzz targets (scripts/fuzz.sh): the SIMD and the
//! portable forms of every dispatched loop (src/simd.rs) must give the same bits, and the
//! searches must equal brute force.
//!
//! The portable forms are forced process-wide (`nbhd::simd::force_portable`), so the bodies run
//! one at a time here; other test binaries are other processes.

#[allow(dead_code)]
#[path = "../fuzz/simd_bodies.rs"]
mod simd_bodies;

use std::path::PathBuf;
use std::sync::Mutex;

type Body = fn(&[u8]);

const TARGETS: [(&str, Body); 2] = [
    ("simd_search", simd_bodies::search),
    ("simd_robust", simd_bodies::robust),
];

/// One body at a time: the switch the bodies flip is the process's.
static ONE_AT_A_TIME: Mutex<()> = Mutex::new(());

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
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    for (target, body) in TARGETS {
        let seeds = inputs("fuzz-seeds", target);
        assert!(seeds.len() >= 3, "{target}: {} seeds", seeds.len());
        for path in seeds.iter().chain(&inputs("fuzz-regressions", target)) {
            body(&std::fs::read(path).unwrap());
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
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let mut rng = R(0x2545_f491_4f6c_dd1d);
    for (target, body) in TARGETS {
        let start = std::time::Instant::now();
        for i in 0..200 {
            let len = 8 + usize::from(rng.next()) * 6;
            let bytes: Vec<u8> = (0..len).map(|_| rng.next()).collect();
            body(&bytes);
            assert!(
                start.elapsed().as_secs() < 120,
                "{target}: {i} inputs took {:?}",
                start.elapsed()
            );
        }
    }
}
