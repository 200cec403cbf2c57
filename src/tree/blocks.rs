//! The neighbourhoods of a tree's own points a block of consecutive tree positions at a time
//! ([`KdTree::with_blocks`]): for callers that work in tree order, consume each block's rows
//! while they are in cache and cannot hold the table of every point at once. The blocks are
//! fixed by the tree before any is searched, and any block can be searched from any thread, so
//! a caller can run whole blocks in parallel (one fork and join for the whole run, rather than
//! several for every block).

use super::search::TreeView;
use super::{group_search, KdTree};
use crate::error::Result;
use crate::index::answer;
use crate::query::Neighborhood;
use crate::scalar::Scalar;
use crate::table::{rows_in_work_order, NeighborTable, CHUNK};

/// A tree's own points cut into blocks of consecutive tree positions, each block's rows
/// computed on request: the rows [`KdTree::neighborhoods`] gives those points.
pub(crate) struct Blocks<'p, T: Scalar> {
    /// Block `b` holds the tree positions `bounds[b]..bounds[b + 1]`.
    bounds: Vec<usize>,
    rows: &'p (dyn Fn(usize) -> Result<NeighborTable<T>> + Sync),
}

impl<T: Scalar> Blocks<'_, T> {
    /// The block bounds: block `b` holds the tree positions `bounds[b]..bounds[b + 1]`.
    pub(crate) fn bounds(&self) -> &[usize] {
        &self.bounds
    }

    /// The rows of block `b`, row `r` for the point at tree position `positions(b).start + r`
    /// (computed in parallel, nested in whatever parallel work calls it).
    pub(crate) fn rows(&self, b: usize) -> Result<NeighborTable<T>> {
        (self.rows)(b)
    }
}

impl<T: Scalar> KdTree<T> {
    /// Runs `f` on the tree's own points cut into [`Blocks`] of about `block` consecutive tree
    /// positions (whole chunks of the grouped search in 1 to 3 dimensions), whose rows are
    /// those of [`KdTree::neighborhoods`] for `nbhd` (`exclude_self` as its option). The
    /// search is prepared once, for every block.
    pub(crate) fn with_blocks<R>(
        &self,
        nbhd: Neighborhood<T>,
        exclude_self: bool,
        block: usize,
        f: impl FnOnce(&Blocks<'_, T>) -> R,
    ) -> Result<R> {
        nbhd.validate()?;
        let block = block.max(1);
        let view = self.view();
        match self.dim {
            3 => return Ok(grouped::<T, 3, R>(&view, nbhd, exclude_self, block, f)),
            2 => return Ok(grouped::<T, 2, R>(&view, nbhd, exclude_self, block, f)),
            1 => return Ok(grouped::<T, 1, R>(&view, nbhd, exclude_self, block, f)),
            _ => {}
        }
        let len = self.len();
        let rows = |b: usize| {
            let start = b * block;
            let positions = start..(start + block).min(len);
            rows_in_work_order(
                positions.len(),
                positions.len(),
                |w| w,
                |w, row, _| {
                    let pos = start + w;
                    let exclude = exclude_self.then_some(self.ids[pos]);
                    answer(self, self.point_at(pos), exclude, nbhd, row);
                    Ok(())
                },
            )
        };
        let bounds = (0..len).step_by(block).chain([len]).collect();
        Ok(f(&Blocks {
            bounds,
            rows: &rows,
        }))
    }
}

/// [`KdTree::with_blocks`] by the grouped search: blocks of whole chunks.
fn grouped<T: Scalar, const D: usize, R>(
    view: &TreeView<'_, T>,
    nbhd: Neighborhood<T>,
    exclude_self: bool,
    block: usize,
    f: impl FnOnce(&Blocks<'_, T>) -> R,
) -> R {
    let plan = group_search::Plan::<T, D>::new(view, nbhd, exclude_self);
    let per_block = block.div_ceil(CHUNK).max(1);
    // block `b` holds the chunks `firsts[b]..firsts[b + 1]`
    let firsts: Vec<usize> = (0..plan.chunks())
        .step_by(per_block)
        .chain([plan.chunks()])
        .collect();
    let rows = |b: usize| {
        let chunks = firsts[b]..firsts[b + 1];
        let positions = plan.positions(chunks.clone());
        let start = positions.start;
        plan.rows(chunks, positions.len(), |pos| pos - start)
    };
    let bounds = firsts.iter().map(|&c| plan.positions(0..c).end).collect();
    f(&Blocks {
        bounds,
        rows: &rows,
    })
}

#[cfg(test)]
mod tests {
    use crate::{BuildOptions, KdTree, NeighborIndex, Neighborhood, PointsView, TableOptions};

    /// Every block's rows are the whole table's rows of its points, in any dimension, for
    /// k-nearest, bounded and radius neighbourhoods, with and without the point itself; the
    /// blocks cover every tree position once.
    #[test]
    fn blocks_give_the_rows_of_the_whole_table() {
        for dim in [1usize, 3, 4] {
            // many copies of a few points among spread ones: rows with ties across blocks
            let n = 5000;
            let mut flat: Vec<f32> = (0..n * dim)
                .map(|i| ((i as u32).wrapping_mul(2_654_435_761) >> 8) as f32 / 16_777_216.0)
                .collect();
            for i in 0..1000 {
                let (to, from) = ((4000 + i) * dim, (i % 5) * dim);
                for j in 0..dim {
                    flat[to + j] = flat[from + j];
                }
            }
            let view = PointsView::from_flat(&flat, dim).unwrap();
            let tree = KdTree::<f32>::build(&view, &BuildOptions::default()).unwrap();
            for nbhd in [
                Neighborhood::Knn { k: 7 },
                Neighborhood::KnnRadius { k: 7, radius: 0.05 },
                Neighborhood::Radius {
                    radius: 0.04,
                    sorted: true,
                },
            ] {
                for exclude_self in [true, false] {
                    let opts = TableOptions {
                        exclude_self,
                        threads: 2,
                        ..Default::default()
                    };
                    let whole = tree.neighborhoods(nbhd, &opts).unwrap();
                    let covered = tree
                        .with_blocks(nbhd, exclude_self, 2000, |blocks| {
                            let mut covered = 0;
                            for (b, w) in blocks.bounds().windows(2).enumerate() {
                                let (positions, t) = (w[0]..w[1], blocks.rows(b).unwrap());
                                assert_eq!(positions.start, covered);
                                assert_eq!(t.len(), positions.len());
                                for (r, pos) in positions.enumerate() {
                                    let i = tree.ids[pos] as usize;
                                    assert_eq!(t.indices_of(r), whole.indices_of(i));
                                    assert_eq!(t.sq_dists_of(r), whole.sq_dists_of(i));
                                    covered += 1;
                                }
                            }
                            covered
                        })
                        .unwrap();
                    assert_eq!(covered, n, "dim {dim}, {nbhd:?}");
                }
            }
        }
    }
}
