//! The iteration driver of the robust smoothing: every decision of a run that depends on the
//! whole cloud, and nothing that depends on one point.
//!
//! A run is a sequence of [`Round`]s. In each round every tile (`robust/tile.rs`: one tile that
//! owns every point on one machine, or many tiles of a split cloud) computes per-point values
//! over the points it owns; those values are reduced over all tiles to the few scalars of
//! [`Reduced`] (two exact medians, an exact sum, a maximum and a minimum), and the run takes
//! them ([`RobustRun::feed`]) to choose the next round. The run holds no point: it is a few
//! scalars and the per-iteration history of the report, so a driver on another machine (a Dask
//! client, the C ABI) can hold it while the tiles work elsewhere.
//!
//! The decisions, items 0, 2 and 5 of the parent module:
//! - the noise scale (`robust/scales.rs`): from the median distance ratio before the first
//!   iteration (the rows widen when it reads as a ball of noise) and, while the rows are wide,
//!   before each later one (they shrink back to `k_plane` once it reads as a surface);
//! - σ̂ = 1.4826 × the median distance of a point to its covariance plane (eq. 2.8–2.10; the
//!   median absolute deviation of a normal distribution), measured before each step;
//! - the stopping rule ([`stop_tolerance`]) and the end of a run whose step moved no point;
//! - the threshold λ of the outputs, `2·inlier_width·σ̂₀/h²` (eq. 2.20 over one spacing).
//!
//! Both medians are exact selections (the element of rank ⌊n/2⌋ in `f64::total_cmp` order), so
//! they are the same bits whether they are taken over one slice ([`median`]) or over parts that
//! are never gathered (`select::radix::select_in_parts`); the squared displacements are added
//! in an [`ExactSum`], whose value does not depend on the order or the split either.

use super::scales;
use super::{RobustOptions, RobustReport};
use crate::error::{NbhdError, Result};
use crate::geometry::neighbors::mean_spacing_of_nearest;
use crate::geometry::Neighbors;
use crate::index::{check_spacing, Length};
use crate::sum::ExactSum;

/// The median absolute deviation of a normal distribution, in units of its standard deviation:
/// σ̂ = `MAD_TO_SIGMA` × the median plane distance.
const MAD_TO_SIGMA: f64 = 1.4826;

/// Which neighbour rows a round reads (`robust/rows.rs`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RowSet {
    /// The `k_plane` nearest other points of each input point.
    Plain,
    /// The `WIDE`·`k_plane` nearest (the noise scale read a ball of noise).
    Wide,
    /// The wide rows cut back to their first `k_plane` as sorted on the proxy of generation
    /// `at` (the noise scale read a surface there).
    Shrunk {
        /// The generation whose proxy chose the `k_plane` kept.
        at: usize,
    },
}

/// What the tiles compute next. A *generation* g is the proxy after g steps (0: the input).
/// Every round reads the rows of its [`RowSet`] measured on the proxy of its generation and cut
/// at ε (the rows' candidates are found once on the input; see the parent module).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Round {
    /// On the input, with the plain rows: each owned point's row length (the longest and the
    /// shortest are reduced) and, with the noise scale, its distance ratio `d₄ₘ/dₘ`.
    Start,
    /// The distance ratios on generation `generation` with the wide rows (an iteration after
    /// the first while the rows are wide).
    Ratio {
        /// The proxy measured.
        generation: usize,
    },
    /// The covariance planes on generation `generation` and each owned point's distance to
    /// its own (σ̂'s median).
    Measure {
        /// The proxy measured.
        generation: usize,
        /// The rows the planes are fitted to.
        rows: RowSet,
    },
    /// The selected normals and one step of generation `generation` into the next, with the
    /// inlier width `inlier_width`·`sigma` and umbrella neighbourhoods of `k`; each owned
    /// point's squared displacement is added up.
    Step {
        /// The proxy that steps.
        generation: usize,
        /// The rows of the planes, normals and step.
        rows: RowSet,
        /// σ̂ of this generation, absolute.
        sigma: f64,
        /// Size of the umbrella neighbourhood.
        k: usize,
    },
    /// The result on the last generation: the points, the normals of the last step (or the
    /// covariance normals if none was taken) and, if asked for, the per-point outputs with the
    /// threshold `lambda`.
    Finish {
        /// The last proxy.
        generation: usize,
        /// The rows of the outputs' neighbourhoods (their first `k`).
        rows: RowSet,
        /// The threshold of the outputs (see [`RobustReport::result`]).
        lambda: f64,
    },
    /// The run is over: [`RobustRun::report`].
    Done,
}

