//! Where a smoothing call takes its neighbourhoods from (Section 2.1.1): its own search — by the
//! k-d tree, or, as the thesis' program offers with 'Use Kd-Tree for NNSearch' switched off
//! (Section 7.3), by the PCA sweep or brute force — or the rows of a table or a tree the caller
//! already has, so that nothing is searched twice.
//!
//! Every source gives the same rows (the k nearest other points, ordered by
//! `(sq_dist, index)`), so the smoothing's result does not depend on the source.

use crate::error::{NbhdError, Result};
use crate::index::NeighborIndex;
use crate::packed::NonFinitePolicy;
use crate::points::PointsView;
use crate::query::brute::BruteForce;
use crate::query::pca_sweep::PcaSweep;
use crate::query::NeighborSearch;
use crate::query::Neighborhood;
use crate::scalar::{Scalar, ScalarType};
use crate::table::{neighborhoods_of_all, NeighborTable};
use crate::tree::KdTree;
use glam::DVec3;

/// The search a smoothing call runs itself.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SearchMethod {
    /// nbhd's k-d tree (the default; 'Use Kd-Tree for NNSearch' on).
    #[default]
    KdTree,
    /// The PCA sweep of Chapter 4 (sorted along the main axis of the points).
    PcaSweep,
    /// Every pair of points.
    BruteForce,
}

/// The neighbourhoods a smoothing call starts from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Neighbors<'a> {
    /// Found by the call itself.
    Search(SearchMethod),
    /// The rows of a table the caller already has, row `i` for point `i`, the point itself not
    /// in its row, nearest first by `(sq_dist, index)`: what [`KdTree::neighborhoods`] returns
    /// with `exclude_self` (a k-nearest, radius or ε-k table). The call takes the first `k` of
    /// each row (within ε), as from its own search; a k-nearest table with at least the
    /// call's `k` gives exactly the result of the call's own search.
    Table(&'a NeighborTable<f64>),
}

impl Default for Neighbors<'_> {
    fn default() -> Self {
        Neighbors::Search(SearchMethod::KdTree)
    }
}

/// The first `k` neighbours of every point (self excluded, ordered by `(sq_dist, index)`) from
/// `neighbors`, and an order to store the points in (the k-d tree's, where the call searched
/// with one, so that neighbours lie close in memory; else the caller's).
pub(crate) fn knn_rows(
    points: &[DVec3],
    neighbors: Neighbors<'_>,
    k: usize,
) -> Result<(NeighborTable<f64>, Vec<u32>)> {
    let identity = || (0..points.len() as u32).collect::<Vec<u32>>();
    let nbhd = Neighborhood::Knn { k };
    match neighbors {
        Neighbors::Search(SearchMethod::KdTree) => {
            if points.is_empty() {
                return Err(NbhdError::EmptyInput);
            }
            crate::tree::exact_knn::nearest_table(points, k)
        }
        Neighbors::Search(method) => {
            let flat: Vec<f64> = points.iter().flat_map(|p| p.to_array()).collect();
            let view = PointsView::from_flat(&flat, 3)?;
            let table = if method == SearchMethod::PcaSweep {
                neighborhoods_of_all(
                    &PcaSweep::<f64>::new(&view, NonFinitePolicy::Reject)?,
                    nbhd,
                    true,
                )?
            } else {
                neighborhoods_of_all(
                    &BruteForce::<f64>::new(&view, NonFinitePolicy::Reject)?,
                    nbhd,
                    true,
                )?
            };
            Ok((table, identity()))
        }
        Neighbors::Table(table) => {
            check_rows(points, table)?;
            Ok((first_of_rows(table, k), identity()))
        }
    }
}

