//! What `KdTree` and `DynamicKdTree` share: both hold the library's runtime handle
//! (`nbhd::handle::AnyIndex`), and each of their queries is one call of a function here over
//! it, so a query is bound once for both classes.

use nbhd::handle::{AnyIndex, AnyTable};
use nbhd::{with_index, with_table, NeighborIndex, NeighborhoodSpec, Query, ScalarType};
use nbhd::{Metric, Neighbor, QueryOptions, Scalar, TableOptions};
use numpy::{Element, PyArray1, PyArrayMethods, PyReadonlyArray1};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict, PyTuple};

use crate::arrays::{as_rows, float_array, vec1, Dtype, Points};
use crate::errors::{value_err, OrRaise};
use crate::tree::PyTable;

/// The numpy dtype of the index's coordinates and distances.
pub(crate) fn dtype(index: &AnyIndex) -> Dtype {
    match index.scalar_type() {
        ScalarType::F32 => Dtype::F32,
        ScalarType::F64 => Dtype::F64,
    }
}

/// The neighbourhood named by `k` and/or `radius`.
pub(crate) fn spec(
    k: Option<usize>,
    radius: Option<f64>,
    sorted: bool,
) -> PyResult<NeighborhoodSpec> {
    if k.is_none() && radius.is_none() {
        return Err(value_err("give k, radius, or both"));
    }
    Ok(NeighborhoodSpec { k, radius, sorted })
}

/// The query options named by `p` (the Minkowski p-norm, 1 ≤ p ≤ ∞), `eps` and `strict`,
/// checked: a bad value raises `NbhdValueError` naming it.
pub(crate) fn options(p: f64, eps: f64, strict: bool) -> PyResult<QueryOptions> {
    let options = QueryOptions {
        metric: Metric::from_p(p).or_raise()?,
        eps,
        strict,
    };
    options.validate().or_raise()?;
    Ok(options)
}

/// One query's neighbours as `(indices, sq_dists)` arrays.
pub(crate) fn pair<'py, T: Scalar + Element>(
    py: Python<'py>,
    found: Vec<Neighbor<T>>,
) -> PyResult<Bound<'py, PyTuple>> {
    let idx: Vec<u32> = found.iter().map(|n| n.index).collect();
    let d2: Vec<T> = found.iter().map(|n| n.sq_dist).collect();
    PyTuple::new(py, [vec1(py, idx).into_any(), vec1(py, d2).into_any()])
}

/// A table of the index as a Python `Table` (`n_points` columns: the index's rows).
pub(crate) fn table(
    py: Python<'_>,
    table: AnyTable,
    n_points: usize,
    options: &QueryOptions,
) -> PyResult<PyTable> {
    with_table!(table, t => PyTable::new(py, t, n_points, options.metric))
}

/// What a query returns: one point's `(indices, sq_dists)` or a batch's table.
pub(crate) enum Answer<'py> {
    One(Bound<'py, PyTuple>),
    Many(PyTable),
}

impl<'py> Answer<'py> {
    /// The answer as Python gets it: a tuple, or a `Table`.
    pub(crate) fn into_py(self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        match self {
            Answer::One(t) => Ok(t.into_any()),
            Answer::Many(t) => Ok(Bound::new(py, t)?.into_any()),
        }
    }

    /// A k-nearest answer: a tuple, or a batch's rows as two (rows, `width`) arrays (`width`
    /// = min(k, size); a batch of no query is (0, `width`)).
    pub(crate) fn dense(self, py: Python<'py>, width: usize) -> PyResult<Bound<'py, PyAny>> {
        match self {
            Answer::One(t) => Ok(t.into_any()),
            Answer::Many(table) => table.dense(py, width),
        }
    }
}

/// A single query (1-D `x`) answered by the index's own search, or a batch (2-D `x`) as a
/// table, in parallel on `threads`; the GIL released in both.
pub(crate) fn query<'py>(
    index: &AnyIndex,
    py: Python<'py>,
    x: &Bound<'py, PyAny>,
    spec: NeighborhoodSpec,
    options: QueryOptions,
    threads: usize,
) -> PyResult<Answer<'py>> {
    let (arr, _) = float_array(x, Some(dtype(index)))?;
    let (arr, single) = as_rows(&arr, "the query")?;
    with_index!(index, t, T => {
        if single {
            let flat = arr.call_method1("reshape", (-1,))?;
            let ro: PyReadonlyArray1<'_, T> = flat.cast::<PyArray1<T>>()?.readonly();
            let q: Vec<T> = ro.as_array().to_vec();
            let nbhd = spec.to_with::<T>(&options).or_raise()?;
            let found = py
                .detach(|| {
                    let mut out = Vec::new();
                    t.search_with(Query::point(&q), nbhd, &options, &mut out).map(|_| out)
                })
                .or_raise()?;
            Ok(Answer::One(pair(py, found)?))
        } else {
            let pts = Points::<T>::new(&arr)?;
            let view = pts.view().or_raise()?;
            let opts = TableOptions { exclude_self: false, threads, query: options };
            let rows = py.detach(|| index.neighborhoods_of(&view, spec, &opts)).or_raise()?;
            Ok(Answer::Many(table(py, rows, index.source_len(), &options)?))
        }
    })
}

