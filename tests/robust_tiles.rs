//! The robust smoothing on a cloud split into tiles equals the one-machine call bit for bit.
//!
//! An in-process driver splits each cloud into 2×2 tiles (a box of owned points plus a halo;
//! the region is unbounded on the cloud's outer sides), runs the rounds of `RobustRun` over
//! `RobustTile::gathered` tiles, reduces their parts with `reduce` (exact selections across the
//! tiles) and exchanges the owned points' positions after every step. A tile whose part is not
//! valid everywhere is gathered again with twice the halo. A driver may also keep no tile
//! between rounds: each round then gathers every tile anew and gives it the proxy of the round's
//! generation, the proxy its rows shrank on and the last step's normals (the stateless tasks of
//! `nbhd.dask`). The result — points, normals,
//! outputs and every figure of the report — must be the bits of `smooth_robust_report`. Two
//! negative controls show the comparison can fail: a halo too narrow whose invalid parts are
//! used anyway, and the median of the tiles' medians in place of the exact median.

use glam::{DVec3, Vec3};
use nbhd::geometry::neighbors::mean_spacing;
use nbhd::shapes::{add_noise, sample, Cube, CylinderPlane, NoiseKind};
use nbhd::smooth::robust::{
    median, reduce, smooth_robust_report, Region, RobustOptions, RobustReport, RobustRun,
    RobustTile, Round, RowSet, TilePart,
};
use nbhd::smooth::{Neighbors, SmoothResult};
use nbhd::NonFinitePolicy;

/// How the driver treats halos and medians.
#[derive(Clone, Copy)]
struct Control {
    /// The first halo, in units of the cloud's spacing.
    halo: f64,
    /// Gather a tile again with twice the halo when its part is not all valid.
    grow: bool,
    /// The negative control: the median of the tiles' medians instead of the exact median.
    median_of_medians: bool,
    /// Gather every tile anew for every round (a driver that keeps nothing between rounds).
    fresh: bool,
    /// Tiles keep their rows in files (`RobustTile::keep_rows_in`) in a directory of this
    /// name, read back by the tiles gathered anew.
    files: Option<&'static str>,
}

const EXACT: Control = Control {
    halo: 6.0,
    grow: true,
    median_of_medians: false,
    fresh: false,
    files: None,
};

/// What a tile gathered anew needs besides its input: the positions of every generation so
/// far (by the cloud's index) and the normals of the last step.
struct History {
    generations: Vec<Vec<DVec3>>,
    normals: Vec<DVec3>,
}

impl History {
    /// Tile `cell` gathered anew with `halo` and given what `round` reads.
    fn gather(&self, points: &[DVec3], mid: DVec3, t: &Tile, halo: f64, round: &Round) -> Tile {
        let mut t = gather(points, mid, t.cell, halo, t.files);
        let of = |v: &[DVec3]| -> Vec<DVec3> { t.gathered.iter().map(|&i| v[i]).collect() };
        let (generation, rows) = match *round {
            Round::Ratio { generation } => (generation, RowSet::Wide),
            Round::Measure { generation, rows }
            | Round::Step {
                generation, rows, ..
            }
            | Round::Finish {
                generation, rows, ..
            } => (generation, rows),
            _ => (0, RowSet::Plain),
        };
        let current = of(&self.generations[generation]);
        let shrink = match rows {
            RowSet::Shrunk { at } => Some((at, of(&self.generations[at]))),
            _ => None,
        };
        let normals =
            (matches!(round, Round::Finish { .. }) && generation > 0).then(|| of(&self.normals));
        if generation > 0 {
            t.tile.set_current(generation, &current).unwrap();
        }
        if let Some((at, proxy)) = shrink {
            t.tile.set_shrink(at, &proxy).unwrap();
        }
        if let Some(normals) = normals {
            t.tile.set_normals(&normals).unwrap();
        }
        t
    }
}

/// One tile: the cloud's indices of its gathered points (ascending) and of its owned ones.
struct Tile {
    tile: RobustTile<'static>,
    cell: usize,
    halo: f64,
    gathered: Vec<usize>,
    owned: Vec<usize>,
    files: Option<&'static str>,
}

/// The cell of a point: 2×2 in x and y about `mid`.
fn cell_of(p: DVec3, mid: DVec3) -> usize {
    usize::from(p.x >= mid.x) + 2 * usize::from(p.y >= mid.y)
}

