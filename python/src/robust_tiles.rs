//! The robust smoothing's step API (`nbhd::smooth::robust`: `RobustRun`, `RobustTile`) and the
//! exact reductions it needs across tiles (`nbhd::select::radix::RankSearch`,
//! `nbhd::sum::ExactSum`), for a driver that runs the tiles elsewhere (`nbhd.dask`). Every
//! decision is the library's: this module converts rounds to dicts and back, arrays to points,
//! and the states to bytes for pickling.

use glam::DVec3;
use nbhd::smooth::robust::{
    median_rank, DigitCounts, RankSearch, RankStep, Reduced, Region, RobustRun, RobustTile, Round,
    RowSet, TilePart,
};
use nbhd::smooth::{Neighbors, RobustOptions};
use nbhd::sum::ExactSum;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict, PyTuple};

use crate::arrays::{bools, dvec3_array, dvec3s, vec1, vector_of};
use crate::errors::{value_err, OrRaise};
use crate::geometry::outputs_dict;
use crate::robust_options::PyRobustOptions;

/// A round as the dict a driver sends to its tiles: `kind` (`start`, `ratio`, `measure`,
/// `step`, `finish`, `done`), the `generation` it reads, its `rows` (`plain`, `wide`,
/// `shrunk` with `shrunk_at`), `sigma` and `k` of a step, `lambda` of the finish, and the run's
/// `epsilon` (absolute).
fn round_dict<'py>(py: Python<'py>, round: &Round, eps: f64) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    let (kind, generation, rows) = match *round {
        Round::Start => ("start", Some(0), Some(RowSet::Plain)),
        Round::Ratio { generation } => ("ratio", Some(generation), Some(RowSet::Wide)),
        Round::Measure { generation, rows } => ("measure", Some(generation), Some(rows)),
        Round::Step {
            generation,
            rows,
            sigma,
            k,
        } => {
            d.set_item("sigma", sigma)?;
            d.set_item("k", k)?;
            ("step", Some(generation), Some(rows))
        }
        Round::Finish {
            generation,
            rows,
            lambda,
        } => {
            d.set_item("lambda", lambda)?;
            ("finish", Some(generation), Some(rows))
        }
        Round::Done => ("done", None, None),
    };
    d.set_item("kind", kind)?;
    d.set_item("generation", generation)?;
    let (name, at) = match rows {
        None => (None, None),
        Some(RowSet::Plain) => (Some("plain"), None),
        Some(RowSet::Wide) => (Some("wide"), None),
        Some(RowSet::Shrunk { at }) => (Some("shrunk"), Some(at)),
    };
    d.set_item("rows", name)?;
    d.set_item("shrunk_at", at)?;
    d.set_item("epsilon", eps)?;
    Ok(d)
}

/// The round of [`round_dict`] and its ε.
fn round_of(d: &Bound<'_, PyDict>) -> PyResult<(Round, f64)> {
    fn get<'py, T: FromPyObjectOwned<'py>>(d: &Bound<'py, PyDict>, key: &str) -> PyResult<T> {
        d.get_item(key)?
            .ok_or_else(|| value_err(format!("a round needs {key:?}")))?
            .extract()
            .map_err(|e| value_err(format!("round {key:?}: {}", Into::<PyErr>::into(e))))
    }
    let kind: String = get(d, "kind")?;
    let eps: f64 = get(d, "epsilon")?;
    if kind == "done" {
        return Ok((Round::Done, eps));
    }
    let generation: usize = get(d, "generation")?;
    let rows = match get::<String>(d, "rows")?.as_str() {
        "plain" => RowSet::Plain,
        "wide" => RowSet::Wide,
        "shrunk" => RowSet::Shrunk {
            at: get(d, "shrunk_at")?,
        },
        other => return Err(value_err(format!("unknown rows {other:?}"))),
    };
    let round = match kind.as_str() {
        "start" => Round::Start,
        "ratio" => Round::Ratio { generation },
        "measure" => Round::Measure { generation, rows },
        "step" => Round::Step {
            generation,
            rows,
            sigma: get(d, "sigma")?,
            k: get(d, "k")?,
        },
        "finish" => Round::Finish {
            generation,
            rows,
            lambda: get(d, "lambda")?,
        },
        other => return Err(value_err(format!("unknown round kind {other:?}"))),
    };
    Ok((round, eps))
}