/// `neighbors` for the finite points `index` of a cloud that has non-finite ones (the
/// non-finite policy's subset): a caller's table is restricted to those points' rows and
/// renumbered (entries naming a skipped point are dropped); a search is left as it is.
/// `holder` keeps the restricted table for as long as the result borrows it.
pub(crate) fn for_finite_subset<'a>(
    neighbors: Neighbors<'a>,
    index: &[usize],
    total: usize,
    holder: &'a mut Option<NeighborTable<f64>>,
) -> Result<Neighbors<'a>> {
    let Neighbors::Table(table) = neighbors else {
        return Ok(neighbors);
    };
    if table.len() != total {
        return Err(NbhdError::InvalidOption {
            name: "table",
            reason: format!("the table has {} rows for {total} points", table.len()),
        });
    }
    let mut renumbered = vec![u32::MAX; total];
    for (k, &i) in index.iter().enumerate() {
        renumbered[i] = k as u32;
    }
    let mut offsets = Vec::with_capacity(index.len() + 1);
    offsets.push(0);
    let (mut ids, mut sq_dist) = (Vec::new(), Vec::new());
    for &i in index {
        for (&j, &d) in table.indices_of(i).iter().zip(table.sq_dists_of(i)) {
            if let Some(&k) = renumbered.get(j as usize).filter(|&&k| k != u32::MAX) {
                ids.push(k);
                sq_dist.push(d);
            }
        }
        offsets.push(ids.len());
    }
    *holder = NeighborTable::from_parts(offsets, ids, sq_dist);
    Ok(holder.as_ref().map_or(neighbors, Neighbors::Table))
}

/// A caller's table fits `points`: a row per point, indices in range, no point in its own
/// row, rows ordered by `(sq_dist, index)` with finite distances ≥ 0.
fn check_rows(points: &[DVec3], table: &NeighborTable<f64>) -> Result<()> {
    let bad = |reason: String| {
        Err(NbhdError::InvalidOption {
            name: "table",
            reason,
        })
    };
    if table.len() != points.len() {
        return bad(format!(
            "the table has {} rows for {} points",
            table.len(),
            points.len()
        ));
    }
    for i in 0..table.len() {
        let (row, d2) = (table.indices_of(i), table.sq_dists_of(i));
        for (r, (&j, &d)) in row.iter().zip(d2).enumerate() {
            if j as usize >= points.len() || j as usize == i {
                return bad(format!(
                    "row {i} names point {j} (out of range, or the point itself)"
                ));
            }
            if !(d.is_finite() && d >= 0.0) {
                return bad(format!("row {i} has the squared distance {d}"));
            }
            if r > 0 && (d, j) <= (d2[r - 1], row[r - 1]) {
                return bad(format!(
                    "row {i} is not ordered by (sq_dist, index) at entry {r}"
                ));
            }
        }
    }
    Ok(())
}

/// The first `k` entries of every row.
fn first_of_rows(table: &NeighborTable<f64>, k: usize) -> NeighborTable<f64> {
    let mut offsets = Vec::with_capacity(table.len() + 1);
    offsets.push(0);
    let (mut index, mut sq_dist) = (Vec::new(), Vec::new());
    for i in 0..table.len() {
        let n = table.indices_of(i).len().min(k);
        index.extend_from_slice(&table.indices_of(i)[..n]);
        sq_dist.extend_from_slice(&table.sq_dists_of(i)[..n]);
        offsets.push(index.len());
    }
    NeighborTable::from_parts(offsets, index, sq_dist).unwrap_or_default()
}

/// The points of a 3-D `tree` in the caller's order and the table of their `k` nearest other
/// points, to smooth what the tree holds without a second build: pass them to a smoothing call
/// as `(&points, Neighbors::Table(&table))`. The table is the tree's own search; an `f32`
/// tree's rows are re-measured in `f64` and re-ordered by `(sq_dist, index)`. A tree that
/// skipped non-finite points is refused ([`NbhdError::InvalidOption`]): its skipped points have
/// no coordinates to smooth.
///
/// ```
/// use nbhd::smooth::source::tree_neighbors;
/// use nbhd::{BuildOptions, KdTree, PointsView};
///
/// // four points on a line, 1 apart: each one's nearest other point is a neighbour on the line
/// let rows = [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0], [3.0, 0.0, 0.0]];
/// let tree = KdTree::<f32>::build(&PointsView::from_rows(&rows)?, &BuildOptions::default())?;
/// let (points, table) = tree_neighbors(&tree, 1)?;
/// assert_eq!(points[2].x, 2.0);
/// assert_eq!(table.indices_of(0), &[1]);
/// assert_eq!(table.indices_of(3), &[2]);
/// // a tie (points 0 and 2 are both 1 from point 1) goes to the smaller index
/// assert_eq!(table.indices_of(1), &[0]);
/// assert_eq!(table.sq_dists_of(1), &[1.0]);
/// # Ok::<(), nbhd::NbhdError>(())
/// ```
pub fn tree_neighbors<T: Scalar>(
    tree: &KdTree<T>,
    k: usize,
) -> Result<(Vec<DVec3>, NeighborTable<f64>)> {
    let n = tree.tree_order().len();
    if tree.dim() != 3 {
        return Err(NbhdError::DimensionMismatch {
            expected: 3,
            got: tree.dim(),
        });
    }
    let mut points = vec![DVec3::ZERO; n];
    let mut held = 0usize;
    for (pos, &id) in tree.tree_order().iter().enumerate() {
        let c = tree.point_at(pos);
        if let Some(p) = points.get_mut(id as usize) {
            *p = DVec3::new(c[0].to_f64(), c[1].to_f64(), c[2].to_f64());
            held += 1;
        }
    }
    if held != n || tree.source_len() != n {
        return Err(NbhdError::InvalidOption {
            name: "tree",
            reason: format!(
                "the tree holds {n} of {} points (it skipped non-finite ones); smooth the \
                 points themselves instead",
                tree.source_len()
            ),
        });
    }
    let rows = tree.neighborhoods(
        Neighborhood::Knn { k },
        &crate::table::TableOptions {
            exclude_self: true,
            threads: 0,
            ..Default::default()
        },
    )?;
    let table = table_in_f64(&points, &rows)?;
    Ok((points, table))
}

