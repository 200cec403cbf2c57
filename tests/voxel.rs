//! Voxel-grid downsampling against a reference transcribed here from PCL 1.13's
//! `VoxelGrid::applyFilter` (native `f32`/`f64` arithmetic, a map from voxel coordinates to
//! points, linear index x fastest), on seeded sets of every kind with NaN points, in 1–4
//! dimensions and several thread counts; and hand-computed cases: points exactly on voxel
//! borders, negative coordinates, per-axis leaves, the minimum per voxel, and the refusals
//! (leaf ≤ 0, NaN, infinite, too small for the extent).

mod common;

use common::{points, to_f32, KINDS};
use nbhd::filter::{voxel_grid, VoxelGrid, VoxelGridOptions};
use nbhd::{NbhdError, PointsView};
use std::collections::BTreeMap;

/// (linear voxel index, centroid, members ascending, nearest member, voxel numbers ⌊x·inv⌋)
type RefVoxel<T> = (u64, Vec<T>, Vec<u32>, u32, Vec<i64>);

macro_rules! reference {
    ($name:ident, $t:ty) => {
        /// PCL's arithmetic in `$t`: inverse leaf, floors of the bounds, voxel coordinates
        /// floor(x·inv) − b_min taken in `$t`, linear index with x fastest; centroid summed
        /// in ascending index and divided by the count; nearest member by f64 distance.
        fn $name(c: &[$t], d: usize, leaf: &[f64], min_pts: usize) -> Vec<RefVoxel<$t>> {
            let n = c.len() / d;
            let inv: Vec<$t> = (0..d).map(|a| 1.0 / (leaf[a % leaf.len()] as $t)).collect();
            let fin = |i: usize| c[i * d..(i + 1) * d].iter().all(|x| x.is_finite());
            let mut lo = vec![<$t>::INFINITY; d];
            let mut hi = vec![<$t>::NEG_INFINITY; d];
            for i in (0..n).filter(|&i| fin(i)) {
                for a in 0..d {
                    lo[a] = lo[a].min(c[i * d + a]);
                    hi[a] = hi[a].max(c[i * d + a]);
                }
            }
            let bmin: Vec<i64> = (0..d).map(|a| (lo[a] * inv[a]).floor() as i64).collect();
            let bmax: Vec<i64> = (0..d).map(|a| (hi[a] * inv[a]).floor() as i64).collect();
            let mut mul = vec![1u64; d];
            for a in 1..d {
                mul[a] = mul[a - 1] * (bmax[a - 1] - bmin[a - 1] + 1) as u64;
            }
            let mut map: BTreeMap<u64, Vec<u32>> = BTreeMap::new();
            for i in (0..n).filter(|&i| fin(i)) {
                let mut idx = 0u64;
                for a in 0..d {
                    let ijk = ((c[i * d + a] * inv[a]).floor() - bmin[a] as $t) as u64;
                    idx += ijk * mul[a];
                }
                map.entry(idx).or_default().push(i as u32);
            }
            map.into_iter()
                .filter(|(_, m)| m.len() >= min_pts)
                .map(|(idx, m)| {
                    let mut sum = vec![0.0 as $t; d];
                    for &i in &m {
                        for a in 0..d {
                            sum[a] += c[i as usize * d + a];
                        }
                    }
                    let cen: Vec<$t> = sum.iter().map(|s| s / m.len() as $t).collect();
                    let dist = |i: u32| -> f64 {
                        (0..d)
                            .map(|a| {
                                let t = c[i as usize * d + a] as f64 - cen[a] as f64;
                                t * t
                            })
                            .sum()
                    };
                    let mut near = m[0];
                    for &i in &m[1..] {
                        if dist(i) < dist(near) {
                            near = i;
                        }
                    }
                    let i0 = m[0] as usize;
                    let cells = (0..d)
                        .map(|a| (c[i0 * d + a] * inv[a]).floor() as i64)
                        .collect();
                    (idx, cen, m, near, cells)
                })
                .collect()
        }
    };
}
reference!(reference_f32, f32);
reference!(reference_f64, f64);

fn check<T: nbhd::Scalar + PartialEq>(got: &VoxelGrid<T>, want: &[RefVoxel<T>], what: &str) {
    assert_eq!(got.len(), want.len(), "{what}: voxel count");
    assert_eq!(got.offsets.len(), want.len() + 1, "{what}");
    assert_eq!(got.cells.len(), want.len() * got.dim, "{what}");
    for (v, (_, cen, m, near, cells)) in want.iter().enumerate() {
        assert_eq!(got.members_of(v), &m[..], "{what}: members of voxel {v}");
        assert_eq!(
            got.cells_of(v),
            &cells[..],
            "{what}: voxel numbers of voxel {v}"
        );
        assert_eq!(got.centroid(v), &cen[..], "{what}: centroid of voxel {v}");
        assert_eq!(got.nearest[v], *near, "{what}: nearest of voxel {v}");
    }
}

