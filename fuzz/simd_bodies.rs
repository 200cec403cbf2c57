//! The bodies of the SIMD differential fuzz targets (`simd_search`, `simd_robust`), shared by
//! the cargo-fuzz targets in fuzz/fuzz_targets/ and by tests/simd_fuzz.rs, which runs them on
//! the stable toolchain (both include this file by path).
//!
//! Each body runs one computation twice: with the widest SIMD forms the processor has, and with
//! every dispatched loop forced to its portable form (`nbhd::simd::force_portable`, see
//! src/simd.rs for the list of loops). Both must give the same bits; the searches must also
//! equal brute force exactly (indices, squared distances, their order).
//!
//! - `search`: up to 160 points of dimension 1 to 5, `f32` or `f64`, whose coordinates come from
//!   palettes that make ties (few values, copies), neighbouring floats, subnormals, huge values
//!   whose squared distances overflow to infinity, or arbitrary finite bits; any pivot policy
//!   and leaf size. The all-point tables (the grouped search: AVX-512 keys and ranks, the
//!   gathered blocks' distances of `f64` in 3-D in AVX lanes, SSE masks, sorting of the first leaf's candidates) of every kind, with and without the point
//!   itself, the tables of outside queries, and single queries by coordinates and by stored
//!   point (their leaf distances of `f64` in 3-D in AVX lanes).
//! - `robust`: the robust smoothing (its AVX lanes: plane scores, weighted sums, steps, the
//!   batched eigen solves) on up to 64 noisy points of a surface.

use glam::DVec3;
use nbhd::smooth::{smooth_robust, RobustOptions};
use nbhd::{
    BruteForce, BuildOptions, KdTree, Neighbor, NeighborIndex, NeighborSearch, Neighborhood,
    NonFinitePolicy, PivotPolicy, PointsView, Query, Scalar, TableOptions,
};

/// Arguments read from the fuzzer's bytes; past the end every read gives 0.
pub struct Input<'a>(&'a [u8]);

impl Input<'_> {
    fn u8(&mut self) -> u8 {
        match self.0.split_first() {
            Some((&b, rest)) => {
                self.0 = rest;
                b
            }
            None => 0,
        }
    }

    fn u32(&mut self) -> u32 {
        u32::from_le_bytes([self.u8(), self.u8(), self.u8(), self.u8()])
    }

    fn below(&mut self, n: usize) -> usize {
        (u16::from_le_bytes([self.u8(), self.u8()]) as usize) % n.max(1)
    }
}

/// How coordinates are drawn: each palette makes the ties and extremes one SIMD path or
/// another could get wrong.
fn coordinate<T: Scalar>(inp: &mut Input<'_>, palette: u8, base: f64) -> T {
    let f32 = T::TYPE.size() == 4;
    let v = match palette % 6 {
        // few values: exact ties at every distance, copies of points
        0 => T::from_f64(f64::from(inp.u8() % 4)),
        // neighbouring floats around `base`: distances differing in the last bit
        1 => {
            let mut v = T::from_f64(base);
            for _ in 0..inp.u8() % 4 {
                v = next_up(v);
            }
            v
        }
        // subnormal and tiny values: squared distances underflow to zero
        2 => T::from_f64(f64::from(inp.u8()) * if f32 { 1e-40 } else { 1e-310 }),
        // huge values (up to 127/128 of the largest): squared distances overflow to infinity
        3 => T::from_f64(f64::from(inp.u8() as i8) * if f32 { 2.6e36 } else { 1.4e306 }),
        // arbitrary finite bits
        4 => T::from_f64(f64::from(f32::from_bits(inp.u32()))),
        // an ordinary spread
        _ => T::from_f64(f64::from(inp.u8()) * 0.125 - 16.0),
    };
    if v.is_finite() {
        v
    } else {
        T::ZERO
    }
}

/// The next representable value above `v` (finite `v`; `f64::next_up` needs a newer Rust).
fn next_up<T: Scalar>(v: T) -> T {
    if T::TYPE.size() == 4 {
        let x = v.to_f64() as f32 + 0.0; // -0 as +0
        let b = x.to_bits();
        T::from_f64(f64::from(f32::from_bits(if x >= 0.0 {
            b + 1
        } else {
            b - 1
        })))
    } else {
        let x = v.to_f64() + 0.0;
        let b = x.to_bits();
        T::from_f64(f64::from_bits(if x >= 0.0 { b + 1 } else { b - 1 }))
    }
}

/// Runs `f` with the SIMD forms, then with the portable forms forced; returns both results
/// (the forms allowed again afterwards, even if `f` panics).
pub fn both_ways<R>(f: impl Fn() -> R) -> (R, R) {
    struct Restore;
    impl Drop for Restore {
        fn drop(&mut self) {
            nbhd::simd::force_portable(false);
        }
    }
    let _restore = Restore;
    nbhd::simd::force_portable(false);
    let wide = f();
    nbhd::simd::force_portable(true);
    let portable = f();
    (wide, portable)
}

/// The bits of an answer: equal only if every index and squared distance is the same bits.
fn bits<T: Scalar>(row: &[Neighbor<T>]) -> Vec<(u32, u64)> {
    row.iter()
        .map(|n| (n.index, n.sq_dist.to_f64().to_bits()))
        .collect()
}

/// `simd_search` (see the top of this file).
pub fn search(data: &[u8]) {
    let mut inp = Input(data);
    if inp.u8() & 1 == 0 {
        search_typed::<f32>(&mut inp);
    } else {
        search_typed::<f64>(&mut inp);
    }
}