/// The f64 values of a 1-D array (any real type), copied.
fn values_of(values: &Bound<'_, PyAny>) -> PyResult<Vec<f64>> {
    vector_of(values, "float64", "values must be a 1-D array of numbers")
}

/// The state of one robust run between rounds, held by the driver (see
/// `nbhd::smooth::robust::RobustRun`): `round()` names what the tiles compute next, `feed()`
/// takes what their parts reduce to, `report()` gives the run's figures.
#[pyclass(module = "nbhd._nbhd", name = "RobustRun")]
pub struct PyRobustRun {
    run: RobustRun,
}

#[pymethods]
impl PyRobustRun {
    /// A run on a cloud of mean spacing `spacing` (the mean distance of each point to its
    /// nearest other, as `smooth_robust` computes it), with the options of `smooth_robust`.
    #[new]
    fn new(spacing: f64, options: PyRef<'_, PyRobustOptions>) -> PyResult<Self> {
        let run = RobustRun::new(&options.options, spacing, Neighbors::default()).or_raise()?;
        Ok(Self { run })
    }

    /// ε in the points' units.
    #[getter]
    fn epsilon(&self) -> f64 {
        self.run.epsilon()
    }

    /// The round the tiles compute next, as a dict (`kind` `done` when the run is over).
    fn round<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        round_dict(py, &self.run.round(), self.run.epsilon())
    }

    /// Takes what the tiles' parts of `round` reduce to: the owned points `count`, the longest
    /// row `max_len` and shortest `min_narrow` (of `start`), the exact `median` of their values
    /// (rank `median_rank(len)`; None when no tile had one) and the `moved_sq` sums merged.
    #[pyo3(signature = (round, *, count, max_len = 0, min_narrow = 0, median = None,
                        moved_sq = None))]
    fn feed(
        &mut self,
        round: &Bound<'_, PyDict>,
        count: u64,
        max_len: usize,
        min_narrow: usize,
        median: Option<f64>,
        moved_sq: Option<PyRef<'_, PyExactSum>>,
    ) -> PyResult<()> {
        let (round, _) = round_of(round)?;
        let mut reduced = Reduced {
            count,
            max_len,
            min_narrow,
            moved_sq: moved_sq.map(|s| s.sum.clone()).unwrap_or_default(),
            ..Reduced::default()
        };
        reduced.set_median(&round, median);
        self.run.feed(&reduced).or_raise()
    }

    /// The rank of the run's medians among `count` values (⌊count/2⌋).
    #[staticmethod]
    fn median_rank(count: u64) -> u64 {
        median_rank(count)
    }

    /// The run's figures so far, with the keys `smooth_robust` returns besides its arrays:
    /// `spacing`, `epsilon`, `lambda`, `min_neighbors`, `noise`, `moved`, `dimension`,
    /// `wide_iterations`.
    fn report<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let r = self.run.report();
        let d = PyDict::new(py);
        d.set_item("spacing", r.result.spacing)?;
        d.set_item("epsilon", r.result.epsilon)?;
        d.set_item("lambda", r.result.lambda)?;
        d.set_item("min_neighbors", r.result.min_neighbors)?;
        d.set_item("noise", vec1(py, r.noise))?;
        d.set_item("moved", vec1(py, r.moved))?;
        d.set_item("dimension", vec1(py, r.dimension))?;
        d.set_item("wide_iterations", r.wide_iterations)?;
        Ok(d)
    }

    /// The mean spacing h from each point's squared distance to its nearest other point, in
    /// the cloud's order (NaN: none), summed in that order: `RobustTile.nearest` of every
    /// tile, put in order.
    #[staticmethod]
    fn spacing_of_nearest(nearest_sq: &Bound<'_, PyAny>) -> PyResult<f64> {
        let v = values_of(nearest_sq)?;
        Ok(RobustRun::spacing_of_nearest(
            v.into_iter().map(|d| Some(d).filter(|d| !d.is_nan())),
        ))
    }
}

