//! `nbhd.KdTree` and `nbhd.Table`: the k-d tree of `nbhd::tree` over an (n, d) numpy array of
//! float32 or float64, its single and batch queries, and its all-point tables as compressed rows.

use nbhd::tree::SavedTreeInfo;
use nbhd::{
    BuildOptions, KdTree, NbhdError, Neighbor, NeighborIndex, NeighborSearch, NeighborTable,
    Neighborhood, Query, Scalar, ScalarType, TableOptions,
};
use numpy::{Element, PyArray1, PyArrayMethods, PyReadonlyArray1};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict, PyTuple, PyType};

use crate::arrays::{as_rows, float_array, ndim, vec1, Dtype, Points};
use crate::errors::{value_err, OrRaise};
use crate::options;

/// The tree of either scalar type.
enum Tree {
    F32(KdTree<f32>),
    F64(KdTree<f64>),
}

/// Runs `$body` with `$t` bound to the tree of either type and `$T` to its scalar type.
macro_rules! with_tree {
    ($tree:expr, $t:ident, $T:ident => $body:expr) => {
        match $tree {
            Tree::F32($t) => {
                type $T = f32;
                $body
            }
            Tree::F64($t) => {
                type $T = f64;
                $body
            }
        }
    };
}

/// A k-d tree over the rows of an (n, d) array (thesis Chapter 3; `nbhd::KdTree`).
///
/// The tree keeps its own compact copy of the points, so the array may change afterwards. It
/// is immutable and may be queried from many Python threads at once; every query and table
/// releases the GIL while it runs.
#[pyclass(frozen, module = "nbhd._nbhd", name = "KdTree")]
pub struct PyKdTree {
    tree: Tree,
}

/// `r` in the tree's type: a radius finite in f64 but not in `T` is
/// [`NbhdError::RadiusOutOfRange`], as in the C ABI; NaN and negative radii are left for the
/// library's own check.
pub(crate) fn radius_in<T: Scalar>(r: f64) -> Result<T, NbhdError> {
    let t = T::from_f64(r);
    if r.is_finite() && !t.is_finite() {
        let (scalar, max) = match T::TYPE {
            ScalarType::F32 => ("f32", (f32::MAX as f64).sqrt()),
            ScalarType::F64 => ("f64", f64::MAX.sqrt()),
        };
        return Err(NbhdError::RadiusOutOfRange {
            radius: r,
            scalar,
            max,
        });
    }
    Ok(t)
}

/// The neighbourhood named by `k` and/or `radius`.
pub(crate) fn neighborhood<T: Scalar>(
    k: Option<usize>,
    radius: Option<f64>,
    sorted: bool,
) -> PyResult<Neighborhood<T>> {
    Ok(match (k, radius) {
        (Some(k), None) => Neighborhood::Knn { k },
        (None, Some(r)) => Neighborhood::Radius {
            radius: radius_in(r).or_raise()?,
            sorted,
        },
        (Some(k), Some(r)) => Neighborhood::KnnRadius {
            k,
            radius: radius_in(r).or_raise()?,
        },
        (None, None) => return Err(value_err("give k, radius, or both")),
    })
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

/// `obj` as the tree's scalar type, (m, d) with whether it was a single 1-D point.
pub(crate) fn queries<'py>(
    obj: &Bound<'py, PyAny>,
    dtype: Dtype,
) -> PyResult<(Bound<'py, PyAny>, bool)> {
    let (arr, _) = float_array(obj, Some(dtype))?;
    as_rows(&arr, "the query")
}

impl PyKdTree {
    fn dtype(&self) -> Dtype {
        match self.tree {
            Tree::F32(_) => Dtype::F32,
            Tree::F64(_) => Dtype::F64,
        }
    }

    fn source_len(&self) -> usize {
        with_tree!(&self.tree, t, _T => t.source_len())
    }

