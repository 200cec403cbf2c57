//! `nbhd tiles IN... --out DIR`: the robust smoothing of a survey delivered as tiles (LAS/LAZ or
//! any format nbhd reads), one tile in memory at a time, identical to `nbhd smooth` on the
//! tiles' points taken together in the order given.
//!
//! The driver of the library's step API (`nbhd::smooth::robust`: `RobustRun` decides every
//! round, `RobustTile` computes one tile's part, `reduce` takes the exact medians): each input
//! file is a tile. A first pass keeps each file's finite positions in a scratch directory; then
//! every round gathers each tile anew with a halo (the points of the other tiles within its box
//! grown by the halo, read from their scratch files, with the positions of the round's
//! generation), computes its part, and writes a step's new positions and normals to the
//! scratch. The library checks each owned point's reach; a tile that fails is gathered again
//! with twice the halo. At the finish each file is read again and written with its points
//! smoothed, its records kept and the normals and curvatures added, as `nbhd smooth` writes it.

use crate::args::{parse_length, PrecisionArgs, RobustArgs};
use crate::error::{Context, Result};
use crate::output::{num, Output};
use crate::progress::Progress;
use crate::read::finite_points;
use crate::write;
use glam::DVec3;
use nbhd::geometry::Orientation;
use nbhd::smooth::robust::{reduce, Region, RobustOptions, RobustRun, RobustTile, Round, RowSet};
use nbhd::smooth::{Length, Neighbors};
use serde_json::json;
use std::fs;
use std::path::{Path, PathBuf};

/// Smooth a survey's tiles with the robust mode, one tile in memory at a time
///
/// For surveys larger than memory, delivered as tiles (LAS/LAZ, or any format nbhd reads):
/// the result is bit for bit that of `nbhd smooth --orient unoriented` on all the tiles'
/// points taken together in the order given, but only one tile and the points of its
/// neighbours near it are held at a time. Each tile is written to the output directory under
/// its own name, with its point records kept and the normals and curvatures added (in LAS:
/// extra bytes NormalX NormalY NormalZ, Curvature, ...). Positions go through a scratch
/// directory (24 bytes per point and generation kept, at most three); besides one tile, the
/// run holds 16 bytes per point of the survey (the spacing's and the medians' values). Progress
/// goes to standard error. The normals are unoriented (propagating an orientation needs the
/// whole cloud).
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Input files, one tile each, in the survey's order (the order of the points)
    #[arg(required = true)]
    pub inputs: Vec<PathBuf>,

    /// Directory of the results: one file per input, under the input's name
    #[arg(long, short)]
    pub out: PathBuf,

    /// Write the results in this format's extension (e.g. ply) instead of the input's
    #[arg(long)]
    pub ext: Option<String>,

    /// Directory in which the positions are kept while the run lasts (in a directory of their
    /// own, removed at the end) [default: OUT]
    #[arg(long)]
    pub scratch: Option<PathBuf>,

    /// Maximum valence k, as `nbhd smooth` [default: 24]
    #[arg(short, long)]
    pub k: Option<usize>,

    /// Influence radius ε (points' units, or 12h), as `nbhd smooth` [default: 12h]
    #[arg(long, short = 'r', value_parser = parse_length, allow_hyphen_values = true)]
    pub radius: Option<Length>,

    /// Step size τ in (0, 1], as `nbhd smooth` [default: 1]
    #[arg(long, allow_hyphen_values = true)]
    pub tau: Option<f64>,

    #[command(flatten)]
    pub robust: RobustArgs,

    #[command(flatten)]
    pub precision: PrecisionArgs,
}

/// One input file as a tile: its finite points are the points it owns, in its order.
struct Tile {
    path: PathBuf,
    /// Finite points.
    count: usize,
    lo: DVec3,
    hi: DVec3,
    /// The halo the tile is gathered with.
    halo: f64,
}

/// The tiles, their scratch files and the cloud's box.
struct Survey {
    tiles: Vec<Tile>,
    scratch: PathBuf,
    lo: DVec3,
    hi: DVec3,
}

/// Points as little-endian f64 triples.
fn save(path: &Path, points: &[DVec3]) -> Result<()> {
    let mut bytes = Vec::with_capacity(points.len() * 24);
    for p in points {
        for c in p.to_array() {
            bytes.extend_from_slice(&c.to_le_bytes());
        }
    }
    let tmp = path.with_extension("tmp");
    fs::write(&tmp, bytes).context(tmp.display())?;
    fs::rename(&tmp, path).context(path.display())
}

