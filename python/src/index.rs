//! What `KdTree` and `DynamicKdTree` share: both hold the library's runtime handle
//! (`nbhd::handle::AnyIndex`), and each of their queries is one call of a function here over
//! it, so a query is bound once for both classes.

use nbhd::filter::{RadiusOutlierOptions, StatisticalOutlierOptions};
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

/// The caller's indices a filter kept, ascending (uint32).
fn kept(py: Python<'_>, kept: nbhd::filter::Kept) -> Bound<'_, PyArray1<u32>> {
    vec1(py, kept.indices)
}

/// Statistical outlier removal over the index's points
/// (`nbhd::filter::statistical_outlier_removal`): the caller's indices of the points kept,
/// ascending.
pub(crate) fn remove_statistical_outliers<'py>(
    index: &AnyIndex,
    py: Python<'py>,
    k: usize,
    std_ratio: f64,
    threads: usize,
) -> PyResult<Bound<'py, PyArray1<u32>>> {
    let options = StatisticalOutlierOptions {
        k,
        std_ratio,
        threads,
    };
    let result = py.detach(|| index.statistical_outlier_removal(&options));
    Ok(kept(py, result.or_raise()?))
}

/// Radius outlier removal over the index's points (`nbhd::filter::radius_outlier_removal`): the
/// caller's indices of the points kept, ascending.
pub(crate) fn remove_radius_outliers<'py>(
    index: &AnyIndex,
    py: Python<'py>,
    radius: f64,
    min_neighbors: usize,
    threads: usize,
) -> PyResult<Bound<'py, PyArray1<u32>>> {
    let options = RadiusOutlierOptions {
        radius,
        min_neighbors,
        threads,
    };
    let result = py.detach(|| index.radius_outlier_removal(&options));
    Ok(kept(py, result.or_raise()?))
}

/// Runs `f` with the index of `other`, a `KdTree` or a `DynamicKdTree` (else `TypeError`).
fn with_other<R>(
    other: &Bound<'_, PyAny>,
    f: impl FnOnce(&AnyIndex) -> PyResult<R>,
) -> PyResult<R> {
    if let Ok(t) = other.cast::<crate::tree::PyKdTree>() {
        return f(&t.get().index);
    }
    if let Ok(t) = other.cast::<crate::dynamic::PyDynamicKdTree>() {
        return f(&t.try_borrow()?.index);
    }
    Err(pyo3::exceptions::PyTypeError::new_err(format!(
        "other must be a KdTree or a DynamicKdTree, not {}",
        other.get_type().name()?
    )))
}

/// The table options of the pair queries (`pairs`, `pairs_with`, `count_pairs`): `options` on
/// `threads`, every other field the default (`exclude_self` does not apply to pairs).
fn pair_options(options: QueryOptions, threads: usize) -> TableOptions {
    TableOptions {
        threads,
        query: options,
        ..TableOptions::default()
    }
}

/// The pairs `i < j` of stored points within `radius` (`nbhd::NeighborIndex::pairs`) as a
/// `Table`: row i holds the j > i ascending, with the pair's key.
pub(crate) fn pairs(
    index: &AnyIndex,
    py: Python<'_>,
    radius: f64,
    options: QueryOptions,
    threads: usize,
) -> PyResult<PyTable> {
    let opts = pair_options(options, threads);
    let rows = py.detach(|| index.pairs(radius, &opts)).or_raise()?;
    table(py, rows, index.source_len(), &options)
}

/// The pairs `(i, j)` of a stored point and a point of `other` within `radius`, measured by
/// `index` (`nbhd::NeighborIndex::pairs_with`), as a `Table` of `index`'s rows whose columns
/// are `other`'s indices, ascending.
pub(crate) fn pairs_with(
    index: &AnyIndex,
    py: Python<'_>,
    other: &Bound<'_, PyAny>,
    radius: f64,
    options: QueryOptions,
    threads: usize,
) -> PyResult<PyTable> {
    let opts = pair_options(options, threads);
    with_other(other, |o| {
        let rows = py
            .detach(|| index.pairs_with(o, radius, &opts))
            .or_raise()?;
        table(py, rows, o.source_len(), &options)
    })
}

