//! The single entry point through which the geometry and smoothing code computes
//! neighbourhoods (Section 2.1.1): a k-d tree with the default build options and its
//! parallel all-point table.

use crate::error::{NbhdError, Result};
use crate::index::NeighborIndex;
use crate::points::PointsView;
use crate::query::Neighborhood;
use crate::table::{NeighborTable, TableOptions};
use crate::tree::{BuildOptions, KdTree};
use glam::DVec3;

/// The neighbourhood of every point of `points` (row `i` for point `i`), with or without the
/// point itself, ordered by `(sq_dist, index)`. Non-finite coordinates are refused
/// ([`NbhdError::NonFinite`]); an empty set gives [`NbhdError::EmptyInput`].
///
/// ```
/// use glam::DVec3;
/// use nbhd::geometry::neighbors::neighbor_table;
/// use nbhd::Neighborhood;
///
/// let points = [DVec3::ZERO, DVec3::X, DVec3::new(3.0, 0.0, 0.0)];
/// let table = neighbor_table(&points, Neighborhood::Knn { k: 1 }, true)?;
/// assert_eq!(table.indices(), [1, 0, 1]);
/// # Ok::<(), nbhd::NbhdError>(())
/// ```
pub fn neighbor_table(
    points: &[DVec3],
    nbhd: Neighborhood<f64>,
    exclude_self: bool,
) -> Result<NeighborTable<f64>> {
    Ok(neighbor_table_and_order(points, nbhd, exclude_self)?.0)
}

/// [`neighbor_table`] and the order of its k-d tree: every index once, the points of a leaf
/// adjacent. Stored in this order, a point's neighbours lie close in memory.
pub(crate) fn neighbor_table_and_order(
    points: &[DVec3],
    nbhd: Neighborhood<f64>,
    exclude_self: bool,
) -> Result<(NeighborTable<f64>, Vec<u32>)> {
    if points.is_empty() {
        return Err(NbhdError::EmptyInput);
    }
    let flat: Vec<f64> = points.iter().flat_map(|p| p.to_array()).collect();
    let view = PointsView::from_flat(&flat, 3)?;
    let tree = KdTree::<f64>::build(&view, &BuildOptions::default())?;
    let table = tree.neighborhoods(
        nbhd,
        &TableOptions {
            exclude_self,
            threads: 0,
            ..Default::default()
        },
    )?;
    let order = if tree.tree_order().len() == points.len() {
        tree.tree_order().to_vec()
    } else {
        (0..points.len() as u32).collect()
    };
    Ok((table, order))
}

/// Mean distance of a point to its nearest other point — the spacing `h` that relative
/// parameters and the quality metrics are measured in ([`crate::index::Spacing`], its one
/// definition). Summed in index order, so the value does not depend on the number of threads.
/// Needs at least two points ([`NbhdError::InvalidOption`] otherwise).
///
/// ```
/// use glam::DVec3;
/// use nbhd::geometry::neighbors::mean_spacing;
///
/// let points = [DVec3::ZERO, DVec3::X, DVec3::new(3.0, 0.0, 0.0)];
/// assert_eq!(mean_spacing(&points)?, (1.0 + 1.0 + 2.0) / 3.0);
/// # Ok::<(), nbhd::NbhdError>(())
/// ```
pub fn mean_spacing(points: &[DVec3]) -> Result<f64> {
    if points.len() < 2 {
        return Err(NbhdError::InvalidOption {
            name: "points",
            reason: "the mean spacing needs at least two points".into(),
        });
    }
    let table = neighbor_table(points, Neighborhood::Knn { k: 1 }, true)?;
    Ok(mean_spacing_of(&table))
}

/// Mean nearest-neighbour distance read off a table whose rows hold the nearest other point
/// first (rows without neighbours are left out; 0 if no row has one).
///
/// ```
/// use nbhd::geometry::neighbors::mean_spacing_of;
/// use nbhd::{BuildOptions, KdTree, NeighborIndex, Neighborhood, PointsView, TableOptions};
///
/// // gaps of 1, 1 and 2: nearest distances 1, 1, 1, 2
/// let pts = [0.0f64, 1.0, 2.0, 4.0];
/// let tree = KdTree::<f64>::build(&PointsView::from_flat(&pts, 1)?, &BuildOptions::default())?;
/// let table = tree.neighborhoods(Neighborhood::Knn { k: 1 }, &TableOptions::default())?;
/// assert_eq!(mean_spacing_of(&table), 1.25);
/// # Ok::<(), nbhd::NbhdError>(())
/// ```
pub fn mean_spacing_of(table: &NeighborTable<f64>) -> f64 {
    mean_spacing_of_nearest((0..table.len()).map(|i| table.sq_dists_of(i).first().copied()))
}

/// [`mean_spacing_of`] from each point's squared distance to its nearest other point, in index
/// order (`None` for a point without neighbours): [`crate::index::Spacing::mean`], without its
/// median.
pub(crate) fn mean_spacing_of_nearest(nearest_sq_dist: impl Iterator<Item = Option<f64>>) -> f64 {
    crate::index::mean_distance(nearest_sq_dist.flatten().map(f64::sqrt))
}

/// Rows of `knn` cut to the points within `eps` (the ε-k-neighbourhood, Section 2.1.1: the
/// k nearest among those within ε are the within-ε prefix of the k nearest).
pub(crate) fn within(knn: &NeighborTable<f64>, eps: f64) -> NeighborTable<f64> {
    let e2 = eps * eps;
    let mut offsets = Vec::with_capacity(knn.len() + 1);
    offsets.push(0);
    let (mut idx, mut d2) = (
        Vec::with_capacity(knn.total()),
        Vec::with_capacity(knn.total()),
    );
    for i in 0..knn.len() {
        for (&j, &d) in knn.indices_of(i).iter().zip(knn.sq_dists_of(i)) {
            if d <= e2 {
                idx.push(j);
                d2.push(d);
            }
        }
        offsets.push(idx.len());
    }
    NeighborTable::from_parts(offsets, idx, d2).unwrap_or_default()
}

/// [`within`] taking the table: rows are sorted by distance, so when every row's farthest
/// neighbour is within ε (the usual case for the defaults) the table is returned as it is,
/// without a copy.
pub(crate) fn cut_to(knn: NeighborTable<f64>, eps: f64) -> NeighborTable<f64> {
    let e2 = eps * eps;
    let inside = |i: usize| knn.sq_dists_of(i).last().is_none_or(|&d| d <= e2);
    if (0..knn.len()).all(inside) {
        knn
    } else {
        within(&knn, eps)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spacing_of_a_grid() {
        let pts: Vec<DVec3> = (0..10)
            .flat_map(|i| (0..10).map(move |j| DVec3::new(i as f64 * 0.5, j as f64 * 0.5, 0.0)))
            .collect();
        assert!((mean_spacing(&pts).unwrap() - 0.5).abs() < 1e-12);
        assert!(mean_spacing(&pts[..1]).is_err());
        assert_eq!(
            neighbor_table(&[], Neighborhood::Knn { k: 1 }, true),
            Err(NbhdError::EmptyInput)
        );
    }
}