/// The neighbourhood of every stored point, as a `Table` of the index's rows.
pub(crate) fn neighborhoods(
    index: &AnyIndex,
    py: Python<'_>,
    spec: NeighborhoodSpec,
    options: QueryOptions,
    exclude_self: bool,
    threads: usize,
) -> PyResult<PyTable> {
    let opts = TableOptions {
        exclude_self,
        threads,
        query: options,
    };
    let rows = py.detach(|| index.neighborhoods(spec, &opts)).or_raise()?;
    table(py, rows, index.source_len(), &options)
}

/// The index in its saved format as `bytes`.
pub(crate) fn to_bytes<'py>(index: &AnyIndex, py: Python<'py>) -> Bound<'py, PyBytes> {
    let bytes = py.detach(|| index.to_bytes());
    PyBytes::new(py, &bytes)
}

/// The index saved in `data` (a growing one with `growing`), of the dtype it was saved with.
pub(crate) fn from_bytes(py: Python<'_>, data: &[u8], growing: bool) -> PyResult<AnyIndex> {
    py.detach(|| AnyIndex::from_bytes(data, growing)).or_raise()
}

/// The stored points inside closed axis-aligned boxes (`min[j] ≤ x[j] ≤ max[j]`,
/// `nbhd::NeighborIndex::in_boxes`), in parallel on `threads`. One box (1-D `min`, `max`): the
/// caller's indices, ascending. A batch ((m, d) `min`, `max`): `(offsets, indices)`, row `i`
/// being `indices[offsets[i]:offsets[i + 1]]`.
pub(crate) fn in_box<'py>(
    index: &AnyIndex,
    py: Python<'py>,
    min: &Bound<'py, PyAny>,
    max: &Bound<'py, PyAny>,
    threads: usize,
) -> PyResult<Bound<'py, PyAny>> {
    let (lo, _) = float_array(min, Some(dtype(index)))?;
    let (hi, _) = float_array(max, Some(dtype(index)))?;
    let (lo, single) = as_rows(&lo, "min")?;
    let (hi, _) = as_rows(&hi, "max")?;
    let (lo_shape, hi_shape): (Vec<usize>, Vec<usize>) = (
        lo.getattr("shape")?.extract()?,
        hi.getattr("shape")?.extract()?,
    );
    if lo_shape != hi_shape {
        return Err(value_err(format!(
            "min and max must have the same shape, not {lo_shape:?} and {hi_shape:?}"
        )));
    }
    let np = py.import("numpy")?;
    let boxes = np.call_method1("concatenate", ((lo, hi), 1))?;
    let rows = with_index!(index, _t, T => {
        let pts = Points::<T>::new(&boxes)?;
        let view = pts.view().or_raise()?;
        py.detach(|| index.in_boxes(&view, threads)).or_raise()?
    });
    if single {
        return Ok(vec1(py, rows.row(0).to_vec()).into_any());
    }
    let offsets: Vec<u64> = rows.offsets().iter().map(|&o| o as u64).collect();
    let tuple = PyTuple::new(
        py,
        [
            vec1(py, offsets).into_any(),
            vec1(py, rows.indices().to_vec()).into_any(),
        ],
    )?;
    Ok(tuple.into_any())
}

/// The mean spacing h of the stored points and its robust twin (`nbhd::NeighborIndex::spacing`):
/// a dict of `mean` (h: the mean distance to the nearest other point, summed in index order),
/// `median` and `points` (how many points it was taken over).
pub(crate) fn spacing<'py>(
    index: &AnyIndex,
    py: Python<'py>,
    threads: usize,
) -> PyResult<Bound<'py, PyDict>> {
    let s = py.detach(|| index.spacing(threads)).or_raise()?;
    let d = PyDict::new(py);
    d.set_item("mean", s.mean)?;
    d.set_item("median", s.median)?;
    d.set_item("points", s.points)?;
    Ok(d)
}