/// Where tile `cell` keeps its rows with `Control::files` of `name`.
fn row_dir(name: &str, cell: usize) -> std::path::PathBuf {
    let run = format!("nbhd-robust-tiles-{}-{name}", std::process::id());
    std::env::temp_dir().join(run).join(format!("tile_{cell}"))
}

/// Tile `cell` with a halo of `halo` (absolute) around its box, unbounded on the outer sides;
/// with `files`, keeping its rows in files of that name.
fn gather(
    points: &[DVec3],
    mid: DVec3,
    cell: usize,
    halo: f64,
    files: Option<&'static str>,
) -> Tile {
    let (inf, ninf) = (f64::INFINITY, f64::NEG_INFINITY);
    let side = |high: bool, m: f64| {
        if high {
            (m - halo, inf)
        } else {
            (ninf, m + halo)
        }
    };
    let (x, y) = (side(cell % 2 == 1, mid.x), side(cell / 2 == 1, mid.y));
    let region = Region {
        lo: DVec3::new(x.0, y.0, ninf),
        hi: DVec3::new(x.1, y.1, inf),
    };
    let gathered: Vec<usize> = (0..points.len())
        .filter(|&i| region.contains(points[i]))
        .collect();
    let owned_flags: Vec<bool> = gathered
        .iter()
        .map(|&i| cell_of(points[i], mid) == cell)
        .collect();
    let owned = gathered
        .iter()
        .copied()
        .filter(|&i| cell_of(points[i], mid) == cell)
        .collect();
    let input = gathered.iter().map(|&i| points[i]).collect();
    let mut tile = RobustTile::gathered(input, &owned_flags, region).unwrap();
    if let Some(name) = files {
        tile.keep_rows_in(row_dir(name, cell));
    }
    Tile {
        tile,
        cell,
        halo,
        gathered,
        owned,
        files,
    }
}

/// What the tiled driver returns.
struct Tiled {
    report: RobustReport,
    /// Tiles gathered again with a wider halo.
    grown: usize,
    /// Owned values used although their tile said they were not valid.
    invalid: usize,
}

/// The driver (see the module documentation) over the finite points of `points` (a cloud's
/// holes are left out, as `NonFinitePolicy::Skip` leaves them out of the neighbourhoods).
fn tiled(points: &[DVec3], options: &RobustOptions, ctl: Control) -> Tiled {
    let points: Vec<DVec3> = points.iter().copied().filter(|p| p.is_finite()).collect();
    let n = points.len();
    let (lo, hi) = points
        .iter()
        .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(l, h), &p| {
            (l.min(p), h.max(p))
        });
    let mid = (lo + hi) / 2.0;
    let h0 = mean_spacing(&points).unwrap();
    let mut tiles: Vec<Tile> = (0..4)
        .map(|c| gather(&points, mid, c, ctl.halo * h0, ctl.files))
        .collect();
    let (mut grown, mut invalid) = (0, 0);
    // the spacing: each owned point's nearest, put in the cloud's order
    let mut nearest = vec![None; n];
    for t in &mut tiles {
        loop {
            let (near, valid) = t.tile.nearest(options).unwrap();
            if ctl.grow && !valid.iter().all(|&v| v) {
                *t = gather(&points, mid, t.cell, 2.0 * t.halo, t.files);
                grown += 1;
                continue;
            }
            invalid += valid.iter().filter(|&&v| !v).count();
            for (&i, d) in t.owned.iter().zip(near) {
                nearest[i] = d;
            }
            break;
        }
    }
    let mut run = RobustRun::new(
        options,
        RobustRun::spacing_of_nearest(nearest),
        Neighbors::default(),
    )
    .unwrap();
    let eps = run.epsilon();
    let mut current = points.clone();
    let mut history = History {
        generations: vec![points.clone()],
        normals: vec![DVec3::NAN; n],
    };
    let mut generation = 0;
    loop {
        let round = run.round();
        if ctl.fresh {
            for t in &mut tiles {
                *t = history.gather(&points, mid, t, t.halo, &round);
            }
        }
        if matches!(round, Round::Finish { .. }) {
            break;
        }
        let mut parts: Vec<TilePart> = Vec::new();
        for t in &mut tiles {
            loop {
                let part = t.tile.round(&round, options, eps).unwrap();
                if ctl.grow && !part.all_valid() {
                    *t = history.gather(&points, mid, t, 2.0 * t.halo, &round);
                    grown += 1;
                    continue;
                }
                invalid += part.valid.iter().filter(|&&v| !v).count();
                parts.push(part);
                break;
            }
        }
        let mut reduced = reduce(&round, &mut parts).unwrap();
        if ctl.median_of_medians {
            let mut medians: Vec<f64> = parts
                .iter_mut()
                .filter_map(|p| median(&mut p.values))
                .collect();
            let m = median(&mut medians);
            reduced.ratio = reduced.ratio.and(m);
            reduced.residual = reduced.residual.and(m);
        }
        run.feed(&reduced).unwrap();
        if matches!(round, Round::Step { .. }) {
            generation += 1;
            for t in &tiles {
                for (&i, p) in t.owned.iter().zip(t.tile.owned_points()) {
                    current[i] = p;
                }
                for (&i, p) in t.owned.iter().zip(t.tile.owned_normals()) {
                    history.normals[i] = p;
                }
            }
            history.generations.push(current.clone());
            for t in &mut tiles {
                let proxy: Vec<DVec3> = t.gathered.iter().map(|&i| current[i]).collect();
                t.tile.set_current(generation, &proxy).unwrap();
            }
        }
    }
    let round = run.round();
    let mut report = run.report();
    report.result.points = vec![DVec3::ZERO; n];
    report.normals = vec![DVec3::ZERO; n];
    let mut outputs = vec![None; n];
    for t in tiles {
        let (pts, normals, outs, _) = t.tile.finish(&round, options, eps).unwrap();
        for (k, &i) in t.owned.iter().enumerate() {
            report.result.points[i] = pts[k];
            report.normals[i] = normals[k];
            outputs[i] = outs.get(k).copied();
        }
    }
    report.result.outputs = outputs.into_iter().flatten().collect();
    Tiled {
        report,
        grown,
        invalid,
    }
}