/// A table of either scalar type as the smoothing reads it: an `f64` table as it is, an `f32`
/// table's rows re-measured in `f64` on `points` and re-ordered by `(sq_dist, index)` (its
/// neighbour sets kept). A table that does not fit `points` is refused
/// ([`NbhdError::InvalidOption`]).
///
/// ```
/// use glam::DVec3;
/// use nbhd::smooth::source::table_in_f64;
/// use nbhd::NeighborTable;
///
/// let points = [DVec3::ZERO, DVec3::X, DVec3::new(3.0, 0.0, 0.0)];
/// // an f32 table whose row 0 lists the far point first: re-measured and re-ordered
/// let f32_table = NeighborTable::<f32>::from_parts(vec![0, 2, 3, 4], vec![2, 1, 0, 1], vec![0.0; 4])
///     .unwrap();
/// let table = table_in_f64(&points, &f32_table)?;
/// assert_eq!(table.indices_of(0), &[1, 2]);
/// assert_eq!(table.sq_dists_of(0), &[1.0, 9.0]);
/// assert_eq!(table.sq_dists_of(2), &[4.0]);
/// // a table naming a point that does not exist is refused
/// let bad = NeighborTable::<f32>::from_parts(vec![0, 1, 1, 1], vec![7], vec![0.0]).unwrap();
/// assert!(table_in_f64(&points, &bad).is_err());
/// # Ok::<(), nbhd::NbhdError>(())
/// ```
pub fn table_in_f64<T: Scalar>(
    points: &[DVec3],
    table: &NeighborTable<T>,
) -> Result<NeighborTable<f64>> {
    if table.len() != points.len() || table.indices().iter().any(|&j| j as usize >= points.len()) {
        return Err(NbhdError::InvalidOption {
            name: "table",
            reason: format!(
                "the table has {} rows for {} points, or names a point out of range",
                table.len(),
                points.len()
            ),
        });
    }
    let mut offsets = Vec::with_capacity(table.len() + 1);
    offsets.push(0);
    let (mut index, mut sq_dist) = (Vec::with_capacity(table.total()), Vec::new());
    let mut row: Vec<(f64, u32)> = Vec::new();
    for i in 0..table.len() {
        row.clear();
        row.extend(
            table
                .indices_of(i)
                .iter()
                .zip(table.sq_dists_of(i))
                .map(|(&j, &d)| {
                    let exact = if T::TYPE == ScalarType::F64 {
                        d.to_f64()
                    } else {
                        points[j as usize].distance_squared(points[i])
                    };
                    (exact, j)
                }),
        );
        if T::TYPE != ScalarType::F64 {
            row.sort_by(|&a, &b| crate::query::order::cmp(a, b));
        }
        index.extend(row.iter().map(|e| e.1));
        sq_dist.extend(row.iter().map(|e| e.0));
        offsets.push(index.len());
    }
    NeighborTable::from_parts(offsets, index, sq_dist).ok_or_else(|| NbhdError::InvalidOption {
        name: "table",
        reason: "the table's rows are inconsistent".into(),
    })
}
