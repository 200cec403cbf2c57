//! The runtime handle of a neighbour index: a static or a growing tree of either scalar type,
//! chosen at run time ([`AnyIndex`]), and a table of either scalar type ([`AnyTable`]). The C
//! ABI's `nbhd_tree` and `nbhd_dynamic_tree` and Python's `KdTree` and `DynamicKdTree` hold an
//! [`AnyIndex`] and bind each of their calls once, over [`NeighborIndex`]: the dispatch over the
//! four kinds of index is written here, once ([`with_index!`](crate::with_index)).
//!
//! ```
//! use nbhd::handle::AnyIndex;
//! use nbhd::{BuildOptions, NeighborhoodSpec, PointsView, ScalarType, TableOptions};
//!
//! let pts = [0.0f64, 0.0, 1.0, 0.0, 0.0, 1.0, 3.0, 3.0];
//! let view = PointsView::from_flat(&pts, 2)?;
//! let fixed = AnyIndex::build(&view, &BuildOptions::default())?;
//! let mut growing = AnyIndex::growing(2, ScalarType::F64, &BuildOptions::default())?;
//! growing.insert(&view)?;
//! let spec = NeighborhoodSpec::knn(2);
//! let a = fixed.neighborhoods(spec, &TableOptions::default())?;
//! let b = growing.neighborhoods(spec, &TableOptions::default())?;
//! assert_eq!(a, b);
//! # Ok::<(), nbhd::NbhdError>(())
//! ```

use std::io::Write;

use crate::dynamic::{DynamicKdTree, DynamicStats, SavedDynamicInfo};
use crate::error::{NbhdError, Result};
use crate::filter::{
    radius_outlier_removal, statistical_outlier_removal, Kept, RadiusOutlierOptions,
    StatisticalOutlierOptions,
};
use crate::index::{IndexRows, NeighborIndex, PairWeights, Spacing};
use crate::points::PointsView;
use crate::query::{NeighborSearch, NeighborhoodSpec};
use crate::scalar::{Scalar, ScalarType};
use crate::table::{NeighborTable, TableOptions};
use crate::tree::{BuildOptions, KdTree, NodeInfo, Persist, SavedTreeInfo, TreeStats};

/// Runs `$body` with `$a` and `$b` bound to the typed indexes inside two [`AnyIndex`] of the
/// same scalar type (any flavours) and `$T` to that type; indexes of different scalar types
/// are [`NbhdError::InvalidOption`] (a pair query compares coordinates of one type).
macro_rules! with_pair {
    ($x:expr, $y:expr, $a:ident, $b:ident, $T:ident => $body:expr) => {{
        use AnyIndex::{GrowingF32 as G32, GrowingF64 as G64, StaticF32 as S32, StaticF64 as S64};
        match ($x, $y) {
            (S32($a), S32($b)) => with_pair!(@ f32, $T => $body),
            (S32($a), G32($b)) => with_pair!(@ f32, $T => $body),
            (G32($a), S32($b)) => with_pair!(@ f32, $T => $body),
            (G32($a), G32($b)) => with_pair!(@ f32, $T => $body),
            (S64($a), S64($b)) => with_pair!(@ f64, $T => $body),
            (S64($a), G64($b)) => with_pair!(@ f64, $T => $body),
            (G64($a), S64($b)) => with_pair!(@ f64, $T => $body),
            (G64($a), G64($b)) => with_pair!(@ f64, $T => $body),
            (x, y) => Err(NbhdError::InvalidOption {
                name: "other",
                reason: format!(
                    "pairs need two indexes of one scalar type, got {:?} and {:?}",
                    x.scalar_type(),
                    y.scalar_type()
                ),
            }),
        }
    }};
    (@ $t:ty, $T:ident => $body:expr) => {{
        #[allow(dead_code)]
        type $T = $t;
        $body
    }};
}

/// A neighbour index whose flavour and scalar type are chosen at run time.
#[derive(Debug)]
pub enum AnyIndex {
    /// A static k-d tree of `f32` coordinates.
    StaticF32(KdTree<f32>),
    /// A static k-d tree of `f64` coordinates.
    StaticF64(KdTree<f64>),
    /// A growing tree of `f32` coordinates.
    GrowingF32(DynamicKdTree<f32>),
    /// A growing tree of `f64` coordinates.
    GrowingF64(DynamicKdTree<f64>),
}

