//! The splits of a descent's complete top levels packed a cache line per block of levels, so
//! that a single query's descent reads several levels from one line (the cache-blocked
//! layout of van Emde Boas trees, as kiddo's immutable tree keeps its split values).
//!
//! The breadth-first descent steps (`src/tree/node.rs`) of a level whose every node is internal are in
//! Eytzinger order: step `i`'s children are `2i + 1` and `2i + 2`. Over those complete levels
//! a block holds the splits of a subtree of `L` levels, `2^L − 1` values in one 64-byte line
//! (`L` = 4 for `f32`: 15 values; `L` = 3 for `f64`: 7), in-block Eytzinger order, and the
//! line's last value carries the nodes' splitting dimensions, two bits each. The blocks end
//! at the last complete level (the top block takes what is left over, `1..=L` levels), so
//! that the levels just above the leaves, the ones whose lines leave the core, come `L` at a
//! time. Blocks are numbered row by row; the child `c` of block `b > 0` is `b·2^L + c + K`,
//! `K = 1 + 2^t − 2^L` for a top block of `t` levels (its own children are `1 + c`).
//!
//! A search names a node by its step (for the smallest indices and the cells it keeps) and,
//! inside these levels, by its place in a block, [`SplitLines::children`]; the values read are
//! the steps' own, so the search visits the same cells in the same order.

use super::node::{Step, DESCENT_LEAF};
use crate::scalar::Scalar;

/// A node outside the blocked levels.
pub(crate) const OUTSIDE: u32 = u32::MAX;

/// The blocked splits (see the module documentation).
#[derive(Clone, Debug, Default)]
pub(crate) struct SplitLines<T> {
    /// The blocks, `per_line::<T>()` values each, from `off` on (a 64-byte boundary when
    /// built; a clone may lose the alignment, never the values).
    raw: Vec<T>,
    off: usize,
    /// Nodes of the top block, `2^t − 1`.
    top_nodes: u32,
    /// `K` of the child rule, modulo 2^32 (negative for a top block of fewer levels).
    k: u32,
    /// Number of blocks.
    blocks: u32,
}

/// Values in one 64-byte line: 16 `f32`, 8 `f64`.
#[inline(always)]
const fn per_line<T>() -> usize {
    64 / std::mem::size_of::<T>()
}

/// Levels per block: 4 for `f32`, 3 for `f64`.
#[inline(always)]
const fn levels<T>() -> u32 {
    per_line::<T>().trailing_zeros()
}

impl<T: Scalar> SplitLines<T> {
    /// The blocks of the complete levels of a descent's `steps`; none for a tree whose root
    /// is a leaf.
    pub(crate) fn new(steps: &[Step<T>]) -> Self {
        let first_leaf = steps
            .iter()
            .position(|s| s.link & 3 == DESCENT_LEAF)
            .unwrap_or(steps.len());
        // Complete levels: every node above level `h` is internal (capped so that a block's
        // number and place fit one `u32`).
        let h = (usize::BITS - 1 - (first_leaf + 1).leading_zeros()).min(24);
        if h == 0 {
            return Self::default();
        }
        let l = levels::<T>();
        let t = (h - 1) % l + 1;
        // Rows of blocks: (level of their roots, levels they hold).
        let mut rows = vec![(0u32, t)];
        let mut level = t;
        while level < h {
            rows.push((level, l));
            level += l;
        }
        let blocks: usize = rows.iter().map(|&(root, _)| 1usize << root).sum();
        let per = per_line::<T>();
        // One spare line, so that the blocks can start on a 64-byte boundary.
        let mut raw: Vec<T> = Vec::with_capacity((blocks + 1) * per);
        let off = raw.as_ptr().align_offset(64).min(per);
        raw.resize(off, T::ZERO);
        for &(root_level, block_levels) in &rows {
            for root in (1usize << root_level) - 1..(2usize << root_level) - 1 {
                raw.extend(Self::fill_line(steps, root, block_levels));
            }
        }
        raw.resize((blocks + 1) * per, T::ZERO);
        Self {
            raw,
            off,
            top_nodes: (1 << t) - 1,
            k: (1u32 + (1 << t)).wrapping_sub(1 << l),
            blocks: blocks as u32,
        }
    }

    /// The line of the block rooted at step `root` holding `block_levels` levels.
    fn fill_line(steps: &[Step<T>], root: usize, block_levels: u32) -> Vec<T> {
        let per = per_line::<T>();
        let mut line = vec![T::ZERO; per];
        let mut dims = 0u32;
        for il in 0..block_levels {
            for j in 0..1usize << il {
                let p = (1usize << il) - 1 + j;
                let s = &steps[((root + 1) << il) - 1 + j];
                line[p] = s.split;
                dims |= (s.link & 3) << (2 * p);
            }
        }
        line[per - 1] = T::from_index_bits(dims);
        line
    }