    /// A single query (1-D `x`) answered by the tree's own search, or a batch (2-D `x`) as a
    /// table, in parallel; the GIL released in both.
    fn query<'py>(
        &self,
        py: Python<'py>,
        x: &Bound<'py, PyAny>,
        k: Option<usize>,
        radius: Option<f64>,
        sorted: bool,
        threads: usize,
    ) -> PyResult<Answer<'py>> {
        let (arr, single) = queries(x, self.dtype())?;
        let source_len = self.source_len();
        with_tree!(&self.tree, t, T => {
            let nbhd = neighborhood::<T>(k, radius, sorted)?;
            if single {
                let flat = arr.call_method1("reshape", (-1,))?;
                let ro: PyReadonlyArray1<'_, T> = flat.cast::<PyArray1<T>>()?.readonly();
                let q: Vec<T> = ro.as_array().to_vec();
                let found = py.detach(|| {
                    let mut out = Vec::new();
                    t.search(Query::point(&q), nbhd, &mut out).map(|_| out)
                }).or_raise()?;
                Ok(Answer::One(pair(py, found)?))
            } else {
                let pts = Points::<T>::new(&arr)?;
                let view = pts.view().or_raise()?;
                let opts = TableOptions { exclude_self: false, threads };
                let table = py
                    .detach(|| t.neighborhoods_of(&view, nbhd, &opts))
                    .or_raise()?;
                Ok(Answer::Many(PyTable::new(py, table, source_len)?))
            }
        })
    }
}

/// What a query returns: one point's `(indices, sq_dists)` or a batch's table.
pub(crate) enum Answer<'py> {
    One(Bound<'py, PyTuple>),
    Many(PyTable),
}

impl<'py> Answer<'py> {
    pub(crate) fn into_py(self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        match self {
            Answer::One(t) => Ok(t.into_any()),
            Answer::Many(t) => Ok(Bound::new(py, t)?.into_any()),
        }
    }
}