/// The one-machine report restricted to the finite points of `points` (in order).
fn one_machine(points: &[DVec3], options: &RobustOptions) -> RobustReport {
    let r = smooth_robust_report(points, options, &mut |_, _| true).unwrap();
    let finite: Vec<usize> = (0..points.len())
        .filter(|&i| points[i].is_finite())
        .collect();
    for i in (0..points.len()).filter(|&i| !points[i].is_finite()) {
        // a hole keeps its input and gets NaN normals
        assert_eq!(
            r.result.points[i].to_array().map(f64::to_bits),
            points[i].to_array().map(f64::to_bits)
        );
        assert!(r.normals[i].is_nan());
    }
    let pick = |v: &[DVec3]| finite.iter().map(|&i| v[i]).collect();
    let outputs = if r.result.outputs.is_empty() {
        Vec::new()
    } else {
        finite.iter().map(|&i| r.result.outputs[i]).collect()
    };
    RobustReport {
        result: SmoothResult {
            points: pick(&r.result.points),
            outputs,
            ..r.result
        },
        normals: pick(&r.normals),
        ..r
    }
}

/// Every figure of a report as bits (floats through `Debug`, which prints each value's
/// shortest exact representation).
fn bits(r: &RobustReport) -> Vec<String> {
    let v = |p: &[DVec3]| {
        p.iter()
            .map(|q| format!("{:?}", q.to_array().map(f64::to_bits)))
            .collect::<Vec<_>>()
    };
    let mut out = v(&r.result.points);
    out.extend(v(&r.normals));
    out.extend(r.result.outputs.iter().map(|o| format!("{o:?}")));
    out.push(format!(
        "{:?} {:?} {:?} {} h {:?} eps {:?} lambda {:?} min {}",
        r.noise,
        r.moved,
        r.dimension,
        r.wide_iterations,
        r.result.spacing,
        r.result.epsilon,
        r.result.lambda,
        r.result.min_neighbors
    ));
    out
}

/// How many entries of two reports' bits differ.
fn differences(a: &RobustReport, b: &RobustReport) -> usize {
    let (a, b) = (bits(a), bits(b));
    assert_eq!(a.len(), b.len());
    a.iter().zip(&b).filter(|(x, y)| x != y).count()
}

fn assert_tiled_equals_one_machine(
    points: &[DVec3],
    options: &RobustOptions,
    ctl: Control,
) -> Tiled {
    let one = one_machine(points, options);
    let t = tiled(points, options, ctl);
    assert_eq!(t.invalid, 0);
    let (a, b) = (bits(&t.report), bits(&one));
    for (x, y) in a.iter().zip(&b) {
        assert_eq!(x, y);
    }
    assert_eq!(a.len(), b.len());
    t
}

