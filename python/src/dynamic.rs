//! `nbhd.DynamicKdTree`: the tree of `nbhd::dynamic` that accepts insertions (in batches) and
//! removals (by index), with the static tree's queries and tables, and pickling through the
//! library's saved format.

use nbhd::dynamic::{DynamicKdTree, SavedDynamicInfo};
use nbhd::{
    BuildOptions, NbhdError, NeighborIndex, NeighborSearch, Query, ScalarType, TableOptions,
};
use numpy::{PyArray1, PyArrayMethods, PyReadonlyArray1};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict, PyType};

use crate::arrays::{float_array, ndim, vec1, Dtype, Points};
use crate::errors::{value_err, OrRaise};
use crate::options;
use crate::tree::{neighborhood, pair, queries, Answer, PyTable};

/// The dynamic tree of either scalar type.
enum Dyn {
    F32(DynamicKdTree<f32>),
    F64(DynamicKdTree<f64>),
}

/// Runs `$body` with `$t` bound to the tree of either type and `$T` to its scalar type.
macro_rules! with_dyn {
    ($tree:expr, $t:ident, $T:ident => $body:expr) => {
        match $tree {
            Dyn::F32($t) => {
                type $T = f32;
                $body
            }
            Dyn::F64($t) => {
                type $T = f64;
                $body
            }
        }
    };
}

/// A k-d tree that accepts insertions and removals (`nbhd::DynamicKdTree`): a forest of static
/// trees of growing sizes with removed points as tombstones. Every query answers exactly what
/// a `KdTree` over the live points answers, under the indices the points were given.
///
/// Index rule: each inserted batch gets consecutive indices continuing from the previous one
/// (the first batch gets 0..n); a point keeps its index until removed, and a removed index is
/// never given again (querying or removing it raises).
///
/// Queries release the GIL and may run from many threads; `insert` and `remove` need the tree
/// to themselves (another thread's call meanwhile raises "Already borrowed").
#[pyclass(module = "nbhd._nbhd", name = "DynamicKdTree")]
pub struct PyDynamicKdTree {
    tree: Dyn,
}

impl PyDynamicKdTree {
    fn dtype(&self) -> Dtype {
        match self.tree {
            Dyn::F32(_) => Dtype::F32,
            Dyn::F64(_) => Dtype::F64,
        }
    }

    fn next(&self) -> usize {
        with_dyn!(&self.tree, t, _T => t.next_index() as usize)
    }

    /// As `KdTree.query`: a single point answered by the tree's search, or a batch as a table.
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
        let rows = self.next();
        with_dyn!(&self.tree, t, T => {
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
                Ok(Answer::Many(PyTable::new(py, table, rows)?))
            }
        })
    }
}

