//! `nbhd.DynamicKdTree`: the tree of `nbhd::dynamic` that accepts insertions (in batches) and
//! removals (by index), with the static tree's queries and tables, and pickling through the
//! library's saved format.

use nbhd::handle::AnyIndex;
use nbhd::{with_index, NeighborIndex, Query, ScalarType};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::arrays::{check_rows, float_array, vec1, Dtype, Points};
use crate::errors::{value_err, OrRaise};
use crate::index::{dtype, index_pymethods};
use crate::options;

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
    /// Always a growing tree.
    pub(crate) index: AnyIndex,
}

/// Inserts the rows of `arr` (of the tree's dtype `T`) into the growing `index`.
fn insert_rows<T: nbhd::Scalar + numpy::Element>(
    index: &mut AnyIndex,
    py: Python<'_>,
    arr: &Bound<'_, PyAny>,
) -> PyResult<u32> {
    let pts = Points::<T>::new(arr)?;
    let view = pts.view().or_raise()?;
    py.detach(|| index.insert(&view)).or_raise()
}

impl PyDynamicKdTree {
    /// The growing tree's statistics.
    fn growing(&self) -> nbhd::dynamic::DynamicStats {
        self.index
            .growing_stats()
            .expect("a DynamicKdTree holds a growing tree")
    }

    /// Indices given so far.
    fn next(&self) -> usize {
        self.index.source_len()
    }
}

index_pymethods!(
    PyDynamicKdTree,
    name = "DynamicKdTree",
    held = "live points",
    absent = "removed and skipped points",
    len = "tree.next_index",
    growing = true,
    {
        /// An empty tree for points of dimension `dim`, computing in `dtype` ("float32" or
        /// "float64"). The build options shape every static tree of the forest (as in `KdTree`);
        /// `non_finite` decides what inserting a NaN/Inf point does: "reject" raises and inserts
        /// nothing of the batch, "skip" gives it its index but leaves it out. `growth` (≥ 2): a
        /// tree is merged into the next older one while that holds fewer than `growth` times its
        /// points — larger keeps fewer trees (faster queries) for more rebuilding.
        /// `boxsize` makes the tree periodic, as in `KdTree` (inserted points must lie in the box).
        #[new]
        #[pyo3(signature = (dim, *, dtype = "float32", pivot = "sliding-midpoint",
                        median = "floyd-rivest", leaf_size = nbhd::tree::DEFAULT_LEAF_SIZE,
                        non_finite = "reject", threads = 0, growth = nbhd::dynamic::GROWTH,
                        boxsize = None))]
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
            boxsize: Option<&Bound<'_, PyAny>>,
        ) -> PyResult<Self> {
            let options = options::build(pivot, median, leaf_size, non_finite, threads)?;
            let scalar = match dtype {
                "float32" => ScalarType::F32,
                "float64" => ScalarType::F64,
                other => {
                    return Err(value_err(format!(
                        "dtype {other:?}: \"float32\" or \"float64\""
                    )))
                }
            };
            let mut index = match options::boxsize(boxsize)? {
                Some(b) => AnyIndex::growing_periodic(dim, scalar, &options, &b),
                None => AnyIndex::growing(dim, scalar, &options),
            }
            .or_raise()?;
            index.set_growth(growth).or_raise()?;
            Ok(Self { index })
        }

        /// Inserts the rows of `points` (an (n, dim) array, converted to the tree's dtype) as one
        /// batch and returns the index of the first: the batch gets `first .. first + n`.
        fn insert(&mut self, py: Python<'_>, points: &Bound<'_, PyAny>) -> PyResult<u32> {
            let (arr, _) = float_array(points, Some(dtype(&self.index)))?;
            check_rows(&arr, "d")?;
            match dtype(&self.index) {
                Dtype::F32 => insert_rows::<f32>(&mut self.index, py, &arr),
                Dtype::F64 => insert_rows::<f64>(&mut self.index, py, &arr),
            }
        }

        /// Removes the live points `indices` (any order; all or nothing). Their indices are never
        /// given again.
        fn remove(&mut self, py: Python<'_>, indices: Vec<u32>) -> PyResult<()> {
            let index = &mut self.index;
            py.detach(|| index.remove(&indices)).or_raise()
        }

        /// Worker threads of the builds that `insert` and `remove` run: 0 a thread per core, 1
        /// serially, n a pool of n (at most 1024). A tree read by `from_bytes` (or unpickled)
        /// starts at 0 whatever the bytes say: saved data is untrusted input.
        #[getter]
        fn threads(&self) -> usize {
            self.index.options().threads
        }

        #[setter]
        fn set_threads(&mut self, threads: usize) -> PyResult<()> {
            self.index.set_threads(threads).or_raise()
        }

        /// Indices given so far (live, removed and skipped): the rows of `neighborhoods`.
        #[getter]
        fn next_index(&self) -> usize {
            self.next()
        }

        /// Whether `index` names a live point.
        fn is_live(&self, index: u32) -> bool {
            self.index.is_live(index)
        }

        /// `live`, `next_index` and `trees`: a list of (live, removed) points per static tree,
        /// oldest first.
        fn stats<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
            let s = self.growing();
            let d = PyDict::new(py);
            d.set_item("live", s.live)?;
            d.set_item("next_index", s.next_index)?;
            d.set_item("trees", s.trees)?;
            Ok(d)
        }

        /// The coordinates of the live point `index` (raises if removed, skipped or not given).
        fn point<'py>(&self, py: Python<'py>, index: u32) -> PyResult<Bound<'py, PyAny>> {
            with_index!(&self.index, t, _T => {
                // the library's error for an index out of range, removed or skipped
                let (p, _) = t.resolve(Query::stored(index)).or_raise()?;
                Ok(vec1(py, p.to_vec()).into_any())
            })
        }

        fn __len__(&self) -> usize {
            self.index.len()
        }

        fn __repr__(&self) -> String {
            format!(
                "DynamicKdTree(live={}, next_index={}, m={}, dtype={})",
                self.size(),
                self.next(),
                self.m(),
                dtype(&self.index).numpy_name()
            )
        }
    }
);