/// Runs `$body` with `$t` bound to the typed index inside an [`AnyIndex`] (`&` or `&mut`, as
/// `$index` is) and `$T` to its scalar type: the one dispatch over the four kinds of index.
/// The body may use what every flavour has ([`NeighborIndex`], `NeighborSearch`).
#[macro_export]
macro_rules! with_index {
    ($index:expr, $t:ident, $T:ident => $body:expr) => {
        match $index {
            $crate::handle::AnyIndex::StaticF32($t) => {
                #[allow(dead_code)]
                type $T = f32;
                $body
            }
            $crate::handle::AnyIndex::StaticF64($t) => {
                #[allow(dead_code)]
                type $T = f64;
                $body
            }
            $crate::handle::AnyIndex::GrowingF32($t) => {
                #[allow(dead_code)]
                type $T = f32;
                $body
            }
            $crate::handle::AnyIndex::GrowingF64($t) => {
                #[allow(dead_code)]
                type $T = f64;
                $body
            }
        }
    };
}

/// Runs `$body` with `$t` bound to the typed table inside an [`AnyTable`].
#[macro_export]
macro_rules! with_table {
    ($table:expr, $t:ident => $body:expr) => {
        match $table {
            $crate::handle::AnyTable::F32($t) => $body,
            $crate::handle::AnyTable::F64($t) => $body,
        }
    };
}

/// A neighbour table of either scalar type (that of the index it came from).
#[derive(Clone, Debug, PartialEq)]
pub enum AnyTable {
    /// Squared distances in `f32`.
    F32(NeighborTable<f32>),
    /// Squared distances in `f64`.
    F64(NeighborTable<f64>),
}

impl From<NeighborTable<f32>> for AnyTable {
    fn from(t: NeighborTable<f32>) -> Self {
        AnyTable::F32(t)
    }
}

impl From<NeighborTable<f64>> for AnyTable {
    fn from(t: NeighborTable<f64>) -> Self {
        AnyTable::F64(t)
    }
}

impl AnyTable {
    /// The scalar type of the squared distances.
    pub fn scalar_type(&self) -> ScalarType {
        match self {
            AnyTable::F32(_) => ScalarType::F32,
            AnyTable::F64(_) => ScalarType::F64,
        }
    }

    /// Row boundaries: row `i` is `offsets[i]..offsets[i + 1]`.
    pub fn offsets(&self) -> &[usize] {
        with_table!(self, t => t.offsets())
    }

    /// All neighbour indices, row after row.
    pub fn indices(&self) -> &[u32] {
        with_table!(self, t => t.indices())
    }

    /// Number of rows.
    pub fn len(&self) -> usize {
        self.offsets().len().saturating_sub(1)
    }

    /// `true` if the table has no rows.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

impl AnyIndex {
    /// A static tree over `points`, computing in their scalar type ([`KdTree::build`]).
    pub fn build(points: &PointsView<'_>, options: &BuildOptions) -> Result<Self> {
        Ok(match points.scalar_type() {
            ScalarType::F32 => AnyIndex::StaticF32(KdTree::build(points, options)?),
            ScalarType::F64 => AnyIndex::StaticF64(KdTree::build(points, options)?),
        })
    }

    /// A static tree over the listed points of `points` ([`KdTree::build_subset`]).
    pub fn build_subset(
        points: &PointsView<'_>,
        indices: &[u32],
        options: &BuildOptions,
    ) -> Result<Self> {
        Ok(match points.scalar_type() {
            ScalarType::F32 => AnyIndex::StaticF32(KdTree::build_subset(points, indices, options)?),
            ScalarType::F64 => AnyIndex::StaticF64(KdTree::build_subset(points, indices, options)?),
        })
    }

    /// An empty growing tree of dimension `dim` computing in `scalar` ([`DynamicKdTree::new`]).
    pub fn growing(dim: usize, scalar: ScalarType, options: &BuildOptions) -> Result<Self> {
        Ok(match scalar {
            ScalarType::F32 => AnyIndex::GrowingF32(DynamicKdTree::new(dim, options)?),
            ScalarType::F64 => AnyIndex::GrowingF64(DynamicKdTree::new(dim, options)?),
        })
    }

    /// A periodic static tree over `points` ([`KdTree::build_periodic`]).
    pub fn build_periodic(
        points: &PointsView<'_>,
        options: &BuildOptions,
        boxsize: &[f64],
    ) -> Result<Self> {
        Ok(match points.scalar_type() {
            ScalarType::F32 => {
                AnyIndex::StaticF32(KdTree::build_periodic(points, options, boxsize)?)
            }
            ScalarType::F64 => {
                AnyIndex::StaticF64(KdTree::build_periodic(points, options, boxsize)?)
            }
        })
    }