#[pymethods]
impl PyKdTree {
    /// Builds the tree over the rows of `points`, an (n, d) array of float32 or float64 (other
    /// types are converted to float64). The array is read in place when its rows are (C order,
    /// row slices, column prefixes of wider records) and copied otherwise.
    ///
    /// pivot: "sliding-midpoint" (default; ANN/FLANN), "cyclic-median" (the thesis' Algorithm
    /// 4), "spread-median", "closest-to-middle".
    /// median: "floyd-rivest" (default), "presorted" (Algorithm 6), "sort", "quickselect",
    /// "median-of-medians" — the same tree for every one (thesis 8.1), at different speeds.
    /// leaf_size: most points per leaf (1 is the thesis' tree shape).
    /// non_finite: "reject" (NaN/Inf points raise) or "skip" (left out; the others keep
    /// their indices).
    /// threads: 0 for a thread per core, n ≥ 1 for n threads; the tree is the same for any.
    #[new]
    #[pyo3(signature = (points, *, pivot = "sliding-midpoint", median = "floyd-rivest",
                        leaf_size = nbhd::tree::DEFAULT_LEAF_SIZE, non_finite = "reject",
                        threads = 0))]
    fn new(
        py: Python<'_>,
        points: &Bound<'_, PyAny>,
        pivot: &str,
        median: &str,
        leaf_size: usize,
        non_finite: &str,
        threads: usize,
    ) -> PyResult<Self> {
        let options = BuildOptions {
            pivot: options::pivot(pivot)?,
            median: options::median(median)?,
            leaf_size,
            non_finite: options::non_finite(non_finite)?,
            threads,
        };
        let (arr, dtype) = float_array(points, None)?;
        if ndim(&arr)? != 2 {
            return Err(value_err(format!(
                "points must be a 2-D array (n, d), not {}-D",
                ndim(&arr)?
            )));
        }
        let tree = match dtype {
            Dtype::F32 => {
                let pts = Points::<f32>::new(&arr)?;
                let view = pts.view().or_raise()?;
                Tree::F32(py.detach(|| KdTree::build(&view, &options)).or_raise()?)
            }
            Dtype::F64 => {
                let pts = Points::<f64>::new(&arr)?;
                let view = pts.view().or_raise()?;
                Tree::F64(py.detach(|| KdTree::build(&view, &options)).or_raise()?)
            }
        };
        Ok(Self { tree })
    }

    /// Number of points held (skipped non-finite points not counted).
    #[getter]
    fn size(&self) -> usize {
        with_tree!(&self.tree, t, _T => t.len())
    }

    /// Number of rows of the array the tree was built from (skipped points included).
    #[getter]
    fn n(&self) -> usize {
        self.source_len()
    }

    /// Dimension of the points.
    #[getter]
    fn m(&self) -> usize {
        with_tree!(&self.tree, t, _T => t.dim())
    }

    /// The tree's scalar type: "float32" or "float64" (queries are converted to it).
    #[getter]
    fn dtype_name(&self) -> &'static str {
        self.dtype().numpy_name()
    }

    /// Caller indices in tree order (the points of one leaf are adjacent).
    #[getter]
    fn tree_order<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<u32>> {
        with_tree!(&self.tree, t, _T => vec1(py, t.tree_order().to_vec()))
    }

    /// Depth, node counts and memory: a dict of `points`, `dim`, `depth`, `nodes`, `leaves`,
    /// `max_leaf_points`, `bytes`.
    fn stats<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let s = with_tree!(&self.tree, t, _T => t.stats());
        let d = PyDict::new(py);
        d.set_item("points", s.points)?;
        d.set_item("dim", s.dim)?;
        d.set_item("depth", s.depth)?;
        d.set_item("nodes", s.nodes)?;
        d.set_item("leaves", s.leaves)?;
        d.set_item("max_leaf_points", s.max_leaf_points)?;
        d.set_item("bytes", s.bytes)?;
        Ok(d)
    }

    /// The build options as a dict (`pivot`, `median`, `leaf_size`, `non_finite`).
    fn options<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let o = *with_tree!(&self.tree, t, _T => t.options());
        let d = PyDict::new(py);
        d.set_item("pivot", o.pivot.name())?;
        d.set_item("median", o.median.name())?;
        d.set_item("leaf_size", o.leaf_size)?;
        d.set_item(
            "non_finite",
            match o.non_finite {
                nbhd::NonFinitePolicy::Reject => "reject",
                nbhd::NonFinitePolicy::Skip => "skip",
            },
        )?;
        Ok(d)
    }

    /// The `k` nearest stored points of `x`, ordered by (sq_dist, index).
    ///
    /// One point (1-D `x` of length d): `(indices, sq_dists)`, each of length min(k, size).
    /// A batch (2-D `x`, m × d): `(indices, sq_dists)` of shape (m, min(k, size)), answered in
    /// parallel (`threads`), identical for any thread count. Distances are squared.
    #[pyo3(signature = (x, k, *, threads = 0))]
    fn knn<'py>(
        &self,
        py: Python<'py>,
        x: &Bound<'py, PyAny>,
        k: usize,
        threads: usize,
    ) -> PyResult<Bound<'py, PyAny>> {
        match self.query(py, x, Some(k), None, true, threads)? {
            Answer::One(t) => Ok(t.into_any()),
            Answer::Many(table) => table.dense(py),
        }
    }

    /// All stored points within `radius` of `x` (plain Euclidean radius, inclusive:
    /// ‖p − x‖ ≤ radius), ordered by (sq_dist, index) unless `sorted=False`.
    ///
    /// One point: `(indices, sq_dists)`. A batch (2-D `x`): a `Table` of rows, one per query.
    #[pyo3(signature = (x, radius, *, sorted = true, threads = 0))]
    fn radius<'py>(
        &self,
        py: Python<'py>,
        x: &Bound<'py, PyAny>,
        radius: f64,
        sorted: bool,
        threads: usize,
    ) -> PyResult<Bound<'py, PyAny>> {
        self.query(py, x, None, Some(radius), sorted, threads)?
            .into_py(py)
    }

    /// The ε-k-neighbourhood of `x`: the `k` nearest among the stored points within `radius`
    /// (thesis Section 2.1.1). One point: `(indices, sq_dists)`; a batch: a `Table`.
    #[pyo3(signature = (x, k, radius, *, threads = 0))]
    fn knn_radius<'py>(
        &self,
        py: Python<'py>,
        x: &Bound<'py, PyAny>,
        k: usize,
        radius: f64,
        threads: usize,
    ) -> PyResult<Bound<'py, PyAny>> {
        self.query(py, x, Some(k), Some(radius), true, threads)?
            .into_py(py)
    }

    /// The neighbourhood of every stored point as a `Table` (row i for the caller's point i;
    /// skipped points get empty rows): the `k` nearest (`k` alone), all within `radius`
    /// (`radius` alone) or the ε-k-neighbourhood (both). `exclude_self` leaves each point out
    /// of its own row (its duplicates at distance 0 stay). Computed in parallel, one tree
    /// descent per group of neighbouring points; identical bytes for any `threads`.
    #[pyo3(signature = (*, k = None, radius = None, exclude_self = true, sorted = true,
                        threads = 0))]
    fn neighborhoods(
        &self,
        py: Python<'_>,
        k: Option<usize>,
        radius: Option<f64>,
        exclude_self: bool,
        sorted: bool,
        threads: usize,
    ) -> PyResult<PyTable> {
        let source_len = self.source_len();
        with_tree!(&self.tree, t, T => {
            let nbhd = neighborhood::<T>(k, radius, sorted)?;
            let opts = TableOptions { exclude_self, threads };
            let table = py.detach(|| t.neighborhoods(nbhd, &opts)).or_raise()?;
            PyTable::new(py, table, source_len)
        })
    }

    /// The tree in the saved-tree format (docs/tree-file-format.md) as `bytes`: a versioned
    /// header with checksums, then the tree as built. `KdTree.from_bytes` reads it back; it is
    /// what `pickle` stores.
    fn to_bytes<'py>(&self, py: Python<'py>) -> Bound<'py, PyBytes> {
        let bytes = py.detach(|| with_tree!(&self.tree, t, _T => t.to_bytes()));
        PyBytes::new(py, &bytes)
    }

    /// The tree saved in `data` (by `to_bytes`, `pickle`, or the Rust and C saves), of the
    /// dtype it was saved with, answering every query exactly as the saved tree did. Damaged,
    /// truncated or foreign bytes (another format version, byte order, or a saved
    /// `DynamicKdTree`) raise `NbhdValueError` naming what differs.
    #[classmethod]
    fn from_bytes(cls: &Bound<'_, PyType>, data: &[u8]) -> PyResult<Self> {
        let tree = cls
            .py()
            .detach(|| -> Result<Tree, NbhdError> {
                Ok(match SavedTreeInfo::from_bytes(data)?.scalar {
                    ScalarType::F32 => Tree::F32(KdTree::from_bytes(data)?),
                    ScalarType::F64 => Tree::F64(KdTree::from_bytes(data)?),
                })
            })
            .or_raise()?;
        Ok(Self { tree })
    }

    /// Pickling: `KdTree.from_bytes(tree.to_bytes())`.
    fn __reduce__<'py>(
        slf: &Bound<'py, Self>,
    ) -> PyResult<(Bound<'py, PyAny>, (Bound<'py, PyBytes>,))> {
        let from = slf.get_type().getattr("from_bytes")?;
        Ok((from, (slf.get().to_bytes(slf.py()),)))
    }

    fn __len__(&self) -> usize {
        self.source_len()
    }

    fn __repr__(&self) -> String {
        format!(
            "KdTree(n={}, m={}, dtype={}, pivot={})",
            self.source_len(),
            self.m(),
            self.dtype().numpy_name(),
            with_tree!(&self.tree, t, _T => t.options().pivot.name())
        )
    }
}