/// One tile of a robust run (`nbhd::smooth::robust::RobustTile`): its gathered points (the
/// owned ones and a halo, finite, in ascending cloud order), and the rows it keeps between
/// rounds.
#[pyclass(module = "nbhd._nbhd", name = "RobustTile")]
pub struct PyRobustTile {
    tile: Option<RobustTile<'static>>,
    options: RobustOptions,
}

impl PyRobustTile {
    fn tile(&mut self) -> PyResult<&mut RobustTile<'static>> {
        self.tile
            .as_mut()
            .ok_or_else(|| value_err("the tile is finished"))
    }
}

/// Validity flags as an array (the library's empty list means all).
fn flags<'py>(
    py: Python<'py>,
    valid: Vec<bool>,
    count: usize,
) -> Bound<'py, numpy::PyArray1<bool>> {
    if valid.is_empty() {
        vec1(py, vec![true; count])
    } else {
        vec1(py, valid)
    }
}

#[pymethods]
impl PyRobustTile {
    /// A tile: `points` (m, 3) every finite point of the cloud inside the closed box
    /// `lo`..`hi` (infinite bounds where the cloud ends), in the cloud's order; `owned` (m,)
    /// whether the tile owns each; the options of the run; `threads` the tile's worker
    /// threads (0: the current pool, a thread per core; 1 in a Dask task of one thread).
    #[new]
    #[pyo3(signature = (points, owned, lo, hi, options, *, threads = 0))]
    fn new(
        py: Python<'_>,
        points: &Bound<'_, PyAny>,
        owned: &Bound<'_, PyAny>,
        lo: [f64; 3],
        hi: [f64; 3],
        options: PyRef<'_, PyRobustOptions>,
        threads: usize,
    ) -> PyResult<Self> {
        let options = RobustOptions {
            threads,
            ..options.options
        };
        let input = dvec3s(points)?;
        let owned = bools(owned)?;
        let region = Region {
            lo: DVec3::from_array(lo),
            hi: DVec3::from_array(hi),
        };
        let tile = py
            .detach(|| RobustTile::gathered(input, &owned, region))
            .or_raise()?;
        Ok(Self {
            tile: Some(tile),
            options,
        })
    }

    /// Keeps the rows the tile searches in files in the directory `dir` and reads them from
    /// there when a tile of the same input and region wrote them (a driver that makes the
    /// tile anew at every round then searches once per row set, with the same results).
    fn keep_rows_in(&mut self, dir: std::path::PathBuf) -> PyResult<()> {
        self.tile()?.keep_rows_in(dir);
        Ok(())
    }