#[pymethods]
impl PyDynamicKdTree {
    /// An empty tree for points of dimension `dim`, computing in `dtype` ("float32" or
    /// "float64"). The build options shape every static tree of the forest (as in `KdTree`);
    /// `non_finite` decides what inserting a NaN/Inf point does: "reject" raises and inserts
    /// nothing of the batch, "skip" gives it its index but leaves it out. `growth` (≥ 2): a
    /// tree is merged into the next older one while that holds fewer than `growth` times its
    /// points — larger keeps fewer trees (faster queries) for more rebuilding.
    #[new]
    #[pyo3(signature = (dim, *, dtype = "float32", pivot = "sliding-midpoint",
                        median = "floyd-rivest", leaf_size = nbhd::tree::DEFAULT_LEAF_SIZE,
                        non_finite = "reject", threads = 0, growth = nbhd::dynamic::GROWTH))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        dim: usize,
        dtype: &str,
        pivot: &str,
        median: &str,
        leaf_size: usize,
        non_finite: &str,
        threads: usize,
        growth: usize,
    ) -> PyResult<Self> {
        let options = BuildOptions {
            pivot: options::pivot(pivot)?,
            median: options::median(median)?,
            leaf_size,
            non_finite: options::non_finite(non_finite)?,
            threads,
        };
        let mut tree = match dtype {
            "float32" => Dyn::F32(DynamicKdTree::new(dim, &options).or_raise()?),
            "float64" => Dyn::F64(DynamicKdTree::new(dim, &options).or_raise()?),
            other => {
                return Err(value_err(format!(
                    "dtype {other:?}: \"float32\" or \"float64\""
                )))
            }
        };
        with_dyn!(&mut tree, t, _T => t.set_growth(growth).or_raise()?);
        Ok(Self { tree })
    }

    /// Inserts the rows of `points` (an (n, dim) array, converted to the tree's dtype) as one
    /// batch and returns the index of the first: the batch gets `first .. first + n`.
    fn insert(&mut self, py: Python<'_>, points: &Bound<'_, PyAny>) -> PyResult<u32> {
        let (arr, _) = float_array(points, Some(self.dtype()))?;
        if ndim(&arr)? != 2 {
            return Err(value_err(format!(
                "points must be a 2-D array (n, d), not {}-D",
                ndim(&arr)?
            )));
        }
        with_dyn!(&mut self.tree, t, T => {
            let pts = Points::<T>::new(&arr)?;
            let view = pts.view().or_raise()?;
            py.detach(|| t.insert(&view)).or_raise()
        })
    }

    /// Removes the live points `indices` (any order; all or nothing). Their indices are never
    /// given again.
    fn remove(&mut self, py: Python<'_>, indices: Vec<u32>) -> PyResult<()> {
        with_dyn!(&mut self.tree, t, _T => py.detach(|| t.remove(&indices)).or_raise())
    }

    /// Live points.
    #[getter]
    fn size(&self) -> usize {
        with_dyn!(&self.tree, t, _T => t.len())
    }

    /// Indices given so far (live, removed and skipped): the rows of `neighborhoods`.
    #[getter]
    fn next_index(&self) -> usize {
        self.next()
    }

    /// Dimension of the points.
    #[getter]
    fn m(&self) -> usize {
        with_dyn!(&self.tree, t, _T => t.dim())
    }

    /// The tree's scalar type: "float32" or "float64".
    #[getter]
    fn dtype_name(&self) -> &'static str {
        self.dtype().numpy_name()
    }

    /// Whether `index` names a live point.
    fn is_live(&self, index: u32) -> bool {
        with_dyn!(&self.tree, t, _T => t.is_live(index))
    }

    /// `live`, `next_index` and `trees`: a list of (live, removed) points per static tree,
    /// oldest first.
    fn stats<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let s = with_dyn!(&self.tree, t, _T => t.stats());
        let d = PyDict::new(py);
        d.set_item("live", s.live)?;
        d.set_item("next_index", s.next_index)?;
        d.set_item("trees", s.trees)?;
        Ok(d)
    }

    /// The coordinates of the live point `index` (raises if removed, skipped or not given).
    fn point<'py>(&self, py: Python<'py>, index: u32) -> PyResult<Bound<'py, PyAny>> {
        with_dyn!(&self.tree, t, _T => match t.point(index) {
            Some(p) => Ok(vec1(py, p.to_vec()).into_any()),
            None => {
                // The library's error for this index: out of range, removed or skipped.
                let mut out = Vec::new();
                t.search(Query::stored(index), nbhd::Neighborhood::Knn { k: 1 }, &mut out)
                    .or_raise()?;
                Err(value_err(format!("index {index} is not live")))
            }
        })
    }

    /// The `k` nearest live points of `x`; as `KdTree.knn`.
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

    /// All live points within `radius` of `x`; as `KdTree.radius`.
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

    /// The `k` nearest among the live points within `radius` of `x`; as `KdTree.knn_radius`.
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

    /// The neighbourhood of every live point as a `Table` with a row per index given (empty
    /// for points not live); as `KdTree.neighborhoods`.
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
        let rows = self.next();
        with_dyn!(&self.tree, t, T => {
            let nbhd = neighborhood::<T>(k, radius, sorted)?;
            let opts = TableOptions { exclude_self, threads };
            let table = py.detach(|| t.neighborhoods(nbhd, &opts)).or_raise()?;
            PyTable::new(py, table, rows)
        })
    }

    /// The tree in the saved dynamic-tree format (docs/tree-file-format.md) as `bytes`; what
    /// `pickle` stores and `DynamicKdTree.from_bytes` reads back.
    fn to_bytes<'py>(&self, py: Python<'py>) -> Bound<'py, PyBytes> {
        let bytes = py.detach(|| with_dyn!(&self.tree, t, _T => t.to_bytes()));
        PyBytes::new(py, &bytes)
    }

    /// The dynamic tree saved in `data`, of the dtype it was saved with: it answers every
    /// query exactly as the saved one did and continues its indices. Damaged, truncated or
    /// foreign bytes (a saved static `KdTree` included) raise `NbhdValueError` naming what
    /// differs.
    #[classmethod]
    fn from_bytes(cls: &Bound<'_, PyType>, data: &[u8]) -> PyResult<Self> {
        let tree = cls
            .py()
            .detach(|| -> Result<Dyn, NbhdError> {
                Ok(match SavedDynamicInfo::from_bytes(data)?.scalar {
                    ScalarType::F32 => Dyn::F32(DynamicKdTree::from_bytes(data)?),
                    ScalarType::F64 => Dyn::F64(DynamicKdTree::from_bytes(data)?),
                })
            })
            .or_raise()?;
        Ok(Self { tree })
    }

    /// Pickling: `DynamicKdTree.from_bytes(tree.to_bytes())`.
    fn __reduce__<'py>(
        slf: &Bound<'py, Self>,
    ) -> PyResult<(Bound<'py, PyAny>, (Bound<'py, PyBytes>,))> {
        let from = slf.get_type().getattr("from_bytes")?;
        let bytes = slf.borrow().to_bytes(slf.py());
        Ok((from, (bytes,)))
    }

    fn __len__(&self) -> usize {
        with_dyn!(&self.tree, t, _T => t.len())
    }

    fn __repr__(&self) -> String {
        format!(
            "DynamicKdTree(live={}, next_index={}, m={}, dtype={})",
            self.size(),
            self.next(),
            self.m(),
            self.dtype().numpy_name()
        )
    }
}