/// What the tiles' values of one round reduce to (each field is read only by the rounds named).
#[derive(Clone, Debug, Default)]
pub struct Reduced {
    /// Points of the whole cloud (every round).
    pub count: u64,
    /// The longest row within ε over all points ([`Round::Start`]).
    pub max_len: usize,
    /// The shortest row within ε, at most `k` ([`Round::Start`]).
    pub min_narrow: usize,
    /// The median distance ratio, `None` when no point has one ([`Round::Start`] with the
    /// noise scale, [`Round::Ratio`]).
    pub ratio: Option<f64>,
    /// The median plane distance ([`Round::Measure`]).
    pub residual: Option<f64>,
    /// The sum of the squared displacements ([`Round::Step`]).
    pub moved_sq: ExactSum,
}

impl Reduced {
    /// Sets the median `value` of the values the tiles gave for `round`: the distance ratios'
    /// ([`Round::Start`], [`Round::Ratio`]) or the plane distances' ([`Round::Measure`]); other
    /// rounds have none.
    pub fn set_median(&mut self, round: &Round, value: Option<f64>) {
        match round {
            Round::Start | Round::Ratio { .. } => self.ratio = value,
            Round::Measure { .. } => self.residual = value,
            _ => {}
        }
    }
}

/// Where a run is.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Phase {
    Start,
    Ratio,
    Measure,
    Step { sigma: f64 },
    Finish,
    Done,
}

/// The state of one robust run between rounds (see the module documentation).
#[derive(Clone, Debug)]
pub struct RobustRun {
    options: RobustOptions,
    /// The mean spacing h and ε resolved with it.
    h: f64,
    eps: f64,
    /// Whether the rows may widen (not for a caller's table).
    can_widen: bool,
    wide: bool,
    started_wide: bool,
    shrunk_at: Option<usize>,
    /// σ̂ of the last iteration that stepped (∞ before the first and after a shrink).
    prev_sigma: f64,
    /// The generation the next round reads: the number of steps taken.
    generation: usize,
    count: u64,
    min_neighbors: usize,
    /// σ̂ of each iteration's input, absolute.
    noise: Vec<f64>,
    /// RMS displacement of each iteration, absolute.
    moved: Vec<f64>,
    dimension: Vec<f64>,
    wide_iterations: usize,
    phase: Phase,
}

impl RobustRun {
    /// A run with `options` on a cloud of mean spacing `spacing` (the mean distance of each
    /// point to its nearest other, in the caller's order); `neighbors` as the call gives them (a
    /// caller's table is measured, never widened).
    ///
    /// # Errors
    ///
    /// The options' [`NbhdError::InvalidOption`], and the same when ε is relative and the
    /// spacing is not positive.
    pub fn new(options: &RobustOptions, spacing: f64, neighbors: Neighbors<'_>) -> Result<Self> {
        options.validate()?;
        check_spacing(spacing, matches!(options.epsilon, Length::Relative(_)))?;
        Ok(Self {
            options: *options,
            h: spacing,
            eps: options.epsilon.resolve(spacing),
            can_widen: !matches!(neighbors, Neighbors::Table(_)),
            wide: false,
            started_wide: false,
            shrunk_at: None,
            prev_sigma: f64::INFINITY,
            generation: 0,
            count: 0,
            min_neighbors: 0,
            noise: Vec::new(),
            moved: Vec::new(),
            dimension: Vec::new(),
            wide_iterations: 0,
            phase: Phase::Start,
        })
    }

    /// The mean spacing h of a cloud from each point's squared distance to its nearest other
    /// point (`None` without one) in the cloud's order ([`RobustTile::nearest`] of every tile,
    /// put in order): the mean of their square roots, summed in that order.
    ///
    /// [`RobustTile::nearest`]: super::RobustTile::nearest
    pub fn spacing_of_nearest(nearest_sq: impl IntoIterator<Item = Option<f64>>) -> f64 {
        mean_spacing_of_nearest(nearest_sq.into_iter())
    }