fn noisy_cube(n: usize, noise: f64, seed: u64) -> Vec<DVec3> {
    let s = sample(&Cube::new(1.0), n, seed);
    let h = mean_spacing(&s.points).unwrap();
    add_noise(&s, noise, h, NoiseKind::Gaussian, seed + 1).unwrap()
}

#[test]
fn tiles_equal_one_machine_at_three_noise_levels() {
    // h is the mean nearest distance of a uniform random sample, about 0.55 of a Poisson-disk
    // sample's: 3h reads as a surface (local dimension 2.66), 5h as a ball of noise, which
    // widens the rows and shrinks them back on the proxy (see `src/smooth/tests.rs`)
    for (noise, n) in [(0.3, 12_000), (1.0, 12_000), (3.0, 12_000), (5.0, 12_000)] {
        let p = noisy_cube(n, noise, 39);
        let t = assert_tiled_equals_one_machine(&p, &RobustOptions::default(), EXACT);
        if noise >= 1.0 {
            // the same with every tile gathered anew for every round
            let fresh = Control {
                fresh: true,
                ..EXACT
            };
            assert_tiled_equals_one_machine(&p, &RobustOptions::default(), fresh);
            // and with the rows searched once and a measure's rows and planes read by its
            // step, from the tiles' files (wide and shrunk rows at 5h)
            let name = ["1h", "3h", "5h"][(noise as usize).min(5) / 2];
            let files = Control {
                files: Some(name),
                ..fresh
            };
            assert_tiled_equals_one_machine(&p, &RobustOptions::default(), files);
            let dir = row_dir(name, 0);
            let kept = std::fs::read_dir(&dir).unwrap().count();
            assert!(
                kept >= 2,
                "{noise}h: searched and measured rows kept in {dir:?}"
            );
            std::fs::remove_dir_all(dir.parent().unwrap()).unwrap();
        }
        let r = &t.report;
        assert!(!r.moved.is_empty(), "{noise}h: iterations ran");
        if noise == 5.0 {
            // the wide rows, then shrunk back on the proxy
            assert!(r.wide_iterations > 0, "{noise}h: {:?}", r.dimension);
            assert!(
                r.wide_iterations < r.moved.len(),
                "{noise}h: {:?}",
                r.dimension
            );
        }
    }
}

#[test]
fn tiles_equal_one_machine_with_duplicates_holes_and_f32() {
    let s = sample(&CylinderPlane::new(1.0, 2.0), 9_000, 7);
    let h = mean_spacing(&s.points).unwrap();
    let mut p = add_noise(&s, 1.0, h, NoiseKind::Gaussian, 8).unwrap();
    // exact copies of points near the tiles' dividing planes (ties at distance 0)
    let mid = p.iter().fold(DVec3::ZERO, |a, &q| a + q) / p.len() as f64;
    let near_mid: Vec<DVec3> = p
        .iter()
        .copied()
        .filter(|q| (q.x - mid.x).abs() < 2.0 * h || (q.y - mid.y).abs() < 2.0 * h)
        .take(300)
        .collect();
    p.extend(near_mid);
    // holes, skipped on both sides
    for i in (0..p.len()).step_by(97) {
        p[i] = DVec3::new(f64::NAN, 0.0, 1.0);
    }
    let skip = RobustOptions {
        non_finite: NonFinitePolicy::Skip,
        ..RobustOptions::default()
    };
    assert_tiled_equals_one_machine(&p, &skip, EXACT);
    let fresh = Control {
        fresh: true,
        ..EXACT
    };
    // with the outputs, which read the last step's normals given to the fresh tiles
    let outputs = RobustOptions {
        outputs: true,
        ..skip
    };
    assert_tiled_equals_one_machine(&p, &outputs, fresh);
    // single precision input, converted to f64 exactly on both sides
    let single: Vec<DVec3> = p
        .iter()
        .map(|q| Vec3::new(q.x as f32, q.y as f32, q.z as f32).as_dvec3())
        .collect();
    assert_tiled_equals_one_machine(&single, &skip, EXACT);
}

#[test]
fn an_outlier_grows_its_tiles_halo_and_stays_identical() {
    let mut p = noisy_cube(8_000, 0.3, 5);
    // far from the cube, beside one tile: its row reaches across the cloud
    p.push(DVec3::new(3.0, 2.5, 0.0));
    let t = assert_tiled_equals_one_machine(&p, &RobustOptions::default(), EXACT);
    assert!(t.grown > 0);
}