/// Pair counts against `other` in bins of `radii` (`nbhd::NeighborIndex::count_pairs_with`):
/// uint64 counts, or with a weight array on either side the float64 sums of the weight
/// products (`weigh_pairs_with`).
#[allow(clippy::too_many_arguments)]
pub(crate) fn count_pairs<'py>(
    index: &AnyIndex,
    py: Python<'py>,
    other: &Bound<'py, PyAny>,
    radii: Vec<f64>,
    cumulative: bool,
    weights: (Option<Vec<f64>>, Option<Vec<f64>>),
    options: QueryOptions,
    threads: usize,
) -> PyResult<Bound<'py, PyAny>> {
    let opts = pair_options(options, threads);
    with_other(other, |o| {
        if weights.0.is_none() && weights.1.is_none() {
            let counts = py.detach(|| index.count_pairs_with(o, &radii, cumulative, &opts));
            return Ok(vec1(py, counts.or_raise()?).into_any());
        }
        let w = nbhd::PairWeights {
            this: weights.0.as_deref(),
            other: weights.1.as_deref(),
        };
        let sums = py.detach(|| index.weigh_pairs_with(o, &radii, w, cumulative, &opts));
        Ok(vec1(py, sums.or_raise()?).into_any())
    })
}

/// Emits the one `#[pymethods]` block of a Python index class (`KdTree`, `DynamicKdTree`): the
/// class's own methods (`own`) and every method the two classes share, each a call of a
/// function of this module over the class's `index: AnyIndex`. PyO3 takes one `#[pymethods]`
/// block per class (unless its `multiple-pymethods` feature, which costs the `inventory`
/// crate), so the shared methods — signatures, defaults and docstrings — are written here once
/// and spliced into both blocks. `held` names the points a query sees, `absent` those it
/// never sees, `len` the attribute that counts the indices given, `growing` whether the class
/// holds a growing tree.
macro_rules! index_pymethods {
    ($class:ident, name = $name:literal, held = $held:literal, absent = $absent:literal,
     len = $len:literal, growing = $growing:literal, { $($own:tt)* }) => {
        #[::pyo3::pymethods]
        impl $class {
            $($own)*

            #[doc = concat!("Number of ", $held, " (", $absent, " not counted).")]
            #[getter]
            fn size(&self) -> usize {
                self.index.len()
            }

            /// Dimension of the points.
            #[getter]
            fn m(&self) -> usize {
                self.index.dim()
            }

            /// The tree's scalar type: "float32" or "float64" (queries are converted to it).
            #[getter]
            fn dtype_name(&self) -> &'static str {
                $crate::index::dtype(&self.index).numpy_name()
            }

            /// The periodic box per axis (0 for an open axis), or None for a tree without one.
            #[getter]
            fn boxsize(&self) -> Option<Vec<f64>> {
                self.index.boxsize()
            }

            #[doc = concat!("The `k` nearest ", $held, " of `x`, ordered by (sq_dist, index).")]
            ///
            /// One point (1-D `x` of length d): `(indices, sq_dists)`, each of length
            /// min(k, size). A batch (2-D `x`, m × d): `(indices, sq_dists)` of shape
            /// (m, min(k, size)), answered in parallel (`threads`), identical for any thread
            /// count. Distances are squared.
            ///
            /// Every query takes `p`, the Minkowski p-norm it measures by (1 ≤ p ≤ ∞; default
            /// 2, Euclidean): `sq_dists` then hold the metric's key — squared for p = 2, the
            /// distance for p = 1 and ∞, Σ|x_j − q_j|^p otherwise (`d = key ** (1 / p)`) — and
            /// a radius is a distance in it. `eps > 0` makes the search approximate (scipy's
            /// rule: the i-th neighbour within `1 + eps` times the true i-th; a radius result
            /// holds every point within `radius / (1 + eps)` and none beyond
            /// `radius * (1 + eps)`); `strict=True` makes a radius exclusive (scipy's
            /// `distance_upper_bound`).
            #[pyo3(signature = (x, k, *, p = 2.0, eps = 0.0, threads = 0))]
            fn knn<'py>(
                &self,
                py: ::pyo3::Python<'py>,
                x: &::pyo3::Bound<'py, ::pyo3::PyAny>,
                k: usize,
                p: f64,
                eps: f64,
                threads: usize,
            ) -> ::pyo3::PyResult<::pyo3::Bound<'py, ::pyo3::PyAny>> {
                let spec = $crate::index::spec(Some(k), None, true)?;
                let options = $crate::index::options(p, eps, false)?;
                let answer = $crate::index::query(&self.index, py, x, spec, options, threads)?;
                answer.dense(py, k.min(self.index.len()))
            }

            #[doc = concat!("All ", $held, " within `radius` of `x` (plain radius, inclusive:")]
            /// ‖p − x‖ ≤ radius, exclusive with `strict=True`), ordered by (sq_dist, index)
            /// unless `sorted=False`. `p`, `eps`: as `knn`.
            ///
            /// One point: `(indices, sq_dists)`. A batch (2-D `x`): a `Table` of rows, one per
            /// query.
            #[pyo3(signature = (x, radius, *, sorted = true, p = 2.0, eps = 0.0, strict = false,
                                threads = 0))]
            #[allow(clippy::too_many_arguments)]
            fn radius<'py>(
                &self,
                py: ::pyo3::Python<'py>,
                x: &::pyo3::Bound<'py, ::pyo3::PyAny>,
                radius: f64,
                sorted: bool,
                p: f64,
                eps: f64,
                strict: bool,
                threads: usize,
            ) -> ::pyo3::PyResult<::pyo3::Bound<'py, ::pyo3::PyAny>> {
                let spec = $crate::index::spec(None, Some(radius), sorted)?;
                let options = $crate::index::options(p, eps, strict)?;
                $crate::index::query(&self.index, py, x, spec, options, threads)?.into_py(py)
            }

            #[doc = concat!("The ε-k-neighbourhood of `x`: the `k` nearest among the ", $held,
                            " within")]
            /// `radius` (thesis Section 2.1.1). One point: `(indices, sq_dists)`; a batch: a
            /// `Table`. `p`, `eps`, `strict`: as `knn` and `radius`.
            #[pyo3(signature = (x, k, radius, *, p = 2.0, eps = 0.0, strict = false,
                                threads = 0))]
            #[allow(clippy::too_many_arguments)]
            fn knn_radius<'py>(
                &self,
                py: ::pyo3::Python<'py>,
                x: &::pyo3::Bound<'py, ::pyo3::PyAny>,
                k: usize,
                radius: f64,
                p: f64,
                eps: f64,
                strict: bool,
                threads: usize,
            ) -> ::pyo3::PyResult<::pyo3::Bound<'py, ::pyo3::PyAny>> {
                let spec = $crate::index::spec(Some(k), Some(radius), true)?;
                let options = $crate::index::options(p, eps, strict)?;
                $crate::index::query(&self.index, py, x, spec, options, threads)?.into_py(py)
            }

            #[doc = concat!("The neighbourhood of each of the ", $held, " as a `Table`: a row")]
            #[doc = concat!("per index (row i for the caller's point i; ", $absent,
                            " get empty rows):")]
            /// the `k` nearest (`k` alone), all within `radius` (`radius` alone) or the
            /// ε-k-neighbourhood (both). `exclude_self` leaves each point out of its own row
            /// (its duplicates at distance 0 stay). Computed in parallel, one tree descent per
            /// group of neighbouring points; identical bytes for any `threads`. `p`, `eps`,
            /// `strict`: as `knn` and `radius` (each row then one search).
            #[pyo3(signature = (*, k = None, radius = None, exclude_self = true, sorted = true,
                                p = 2.0, eps = 0.0, strict = false, threads = 0))]
            #[allow(clippy::too_many_arguments)]
            fn neighborhoods(
                &self,
                py: ::pyo3::Python<'_>,
                k: Option<usize>,
                radius: Option<f64>,
                exclude_self: bool,
                sorted: bool,
                p: f64,
                eps: f64,
                strict: bool,
                threads: usize,
            ) -> ::pyo3::PyResult<$crate::tree::PyTable> {
                let spec = $crate::index::spec(k, radius, sorted)?;
                let options = $crate::index::options(p, eps, strict)?;
                $crate::index::neighborhoods(&self.index, py, spec, options, exclude_self, threads)
            }

            #[doc = concat!("Every pair i < j of ", $held, " within `radius` of each other")]
            /// (inclusive; scipy's `query_pairs`) as a `Table`: row i holds the j > i in
            /// ascending order (not by distance) with the pair's key in `sq_dists` (as `knn`).
            /// `p`, `eps`, `strict`: as `knn` and `radius` (with `eps`, every pair within
            /// `radius * (1 + eps)`: inside scipy's contract, and what scipy's own test of
            /// `query_pairs` with eps counts on). Periodic trees pair nearest images.
            /// Identical for any `threads`.
            #[pyo3(signature = (radius, *, p = 2.0, eps = 0.0, strict = false, threads = 0))]
            fn pairs(
                &self,
                py: ::pyo3::Python<'_>,
                radius: f64,
                p: f64,
                eps: f64,
                strict: bool,
                threads: usize,
            ) -> ::pyo3::PyResult<$crate::tree::PyTable> {
                let options = $crate::index::options(p, eps, strict)?;
                $crate::index::pairs(&self.index, py, radius, options, threads)
            }

            #[doc = concat!("The pairs (i, j) of ", $held, " i and points j of `other` (a")]
            /// `KdTree` or `DynamicKdTree` of the same dimension and dtype) within `radius`
            /// (inclusive; scipy's `query_ball_tree` and `sparse_distance_matrix`), measured by
            /// this tree (its `p`, its periodic box; `other`'s box is not used): a `Table` with
            /// a row per index of this tree holding `other`'s indices ascending and the pairs'
            /// keys (zero distances included; `to_csr(distances=True)` gives scipy's sparse
            /// distance matrix). `p`, `eps`, `strict`: as `pairs`.
            #[pyo3(signature = (other, radius, *, p = 2.0, eps = 0.0, strict = false,
                                threads = 0))]
            #[allow(clippy::too_many_arguments)]
            fn pairs_with(
                &self,
                py: ::pyo3::Python<'_>,
                other: &::pyo3::Bound<'_, ::pyo3::PyAny>,
                radius: f64,
                p: f64,
                eps: f64,
                strict: bool,
                threads: usize,
            ) -> ::pyo3::PyResult<$crate::tree::PyTable> {
                let options = $crate::index::options(p, eps, strict)?;
                $crate::index::pairs_with(&self.index, py, other, radius, options, threads)
            }

            #[doc = concat!("How many pairs (i, j) of ", $held, " i and points j of `other`")]
            /// lie within each radius of `radii` (scipy's `count_neighbors`), measured as
            /// `pairs_with`; `other` may be this tree (each point then counts with itself and
            /// each pair twice). `cumulative=True`: entry k counts distances ≤ radii[k];
            /// otherwise those in (radii[k-1], radii[k]] (radii non-decreasing; of equal radii
            /// the first gets the count). A negative radius counts nothing, inf everything.
            /// Unweighted: uint64 counts. With `weights` (one per index of this tree) and/or
            /// `other_weights` (one per index of `other`; a missing side weighs 1): float64
            /// sums of the products, each correctly rounded (the same bits for any `threads`).
            #[pyo3(signature = (other, radii, *, cumulative = true, weights = None,
                                other_weights = None, p = 2.0, strict = false, threads = 0))]
            #[allow(clippy::too_many_arguments)]
            fn count_pairs<'py>(
                &self,
                py: ::pyo3::Python<'py>,
                other: &::pyo3::Bound<'py, ::pyo3::PyAny>,
                radii: Vec<f64>,
                cumulative: bool,
                weights: Option<Vec<f64>>,
                other_weights: Option<Vec<f64>>,
                p: f64,
                strict: bool,
                threads: usize,
            ) -> ::pyo3::PyResult<::pyo3::Bound<'py, ::pyo3::PyAny>> {
                let options = $crate::index::options(p, 0.0, strict)?;
                let w = (weights, other_weights);
                $crate::index::count_pairs(&self.index, py, other, radii, cumulative, w, options,
                                           threads)
            }

            #[doc = concat!("The ", $held, " inside closed axis-aligned boxes")]
            /// (`min[j] <= x[j] <= max[j]`; bounds may be infinite; a NaN bound or `min > max`
            #[doc = concat!("raises NbhdValueError; ", $absent, " are never inside). One box")]
            /// (1-D `min`, `max`): the caller's indices, ascending. A batch ((m, d) arrays):
            /// `(offsets, indices)`, box i's points being `indices[offsets[i]:offsets[i + 1]]`;
            /// identical for any `threads`.
            #[pyo3(signature = (min, max, *, threads = 0))]
            fn in_box<'py>(
                &self,
                py: ::pyo3::Python<'py>,
                min: &::pyo3::Bound<'py, ::pyo3::PyAny>,
                max: &::pyo3::Bound<'py, ::pyo3::PyAny>,
                threads: usize,
            ) -> ::pyo3::PyResult<::pyo3::Bound<'py, ::pyo3::PyAny>> {
                $crate::index::in_box(&self.index, py, min, max, threads)
            }

            #[doc = concat!("The spacing of the ", $held, ": a dict of `mean` (h, the mean")]
            /// distance of a point to its nearest other point, the unit of every relative
            /// length), `median` and `points` (how many it was taken over); the same bits for
            /// any `threads`. Fewer than two points raise.
            #[pyo3(signature = (*, threads = 0))]
            fn spacing<'py>(
                &self,
                py: ::pyo3::Python<'py>,
                threads: usize,
            ) -> ::pyo3::PyResult<::pyo3::Bound<'py, ::pyo3::types::PyDict>> {
                $crate::index::spacing(&self.index, py, threads)
            }

            #[doc = concat!("Statistical outlier removal over the ", $held, " (PCL's")]
            /// StatisticalOutlierRemoval, Open3D's `remove_statistical_outlier`): for each point
            /// its mean distance d_i to its `k` nearest other points (PCL's `setMeanK(k)`,
            /// Open3D's `nb_neighbors`); over all points the mean m and the sample standard
            /// deviation s; a point is kept when d_i <= m + std_ratio * s (`std_ratio` finite,
            /// may be negative). `k` must be at least 1 and below `size`.
            ///
            /// Returns the caller's indices of the kept points, ascending (uint32; Open3D's
            /// `ind`): `points[kept]` is the cleaned cloud, and `mask[kept] = True` on a
            #[doc = concat!("`np.zeros(", $len, ", bool)` gives a mask; ", $absent,
                            " are never kept.")]
            #[pyo3(signature = (*, k = 50, std_ratio = 1.0, threads = 0))]
            fn remove_statistical_outliers<'py>(
                &self,
                py: ::pyo3::Python<'py>,
                k: usize,
                std_ratio: f64,
                threads: usize,
            ) -> ::pyo3::PyResult<::pyo3::Bound<'py, numpy::PyArray1<u32>>> {
                $crate::index::remove_statistical_outliers(&self.index, py, k, std_ratio, threads)
            }

            #[doc = concat!("Radius outlier removal over the ", $held, " (PCL's")]
            /// RadiusOutlierRemoval, Open3D's `remove_radius_outlier`): a point is kept when at
            /// least `min_neighbors` *other* points lie within `radius` (plain Euclidean,
            /// inclusive; duplicates count). PCL's `setMinNeighborsInRadius(m)` is the same m;
            /// Open3D's `nb_points` counts the point itself (`nb_points = min_neighbors + 1`).
            /// `min_neighbors = 0` keeps every point.
            ///
            /// Returns the caller's indices of the kept points, ascending (uint32), as
            #[doc = concat!("`remove_statistical_outliers`; ", $absent, " are never kept.")]
            #[pyo3(signature = (radius, *, min_neighbors = 2, threads = 0))]
            fn remove_radius_outliers<'py>(
                &self,
                py: ::pyo3::Python<'py>,
                radius: f64,
                min_neighbors: usize,
                threads: usize,
            ) -> ::pyo3::PyResult<::pyo3::Bound<'py, numpy::PyArray1<u32>>> {
                let index = &self.index;
                $crate::index::remove_radius_outliers(index, py, radius, min_neighbors, threads)
            }

            #[doc = concat!("The ", $name, " in its saved format (docs/tree-file-format.md) as")]
            #[doc = concat!("`bytes`: what `pickle` stores and `", $name,
                            ".from_bytes` reads back.")]
            fn to_bytes<'py>(
                &self,
                py: ::pyo3::Python<'py>,
            ) -> ::pyo3::Bound<'py, ::pyo3::types::PyBytes> {
                $crate::index::to_bytes(&self.index, py)
            }

            #[doc = concat!("The ", $name, " saved in `data` (by `to_bytes`, `pickle`, or the")]
            /// Rust and C saves), of the dtype it was saved with, answering every query exactly
            /// as the saved one did. Damaged, truncated or foreign bytes (another format version,
            /// byte order, or a saved tree of the other class) raise `NbhdValueError` naming
            /// what differs.
            #[classmethod]
            fn from_bytes(
                cls: &::pyo3::Bound<'_, ::pyo3::types::PyType>,
                data: &[u8],
            ) -> ::pyo3::PyResult<Self> {
                Ok(Self {
                    index: $crate::index::from_bytes(cls.py(), data, $growing)?,
                })
            }

            #[doc = concat!("Pickling: `", $name, ".from_bytes(tree.to_bytes())`.")]
            fn __reduce__<'py>(
                slf: &::pyo3::Bound<'py, Self>,
            ) -> ::pyo3::PyResult<(
                ::pyo3::Bound<'py, ::pyo3::PyAny>,
                (::pyo3::Bound<'py, ::pyo3::types::PyBytes>,),
            )> {
                let from = slf.get_type().getattr("from_bytes")?;
                let bytes = $crate::index::to_bytes(&slf.borrow().index, slf.py());
                Ok((from, (bytes,)))
            }
        }
    };
}
pub(crate) use index_pymethods;