/// The points of [`save`].
fn load(path: &Path) -> Result<Vec<DVec3>> {
    let bytes = fs::read(path).context(path.display())?;
    let f = |c: &[u8]| f64::from_le_bytes(c.try_into().expect("8 bytes"));
    Ok(bytes
        .chunks_exact(24)
        .map(|c| DVec3::new(f(&c[..8]), f(&c[8..16]), f(&c[16..])))
        .collect())
}

/// Where tile `t`'s positions of generation `g` (or the normals of the step into it) are kept
/// in the directory `scratch`.
fn scratch_file(scratch: &Path, g: usize, t: usize, kind: Kind) -> PathBuf {
    let what = if kind == Kind::Points { "p" } else { "n" };
    scratch.join(format!("{what}{g:04}_{t:06}.bin"))
}

/// What a gathered tile reads besides the input: the positions of a generation (0: the
/// input) or the normals of the step into it.
#[derive(Clone, Copy, PartialEq)]
enum Kind {
    Points,
    Normals,
}

impl Survey {
    /// Reads every input once and keeps its finite positions in the scratch directory.
    fn ingest(paths: &[PathBuf], scratch: PathBuf, bar: &Progress) -> Result<Self> {
        fs::create_dir_all(&scratch).context(scratch.display())?;
        let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
        let mut tiles = Vec::with_capacity(paths.len());
        for (t, path) in paths.iter().enumerate() {
            let cloud = crate::read::cloud(path, None)?;
            let (points, _) = finite_points(&cloud);
            let (a, b) = points
                .iter()
                .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(l, h), &p| {
                    (l.min(p), h.max(p))
                });
            lo = lo.min(a);
            hi = hi.max(b);
            save(&scratch_file(&scratch, 0, t, Kind::Points), &points)?;
            tiles.push(Tile {
                path: path.clone(),
                count: points.len(),
                lo: a,
                hi: b,
                halo: 0.0,
            });
            bar.inc(1);
        }
        Ok(Survey {
            tiles,
            scratch,
            lo,
            hi,
        })
    }

    /// Where tile `t`'s positions of generation `g` (or the normals of the step into it) are.
    fn file(&self, g: usize, t: usize, kind: Kind) -> PathBuf {
        scratch_file(&self.scratch, g, t, kind)
    }

    /// The first halo of each tile: three hops of the radius of a disc holding `k_plane` of
    /// its points if they covered its box's two largest extents evenly, a third more for the
    /// spread of the distances (as `nbhd.dask` starts its robust tiles); the library checks it.
    fn first_halos(&mut self, k_plane: usize) {
        let scale = (self.hi - self.lo).max_element().max(f64::MIN_POSITIVE);
        for tile in &mut self.tiles {
            let mut ext = (tile.hi - tile.lo).max(DVec3::ZERO).to_array();
            ext.sort_by(|a, b| b.total_cmp(a));
            let live: Vec<f64> = ext[..2].iter().copied().filter(|&e| e > 0.0).collect();
            let count = tile.count.max(1) as f64;
            tile.halo = match live.as_slice() {
                [a, b] => 4.0 * (a * b * k_plane as f64 / (count * std::f64::consts::PI)).sqrt(),
                [a] => 4.0 * a * k_plane as f64 / (count * 2.0),
                _ => scale * 1e-6,
            };
        }
    }

    /// Tile `t` with its halo, for `round` (which says the generation, the shrink proxy and
    /// whether the last step's normals are needed): the gathered points of every tile near it,
    /// in the cloud's order, and which tile owns each at which position.
    fn gather(&self, t: usize, round: &Round) -> Result<RobustTile<'static>> {
        let tile = &self.tiles[t];
        let (a, b) = (tile.lo - tile.halo, tile.hi + tile.halo);
        let region = Region {
            lo: DVec3::select(a.cmple(self.lo), DVec3::NEG_INFINITY, a),
            hi: DVec3::select(b.cmpge(self.hi), DVec3::INFINITY, b),
        };
        let mut from: Vec<(usize, Vec<usize>)> = Vec::new();
        let mut input = Vec::new();
        for (u, other) in self.tiles.iter().enumerate() {
            if other.hi.cmplt(a).any() || other.lo.cmpgt(b).any() {
                continue;
            }
            let points = load(&self.file(0, u, Kind::Points))?;
            let at: Vec<usize> = (0..points.len())
                .filter(|&i| region.contains(points[i]))
                .collect();
            input.extend(at.iter().map(|&i| points[i]));
            from.push((u, at));
        }
        let owned: Vec<bool> = from
            .iter()
            .flat_map(|(u, at)| std::iter::repeat_n(*u == t, at.len()))
            .collect();
        let mut gathered = RobustTile::gathered(input, &owned, region)?;
        let of = |g: usize, kind: Kind| -> Result<Vec<DVec3>> {
            let mut v = Vec::with_capacity(owned.len());
            for (u, at) in &from {
                let all = load(&self.file(g, *u, kind))?;
                v.extend(at.iter().map(|&i| all[i]));
            }
            Ok(v)
        };
        let (g, rows, finish) = match *round {
            Round::Start => (0, RowSet::Plain, false),
            Round::Ratio { generation } => (generation, RowSet::Wide, false),
            Round::Measure { generation, rows }
            | Round::Step {
                generation, rows, ..
            } => (generation, rows, false),
            Round::Finish {
                generation, rows, ..
            } => (generation, rows, true),
            Round::Done => (0, RowSet::Plain, false),
        };
        if g > 0 {
            gathered.set_current(g, &of(g, Kind::Points)?)?;
        }
        if let RowSet::Shrunk { at } = rows {
            if at != g {
                gathered.set_shrink(at, &of(at, Kind::Points)?)?;
            }
        }
        if finish && g > 0 {
            gathered.set_normals(&of(g, Kind::Normals)?)?;
        }
        Ok(gathered)
    }

    /// Runs `f` on tile `t` gathered for `round`, gathering it again with twice the halo until
    /// every owned value is the cloud's (`f` says whether they are); returns what `f` gave and
    /// the tile.
    fn each<R>(
        &mut self,
        t: usize,
        round: &Round,
        mut f: impl FnMut(&mut RobustTile<'static>) -> nbhd::Result<(R, bool)>,
    ) -> Result<(R, RobustTile<'static>)> {
        loop {
            let mut tile = self.gather(t, round)?;
            let (r, valid) = f(&mut tile)?;
            if valid {
                return Ok((r, tile));
            }
            self.tiles[t].halo *= 2.0;
        }
    }

    /// Deletes generation `g`'s files.
    fn drop_generation(&self, g: usize) {
        for t in 0..self.tiles.len() {
            for kind in [Kind::Points, Kind::Normals] {
                let _ = fs::remove_file(self.file(g, t, kind));
            }
        }
    }
}

