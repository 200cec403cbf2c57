//! `nbhd.KdTree` and `nbhd.Table`: the k-d tree of `nbhd::tree` over an (n, d) numpy array of
//! float32 or float64, its single and batch queries, and its all-point tables as compressed rows.

use nbhd::handle::AnyIndex;
use nbhd::{NbhdError, NeighborTable, Scalar};
use numpy::{Element, PyArray1, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};

use crate::arrays::{check_rows, float_array, vec1, vec2, Dtype, Points};
use crate::errors::{value_err, OrRaise};
use crate::index::{dtype, index_pymethods};
use crate::options;

/// A k-d tree over the rows of an (n, d) array (thesis Chapter 3; `nbhd::KdTree`).
///
/// The tree keeps its own compact copy of the points, so the array may change afterwards. It
/// is immutable and may be queried from many Python threads at once; every query and table
/// releases the GIL while it runs.
#[pyclass(frozen, module = "nbhd._nbhd", name = "KdTree")]
pub struct PyKdTree {
    /// Always a static tree.
    pub(crate) index: AnyIndex,
}

index_pymethods!(
    PyKdTree,
    name = "KdTree",
    held = "stored points",
    absent = "skipped non-finite points",
    len = "tree.n",
    growing = false,
    {
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
        /// boxsize: a periodic box (a torus, scipy's `boxsize`): one size L for every axis or one
        /// per axis, 0 (or inf) for an open axis. Points must lie in [0, L) on the periodic axes
        /// (else `NbhdValueError`); every query is wrapped into the box and measures each axis
        /// difference at its nearest image, under any `p`.
        #[new]
        #[pyo3(signature = (points, *, pivot = "sliding-midpoint", median = "floyd-rivest",
                        leaf_size = nbhd::tree::DEFAULT_LEAF_SIZE, non_finite = "reject",
                        threads = 0, boxsize = None))]
        #[allow(clippy::too_many_arguments)]
        fn new(
            py: Python<'_>,
            points: &Bound<'_, PyAny>,
            pivot: &str,
            median: &str,
            leaf_size: usize,
            non_finite: &str,
            threads: usize,
            boxsize: Option<&Bound<'_, PyAny>>,
        ) -> PyResult<Self> {
            let options = options::build(pivot, median, leaf_size, non_finite, threads)?;
            let boxsize = options::boxsize(boxsize)?;
            let build = |view: &nbhd::PointsView<'_>| match &boxsize {
                Some(b) => AnyIndex::build_periodic(view, &options, b),
                None => AnyIndex::build(view, &options),
            };
            let (arr, dtype) = float_array(points, None)?;
            check_rows(&arr, "d")?;
            let index = match dtype {
                Dtype::F32 => {
                    let pts = Points::<f32>::new(&arr)?;
                    let view = pts.view().or_raise()?;
                    py.detach(|| build(&view)).or_raise()?
                }
                Dtype::F64 => {
                    let pts = Points::<f64>::new(&arr)?;
                    let view = pts.view().or_raise()?;
                    py.detach(|| build(&view)).or_raise()?
                }
            };
            Ok(Self { index })
        }

        /// Number of rows of the array the tree was built from (skipped points included).
        #[getter]
        fn n(&self) -> usize {
            self.index.source_len()
        }

        /// Caller indices in tree order (the points of one leaf are adjacent).
        #[getter]
        fn tree_order<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<u32>> {
            let order = self
                .index
                .tree_order()
                .expect("a KdTree holds a static tree");
            vec1(py, order.to_vec())
        }

        /// The tree's nodes in preorder (`nbhd::KdTree::nodes`), as a dict of equal-length
        /// arrays: `level` (edges from the root), `split_dim` (-1 for a leaf), `split` (float64;
        /// left subtree ≤ split ≤ right subtree, so points equal to the split may lie on both
        /// sides), `left` and `right` (the children's positions in this list, -1 for a leaf),
        /// `start` and `end` (the node's points are `tree_order[start:end]`). Identical points
        /// are split by index like any others: every leaf holds at most `leaf_size` points.
        fn nodes<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
            let nodes = self.index.nodes().expect("a KdTree holds a static tree");
            let column = |f: &dyn Fn(&nbhd::NodeInfo<f64>) -> i64| -> Vec<i64> {
                nodes.iter().map(f).collect()
            };
            let d = PyDict::new(py);
            d.set_item("level", vec1(py, column(&|n| n.level as i64)))?;
            let dim = column(&|n| n.split_dim.map_or(-1, |k| k as i64));
            d.set_item("split_dim", vec1(py, dim))?;
            d.set_item("split", vec1(py, nodes.iter().map(|n| n.split).collect()))?;
            let left = column(&|n| n.children.map_or(-1, |c| c.0 as i64));
            let right = column(&|n| n.children.map_or(-1, |c| c.1 as i64));
            d.set_item("left", vec1(py, left))?;
            d.set_item("right", vec1(py, right))?;
            d.set_item("start", vec1(py, column(&|n| n.start as i64)))?;
            d.set_item("end", vec1(py, column(&|n| n.end as i64)))?;
            Ok(d)
        }

        /// The sum of `weights` (one per row of the array the tree was built from) over each
        /// node's points, in the order of `nodes()` (scipy's `_build_weights`): float64, a
        /// leaf summed in tree order, an internal node as its left child's sum plus its right
        /// child's. A length other than `n` or a non-finite weight raises `NbhdValueError`.
        fn node_weights<'py>(
            &self,
            py: Python<'py>,
            weights: Vec<f64>,
        ) -> PyResult<Bound<'py, PyArray1<f64>>> {
            let sums = self
                .index
                .node_weights(&weights)
                .expect("a KdTree holds a static tree")
                .or_raise()?;
            Ok(vec1(py, sums))
        }

        /// Depth, node counts and memory: a dict of `points`, `dim`, `depth`, `nodes`, `leaves`,
        /// `max_leaf_points`, `bytes`.
        fn stats<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
            let s = self
                .index
                .tree_stats()
                .expect("a KdTree holds a static tree");
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
            let o = *self.index.options();
            let d = PyDict::new(py);
            d.set_item("pivot", o.pivot.name())?;
            d.set_item("median", o.median.name())?;
            d.set_item("leaf_size", o.leaf_size)?;
            d.set_item("non_finite", o.non_finite.name())?;
            Ok(d)
        }

        fn __len__(&self) -> usize {
            self.index.source_len()
        }

        fn __repr__(&self) -> String {
            format!(
                "KdTree(n={}, m={}, dtype={}, pivot={})",
                self.index.source_len(),
                self.index.dim(),
                dtype(&self.index).numpy_name(),
                self.index.options().pivot.name()
            )
        }
    }
);

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
    /// The metric the rows were measured in: `sq_dists` hold its keys (`to_csr`).
    metric: nbhd::Metric,
}