    /// Each owned point's squared distance to its nearest other point (NaN: none) and whether
    /// each is the whole cloud's, in the tile's order (the input of the spacing h).
    #[allow(clippy::type_complexity)]
    fn nearest<'py>(
        &mut self,
        py: Python<'py>,
    ) -> PyResult<(
        Bound<'py, numpy::PyArray1<f64>>,
        Bound<'py, numpy::PyArray1<bool>>,
    )> {
        let options = self.options;
        let tile = self.tile()?;
        let (near, valid) = py.detach(|| tile.nearest(&options)).or_raise()?;
        let n = near.len();
        let near: Vec<f64> = near.into_iter().map(|d| d.unwrap_or(f64::NAN)).collect();
        Ok((vec1(py, near), flags(py, valid, n)))
    }

    /// Sets the proxy of `generation` for every gathered point, (m, 3) in the tile's order.
    fn set_current(&mut self, generation: usize, current: &Bound<'_, PyAny>) -> PyResult<()> {
        let current = dvec3s(current)?;
        self.tile()?.set_current(generation, &current).or_raise()
    }

    /// Sets the proxy of generation `at` on which the run's rows shrank, (m, 3) in the tile's
    /// order, for a tile gathered at a later generation.
    fn set_shrink(&mut self, at: usize, proxy: &Bound<'_, PyAny>) -> PyResult<()> {
        let proxy = dvec3s(proxy)?;
        self.tile()?.set_shrink(at, &proxy).or_raise()
    }

    /// Sets the normals of the step into the current generation, (m, 3) in the tile's order,
    /// for a tile gathered after that step (its `finish` returns and reads them).
    fn set_normals(&mut self, normals: &Bound<'_, PyAny>) -> PyResult<()> {
        let normals = dvec3s(normals)?;
        self.tile()?.set_normals(&normals).or_raise()
    }

    /// Computes `round` (a dict of `RobustRun.round`) and returns the owned points' part: a
    /// dict of `count`, `valid` (per owned point), `values` (distance ratios or plane
    /// distances, for the median), `moved_sq` (an `ExactSum`), `max_len` and `min_narrow`.
    fn round<'py>(
        &mut self,
        py: Python<'py>,
        round: &Bound<'py, PyDict>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let (round, eps) = round_of(round)?;
        let options = self.options;
        let tile = self.tile()?;
        let part: TilePart = py.detach(|| tile.round(&round, &options, eps)).or_raise()?;
        let d = PyDict::new(py);
        d.set_item("count", part.count)?;
        d.set_item("valid", flags(py, part.valid, part.count as usize))?;
        d.set_item("values", vec1(py, part.values))?;
        d.set_item("moved_sq", PyExactSum { sum: part.moved_sq })?;
        d.set_item("max_len", part.max_len)?;
        d.set_item("min_narrow", part.min_narrow)?;
        Ok(d)
    }

    /// The owned points of the current proxy, (m, 3) in the tile's order.
    fn owned_points<'py>(&mut self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let pts = self.tile()?.owned_points();
        Ok(dvec3_array(py, &pts)?.into_any())
    }

    /// The owned points' normals of the last step, (m, 3) in the tile's order ((0, 3) before
    /// a step).
    fn owned_normals<'py>(&mut self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let normals = self.tile()?.owned_normals();
        Ok(dvec3_array(py, &normals)?.into_any())
    }

    /// The last round (`finish`): a dict of the owned points' `points`, `normals`, `outputs`
    /// (a dict of arrays, or None) and `valid`. The tile is done afterwards.
    fn finish<'py>(
        &mut self,
        py: Python<'py>,
        round: &Bound<'py, PyDict>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let (round, eps) = round_of(round)?;
        let options = self.options;
        let tile = self
            .tile
            .take()
            .ok_or_else(|| value_err("the tile is finished"))?;
        let (points, normals, outputs, valid) = py
            .detach(|| tile.finish(&round, &options, eps))
            .or_raise()?;
        let d = PyDict::new(py);
        d.set_item("valid", flags(py, valid, points.len()))?;
        d.set_item("points", dvec3_array(py, &points)?)?;
        d.set_item("normals", dvec3_array(py, &normals)?)?;
        if outputs.is_empty() {
            d.set_item("outputs", py.None())?;
        } else {
            d.set_item("outputs", outputs_dict(py, &outputs)?)?;
        }
        Ok(d)
    }
}

/// The outputs of `count` points skipped for their non-finite coordinates (NaN values, the
/// skipped flag), as `smooth_robust` gives them with `non_finite="skip"`.
#[pyfunction]
pub fn _skipped_outputs(py: Python<'_>, count: usize) -> PyResult<Bound<'_, PyDict>> {
    outputs_dict(py, &vec![nbhd::smooth::PointOutput::skipped(); count])
}

/// Emits the one `#[pymethods]` block of a class that wraps a state of the step API held in
/// its field `$field` of type `$ty` (which has `to_bytes` and `from_bytes`): the class's own
/// methods (`own`) and the three that carry the state between processes — `to_bytes`,
/// `from_bytes` and `__reduce__` (a pickle is the bytes) — written here once for all three
/// classes (PyO3 takes one `#[pymethods]` block per class; see `index_pymethods!` in
/// `index.rs`).
macro_rules! bytes_pymethods {
    ($class:ident, $field:ident : $ty:ident, { $($own:tt)* }) => {
        #[pymethods]
        impl $class {
            $($own)*

            /// The state as bytes (`from_bytes` reads them back, in any process).
            fn to_bytes<'py>(&self, py: Python<'py>) -> Bound<'py, PyBytes> {
                PyBytes::new(py, &self.$field.to_bytes())
            }

            /// The state of `to_bytes`.
            #[staticmethod]
            fn from_bytes(bytes: &[u8]) -> PyResult<Self> {
                Ok(Self {
                    $field: $ty::from_bytes(bytes).or_raise()?,
                })
            }

            fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyTuple>> {
                let py = slf.py();
                let from = slf.get_type().getattr("from_bytes")?;
                let bytes = slf.borrow().to_bytes(py);
                PyTuple::new(py, [from, PyTuple::new(py, [bytes])?.into_any()])
            }
        }
    };
}