/// Whether every flag is set (the library's empty list means all).
fn all(valid: &[bool]) -> bool {
    valid.iter().all(|&v| v)
}

/// The round's name on the progress line.
fn round_name(round: &Round) -> &'static str {
    match round {
        Round::Start => "start",
        Round::Ratio { .. } => "noise scale",
        Round::Measure { .. } => "planes",
        Round::Step { .. } => "step",
        Round::Finish { .. } => "finish",
        Round::Done => "done",
    }
}

/// The spacing h: each tile's owned points' nearest squared distances, in the cloud's order.
fn spacing(survey: &mut Survey, options: &RobustOptions) -> Result<f64> {
    let mut nearest = Vec::new();
    for t in 0..survey.tiles.len() {
        let (near, _) = survey.each(t, &Round::Start, |tile| {
            let (near, valid) = tile.nearest(options)?;
            Ok((near, all(&valid)))
        })?;
        nearest.extend(near);
    }
    Ok(RobustRun::spacing_of_nearest(nearest))
}

/// The rounds of the run up to the finish, each over every tile; a step's positions and
/// normals go to the scratch directory. Returns the run, at its finish.
fn rounds(
    survey: &mut Survey,
    options: &RobustOptions,
    h: f64,
    bar: &Progress,
) -> Result<RobustRun> {
    let mut run = RobustRun::new(options, h, Neighbors::default())?;
    let eps = run.epsilon();
    let tiles = survey.tiles.len();
    let mut iteration = 1;
    loop {
        let round = run.round();
        if matches!(round, Round::Finish { .. } | Round::Done) {
            return Ok(run);
        }
        bar.message(format!("iteration {iteration}: {}", round_name(&round)));
        bar.set(0);
        let mut parts = Vec::with_capacity(tiles);
        for t in 0..tiles {
            let (part, tile) = survey.each(t, &round, |tile| {
                let part = tile.round(&round, options, eps)?;
                let valid = part.all_valid();
                Ok((part, valid))
            })?;
            if let Round::Step { generation, .. } = round {
                let g = generation + 1;
                save(&survey.file(g, t, Kind::Points), &tile.owned_points())?;
                save(&survey.file(g, t, Kind::Normals), &tile.owned_normals())?;
            }
            parts.push(part);
            bar.inc(1);
        }
        run.feed(&reduce(&round, &mut parts)?)?;
        if let Round::Step { generation, .. } = round {
            iteration += 1;
            let keep = matches!(run.round(), Round::Step { rows: RowSet::Shrunk { at }, .. }
                | Round::Measure { rows: RowSet::Shrunk { at }, .. }
                | Round::Finish { rows: RowSet::Shrunk { at }, .. } if at == generation);
            if generation > 0 && !keep {
                survey.drop_generation(generation);
            }
        }
    }
}