impl PyTable {
    pub(crate) fn new<T: Scalar + Element>(
        py: Python<'_>,
        table: NeighborTable<T>,
        n_points: usize,
        metric: nbhd::Metric,
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
            metric,
        })
    }

    /// The rows as two (rows, width) arrays when every row has the same length (a k-nearest
    /// batch: min(k, size) each, `width`; a batch of no query is (0, width)).
    pub(crate) fn dense<'py>(&self, py: Python<'py>, width: usize) -> PyResult<Bound<'py, PyAny>> {
        let total = *self.starts.last().unwrap_or(&0);
        let width = total.checked_div(self.rows).unwrap_or(width);
        if self.starts.iter().enumerate().any(|(i, &o)| o != i * width) {
            return Err(value_err("internal: k-nearest rows of unequal length"));
        }
        let shape = (self.rows, width);
        let idx = self.indices.bind(py).call_method1("reshape", shape)?;
        let d2 = self.sq_dists.bind(py).call_method1("reshape", shape)?;
        Ok(PyTuple::new(py, [idx, d2])?.into_any())
    }
}

/// The `(row, column)` pairs of the entries of the rows `starts` (their columns `cols`), row
/// after row, as one flat `intp` vector: written by every core, blocks of rows each (the
/// zeroed vector's pages are first touched by the threads that fill them).
fn stacked_pairs(starts: &[usize], cols: &[u32]) -> Vec<isize> {
    use rayon::prelude::*;
    const ROWS_PER_BLOCK: usize = 16_384;
    let rows = starts.len().saturating_sub(1);
    let mut both = vec![0isize; 2 * cols.len()];
    let mut parts = Vec::with_capacity(rows.div_ceil(ROWS_PER_BLOCK));
    let mut rest = &mut both[..];
    for lo in (0..rows).step_by(ROWS_PER_BLOCK) {
        let hi = (lo + ROWS_PER_BLOCK).min(rows);
        let (part, next) = rest.split_at_mut(2 * (starts[hi] - starts[lo]));
        parts.push((lo, hi, part));
        rest = next;
    }
    parts.into_par_iter().for_each(|(lo, hi, part)| {
        let mut out = part.chunks_exact_mut(2);
        for i in lo..hi {
            for (&j, o) in cols[starts[i]..starts[i + 1]].iter().zip(&mut out) {
                o.copy_from_slice(&[i as isize, j as isize]);
            }
        }
    });
    both
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

    /// The entries' coordinates, row after row: `(rows, cols)`, the row and the column (the
    /// neighbour's index) of every entry as intp arrays — scipy.sparse's COO form, whose data
    /// are `sq_dists`. With `stacked=True` one (entries, 2) intp array of `(row, col)` pairs
    /// instead (scipy's `query_pairs(output_type='ndarray')`).
    #[pyo3(signature = (*, stacked = false))]
    fn coordinates<'py>(&self, py: Python<'py>, stacked: bool) -> PyResult<Bound<'py, PyAny>> {
        let indices = self.indices.bind(py).cast::<PyArray1<u32>>()?.readonly();
        let cols = indices.as_slice()?;
        let total = cols.len();
        let rows = self.starts.windows(2).enumerate();
        if stacked {
            let starts = &self.starts;
            let both = py.detach(|| stacked_pairs(starts, cols));
            return Ok(vec2(py, both, total, 2)?.into_any());
        }
        let mut of_row: Vec<isize> = Vec::with_capacity(total);
        for (i, w) in rows {
            of_row.resize(w[1], i as isize);
        }
        let of_col: Vec<isize> = cols.iter().map(|&j| j as isize).collect();
        let pair = [vec1(py, of_row).into_any(), vec1(py, of_col).into_any()];
        Ok(PyTuple::new(py, pair)?.into_any())
    }

    /// Number of entries in each row (uint64).
    fn row_lengths<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<usize>> {
        vec1(py, self.starts.windows(2).map(|w| w[1] - w[0]).collect())
    }

    /// The table as a `scipy.sparse.csr_matrix` of shape (rows, n_points) whose entries are the
    /// squared distances (`distances=True`: the distances, as cKDTree's
    /// `sparse_distance_matrix` gives). Entries at distance 0 (duplicates, or the point itself
    /// with `exclude_self=False`) are stored explicitly, so the sparsity pattern is the table.
    /// With `distances=True` the keys become distances in the table's metric: the square root
    /// for p = 2, the p-th root for any other finite p > 1; for p = 1 and ∞ they already are.
    #[pyo3(signature = (*, distances = false))]
    fn to_csr<'py>(&self, py: Python<'py>, distances: bool) -> PyResult<Bound<'py, PyAny>> {
        let np = py.import("numpy")?;
        let sparse = py.import("scipy.sparse")?;
        let mut data = self.sq_dists.bind(py).clone();
        if distances {
            // the keys' distances, as `nbhd::Metric::distance_of` (and scipy) computes them
            data = match self.metric {
                nbhd::Metric::Euclidean => np.call_method1("sqrt", (data,))?,
                nbhd::Metric::Manhattan | nbhd::Metric::Chebyshev => data.call_method0("copy")?,
                nbhd::Metric::Minkowski(p) => np.call_method1("power", (data, 1.0 / p))?,
            };
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