fn opts(leaf: &[f64], min_pts: usize, threads: usize) -> VoxelGridOptions {
    VoxelGridOptions {
        leaf: leaf.to_vec(),
        min_points_per_voxel: min_pts,
        threads,
    }
}

/// Seeded sets with some NaN points; the reference in both types, output the same for 1, 2, 3
/// threads and the current pool.
#[test]
fn matches_reference_on_every_kind() {
    for (ki, &kind) in KINDS.iter().enumerate() {
        for d in 1..=4 {
            for (li, leaf) in [vec![0.37], vec![0.05], vec![2.0]].iter().enumerate() {
                let n = 700 + 50 * d;
                let mut c = points(kind, n, d, 11 + ki as u64 * 7 + d as u64);
                for i in (3..n).step_by(97) {
                    c[i * d + (i % d)] = f64::NAN;
                }
                c[d * 5] = f64::INFINITY;
                let c32 = to_f32(&c);
                let min_pts = li; // 0, 1, 2
                let want64 = reference_f64(&c, d, leaf, min_pts);
                let want32 = reference_f32(&c32, d, leaf, min_pts);
                let v64 = PointsView::from_flat(&c, d).unwrap();
                let v32 = PointsView::from_flat(&c32, d).unwrap();
                let mut first: Option<VoxelGrid<f64>> = None;
                for threads in [0, 1, 2, 3] {
                    let what = format!("{kind:?} d={d} leaf={leaf:?} threads={threads}");
                    let o = opts(leaf, min_pts, threads);
                    let g64 = voxel_grid::<f64>(&v64, &o).unwrap();
                    check(&g64, &want64, &what);
                    let g32 = voxel_grid::<f32>(&v32, &o).unwrap();
                    check(&g32, &want32, &what);
                    match &first {
                        None => first = Some(g64),
                        Some(f) => assert_eq!(f, &g64, "{what}: same for any thread count"),
                    }
                }
            }
        }
    }
}

/// More points than one parallel piece, per-axis leaves.
#[test]
fn large_set_per_axis_leaves() {
    let d = 3;
    let c = points(common::Kind::Clustered, 40_000, d, 5);
    let c32 = to_f32(&c);
    let leaf = [0.02, 0.05, 0.03];
    let v = PointsView::from_flat(&c32, d).unwrap();
    let want = reference_f32(&c32, d, &leaf, 0);
    for threads in [1, 2] {
        let g = voxel_grid::<f32>(&v, &opts(&leaf, 0, threads)).unwrap();
        check(&g, &want, &format!("threads={threads}"));
        // every point in exactly one voxel
        let mut all = g.members.clone();
        all.sort_unstable();
        assert_eq!(all, (0..40_000u32).collect::<Vec<_>>());
    }
}

/// Hand-computed: leaf 0.5 (exact in binary), points on borders belong to the voxel above.
#[test]
fn borders_and_negative_coordinates() {
    // x: -0.5 → ⌊-1⌋ = -1; -0.25 → -1; 0 → 0; 0.5 → 1; 1.0 → 2 (b_min = -1)
    let c: Vec<f64> = vec![
        1.0,
        0.0, // 0: voxel (3, 0)
        -0.5,
        0.0, // 1: voxel (0, 0)
        0.5,
        0.0, // 2: voxel (2, 0)
        -0.25,
        0.0, // 3: voxel (0, 0)
        0.0,
        0.5, // 4: voxel (1, 1)
        0.25,
        0.25, // 5: voxel (1, 0)
        0.0,
        0.0, // 6: voxel (1, 0)
        f64::NAN,
        0.0, // 7: none
    ];
    let v = PointsView::from_flat(&c, 2).unwrap();
    let g = voxel_grid::<f64>(&v, &VoxelGridOptions::cube(0.5)).unwrap();
    // 4 voxels along x (-1 ..= 2), linear index x + 4 y
    let members: Vec<&[u32]> = (0..g.len()).map(|i| g.members_of(i)).collect();
    assert_eq!(members, vec![&[1, 3][..], &[5, 6], &[2], &[0], &[4]]);
    assert_eq!(g.centroid(0), &[-0.375, 0.0]);
    assert_eq!(g.centroid(1), &[0.125, 0.125]);
    assert_eq!(g.centroid(4), &[0.0, 0.5]);
    // voxel 1: both points at the same distance from (0.125, 0.125): the smaller index
    assert_eq!(g.nearest, vec![1, 5, 2, 0, 4]);
    assert_eq!(g.source_len, 8);
    // the voxel numbers ⌊x/0.5⌋, not less the grid's lowest (-1 along x)
    assert_eq!(g.cells, vec![-1, 0, 0, 0, 1, 0, 2, 0, 0, 1]);
    // a voxel minimum of 2 keeps the first two
    let g2 = voxel_grid::<f64>(&v, &opts(&[0.5], 2, 1)).unwrap();
    assert_eq!(g2.members, vec![1, 3, 5, 6]);
    assert_eq!(g2.offsets, vec![0, 2, 4]);
    // per-axis leaf: y in voxels of 1 puts 4 with 6 and 5
    let g3 = voxel_grid::<f64>(&v, &opts(&[0.5, 1.0], 0, 1)).unwrap();
    assert_eq!(g3.members_of(1), &[4, 5, 6]);
}