    /// ε in the points' units.
    pub fn epsilon(&self) -> f64 {
        self.eps
    }

    /// The rows the run reads now.
    fn rows(&self) -> RowSet {
        match (self.wide, self.shrunk_at) {
            (true, _) => RowSet::Wide,
            (false, Some(at)) => RowSet::Shrunk { at },
            (false, None) => RowSet::Plain,
        }
    }

    /// The round the tiles compute next.
    pub fn round(&self) -> Round {
        let (generation, rows) = (self.generation, self.rows());
        match self.phase {
            Phase::Start => Round::Start,
            Phase::Ratio => Round::Ratio { generation },
            Phase::Measure => Round::Measure { generation, rows },
            Phase::Step { sigma } => Round::Step {
                generation,
                rows,
                sigma,
                k: self.options.k * if self.wide { scales::WIDE } else { 1 },
            },
            Phase::Finish => Round::Finish {
                generation,
                rows,
                lambda: self.lambda(),
            },
            Phase::Done => Round::Done,
        }
    }

    /// Takes the reduced values of the round [`RobustRun::round`] gave.
    ///
    /// # Errors
    ///
    /// [`NbhdError::Degenerate`] after [`Round::Start`] when no row reaches 3 points (with the
    /// point itself), the same refusal as every smoothing call; [`NbhdError::InvalidOption`]
    /// when a median is missing where the round needs one, or the run is done.
    pub fn feed(&mut self, reduced: &Reduced) -> Result<()> {
        match self.phase {
            Phase::Start => self.feed_start(reduced)?,
            Phase::Ratio => {
                // the noise scale again, on the proxy: back to the usual rows once it reads as
                // a surface (σ̂ is then measured on other rows: no comparison with the last one)
                self.dimension.extend(reduced.ratio.map(scales::dimension));
                if !scales::is_ball(reduced.ratio, true) {
                    self.wide = false;
                    self.shrunk_at = Some(self.generation);
                    self.prev_sigma = f64::INFINITY;
                }
                self.phase = Phase::Measure;
            }
            Phase::Measure => {
                let residual = reduced.residual.ok_or_else(|| missing("plane distances"))?;
                self.feed_sigma(MAD_TO_SIGMA * residual);
            }
            Phase::Step { .. } => {
                let rms = (reduced.moved_sq.value() / self.count as f64).sqrt();
                self.moved.push(rms);
                self.generation += 1;
                self.phase = if rms == 0.0 {
                    Phase::Finish
                } else {
                    self.iteration_phase()
                };
            }
            Phase::Finish => self.phase = Phase::Done,
            Phase::Done => return Err(missing("a round after the run's end")),
        }
        Ok(())
    }

    /// [`RobustRun::feed`] after [`Round::Start`]: the refusal of degenerate rows, the
    /// smallest neighbourhood, and the noise scale's first reading.
    fn feed_start(&mut self, reduced: &Reduced) -> Result<()> {
        self.count = reduced.count;
        if reduced.max_len + 1 < 3 {
            return Err(NbhdError::Degenerate {
                points: reduced.count as usize,
                largest: reduced.max_len + 1,
                flagged: 0,
                epsilon: self.eps,
                spacing: self.h,
                relative: matches!(self.options.epsilon, Length::Relative(_)),
            });
        }
        self.min_neighbors = reduced.min_narrow;
        if self.options.noise_scale {
            self.dimension.extend(reduced.ratio.map(scales::dimension));
            // a caller's table has the rows it has: measured, never widened
            self.wide = scales::is_ball(reduced.ratio, false) && self.can_widen;
        }
        self.started_wide = self.wide;
        self.phase = self.iteration_phase();
        Ok(())
    }

    /// The first phase of the iteration at the current generation (or the end).
    fn iteration_phase(&self) -> Phase {
        if self.generation >= self.options.max_iterations {
            Phase::Finish
        } else if self.wide && self.generation > 0 {
            Phase::Ratio
        } else {
            Phase::Measure
        }
    }