fn search_typed<T: Scalar>(inp: &mut Input<'_>) {
    let dim = 1 + inp.below(5);
    let n = inp.below(161);
    let palette = inp.u8();
    let base = f64::from(inp.u8()) - 100.0;
    let coords: Vec<T> = (0..n * dim)
        .map(|i| {
            coordinate(
                inp,
                palette.rotate_left((i % 8) as u32 * (palette >> 7) as u32),
                base,
            )
        })
        .collect();
    let queries: Vec<T> = (0..inp.below(9) * dim)
        .map(|_| coordinate(inp, palette, base))
        .collect();
    let options = BuildOptions {
        pivot: PivotPolicy::ALL[inp.below(4)],
        leaf_size: 1 + inp.below(16),
        threads: 1,
        ..BuildOptions::default()
    };
    let k = 1 + inp.below(40);
    let radius = {
        // any radius whose square the tree's type holds (larger ones are refused)
        let largest = if T::TYPE.size() == 4 { 1.8e19 } else { 1.3e154 };
        T::from_f64(
            coordinate::<T>(inp, palette, base)
                .to_f64()
                .abs()
                .min(largest),
        )
    };
    let view = PointsView::from_flat(&coords, dim).unwrap();
    let tree = KdTree::<T>::build(&view, &options).unwrap();
    let brute = BruteForce::<T>::new(&view, NonFinitePolicy::Reject).unwrap();
    let qview = PointsView::from_flat(&queries, dim).unwrap();
    let kinds = [
        Neighborhood::Knn { k },
        Neighborhood::Radius {
            radius,
            sorted: true,
        },
        Neighborhood::KnnRadius { k, radius },
    ];
    for nb in kinds {
        for exclude_self in [false, true] {
            let o = TableOptions {
                exclude_self,
                threads: 1,
                ..Default::default()
            };
            let (wide, portable) = both_ways(|| tree.neighborhoods(nb, &o).unwrap());
            assert_eq!(wide.offsets(), portable.offsets(), "{nb:?}");
            assert_eq!(wide.indices(), portable.indices(), "{nb:?}");
            let same = wide
                .sq_dists()
                .iter()
                .zip(portable.sq_dists())
                .all(|(a, b)| a.to_f64().to_bits() == b.to_f64().to_bits());
            assert!(
                same,
                "{nb:?}: squared distances differ between the SIMD and portable forms"
            );
            let mut want = Vec::new();
            for i in 0..n {
                let q = if exclude_self {
                    Query::stored_excluding_self(i as u32)
                } else {
                    Query::stored(i as u32)
                };
                brute.search(q, nb, &mut want).unwrap();
                let row: Vec<Neighbor<T>> = wide
                    .indices_of(i)
                    .iter()
                    .zip(wide.sq_dists_of(i))
                    .map(|(&index, &sq_dist)| Neighbor { index, sq_dist })
                    .collect();
                assert_eq!(
                    bits(&row),
                    bits(&want),
                    "{nb:?} row {i} against brute force"
                );
            }
        }
        let o = TableOptions::default();
        let (wide, portable) = both_ways(|| tree.neighborhoods_of(&qview, nb, &o).unwrap());
        assert_eq!(wide.indices(), portable.indices(), "{nb:?} queries");
        single_queries(&tree, &brute, &queries, dim, n, nb);
    }
}

/// Single queries by coordinates and by stored point: both forms and brute force agree.
fn single_queries<T: Scalar>(
    tree: &KdTree<T>,
    brute: &BruteForce<T>,
    queries: &[T],
    dim: usize,
    n: usize,
    nb: Neighborhood<T>,
) {
    let mut all: Vec<Query<'_, T>> = queries.chunks_exact(dim).map(Query::point).collect();
    all.extend((0..n.min(12)).map(|i| Query::stored(i as u32)));
    let mut want = Vec::new();
    for q in all {
        let (wide, portable) = both_ways(|| {
            let mut out = Vec::new();
            tree.search(q, nb, &mut out).unwrap();
            bits(&out)
        });
        assert_eq!(wide, portable, "{nb:?} {q:?}");
        brute.search(q, nb, &mut want).unwrap();
        assert_eq!(wide, bits(&want), "{nb:?} {q:?} against brute force");
    }
}

/// `simd_robust` (see the top of this file).
pub fn robust(data: &[u8]) {
    let mut inp = Input(data);
    let n = 8 + inp.below(57);
    let noise = f64::from(inp.u8()) * 1e-4;
    // a wavy sheet with a crease (the robust mode's case), and noise from the bytes
    let points: Vec<DVec3> = (0..n)
        .map(|i| {
            let (u, v) = ((i % 8) as f64 * 0.1, (i / 8) as f64 * 0.1);
            let z = if u < 0.35 { u * 0.5 } else { 0.35 - u } + (v * 3.0).sin() * 0.05;
            let e = |inp: &mut Input<'_>| (f64::from(inp.u8()) - 127.5) * noise;
            DVec3::new(u + e(&mut inp), v + e(&mut inp), z + e(&mut inp))
        })
        .collect();
    let options = RobustOptions {
        k: 6 + inp.below(10),
        k_plane: 6 + inp.below(10),
        max_iterations: 1 + inp.below(3),
        threads: 1,
        ..RobustOptions::default()
    };
    let (wide, portable) = both_ways(|| {
        smooth_robust(&points, &options).map(|r| {
            r.points
                .iter()
                .flat_map(|p| p.to_array().map(f64::to_bits))
                .collect::<Vec<u64>>()
        })
    });
    assert_eq!(
        wide, portable,
        "robust smoothing differs between the SIMD and portable forms"
    );
}
