//! The tiled run's exact reductions against their plain one-machine forms, side by side in one
//! run, alternating, one thread:
//!
//! - `ExactSum` (`src/sum.rs`) against a plain left-to-right `f64` sum of the same slice: time
//!   per value;
//! - `select_in_parts` (`src/select/radix.rs`) over the slice as one part and split into 16
//!   parts, against `select_nth_unstable_by(total_cmp)` on a copy (the copy timed apart), for
//!   the median.
//!
//! Values: uniform in `[0, 1)` and residual-like `|N(0, 1)|` magnitudes (what the robust
//! mode's medians select among). Medians of `NBHD_EXACT_REPS` (default 7) runs; each run times
//! every method once, in turn, so load on the shared machine falls on all of them alike.
//!
//! Run: `cargo bench --bench exact` (environment: `NBHD_EXACT_SIZES`, a comma list, default
//! `1000000,10000000`; `NBHD_EXACT_REPS`). A benchmark, not a test.

use std::hint::black_box;
use std::time::Instant;

use nbhd::shapes::Rng;
use nbhd::{select_in_parts, ExactSum};

fn env_list(name: &str, default: &str) -> Vec<usize> {
    std::env::var(name)
        .unwrap_or_else(|_| default.into())
        .split(',')
        .filter_map(|t| t.trim().parse().ok())
        .collect()
}

/// `n` seeded values (`nbhd::shapes::Rng`): uniform in `[0, 1)`, or `|N(0, 1)|`.
fn values(n: usize, seed: u64, normal: bool) -> Vec<f64> {
    let mut rng = Rng::new(seed);
    (0..n)
        .map(|_| {
            if normal {
                rng.gaussian().abs()
            } else {
                rng.unit()
            }
        })
        .collect()
}

fn median(mut t: Vec<f64>) -> f64 {
    t.sort_by(f64::total_cmp);
    t[t.len() / 2]
}

/// Seconds of one call of `f`, and its result.
fn timed<R>(f: impl FnOnce() -> R) -> (f64, R) {
    let t = Instant::now();
    let r = black_box(f());
    (t.elapsed().as_secs_f64(), r)
}

fn sums(v: &[f64], reps: usize) {
    let (mut plain, mut exact) = (Vec::new(), Vec::new());
    for _ in 0..reps {
        let (t, p) = timed(|| black_box(v).iter().fold(0.0, |s, &x| s + x));
        plain.push(t);
        let (t, e) = timed(|| {
            let mut s = ExactSum::new();
            s.add_slice(black_box(v));
            s.value()
        });
        exact.push(t);
        assert!((p - e).abs() <= 1e-9 * e.abs(), "{p} vs {e}");
    }
    let ns = |t: f64| t * 1e9 / v.len() as f64;
    let (p, e) = (median(plain), median(exact));
    println!(
        "  sum: plain {:.2} ns/value, ExactSum {:.2} ns/value, ratio {:.1}",
        ns(p),
        ns(e),
        e / p
    );
}

fn selections(v: &[f64], reps: usize) {
    let rank = v.len() / 2;
    let parts16: Vec<&[f64]> = v.chunks(v.len().div_ceil(16)).collect();
    let (mut copy, mut std_sel, mut one, mut sixteen) = (vec![], vec![], vec![], vec![]);
    for _ in 0..reps {
        let (tc, mut c) = timed(|| v.to_vec());
        copy.push(tc);
        let (t, want) = timed(|| *c.select_nth_unstable_by(rank, f64::total_cmp).1);
        std_sel.push(t);
        let (t, a) = timed(|| select_in_parts(&[v], rank as u64).unwrap());
        one.push(t);
        let (t, b) = timed(|| select_in_parts(&parts16, rank as u64).unwrap());
        sixteen.push(t);
        assert_eq!((a.to_bits(), b.to_bits()), (want.to_bits(), want.to_bits()));
    }
    let ms = |t: f64| t * 1e3;
    let (c, s, o, p) = (median(copy), median(std_sel), median(one), median(sixteen));
    println!(
        "  median: select_nth_unstable {:.1} ms (+ copy {:.1} ms), radix 1 part {:.1} ms \
         ({:.2}×), 16 parts {:.1} ms ({:.2}×)",
        ms(s),
        ms(c),
        ms(o),
        o / s,
        ms(p),
        p / s
    );
}

fn main() {
    let sizes = env_list("NBHD_EXACT_SIZES", "1000000,10000000");
    let reps = env_list("NBHD_EXACT_REPS", "7")
        .first()
        .copied()
        .unwrap_or(7)
        .max(1);
    println!("exact reductions, one thread, medians of {reps} alternating runs");
    for &n in &sizes {
        for (name, normal) in [("uniform [0, 1)", false), ("|N(0, 1)|", true)] {
            println!("{n} values, {name}:");
            let v = values(n, 39, normal);
            sums(&v, reps);
            selections(&v, reps);
        }
    }
}