/// Neighbourhoods as compressed rows (`nbhd::NeighborTable`): row i holds
/// `indices[offsets[i]:offsets[i+1]]` and their `sq_dists`, ordered by (sq_dist, index).
#[pyclass(frozen, module = "nbhd._nbhd", name = "Table")]
pub struct PyTable {
    /// Row starts, one more than there are rows (uint64).
    #[pyo3(get)]
    offsets: Py<PyAny>,
    /// The caller's indices of the neighbours, row after row (uint32).
    #[pyo3(get)]
    indices: Py<PyAny>,
    /// Squared distances, row after row, in the tree's type.
    #[pyo3(get)]
    sq_dists: Py<PyAny>,
    /// Number of points the indices refer to (the tree's n): the columns of `to_csr()`.
    #[pyo3(get)]
    n_points: usize,
    rows: usize,
    /// Row starts, kept for `row()`.
    starts: Vec<usize>,
}

impl PyTable {
    pub(crate) fn new<T: Scalar + Element>(
        py: Python<'_>,
        table: NeighborTable<T>,
        n_points: usize,
    ) -> PyResult<Self> {
        let rows = table.len();
        let (offsets, indices, sq_dists) = table.into_parts();
        let starts = offsets.clone();
        Ok(Self {
            offsets: vec1(py, offsets).into_any().unbind(),
            indices: vec1(py, indices).into_any().unbind(),
            sq_dists: vec1(py, sq_dists).into_any().unbind(),
            n_points,
            rows,
            starts,
        })
    }

