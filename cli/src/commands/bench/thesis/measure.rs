//! How Chapter 8 measures: samples of a geometry, trees of the thesis' shape (one point per
//! leaf, one thread), and the time of an all-point table from a k-d tree, the PCA sweep or
//! brute force.

use super::setup::Geometry;
use crate::error::Result;
use crate::output::ms;
use nbhd::shapes::sample;
use nbhd::table::neighborhoods_of_all;
use nbhd::NeighborIndex;
use nbhd::{
    BuildOptions, KdTree, MedianAlgorithm, NeighborSearch, Neighborhood, PivotPolicy, PointsView,
    TableOptions,
};
use std::time::Instant;

/// A uniform random sample of a geometry (seed 2024, as every figure uses).
pub(super) struct Sample {
    /// x, y, z of each point in turn.
    coords: Vec<f64>,
    /// Diagonal of the bounding box.
    pub diameter: f64,
}

impl Sample {
    /// `n` points of `g`.
    pub fn new(g: &Geometry, n: usize) -> Self {
        let points = sample(g.shape.as_ref(), n, 2024).points;
        let (lo, hi) = points.iter().fold(
            (
                glam::DVec3::splat(f64::INFINITY),
                glam::DVec3::splat(f64::NEG_INFINITY),
            ),
            |(lo, hi), &p| (lo.min(p), hi.max(p)),
        );
        Self {
            coords: points.iter().flat_map(|p| p.to_array()).collect(),
            diameter: (hi - lo).length(),
        }
    }

    /// The points as the library takes them.
    pub fn view(&self) -> Result<PointsView<'_>> {
        Ok(PointsView::from_flat(&self.coords, 3)?)
    }
}

/// The median of `v` (the upper one of an even count).
pub(super) fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Build options of the thesis' trees: one point per leaf, one thread.
pub(super) fn thesis_options(pivot: PivotPolicy, median: MedianAlgorithm) -> BuildOptions {
    BuildOptions {
        leaf_size: 1,
        threads: 1,
        ..BuildOptions::with(pivot, median)
    }
}

/// The thesis' "Sorting" tree: cyclic median from presorted lists.
pub(super) fn sorting_tree(view: &PointsView<'_>) -> Result<KdTree<f64>> {
    let opts = thesis_options(PivotPolicy::CyclicMedian, MedianAlgorithm::Presorted);
    Ok(KdTree::<f64>::build(view, &opts)?)
}

/// The thesis' "Closest to Middle" tree (Moore).
pub(super) fn closest_to_middle_tree(view: &PointsView<'_>) -> Result<KdTree<f64>> {
    let opts = thesis_options(PivotPolicy::ClosestToMiddle, MedianAlgorithm::FloydRivest);
    Ok(KdTree::<f64>::build(view, &opts)?)
}

/// The "Sorting" and the "Closest to Middle" tree of one sample, labelled.
pub(super) fn sorting_and_closest_to_middle(
    view: &PointsView<'_>,
) -> Result<[(&'static str, KdTree<f64>); 2]> {
    Ok([
        ("Sorting", sorting_tree(view)?),
        ("Closest to Middle", closest_to_middle_tree(view)?),
    ])
}

/// Milliseconds of the all-point table of `searcher` for `nbhd` (self excluded): the
/// faster of two runs, so that the first run's page faults do not count.
pub(super) fn table_ms(searcher: &dyn Searcher, nbhd: Neighborhood<f64>) -> Result<(f64, usize)> {
    let mut best = f64::INFINITY;
    let mut total = 0;
    for _ in 0..2 {
        let t = Instant::now();
        total = searcher.table(nbhd)?;
        best = best.min(ms(t));
    }
    Ok((best, total))
}

/// The three searchers behind one call.
pub(super) trait Searcher {
    /// The all-point table (self excluded, one thread); returns the neighbour total.
    fn table(&self, nbhd: Neighborhood<f64>) -> Result<usize>;
}

impl Searcher for KdTree<f64> {
    fn table(&self, nbhd: Neighborhood<f64>) -> Result<usize> {
        let opts = TableOptions {
            exclude_self: true,
            threads: 1,
            ..Default::default()
        };
        Ok(self.neighborhoods(nbhd, &opts)?.total())
    }
}

/// A searcher without a table of its own (the PCA sweep, brute force).
pub(super) struct Baseline<S>(pub S);

impl<S: NeighborSearch<f64>> Searcher for Baseline<S> {
    fn table(&self, nbhd: Neighborhood<f64>) -> Result<usize> {
        Ok(neighborhoods_of_all(&self.0, nbhd, true)?.total())
    }
}