    /// An empty periodic growing tree ([`DynamicKdTree::new_periodic`]).
    pub fn growing_periodic(
        dim: usize,
        scalar: ScalarType,
        options: &BuildOptions,
        boxsize: &[f64],
    ) -> Result<Self> {
        Ok(match scalar {
            ScalarType::F32 => {
                AnyIndex::GrowingF32(DynamicKdTree::new_periodic(dim, options, boxsize)?)
            }
            ScalarType::F64 => {
                AnyIndex::GrowingF64(DynamicKdTree::new_periodic(dim, options, boxsize)?)
            }
        })
    }

    /// The box sizes of a periodic index per axis (0 for an open axis), `None` for an index
    /// without a period ([`Period::sizes`](crate::metric::Period::sizes)).
    pub fn boxsize(&self) -> Option<Vec<f64>> {
        with_index!(self, t, _T => NeighborIndex::period(t).map(|p| p.sizes()))
    }

    /// The index saved in `bytes`, of the scalar type it was saved with: a static tree, or
    /// with `growing` a growing one (the other kind is [`NbhdError::SavedTree`], naming it).
    pub fn from_bytes(bytes: &[u8], growing: bool) -> Result<Self> {
        Ok(if growing {
            match SavedDynamicInfo::from_bytes(bytes)?.scalar {
                ScalarType::F32 => AnyIndex::GrowingF32(DynamicKdTree::from_bytes(bytes)?),
                ScalarType::F64 => AnyIndex::GrowingF64(DynamicKdTree::from_bytes(bytes)?),
            }
        } else {
            match SavedTreeInfo::from_bytes(bytes)?.scalar {
                ScalarType::F32 => AnyIndex::StaticF32(KdTree::from_bytes(bytes)?),
                ScalarType::F64 => AnyIndex::StaticF64(KdTree::from_bytes(bytes)?),
            }
        })
    }

    /// The scalar type of the coordinates, of query points and of squared distances.
    pub fn scalar_type(&self) -> ScalarType {
        match self {
            AnyIndex::StaticF32(_) | AnyIndex::GrowingF32(_) => ScalarType::F32,
            AnyIndex::StaticF64(_) | AnyIndex::GrowingF64(_) => ScalarType::F64,
        }
    }

    /// `true` for a growing tree.
    pub fn is_growing(&self) -> bool {
        matches!(self, AnyIndex::GrowingF32(_) | AnyIndex::GrowingF64(_))
    }

    /// Dimension.
    pub fn dim(&self) -> usize {
        with_index!(self, t, _T => t.dim())
    }

    /// Points held ([`NeighborIndex::len`]).
    pub fn len(&self) -> usize {
        with_index!(self, t, _T => NeighborIndex::len(t))
    }

    /// `true` if no point is held.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The range of caller indices, and the rows of an all-point table.
    pub fn source_len(&self) -> usize {
        with_index!(self, t, _T => t.source_len())
    }

    /// The build options of the tree (of every tree of a growing one).
    pub fn options(&self) -> &BuildOptions {
        with_index!(self, t, _T => t.options())
    }

    /// Depth, node counts and memory of a static tree (`None` for a growing one).
    pub fn tree_stats(&self) -> Option<TreeStats> {
        match self {
            AnyIndex::StaticF32(t) => Some(t.stats()),
            AnyIndex::StaticF64(t) => Some(t.stats()),
            _ => None,
        }
    }

    /// The caller indices in tree order of a static tree (`None` for a growing one).
    pub fn tree_order(&self) -> Option<&[u32]> {
        match self {
            AnyIndex::StaticF32(t) => Some(t.tree_order()),
            AnyIndex::StaticF64(t) => Some(t.tree_order()),
            _ => None,
        }
    }

    /// The nodes of a static tree in preorder (`KdTree::nodes`), splits as `f64` (`None` for a
    /// growing one: a forest of trees that merge as it grows has no one node list).
    pub fn nodes(&self) -> Option<Vec<NodeInfo<f64>>> {
        fn widen<T: Scalar>(n: NodeInfo<T>) -> NodeInfo<f64> {
            NodeInfo {
                split: n.split.to_f64(),
                level: n.level,
                split_dim: n.split_dim,
                start: n.start,
                end: n.end,
                children: n.children,
            }
        }
        match self {
            AnyIndex::StaticF32(t) => Some(t.nodes().into_iter().map(widen).collect()),
            AnyIndex::StaticF64(t) => Some(t.nodes().into_iter().map(widen).collect()),
            _ => None,
        }
    }