/// The finish, tile by tile: each input file read again, its finite points smoothed, the
/// normals and curvatures added, and written under its name in `a.out`. Returns the points
/// written.
fn finish(
    survey: &mut Survey,
    run: &RobustRun,
    options: &RobustOptions,
    a: &Args,
    bar: &Progress,
) -> Result<usize> {
    let round = run.round();
    let eps = run.epsilon();
    let mut written = 0;
    bar.message("writing the tiles");
    bar.set(0);
    for t in 0..survey.tiles.len() {
        let (points, outputs) = loop {
            let tile = survey.gather(t, &round)?;
            let (points, _, outputs, valid) = tile.finish(&round, options, eps)?;
            if all(&valid) {
                break (points, outputs);
            }
            survey.tiles[t].halo *= 2.0;
        };
        let path = &survey.tiles[t].path;
        let mut cloud = crate::read::cloud(path, None)?;
        let (_, index) = finite_points(&cloud);
        for (&i, p) in index.iter().zip(&points) {
            cloud.positions[i] = p.to_array();
        }
        write::add_fields(&mut cloud, &index, &outputs, true)?;
        write::cloud(&output_path(a, path), &cloud, &a.precision.write_options())?;
        written += cloud.len();
        bar.inc(1);
    }
    Ok(written)
}

/// Where the result of the input `path` goes: its name in `a.out`, with `a.ext` if given.
fn output_path(a: &Args, path: &Path) -> PathBuf {
    let name = path.file_name().map(PathBuf::from).unwrap_or_default();
    let name = match &a.ext {
        Some(ext) => name.with_extension(ext.trim_start_matches('.')),
        None => name,
    };
    a.out.join(name)
}

/// The whole run with its scratch files in `scratch`: the run at its finish, the finite points
/// and the points written.
fn smooth_survey(a: &Args, scratch: PathBuf, out: &Output) -> Result<(RobustRun, usize, usize)> {
    let options = RobustOptions {
        orientation: Orientation::Unoriented,
        ..a.robust.options(a.k, a.radius, a.tau)
    };
    let bar = Progress::bar(out, a.inputs.len() as u64, "reading the tiles");
    let mut survey = Survey::ingest(&a.inputs, scratch, &bar)?;
    let points: usize = survey.tiles.iter().map(|t| t.count).sum();
    if points == 0 {
        return Err("no point with finite coordinates in the tiles".into());
    }
    survey.first_halos(options.k_plane);
    bar.message("nearest: the spacing h");
    let h = spacing(&mut survey, &options)?;
    let run = rounds(&mut survey, &options, h, &bar)?;
    let written = finish(&mut survey, &run, &options, a, &bar)?;
    Ok((run, points, written))
}

pub fn run(a: Args, out: &Output) -> Result<()> {
    let mut names: Vec<PathBuf> = a.inputs.iter().map(|p| output_path(&a, p)).collect();
    names.sort();
    if let Some(w) = names.windows(2).find(|w| w[0] == w[1]) {
        return Err(format!("two inputs would be written to {}", w[0].display()).into());
    }
    fs::create_dir_all(&a.out).context(a.out.display())?;
    let scratch = a
        .scratch
        .as_ref()
        .unwrap_or(&a.out)
        .join(format!(".nbhd-tiles-{}", std::process::id()));
    let started = std::time::Instant::now();
    let done = smooth_survey(&a, scratch.clone(), out);
    let _ = fs::remove_dir_all(&scratch);
    let (run, points, written) = done?;
    let rep = run.report();
    let secs = started.elapsed().as_secs_f64();
    out.json(&json!({
        "inputs": a.inputs.len(),
        "output": a.out.display().to_string(),
        "points": written,
        "skipped_non_finite": written - points,
        "spacing_h": num(rep.result.spacing),
        "radius": num(rep.result.epsilon),
        "iterations": rep.moved.len(),
        "noise_h": rep.noise.iter().map(|&v| num(v)).collect::<Vec<_>>(),
        "moved_h": rep.moved.iter().map(|&v| num(v)).collect::<Vec<_>>(),
        "wide_iterations": rep.wide_iterations,
        "seconds": num(secs),
    }));
    let noise: Vec<String> = rep.noise.iter().map(|v| format!("{v:.3}h")).collect();
    out.text(format!(
        "{} tiles -> {}: {written} points ({} skipped as non-finite) smoothed, method robust: \
         {} iterations, noise estimate σ̂ before each: {}; h = {:.6}; {secs:.2} s",
        a.inputs.len(),
        a.out.display(),
        written - points,
        rep.moved.len(),
        noise.join(", "),
        rep.result.spacing,
    ));
    Ok(())
}
