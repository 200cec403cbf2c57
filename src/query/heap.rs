//! A bounded max-heap of candidates keyed by `(sq_dist, index)`: the k best seen so far, with
//! the worst on top, so that a candidate is accepted or rejected in O(1) and inserted in
//! O(log k). It borrows the caller's result vector, so a query allocates nothing once that
//! vector has grown to `k`.

use super::{order, Neighbor};
use crate::scalar::Scalar;

/// The k best `(sq_dist, index)` pairs seen so far, within a squared radius.
pub struct NeighborHeap<'a, T> {
    items: &'a mut Vec<Neighbor<T>>,
    k: usize,
    sq_radius: T,
}

impl<'a, T: Scalar> NeighborHeap<'a, T> {
    /// An empty heap keeping at most `k` items with `sq_dist ≤ sq_radius`, stored in `items`
    /// (cleared).
    pub fn new(items: &'a mut Vec<Neighbor<T>>, k: usize, sq_radius: T) -> Self {
        items.clear();
        Self {
            items,
            k,
            sq_radius,
        }
    }

    /// Continues a heap kept in `items` by an earlier [`NeighborHeap`] with the same `k` and
    /// `sq_radius` (not cleared): lets one search hold the heaps of many queries.
    #[inline]
    pub(crate) fn resume(items: &'a mut Vec<Neighbor<T>>, k: usize, sq_radius: T) -> Self {
        Self {
            items,
            k,
            sq_radius,
        }
    }

    /// The worst key a candidate must precede (or equal in distance with a smaller index) to
    /// be accepted: `(sq_radius, u32::MAX)` until the heap is full, then the worst item held.
    #[inline]
    pub(crate) fn worst_key(&self) -> (T, u32) {
        if self.items.len() < self.k {
            (self.sq_radius, u32::MAX)
        } else {
            (self.items[0].sq_dist, self.items[0].index)
        }
    }

    /// The squared distance a candidate must not exceed to be accepted: the radius until the
    /// heap is full, then the k-th best distance (a candidate at exactly that distance may
    /// still win on its index).
    #[inline]
    pub fn bound(&self) -> T {
        if self.items.len() < self.k {
            self.sq_radius
        } else {
            self.items[0].sq_dist
        }
    }

    /// Offers a candidate.
    #[inline]
    pub fn push(&mut self, index: u32, sq_dist: T) {
        let admitted = if self.items.len() < self.k {
            sq_dist <= self.sq_radius
        } else {
            order::precedes((sq_dist, index), self.items[0].key())
        };
        if admitted {
            self.insert(index, sq_dist);
        }
    }

    /// Adds a candidate that precedes [`Self::worst_key`] (checked by the caller).
    #[inline(always)]
    pub(crate) fn insert(&mut self, index: u32, sq_dist: T) {
        let cand = Neighbor { index, sq_dist };
        if self.items.len() < self.k {
            self.items.push(cand);
            self.sift_up(self.items.len() - 1);
        } else {
            self.items[0] = cand;
            self.sift_down(0);
        }
    }

    /// Sorts the items by `(sq_dist, index)` in place; the vector then holds the result.
    pub fn finish(self) {
        self.items.sort_unstable_by(|a, b| a.cmp_by_distance(b));
    }

    fn sift_up(&mut self, mut i: usize) {
        while i > 0 {
            let parent = (i - 1) / 2;
            if self.items[parent].precedes(&self.items[i]) {
                self.items.swap(parent, i);
                i = parent;
            } else {
                break;
            }
        }
    }

    fn sift_down(&mut self, mut i: usize) {
        let n = self.items.len();
        loop {
            let l = 2 * i + 1;
            if l >= n {
                break;
            }
            let r = l + 1;
            let worst = if r < n && self.items[l].precedes(&self.items[r]) {
                r
            } else {
                l
            };
            if self.items[i].precedes(&self.items[worst]) {
                self.items.swap(i, worst);
                i = worst;
            } else {
                break;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keeps_k_best_with_index_tie_break() {
        let mut v = Vec::new();
        let mut h = NeighborHeap::new(&mut v, 3, f64::INFINITY);
        for (i, d) in [
            (5u32, 1.0),
            (4, 1.0),
            (3, 2.0),
            (2, 0.5),
            (1, 1.0),
            (0, 3.0),
        ] {
            h.push(i, d);
        }
        h.finish();
        let got: Vec<_> = v.iter().map(|n| (n.index, n.sq_dist)).collect();
        assert_eq!(got, vec![(2, 0.5), (1, 1.0), (4, 1.0)]);
    }

    #[test]
    fn radius_bound_is_inclusive() {
        let mut v = Vec::new();
        let mut h = NeighborHeap::new(&mut v, usize::MAX, 1.0f32);
        h.push(0, 1.0);
        h.push(1, 1.0000001);
        h.finish();
        assert_eq!(v.len(), 1);
    }
}