#[test]
fn a_narrow_halo_or_an_approximate_median_differs() {
    let p = noisy_cube(12_000, 1.0, 11);
    let options = RobustOptions::default();
    let one = one_machine(&p, &options);
    // halos of one spacing, used although the tiles say they are not valid
    let narrow = tiled(
        &p,
        &options,
        Control {
            halo: 1.0,
            grow: false,
            ..EXACT
        },
    );
    assert!(narrow.invalid > 0);
    let d = differences(&narrow.report, &one);
    // the wrong plane distances at the borders move σ̂ too, and with it every point
    assert!(d > 0, "{d} differences");
    // the median of the tiles' medians for σ̂ and the noise scale
    let approx = tiled(
        &p,
        &options,
        Control {
            median_of_medians: true,
            ..EXACT
        },
    );
    assert_eq!(approx.invalid, 0);
    assert_ne!(approx.report.noise, one.noise);
    assert!(differences(&approx.report, &one) > p.len() / 2);
}

#[test]
fn the_reach_flags_only_values_that_are_the_whole_clouds() {
    // a brute-force check of `robust/reach.rs`: one tile with a narrow halo runs every round
    // beside the whole cloud (fed the whole cloud's proxy after each step); every owned value
    // it flags valid must be the whole cloud's, and some it flags invalid must differ (the
    // points beyond its halo change them), so the flags are neither wrong nor vacuous
    let p = noisy_cube(6_000, 1.0, 21);
    let options = RobustOptions::default();
    let h0 = mean_spacing(&p).unwrap();
    let everything = Region {
        lo: DVec3::NEG_INFINITY,
        hi: DVec3::INFINITY,
    };
    let mut whole = RobustTile::gathered(p.clone(), &vec![true; p.len()], everything).unwrap();
    let (lo, hi) = p
        .iter()
        .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(l, h), &q| {
            (l.min(q), h.max(q))
        });
    let mut t = gather(&p, (lo + hi) / 2.0, 0, 4.0 * h0, None);
    let (near, _) = whole.nearest(&options).unwrap();
    t.tile.nearest(&options).unwrap();
    let mut run = RobustRun::new(
        &options,
        RobustRun::spacing_of_nearest(near),
        Neighbors::default(),
    )
    .unwrap();
    let eps = run.epsilon();
    // (valid and equal, valid and different, invalid and different) per kind of round
    let mut tally = [[0usize; 3]; 2];
    let mut count = |kind: usize, valid: bool, same: bool| match (valid, same) {
        (true, true) => tally[kind][0] += 1,
        (true, false) => tally[kind][1] += 1,
        (false, false) => tally[kind][2] += 1,
        (false, true) => {}
    };
    let mut generation = 0;
    loop {
        let round = run.round();
        if matches!(round, Round::Finish { .. }) {
            break;
        }
        let mut w = [whole.round(&round, &options, eps).unwrap()];
        let part = t.tile.round(&round, &options, eps).unwrap();
        match round {
            Round::Measure { .. } => {
                for (k, &i) in t.owned.iter().enumerate() {
                    let same = part.values[k].to_bits() == w[0].values[i].to_bits();
                    count(0, part.valid[k], same);
                }
            }
            Round::Step { .. } => {
                let (a, b) = (t.tile.owned_points(), whole.owned_points());
                for (k, &i) in t.owned.iter().enumerate() {
                    let same =
                        a[k].to_array().map(f64::to_bits) == b[i].to_array().map(f64::to_bits);
                    count(1, part.valid[k], same);
                }
            }
            _ => {}
        }
        run.feed(&reduce(&round, &mut w).unwrap()).unwrap();
        if matches!(round, Round::Step { .. }) {
            generation += 1;
            let proxy = whole.owned_points();
            let gathered: Vec<DVec3> = t.gathered.iter().map(|&i| proxy[i]).collect();
            t.tile.set_current(generation, &gathered).unwrap();
        }
    }
    for (kind, [right, wrong, differs]) in ["plane distances", "steps"].iter().zip(tally) {
        assert!(right > 0, "{kind}: no owned value flagged valid");
        assert_eq!(
            wrong, 0,
            "{kind}: values flagged valid that are not the cloud's"
        );
        assert!(differs > 0, "{kind}: no value flagged invalid differs");
    }
}