/// An exact selection across parts (`nbhd::select::radix::RankSearch` of f64): the value of
/// rank `rank` among values spread over parts that are never gathered.
#[pyclass(module = "nbhd._nbhd", name = "RankSearch")]
#[derive(Clone)]
pub struct PyRankSearch {
    search: RankSearch<f64>,
}

bytes_pymethods!(PyRankSearch, search: RankSearch, {
    #[new]
    fn new(rank: u64) -> Self {
        Self {
            search: RankSearch::new(rank),
        }
    }

    /// What the search needs next: `("counts", None)` (every part's `digit_counts`, merged,
    /// to `feed_counts`), `("values", None)` (every part's `matching_values` to
    /// `feed_values`) or `("found", value)`.
    fn step(&self) -> (&'static str, Option<f64>) {
        match self.search.step() {
            RankStep::Counts => ("counts", None),
            RankStep::Values => ("values", None),
            RankStep::Found(v) => ("found", Some(v)),
        }
    }

    /// A part's counts of the next digit among `values`.
    fn digit_counts(&self, py: Python<'_>, values: &Bound<'_, PyAny>) -> PyResult<PyDigitCounts> {
        let v = values_of(values)?;
        let counts = py.detach(|| self.search.digit_counts(&v));
        Ok(PyDigitCounts { counts })
    }

    /// A part's values in the bucket the search is in.
    fn matching_values<'py>(
        &self,
        py: Python<'py>,
        values: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, numpy::PyArray1<f64>>> {
        let v = values_of(values)?;
        Ok(vec1(py, self.search.matching_values(&v)))
    }

    /// Takes the parts' counts, merged.
    fn feed_counts(&mut self, counts: &PyDigitCounts) -> PyResult<()> {
        self.search.feed_counts(&counts.counts).or_raise()
    }

    /// Takes the parts' matching values, concatenated.
    fn feed_values(&mut self, values: &Bound<'_, PyAny>) -> PyResult<()> {
        let v = values_of(values)?;
        self.search.feed_values(&v).or_raise()
    }
});

/// One part's (or several parts' merged) counts of a `RankSearch` round.
#[pyclass(module = "nbhd._nbhd", name = "DigitCounts")]
#[derive(Clone)]
pub struct PyDigitCounts {
    counts: DigitCounts,
}

bytes_pymethods!(PyDigitCounts, counts: DigitCounts, {
    /// Adds another part's counts of the same round.
    fn merge(&mut self, other: &PyDigitCounts) -> PyResult<()> {
        self.counts.merge(&other.counts).or_raise()
    }

    /// How many values the counts cover.
    #[getter]
    fn total(&self) -> u64 {
        self.counts.total()
    }
});

/// An exactly rounded sum of f64 values whose value does not depend on their order or split
/// (`nbhd::sum::ExactSum`).
#[pyclass(module = "nbhd._nbhd", name = "ExactSum")]
#[derive(Clone, Default)]
pub struct PyExactSum {
    sum: ExactSum,
}

impl PyExactSum {
    /// The sum as a Python object (for the filters' tiled steps, `filter.rs`).
    pub(crate) fn of(sum: ExactSum) -> Self {
        Self { sum }
    }

    /// The sum held.
    pub(crate) fn sum(&self) -> &ExactSum {
        &self.sum
    }
}

bytes_pymethods!(PyExactSum, sum: ExactSum, {
    #[new]
    fn new() -> Self {
        Self::default()
    }

    /// Adds finite `values` (a 1-D array).
    fn add(&mut self, values: &Bound<'_, PyAny>) -> PyResult<()> {
        let v = values_of(values)?;
        self.sum.add_slice(&v);
        Ok(())
    }

    /// Adds another sum.
    fn merge(&mut self, other: &PyExactSum) {
        self.sum.merge(&other.sum);
    }

    /// The sum, rounded once to the nearest f64.
    fn value(&self) -> f64 {
        self.sum.value()
    }
});