/// All points non-finite: no voxel, no error.
#[test]
fn all_nan_gives_nothing() {
    let c = vec![f64::NAN, 1.0, 2.0, f64::INFINITY];
    let v = PointsView::from_flat(&c, 2).unwrap();
    let g = voxel_grid::<f64>(&v, &VoxelGridOptions::cube(1.0)).unwrap();
    assert!(g.is_empty());
    assert_eq!(g.offsets, vec![0]);
}

fn leaf_refused(r: nbhd::Result<VoxelGrid<f64>>) -> String {
    match r {
        Err(NbhdError::InvalidOption {
            name: "leaf",
            reason,
        }) => reason,
        other => panic!("expected a refused leaf, got {other:?}"),
    }
}

#[test]
fn bad_leaves_are_refused() {
    let c = vec![0.0, 0.0, 1.0, 1.0];
    let v = PointsView::from_flat(&c, 2).unwrap();
    for leaf in [0.0, -1.0, f64::NAN, f64::INFINITY, -0.0] {
        leaf_refused(voxel_grid::<f64>(&v, &VoxelGridOptions::cube(leaf)));
    }
    // three values for 2-d points
    leaf_refused(voxel_grid::<f64>(&v, &opts(&[1.0, 1.0, 1.0], 0, 0)));
    // fine in f64 but 0 in f32
    let c32 = to_f32(&c);
    let v32 = PointsView::from_flat(&c32, 2).unwrap();
    assert!(matches!(
        voxel_grid::<f32>(&v32, &VoxelGridOptions::cube(1e-50)),
        Err(NbhdError::InvalidOption { name: "leaf", .. })
    ));
    // too many threads
    assert!(matches!(
        voxel_grid::<f64>(&v, &opts(&[1.0], 0, 100_000)),
        Err(NbhdError::InvalidOption {
            name: "threads",
            ..
        })
    ));
}

#[test]
fn huge_extents_are_refused() {
    // 1e4 + 1 voxels per axis in 4 dimensions fit 64 bits; (1e8 + 1)^4 do not
    let ok = vec![0.0, 0.0, 0.0, 0.0, 1e4, 1e4, 1e4, 1e4];
    let v = PointsView::from_flat(&ok, 4).unwrap();
    let g = voxel_grid::<f64>(&v, &VoxelGridOptions::cube(1.0)).unwrap();
    assert_eq!(g.len(), 2);
    let too_many = vec![0.0, 0.0, 0.0, 0.0, 1e6, 1e6, 1e6, 1e6];
    let v = PointsView::from_flat(&too_many, 4).unwrap();
    let r = leaf_refused(voxel_grid::<f64>(&v, &VoxelGridOptions::cube(0.01)));
    assert!(r.contains("2^64"), "{r}");
    // a voxel number beyond 2^53 in f64
    let far = vec![0.0, 1e10];
    let v = PointsView::from_flat(&far, 1).unwrap();
    let r = leaf_refused(voxel_grid::<f64>(&v, &VoxelGridOptions::cube(1e-7)));
    assert!(r.contains("2^53"), "{r}");
    // beyond 2^24 in f32 (PCL's voxels would be rounded there)
    let far32 = vec![0.0f32, 2e7];
    let v = PointsView::from_flat(&far32, 1).unwrap();
    match voxel_grid::<f32>(&v, &VoxelGridOptions::cube(1.0)) {
        Err(NbhdError::InvalidOption {
            name: "leaf",
            reason,
        }) => {
            assert!(reason.contains("2^24"), "{reason}")
        }
        other => panic!("{other:?}"),
    }
    // 1.6e7 voxels along one axis are fine in f32
    let near32 = vec![0.0f32, 1.6e7];
    let v = PointsView::from_flat(&near32, 1).unwrap();
    assert_eq!(
        voxel_grid::<f32>(&v, &VoxelGridOptions::cube(1.0))
            .unwrap()
            .len(),
        2
    );
    // products and sums that overflow f64 itself
    let inf = vec![-1e308, 1e308];
    let v = PointsView::from_flat(&inf, 1).unwrap();
    leaf_refused(voxel_grid::<f64>(&v, &VoxelGridOptions::cube(1e-10)));
}