    /// The rows as two (rows, width) arrays when every row has the same length (a k-nearest
    /// batch: min(k, size) each).
    pub(crate) fn dense<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let total = *self.starts.last().unwrap_or(&0);
        let width = total.checked_div(self.rows).unwrap_or(0);
        if self.starts.iter().enumerate().any(|(i, &o)| o != i * width) {
            return Err(value_err("internal: k-nearest rows of unequal length"));
        }
        let shape = (self.rows, width);
        let idx = self.indices.bind(py).call_method1("reshape", shape)?;
        let d2 = self.sq_dists.bind(py).call_method1("reshape", shape)?;
        Ok(PyTuple::new(py, [idx, d2])?.into_any())
    }
}

#[pymethods]
impl PyTable {
    /// Number of rows.
    fn __len__(&self) -> usize {
        self.rows
    }

    /// Row i as `(indices, sq_dists)` (views into the table's arrays).
    fn row<'py>(&self, py: Python<'py>, i: usize) -> PyResult<Bound<'py, PyTuple>> {
        if i >= self.rows {
            return Err(crate::errors::nbhd_err(NbhdError::IndexOutOfRange {
                index: i,
                count: self.rows,
            }));
        }
        let (a, b) = (self.starts[i], self.starts[i + 1]);
        let slice = pyo3::types::PySlice::new(py, a as isize, b as isize, 1);
        let idx = self.indices.bind(py).get_item(&slice)?;
        let d2 = self.sq_dists.bind(py).get_item(&slice)?;
        PyTuple::new(py, [idx, d2])
    }

    /// Number of entries in each row (uint64).
    fn row_lengths<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<usize>> {
        vec1(py, self.starts.windows(2).map(|w| w[1] - w[0]).collect())
    }

    /// The table as a `scipy.sparse.csr_matrix` of shape (rows, n_points) whose entries are the
    /// squared distances (`distances=True`: the distances, as cKDTree's
    /// `sparse_distance_matrix` gives). Entries at distance 0 (duplicates, or the point itself
    /// with `exclude_self=False`) are stored explicitly, so the sparsity pattern is the table.
    #[pyo3(signature = (*, distances = false))]
    fn to_csr<'py>(&self, py: Python<'py>, distances: bool) -> PyResult<Bound<'py, PyAny>> {
        let np = py.import("numpy")?;
        let sparse = py.import("scipy.sparse")?;
        let mut data = self.sq_dists.bind(py).clone();
        if distances {
            data = np.call_method1("sqrt", (data,))?;
        }
        let index_type = if self.n_points <= i32::MAX as usize
            && *self.starts.last().unwrap_or(&0) <= i32::MAX as usize
        {
            "int32"
        } else {
            "int64"
        };
        let indices = self
            .indices
            .bind(py)
            .call_method1("astype", (index_type,))?;
        let indptr = self
            .offsets
            .bind(py)
            .call_method1("astype", (index_type,))?;
        let args = PyTuple::new(py, [data, indices, indptr])?;
        let kwargs = PyDict::new(py);
        kwargs.set_item("shape", (self.rows, self.n_points))?;
        sparse.call_method("csr_matrix", (args,), Some(&kwargs))
    }

    fn __repr__(&self) -> String {
        format!(
            "Table(rows={}, entries={}, n_points={})",
            self.rows,
            self.starts.last().unwrap_or(&0),
            self.n_points
        )
    }
}
