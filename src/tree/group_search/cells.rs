//! One tree as the grouped search reads it: its nodes, each node's tight bounding box and
//! smallest caller index, its points' caller indices and its coordinates stored by dimension,
//! all in tree order. Prepared ([`Cells`]) for one table of a static tree, or once for every
//! batch on a tree of a forest (its indices then shifted to the forest's, `src/dynamic/`), and
//! read through a [`CellView`] of plain slices.

use rayon::prelude::*;

use super::BLOCK;
use crate::scalar::Scalar;
use crate::tree::kernel::sq_dists_below_by_dim;
use crate::tree::node::Node;
use crate::tree::search::TreeView;

/// The coordinates in tree order as struct-of-arrays, dimension `j` at `v[j * stride..]`,
/// padded by a block so that a leaf's last block can be read whole.
pub(crate) struct Soa<T, const D: usize> {
    pub(super) stride: usize,
    pub(super) v: Vec<T>,
}

impl<T: Scalar, const D: usize> Soa<T, D> {
    fn new(coords: &[T]) -> Self {
        let n = coords.len() / D;
        let stride = n + BLOCK;
        let mut v = vec![T::ZERO; D * stride];
        // one dimension at a time, its points in parallel pieces
        for (j, dim) in v.chunks_exact_mut(stride).enumerate() {
            dim[..n]
                .par_chunks_mut(4096)
                .zip(coords.par_chunks(4096 * D))
                .for_each(|(out, c)| {
                    for (o, p) in out.iter_mut().zip(c.chunks_exact(D)) {
                        *o = p[j];
                    }
                });
        }
        Self { stride, v }
    }

    /// Squared distances from `q` to the points at tree positions `start..start + BLOCK`, and
    /// the bits of those within `bound` (`sse`, `avx` as in `tree/kernel.rs`,
    /// [`sq_dists_below_by_dim`]).
    #[inline(always)]
    pub(super) fn block_sq_dists_below(
        &self,
        q: &[T; D],
        start: usize,
        bound: T,
        (sse, avx): (bool, bool),
    ) -> ([T; BLOCK], u32) {
        sq_dists_below_by_dim(
            q,
            |j| &self.v[j * self.stride + start..][..BLOCK],
            bound,
            sse,
            avx,
        )
    }
}

/// What the grouped search prepares of one tree: the nodes' tight boxes, the coordinates by
/// dimension, and — for a tree of a forest — its caller indices shifted to the forest's.
pub(crate) struct Cells<T, const D: usize> {
    lo: Vec<[T; D]>,
    hi: Vec<[T; D]>,
    soa: Soa<T, D>,
    /// The shifted caller index of every tree position and of every node's smallest (`None`:
    /// the tree's own).
    shifted: Option<(Vec<u32>, Vec<u32>)>,
}

impl<T: Scalar, const D: usize> Cells<T, D> {
    /// The cells of `tree`, its caller indices shifted by `shift` (the first index of a tree of
    /// a forest; 0 for a tree on its own).
    pub(crate) fn new(tree: &TreeView<'_, T>, shift: u32) -> Self {
        Self::boxes_of(tree, shift).with_coords(tree)
    }

    /// The nodes' tight boxes (and the shifted indices), without the coordinates yet: the
    /// leaves' boxes are made from their points in parallel (they read every point), then the
    /// internal nodes' bottom-up over the preorder node array (children follow their parent).
    pub(crate) fn boxes_of(tree: &TreeView<'_, T>, shift: u32) -> Boxes<T, D> {
        let n = tree.nodes.len();
        let neg_inf = T::ZERO - T::INFINITY;
        let mut lo = vec![[T::INFINITY; D]; n];
        let mut hi = vec![[neg_inf; D]; n];
        lo.par_iter_mut()
            .zip(hi.par_iter_mut())
            .zip(tree.nodes.par_iter())
            .with_min_len(1024)
            .filter(|(_, nd)| nd.is_leaf())
            .for_each(|((l, h), nd)| {
                let points = &tree.coords[nd.a as usize * D..nd.b as usize * D];
                for p in points.chunks_exact(D) {
                    for j in 0..D {
                        l[j] = l[j].min_of(p[j]);
                        h[j] = h[j].max_of(p[j]);
                    }
                }
            });
        for i in (0..n).rev() {
            let nd = &tree.nodes[i];
            if !nd.is_leaf() {
                let (a, b) = (i + 1, nd.a as usize);
                for j in 0..D {
                    lo[i][j] = lo[a][j].min_of(lo[b][j]);
                    hi[i][j] = hi[a][j].max_of(hi[b][j]);
                }
            }
        }
        let shifted = (shift > 0).then(|| {
            let ids = tree.ids.iter().map(|&i| i + shift).collect();
            let min_id = tree.min_id.iter().map(|&i| i + shift).collect();
            (ids, min_id)
        });
        Boxes { lo, hi, shifted }
    }

    /// The cells as plain slices, with `tree` (the tree they were made of); `not_live` marks
    /// the (shifted) indices a search must skip, for a tree of a forest holding removed points.
    pub(crate) fn view<'a>(
        &'a self,
        tree: &TreeView<'a, T>,
        not_live: Option<&'a [u64]>,
    ) -> CellView<'a, T, D> {
        let (ids, min_id) = match &self.shifted {
            Some((ids, min_id)) => (&ids[..], &min_id[..]),
            None => (tree.ids, tree.min_id),
        };
        CellView {
            nodes: tree.nodes,
            coords: tree.coords,
            lo: &self.lo,
            hi: &self.hi,
            min_id,
            ids,
            soa: &self.soa,
            not_live,
        }
    }
}

/// The first part of a tree's [`Cells`]: the nodes' boxes and shifted indices.
pub(crate) struct Boxes<T, const D: usize> {
    lo: Vec<[T; D]>,
    hi: Vec<[T; D]>,
    shifted: Option<(Vec<u32>, Vec<u32>)>,
}

impl<T: Scalar, const D: usize> Boxes<T, D> {
    /// The cells, with the coordinates of `tree` (the tree the boxes were made of) by dimension.
    pub(crate) fn with_coords(self, tree: &TreeView<'_, T>) -> Cells<T, D> {
        Cells {
            lo: self.lo,
            hi: self.hi,
            soa: Soa::new(tree.coords),
            shifted: self.shifted,
        }
    }
}

/// A tree's cells as the grouped search reads them (see [`Cells`]).
#[derive(Clone, Copy)]
pub(crate) struct CellView<'a, T, const D: usize> {
    pub(super) nodes: &'a [Node<T>],
    /// Coordinates in tree order, packed.
    pub(super) coords: &'a [T],
    /// Node `i`'s tight box is `lo[i]..=hi[i]`.
    pub(super) lo: &'a [[T; D]],
    pub(super) hi: &'a [[T; D]],
    /// Smallest caller index of every node's subtree.
    pub(super) min_id: &'a [u32],
    /// Caller index of every tree position.
    pub(super) ids: &'a [u32],
    pub(super) soa: &'a Soa<T, D>,
    /// One bit per caller index, set for the points the search skips (removed from a forest).
    pub(super) not_live: Option<&'a [u64]>,
}