    /// Item 5 of the parent module: σ̂ of this generation's input, then the step or the end.
    fn feed_sigma(&mut self, sigma: f64) {
        self.noise.push(sigma);
        // while the rows are balls of noise σ̂ measures the ball: the noise scale ends them
        if self.generation > 0
            && !self.wide
            && sigma
                > (1.0 - stop_tolerance(sigma, &self.noise, self.started_wide, &self.options))
                    * self.prev_sigma
        {
            self.phase = Phase::Finish;
            return;
        }
        self.wide_iterations += usize::from(self.wide);
        self.prev_sigma = sigma;
        self.phase = Phase::Step { sigma };
    }

    /// h, or 1 where there is no spacing (absolute units).
    fn unit(&self) -> f64 {
        if self.h > 0.0 {
            self.h
        } else {
            1.0
        }
    }

    /// The threshold λ of the outputs: `2·inlier_width·σ̂₀/h²` (eq. 2.20 over one spacing).
    fn lambda(&self) -> f64 {
        let hu = self.unit();
        let sigma0 = self.noise.first().copied().unwrap_or(0.0);
        2.0 * self.options.inlier_width * sigma0 / (hu * hu)
    }

    /// The report of the run so far, with `result.points` and `result.outputs` empty and no
    /// normals (the tiles hold them).
    pub fn report(&self) -> RobustReport {
        let hu = self.unit();
        RobustReport {
            result: super::super::SmoothResult {
                points: Vec::new(),
                outputs: Vec::new(),
                spacing: self.h,
                epsilon: self.eps,
                lambda: self.lambda(),
                min_neighbors: self.min_neighbors,
            },
            normals: Vec::new(),
            noise: self.noise.iter().map(|v| v / hu).collect(),
            moved: self.moved.iter().map(|v| v / hu).collect(),
            dimension: self.dimension.clone(),
            wide_iterations: self.wide_iterations,
        }
    }
}

fn missing(what: &str) -> NbhdError {
    NbhdError::InvalidOption {
        name: "robust run",
        reason: format!("{what} missing or out of turn"),
    }
}

/// The rank of the run's medians among `count` values, ⌊count/2⌋ (0-based, in `total_cmp`
/// order): the rank a driver that selects across parts asks for.
pub fn median_rank(count: u64) -> u64 {
    count / 2
}

/// The value of rank ⌊n/2⌋ of `values` in `f64::total_cmp` order (`None` when empty): the
/// medians of the run taken over one slice, the same bits as `select::radix::select_in_parts`
/// over any split of the values.
pub fn median(values: &mut [f64]) -> Option<f64> {
    if values.is_empty() {
        return None;
    }
    let m = median_rank(values.len() as u64) as usize;
    values.select_nth_unstable_by(m, f64::total_cmp);
    Some(values[m])
}

/// Fraction of the first noise estimate above which what is left is mostly the surface's own
/// shape (see [`stop_tolerance`]).
const SHAPE_SPREAD: f64 = 0.4;

/// The stopping rule's tolerance where what is left is mostly shape.
const SHAPE_TOLERANCE: f64 = 0.25;

/// The first iteration the shape rule may refuse (the third; the second is judged by
/// `options.tolerance` alone). The fall of σ̂ over the first iteration cannot tell shape from
/// noise left: σ̂₀ itself holds the curvature the plane fit reads as noise. Measured: on a
/// torus of 4,000 points (tube radius about 13h) at 1h of noise σ̂ falls 0.82h → 0.64h
/// (0.78), and the second iteration takes the RMS distance to the surface from 0.31h to
/// 0.23h; on the protocol's meshes at 10K and 1 % only the turbine's thin blades lose by it
/// (CD 3.54 → 4.88 ×10⁻⁴), every other cell of the protocol is the same bits
/// (docs/smoothing-results.md).
const SHAPE_FROM: usize = 2;