    /// Per-node sums of `weights` of a static tree (`KdTree::node_weights`; `None` for a
    /// growing one).
    pub fn node_weights(&self, weights: &[f64]) -> Option<Result<Vec<f64>>> {
        match self {
            AnyIndex::StaticF32(t) => Some(t.node_weights(weights)),
            AnyIndex::StaticF64(t) => Some(t.node_weights(weights)),
            _ => None,
        }
    }

    /// Live points and trees of a growing tree (`None` for a static one).
    pub fn growing_stats(&self) -> Option<DynamicStats> {
        match self {
            AnyIndex::GrowingF32(t) => Some(t.stats()),
            AnyIndex::GrowingF64(t) => Some(t.stats()),
            _ => None,
        }
    }

    /// Whether `index` names a live point (held by the index).
    pub fn is_live(&self, index: u32) -> bool {
        match self {
            AnyIndex::StaticF32(t) => t.point(index).is_some(),
            AnyIndex::StaticF64(t) => t.point(index).is_some(),
            AnyIndex::GrowingF32(t) => t.is_live(index),
            AnyIndex::GrowingF64(t) => t.is_live(index),
        }
    }

    /// Sets the growth factor of a growing tree ([`DynamicKdTree::set_growth`]); a static tree
    /// refuses ([`NbhdError::InvalidOption`]).
    pub fn set_growth(&mut self, growth: usize) -> Result<()> {
        match self {
            AnyIndex::GrowingF32(t) => t.set_growth(growth),
            AnyIndex::GrowingF64(t) => t.set_growth(growth),
            _ => Err(static_tree("grow by a factor of")),
        }
    }

    /// Sets the worker threads of a growing tree's later builds
    /// ([`DynamicKdTree::set_threads`]); a static tree refuses ([`NbhdError::InvalidOption`]).
    pub fn set_threads(&mut self, threads: usize) -> Result<()> {
        match self {
            AnyIndex::GrowingF32(t) => t.set_threads(threads),
            AnyIndex::GrowingF64(t) => t.set_threads(threads),
            _ => Err(static_tree("set the threads of its builds")),
        }
    }

    /// Inserts a batch into a growing tree ([`DynamicKdTree::insert`]); a static tree refuses
    /// ([`NbhdError::InvalidOption`]).
    pub fn insert(&mut self, points: &PointsView<'_>) -> Result<u32> {
        match self {
            AnyIndex::GrowingF32(t) => t.insert(points),
            AnyIndex::GrowingF64(t) => t.insert(points),
            _ => Err(static_tree("insert points")),
        }
    }

    /// Removes points from a growing tree ([`DynamicKdTree::remove`]); a static tree refuses
    /// ([`NbhdError::InvalidOption`]).
    pub fn remove(&mut self, indices: &[u32]) -> Result<()> {
        match self {
            AnyIndex::GrowingF32(t) => t.remove(indices),
            AnyIndex::GrowingF64(t) => t.remove(indices),
            _ => Err(static_tree("remove points")),
        }
    }

    /// [`NeighborIndex::neighborhoods`], the radius converted to the index's type.
    pub fn neighborhoods(
        &self,
        spec: NeighborhoodSpec,
        options: &TableOptions,
    ) -> Result<AnyTable> {
        with_index!(self, t, T => Ok(t.neighborhoods(spec.to_with::<T>(&options.query)?, options)?.into()))
    }

    /// [`NeighborIndex::neighborhoods_at`], the radius converted to the index's type.
    pub fn neighborhoods_at(
        &self,
        indices: &[u32],
        spec: NeighborhoodSpec,
        options: &TableOptions,
    ) -> Result<AnyTable> {
        with_index!(self, t, T => Ok(t.neighborhoods_at(indices, spec.to_with::<T>(&options.query)?, options)?.into()))
    }

    /// [`NeighborIndex::neighborhoods_of`], the queries converted to the index's type.
    pub fn neighborhoods_of(
        &self,
        queries: &PointsView<'_>,
        spec: NeighborhoodSpec,
        options: &TableOptions,
    ) -> Result<AnyTable> {
        with_index!(self, t, T => Ok(t.neighborhoods_of(queries, spec.to_with::<T>(&options.query)?, options)?.into()))
    }