    /// The blocks from a 64-byte boundary (a block a line; any start is correct).
    #[inline(always)]
    pub(crate) fn lines(&self) -> &[T] {
        &self.raw[self.off..]
    }

    /// The place of the root: block 0, node 0; [`OUTSIDE`] for a tree without blocks.
    #[inline(always)]
    pub(crate) fn root(&self) -> u32 {
        if self.blocks == 0 {
            OUTSIDE
        } else {
            0
        }
    }

    /// The split value and splitting dimension of the node at `at` (block `at >> 4`, node
    /// `at & 15`) in `lines` (from [`SplitLines::lines`]).
    #[inline(always)]
    pub(crate) fn read(lines: &[T], at: u32) -> (T, usize) {
        let line = Self::block(lines, at);
        let p = at & 15;
        let dims = line[per_line::<T>() - 1].index_bits();
        (line[p as usize], ((dims >> (2 * p)) & 3) as usize)
    }

    /// The line of the block of the node at `at` in `lines`.
    #[inline(always)]
    pub(crate) fn block(lines: &[T], at: u32) -> &[T] {
        let per = per_line::<T>();
        let base = (at >> 4) as usize * per;
        &lines[base..base + per]
    }

    /// The places of the two children of the node at `at`: the left one's, and what to add
    /// for the right one's (1 inside the block, 16 in the next block: the line to request).
    /// [`OUTSIDE`] for both below the blocked levels.
    #[inline(always)]
    pub(crate) fn children(&self, at: u32) -> (u32, u32) {
        let (b, p) = (at >> 4, at & 15);
        let nodes = if b == 0 {
            self.top_nodes
        } else {
            (1 << levels::<T>()) - 1
        };
        let cp = 2 * p + 1;
        if cp < nodes {
            return (b << 4 | cp, 1);
        }
        let first = if b == 0 {
            1
        } else {
            (b << levels::<T>()).wrapping_add(self.k)
        } + (cp - nodes);
        if first < self.blocks {
            (first << 4, 16)
        } else {
            (OUTSIDE, 0)
        }
    }

    /// Bytes held.
    pub(crate) fn bytes(&self) -> usize {
        self.raw.len() * std::mem::size_of::<T>()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tree::{BuildOptions, KdTree, PivotPolicy};

    /// Walks every node of the blocked levels from the root and checks that each place names
    /// the step the Eytzinger rule gives, with that step's split and dimension, and that the
    /// places leave the blocks exactly at the first level holding a leaf.
    fn check<T: Scalar>(tree: &KdTree<T>) {
        let Some(descent) = tree.descent.as_ref() else {
            return;
        };
        let lines = &descent.lines;
        let mut todo = vec![(0usize, lines.root())];
        let mut inside = 0;
        while let Some((step, at)) = todo.pop() {
            let s = descent.steps[step];
            if at == OUTSIDE {
                continue;
            }
            inside += 1;
            assert_ne!(s.link & 3, DESCENT_LEAF, "a blocked node is internal");
            assert_eq!(s.link >> 2, 2 * step as u32 + 1, "Eytzinger children");
            let (split, dim) = SplitLines::read(lines.lines(), at);
            assert_eq!(split.to_f64().to_bits(), s.split.to_f64().to_bits());
            assert_eq!(dim as u32, s.link & 3);
            let (left, next) = lines.children(at);
            todo.push((2 * step + 1, left));
            todo.push((2 * step + 2, left.wrapping_add(next)));
        }
        // Every internal node above the first level with a leaf was reached inside.
        let first_leaf = descent
            .steps
            .iter()
            .position(|s| s.link & 3 == DESCENT_LEAF)
            .unwrap();
        let h = usize::BITS - 1 - (first_leaf + 1).leading_zeros();
        assert_eq!(inside, (1usize << h.min(24)) - 1);
    }

    #[test]
    fn the_blocks_hold_the_steps_of_every_complete_level() {
        for n in [1usize, 2, 40, 700, 5000, 40_000] {
            for dim in 1..=3 {
                let coords: Vec<f64> = (0..n * dim)
                    .map(|i| ((i as u64).wrapping_mul(2_654_435_761) % 1000) as f64 * 0.37)
                    .collect();
                for pivot in PivotPolicy::ALL {
                    let opts = BuildOptions {
                        pivot,
                        threads: 1,
                        ..BuildOptions::default()
                    };
                    check(&KdTree::from_flat(&coords, dim, &opts).unwrap());
                    let c32: Vec<f32> = coords.iter().map(|&x| x as f32).collect();
                    check(&KdTree::from_flat(&c32, dim, &opts).unwrap());
                }
            }
        }
    }
}