/// The tolerance of the stopping rule (item 5 of the parent module) for an iteration whose
/// input has the noise estimate `sigma` (the last of `noise`, the estimates so far):
/// `options.tolerance`, unless more than [`SHAPE_SPREAD`] of the first estimate is left on a
/// cloud that did not start as a ball of noise, from iteration [`SHAPE_FROM`] on. There the
/// spread about the planes is mostly the surface's own shape (curvature and detail finer than
/// the neighbourhoods, which the plane fit reads as noise): smoothing it further erodes the
/// detail, so the iterations go on only while each still lowers σ̂ by [`SHAPE_TOLERANCE`].
/// Measured on the meshes of the denoising protocol at 10K points and 1 % noise
/// (docs/smoothing-results.md): σ̂ falls to 0.5–0.7 of the first estimate on detailed shapes
/// (the dragon, the armadillo) and the iterations after the first erode them; on the cube's
/// faces it falls below 0.3 after one iteration, and further iterations keep lowering the
/// noise.
fn stop_tolerance(sigma: f64, noise: &[f64], started_wide: bool, options: &RobustOptions) -> f64 {
    let first = noise.first().copied().unwrap_or(sigma);
    // `noise` holds the estimate of this iteration's input: iteration i has i + 1
    let shape = !started_wide && noise.len() > SHAPE_FROM && sigma > SHAPE_SPREAD * first;
    if options.tolerance > 0.0 && shape {
        options.tolerance.max(SHAPE_TOLERANCE)
    } else {
        options.tolerance
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::table::NeighborTable;

    /// The reduced values of a round: `residual` a median plane distance, `ratio` a median
    /// distance ratio, `moved` the squared displacements.
    fn reduced(count: u64, residual: f64, ratio: f64, moved: &[f64]) -> Reduced {
        Reduced {
            count,
            max_len: 48,
            min_narrow: 24,
            ratio: Some(ratio),
            residual: Some(residual),
            moved_sq: moved.iter().copied().collect(),
        }
    }

    /// The distance ratio of the local dimension `d`: `4^(1/d)`.
    fn ratio_of(d: f64) -> f64 {
        4f64.powf(1.0 / d)
    }

    #[test]
    fn a_surface_steps_until_sigma_stops_falling() {
        let mut run = RobustRun::new(&RobustOptions::default(), 1.0, Neighbors::default()).unwrap();
        assert_eq!(run.round(), Round::Start);
        run.feed(&reduced(4, 0.0, ratio_of(2.0), &[])).unwrap();
        let rows = RowSet::Plain;
        assert_eq!(
            run.round(),
            Round::Measure {
                generation: 0,
                rows
            }
        );
        run.feed(&reduced(4, 1.0, 0.0, &[])).unwrap();
        let sigma = MAD_TO_SIGMA;
        assert_eq!(
            run.round(),
            Round::Step {
                generation: 0,
                rows,
                sigma,
                k: 24
            }
        );
        run.feed(&reduced(4, 0.0, 0.0, &[1.0, 1.0, 1.0, 1.0]))
            .unwrap();
        assert_eq!(
            run.round(),
            Round::Measure {
                generation: 1,
                rows
            }
        );
        // σ̂ fell by half: the next step
        run.feed(&reduced(4, 0.5, 0.0, &[])).unwrap();
        assert!(matches!(run.round(), Round::Step { generation: 1, .. }));
        run.feed(&reduced(4, 0.0, 0.0, &[0.25; 4])).unwrap();
        // σ̂ fell by 4 % < 5 %: the run ends before the step, on generation 2
        run.feed(&reduced(4, 0.48, 0.0, &[])).unwrap();
        let Round::Finish {
            generation, lambda, ..
        } = run.round()
        else {
            panic!("{:?}", run.round());
        };
        assert_eq!(generation, 2);
        assert_eq!(lambda, 2.0 * 5.0 * MAD_TO_SIGMA);
        run.feed(&Reduced::default()).unwrap();
        assert_eq!(run.round(), Round::Done);
        assert!(run.feed(&Reduced::default()).is_err());
        let r = run.report();
        assert_eq!(r.noise, [1.0, 0.5, 0.48].map(|m| m * MAD_TO_SIGMA));
        assert_eq!(r.moved, [1.0, 0.5]);
        assert_eq!((r.dimension.len(), r.wide_iterations), (1, 0));
        assert_eq!(r.result.min_neighbors, 24);
    }

    #[test]
    fn the_shape_rule_and_a_step_that_moves_nothing_end_the_run() {
        let options = RobustOptions::default();
        let mut run = RobustRun::new(&options, 1.0, Neighbors::default()).unwrap();
        run.feed(&reduced(2, 0.0, ratio_of(2.0), &[])).unwrap();
        // σ̂ 1 → 0.8 → 0.62 (−22.5 % at iteration 2, more than 0.4 of the first left): the
        // shape rule asks for 25 % from iteration 2 on
        for (residual, moved) in [(1.0, 1.0), (0.8, 1.0)] {
            run.feed(&reduced(2, residual, 0.0, &[])).unwrap();
            run.feed(&reduced(2, 0.0, 0.0, &[moved])).unwrap();
        }
        run.feed(&reduced(2, 0.62, 0.0, &[])).unwrap();
        assert!(matches!(run.round(), Round::Finish { generation: 2, .. }));
        // a step that moved no point ends the run before measuring again
        let mut run = RobustRun::new(&options, 1.0, Neighbors::default()).unwrap();
        run.feed(&reduced(2, 0.0, ratio_of(2.0), &[])).unwrap();
        run.feed(&reduced(2, 1.0, 0.0, &[])).unwrap();
        run.feed(&reduced(2, 0.0, 0.0, &[0.0, 0.0])).unwrap();
        assert!(matches!(run.round(), Round::Finish { generation: 1, .. }));
        assert_eq!(run.report().moved, [0.0]);
    }

    #[test]
    fn a_ball_of_noise_widens_then_shrinks_on_the_proxy() {
        let options = RobustOptions::default();
        let mut run = RobustRun::new(&options, 2.0, Neighbors::default()).unwrap();
        run.feed(&reduced(3, 0.0, ratio_of(2.9), &[])).unwrap();
        let wide = RowSet::Wide;
        assert_eq!(
            run.round(),
            Round::Measure {
                generation: 0,
                rows: wide
            }
        );
        run.feed(&reduced(3, 1.0, 0.0, &[])).unwrap();
        assert!(matches!(
            run.round(),
            Round::Step {
                k: 72,
                rows: RowSet::Wide,
                ..
            }
        ));
        run.feed(&reduced(3, 0.0, 0.0, &[4.0; 3])).unwrap();
        // still a ball (above KEEP_DIMENSION): wide again, σ̂ rising is no reason to stop
        assert_eq!(run.round(), Round::Ratio { generation: 1 });
        run.feed(&reduced(3, 0.0, ratio_of(2.6), &[])).unwrap();
        run.feed(&reduced(3, 2.0, 0.0, &[])).unwrap();
        run.feed(&reduced(3, 0.0, 0.0, &[4.0; 3])).unwrap();
        // a surface now: shrunk on generation 2, and σ̂ is not compared with the wide ones
        run.feed(&reduced(3, 0.0, ratio_of(2.3), &[])).unwrap();
        let rows = RowSet::Shrunk { at: 2 };
        assert_eq!(
            run.round(),
            Round::Measure {
                generation: 2,
                rows
            }
        );
        run.feed(&reduced(3, 5.0, 0.0, &[])).unwrap();
        assert!(matches!(
            run.round(),
            Round::Step {
                k: 24,
                generation: 2,
                ..
            }
        ));
        let r = run.report();
        assert_eq!((r.wide_iterations, r.dimension.len()), (2, 3));
        assert_eq!(r.moved, [1.0, 1.0]); // √(12/3) = 2 = h
                                         // a caller's table is measured, never widened
        let table = NeighborTable::default();
        let mut run = RobustRun::new(&options, 1.0, Neighbors::Table(&table)).unwrap();
        run.feed(&reduced(3, 0.0, ratio_of(2.9), &[])).unwrap();
        assert_eq!(
            run.round(),
            Round::Measure {
                generation: 0,
                rows: RowSet::Plain
            }
        );
    }

    #[test]
    fn rows_of_fewer_than_three_points_are_refused() {
        let mut run = RobustRun::new(&RobustOptions::default(), 1.0, Neighbors::default()).unwrap();
        let r = Reduced {
            max_len: 1,
            count: 5,
            ..Reduced::default()
        };
        assert!(matches!(
            run.feed(&r),
            Err(NbhdError::Degenerate {
                points: 5,
                largest: 2,
                ..
            })
        ));
        assert!(RobustRun::new(&RobustOptions::default(), 0.0, Neighbors::default()).is_err());
    }
}