    /// The points in each box of a batch ([`NeighborIndex::in_boxes`]): `boxes` holds one box
    /// per point of dimension `2 · dim` (its `min` corner, then its `max` corner), converted to
    /// the index's type (exactly, when it is that type).
    pub fn in_boxes(&self, boxes: &PointsView<'_>, threads: usize) -> Result<IndexRows> {
        if boxes.dim() != 2 * self.dim() {
            return Err(NbhdError::DimensionMismatch {
                expected: 2 * self.dim(),
                got: boxes.dim(),
            });
        }
        with_index!(self, t, T => {
            let mut values = vec![<T as crate::scalar::Scalar>::ZERO; boxes.len() * boxes.dim()];
            for (i, b) in values.chunks_exact_mut(boxes.dim()).enumerate() {
                boxes.read_point(i, b);
            }
            t.in_boxes(&values, threads)
        })
    }

    /// [`NeighborIndex::spacing`].
    pub fn spacing(&self, threads: usize) -> Result<Spacing> {
        with_index!(self, t, _T => t.spacing(threads))
    }

    /// [`statistical_outlier_removal`] over this index.
    pub fn statistical_outlier_removal(&self, options: &StatisticalOutlierOptions) -> Result<Kept> {
        with_index!(self, t, _T => statistical_outlier_removal(t, options))
    }

    /// [`radius_outlier_removal`] over this index.
    pub fn radius_outlier_removal(&self, options: &RadiusOutlierOptions) -> Result<Kept> {
        with_index!(self, t, _T => radius_outlier_removal(t, options))
    }

    /// [`NeighborIndex::pairs`], the radius converted to the index's type.
    pub fn pairs(&self, radius: f64, options: &TableOptions) -> Result<AnyTable> {
        with_index!(self, t, T => Ok(t.pairs(<T as crate::scalar::Scalar>::from_f64(radius), options)?.into()))
    }

    /// [`NeighborIndex::pairs_with`] against `other` (of the same scalar type, either
    /// flavour), the radius converted to the indexes' type.
    pub fn pairs_with(
        &self,
        other: &AnyIndex,
        radius: f64,
        options: &TableOptions,
    ) -> Result<AnyTable> {
        with_pair!(self, other, a, b, T => Ok(a.pairs_with(b, <T as crate::scalar::Scalar>::from_f64(radius), options)?.into()))
    }

    /// [`NeighborIndex::count_pairs_with`] against `other` (of the same scalar type), the
    /// radii converted to the indexes' type.
    pub fn count_pairs_with(
        &self,
        other: &AnyIndex,
        radii: &[f64],
        cumulative: bool,
        options: &TableOptions,
    ) -> Result<Vec<u64>> {
        with_pair!(self, other, a, b, T => {
            let radii: Vec<T> = radii.iter().map(|&r| <T as crate::scalar::Scalar>::from_f64(r)).collect();
            a.count_pairs_with(b, &radii, cumulative, options)
        })
    }

    /// [`NeighborIndex::weigh_pairs_with`] against `other` (of the same scalar type), the
    /// radii converted to the indexes' type.
    pub fn weigh_pairs_with(
        &self,
        other: &AnyIndex,
        radii: &[f64],
        weights: PairWeights<'_>,
        cumulative: bool,
        options: &TableOptions,
    ) -> Result<Vec<f64>> {
        with_pair!(self, other, a, b, T => {
            let radii: Vec<T> = radii.iter().map(|&r| <T as crate::scalar::Scalar>::from_f64(r)).collect();
            a.weigh_pairs_with(b, &radii, weights, cumulative, options)
        })
    }

    /// Bytes [`AnyIndex::save`] writes.
    pub fn saved_len(&self) -> usize {
        with_index!(self, t, _T => t.saved_len())
    }

    /// Writes the index in its saved format (docs/tree-file-format.md).
    pub fn save<W: Write>(&self, w: W) -> Result<()> {
        with_index!(self, t, _T => t.save(w))
    }

    /// Writes the index to the file `path` (created or truncated).
    pub fn save_file(&self, path: impl AsRef<std::path::Path>) -> Result<()> {
        with_index!(self, t, _T => t.save_file(path))
    }

    /// The index as the bytes [`AnyIndex::save`] writes.
    pub fn to_bytes(&self) -> Vec<u8> {
        with_index!(self, t, _T => t.to_bytes())
    }
}

/// The error of a growing tree's operation asked of a static tree.
fn static_tree(what: &str) -> NbhdError {
    NbhdError::InvalidOption {
        name: "index",
        reason: format!("a static tree cannot {what} (a growing tree can)"),
    }
}
