//! The result-set policy every search fills (as nanoflann's `KNNResultSet` and
//! `RadiusResultSet` serve one search): a set is offered candidates `(index, sq_dist)` and
//! says, through its worst admissible key, which candidates can still enter. The searches —
//! the single-query descent (`src/tree/search.rs`), the grouped all-point search
//! (`src/tree/group_search.rs`) and the baselines — only offer; what is kept is decided here:
//!
//! - `NeighborHeap` (`src/query/heap.rs`): the k nearest within a radius, any `k`;
//! - `KnnRow`: the same for one single query with small `k`, packed keys sorted by insertion
//!   (its first leaf as one sorted block);
//! - `KnnBuf`: the same for one single query with larger `k`, packed keys appended unsorted;
//! - `WithinRadius`: every point within a radius.
//!
//! All of them order by `(sq_dist, index)` (`src/query/order.rs`).

use super::order::{self, PackedKey};
use super::{Neighbor, NeighborHeap};
use crate::scalar::Scalar;
use crate::select::network::sort32;

/// Where a search puts its candidates.
pub trait ResultSet<T: Scalar> {
    /// The worst key `(sq_dist, index)` a candidate must precede to be accepted:
    /// `(sq_radius, u32::MAX)` while the set is not full (caller indices are below `u32::MAX`),
    /// then its worst member.
    fn worst_key(&self) -> (T, u32);

    /// The largest squared distance still of interest (a candidate at exactly this distance
    /// may still enter by its index).
    #[inline(always)]
    fn bound(&self) -> T {
        self.worst_key().0
    }

    /// Adds a candidate that precedes [`Self::worst_key`] (the caller has checked it).
    fn insert(&mut self, index: u32, sq_dist: T);

    /// Offers a candidate: it enters if it precedes [`Self::worst_key`] — while the set is not
    /// full, if it lies within the radius (inclusive).
    #[inline(always)]
    fn offer(&mut self, index: u32, sq_dist: T) {
        if order::precedes((sq_dist, index), self.worst_key()) {
            self.insert(index, sq_dist);
        }
    }

    /// Offers the points of a leaf block (`src/tree/search.rs`): for every bit `j` of `mask`
    /// (set where `sq_dists[j]` is within [`Self::bound`] at the block's start), the point
    /// `ids[j]` at `sq_dists[j]` unless its index is `excluded`, in increasing `j`.
    #[inline(always)]
    fn offer_block(&mut self, ids: &[u32], sq_dists: &[T], mask: u32, excluded: u32) {
        offer_each(self, ids, sq_dists, mask, excluded);
    }
}

/// [`ResultSet::offer_block`] as one [`ResultSet::offer`] per candidate: the default, and what
/// a set that takes some blocks at once does with the others.
#[inline(always)]
fn offer_each<T: Scalar, R: ResultSet<T> + ?Sized>(
    set: &mut R,
    ids: &[u32],
    sq_dists: &[T],
    mut mask: u32,
    excluded: u32,
) {
    while mask != 0 {
        let j = mask.trailing_zeros() as usize;
        mask &= mask - 1;
        // The index (another cache line) is read only for a candidate within the bound.
        let id = ids[j];
        if id != excluded {
            set.offer(id, sq_dists[j]);
        }
    }
}

impl<T: Scalar> ResultSet<T> for NeighborHeap<'_, T> {
    #[inline(always)]
    fn worst_key(&self) -> (T, u32) {
        NeighborHeap::worst_key(self)
    }
    #[inline(always)]
    fn bound(&self) -> T {
        NeighborHeap::bound(self)
    }
    #[inline(always)]
    fn insert(&mut self, index: u32, sq_dist: T) {
        NeighborHeap::insert(self, index, sq_dist)
    }
    #[inline(always)]
    fn offer(&mut self, index: u32, sq_dist: T) {
        self.push(index, sq_dist)
    }
}

/// Every point with `sq_dist ≤ sq_radius`, in the order offered.
pub(crate) struct WithinRadius<'a, T> {
    /// The result (appended to).
    pub out: &'a mut Vec<Neighbor<T>>,
    /// The squared radius.
    pub sq_radius: T,
}

impl<T: Scalar> ResultSet<T> for WithinRadius<'_, T> {
    #[inline(always)]
    fn worst_key(&self) -> (T, u32) {
        (self.sq_radius, u32::MAX)
    }
    #[inline(always)]
    fn bound(&self) -> T {
        self.sq_radius
    }
    #[inline(always)]
    fn insert(&mut self, index: u32, sq_dist: T) {
        self.out.push(Neighbor { index, sq_dist });
    }
    #[inline(always)]
    fn offer(&mut self, index: u32, sq_dist: T) {
        if sq_dist <= self.sq_radius {
            self.insert(index, sq_dist);
        }
    }
}

/// How a sorted row of the grouped search (`src/tree/group_search/rows.rs`) holds a neighbour: as a [`Neighbor`], or packed into one integer key
/// (`src/query/order.rs`) so that the insertion compares one integer.
pub(crate) trait RowEntry<T>: Copy {
    /// The entry of a candidate.
    fn of(index: u32, sq_dist: T) -> Self;
    /// Its `(sq_dist, index)`.
    fn pair(self) -> (T, u32);
    /// Whether it comes before `other` in `(sq_dist, index)` order.
    fn precedes(self, other: Self) -> bool;
}

impl<T: Scalar> RowEntry<T> for Neighbor<T> {
    #[inline(always)]
    fn of(index: u32, sq_dist: T) -> Self {
        Neighbor { index, sq_dist }
    }
    #[inline(always)]
    fn pair(self) -> (T, u32) {
        self.key()
    }
    #[inline(always)]
    fn precedes(self, other: Self) -> bool {
        Neighbor::precedes(&self, &other)
    }
}

/// An `f32` neighbour as its packed `u64` key ([`order::key32`]); only for `T = f32`.
#[derive(Clone, Copy, Default)]
pub(crate) struct Key32(u64);

impl<T: Scalar> RowEntry<T> for Key32 {
    #[inline(always)]
    fn of(index: u32, sq_dist: T) -> Self {
        Key32(order::key32(sq_dist, index))
    }
    #[inline(always)]
    fn pair(self) -> (T, u32) {
        order::unkey32(self.0)
    }
    #[inline(always)]
    fn precedes(self, other: Self) -> bool {
        self.0 < other.0
    }
}

/// The k nearest within a radius for one single query with small `k`, kept sorted in a
/// borrowed slice of length `k` that [`KnnRow::new`] fills with the sentinel
/// `(sq_radius, u32::MAX)`, as packed keys `K` (`src/query/order.rs`: `u64` for `f32`, `u128`
/// for `f64`). The sentinel is the worst admissible key of a set that is not yet full (caller
/// indices are below `u32::MAX`), so the worst key is always the last entry and no count is
/// tested on every offer (cachegrind's branch simulation counted that test among the most
/// mispredicted of a single query, docs/speed-log.md "Single queries, the floor, and copies of
/// a point"); an insertion shifts the entries that follow the candidate, and the query's first
/// leaf enters as one sorted block ([`ResultSet::offer_block`]).
pub(crate) struct KnnRow<'a, K> {
    /// Storage of `k ≥ 1` entries, sorted, sentinels last.
    row: &'a mut [K],
}

impl<'a, K: RowKey> KnnRow<'a, K> {
    /// A set over `row` (its length is `k`, at least 1), every entry the sentinel.
    pub(crate) fn new<T: Scalar>(row: &'a mut [K], sq_radius: T) -> Self
    where
        K: PackedKey<T>,
    {
        row.fill(K::of(u32::MAX, sq_radius));
        Self { row }
    }

    /// The entries held, in `(sq_dist, index)` order.
    pub(crate) fn held(&self) -> impl Iterator<Item = K> + '_ {
        self.row
            .iter()
            .copied()
            .take_while(|e| e.index() != u32::MAX)
    }
}

impl<T: Scalar, K: RowKey + PackedKey<T>> ResultSet<T> for KnnRow<'_, K> {
    #[inline(always)]
    fn worst_key(&self) -> (T, u32) {
        self.row[self.row.len() - 1].pair()
    }

    #[inline(always)]
    fn insert(&mut self, index: u32, sq_dist: T) {
        let cand = K::of(index, sq_dist);
        let row = &mut *self.row;
        let mut j = row.len() - 1;
        while j > 0 && cand < row[j - 1] {
            row[j] = row[j - 1];
            j -= 1;
        }
        row[j] = cand;
    }

    #[inline(always)]
    fn offer(&mut self, index: u32, sq_dist: T) {
        if K::of(index, sq_dist) < self.row[self.row.len() - 1] {
            <Self as ResultSet<T>>::insert(self, index, sq_dist);
        }
    }

    /// An empty row (the query's first leaf) takes the block's candidates at once: their keys
    /// sorted and the first `k` copied in ([`RowKey::first_block`]), instead of one insertion
    /// each. Most of a single query's insertions come from its first leaf (every point of it is
    /// within the sentinel bound), each shifting the sentinels behind it; the kept keys are the
    /// same `k` smallest, so the row, its bound and all later pruning are unchanged.
    #[inline(always)]
    fn offer_block(&mut self, ids: &[u32], sq_dists: &[T], mask: u32, excluded: u32) {
        if self.row[0].index() != u32::MAX {
            return offer_each(self, ids, sq_dists, mask, excluded);
        }
        K::first_block(self.row, ids, sq_dists, mask, excluded);
    }
}

/// A packed key of a [`KnnRow`], with the way an empty row takes a whole block.
pub(crate) trait RowKey: Copy + Ord + Default {
    /// Single queries up to this `k` keep a [`KnnRow`], larger ones a [`KnnBuf`]
    /// (`src/index/search.rs`).
    const ROW_MAX_K: usize;
    /// The index of a key.
    fn index(self) -> u32;
    /// Writes into `row` the `min(k, n)` smallest keys, in order, of the `n` candidates of a
    /// block: the entries `j` of `mask`, the point `ids[j]` at `sq_dists[j]`, unless its index is
    /// `excluded` (every candidate precedes the row's sentinels).
    fn first_block<T: Scalar>(
        row: &mut [Self],
        ids: &[u32],
        sq_dists: &[T],
        mask: u32,
        excluded: u32,
    );
}

/// The keys of a block's candidates, packed by `key(j)` for its entries `j` of `mask` except
/// the `excluded` index, then `u64::MAX` (which sorts last), sorted by a network
/// (`src/select/network.rs`; a comparison sort mispredicted about ten branches a query); and
/// their number.
#[inline(always)]
fn sorted_block(
    ids: &[u32],
    mut mask: u32,
    excluded: u32,
    key: impl Fn(usize) -> u64,
) -> ([u64; 33], usize) {
    // The excluded index's key is written at `n` and not counted: the next one, or the final
    // `u64::MAX`, overwrites it.
    let mut keys = [u64::MAX; 33];
    let mut n = 0;
    while mask != 0 {
        let j = mask.trailing_zeros() as usize;
        mask &= mask - 1;
        keys[n] = key(j);
        n += (ids[j] != excluded) as usize;
    }
    keys[n] = u64::MAX;
    let sorted: &mut [u64; 32] = (&mut keys[..32]).try_into().unwrap();
    sort32(sorted);
    (keys, n)
}

/// `f32` neighbours: their exact keys sorted.
impl RowKey for u64 {
    /// On the 77k torus (docs/speed-log.md, "Single queries, the floor, and copies of a point")
    /// the buffer took 0.87x the sorted row's time at k = 30 and 1.14x at k = 10.
    const ROW_MAX_K: usize = 16;
    #[inline(always)]
    fn index(self) -> u32 {
        self as u32
    }
    #[inline(always)]
    fn first_block<T: Scalar>(
        row: &mut [u64],
        ids: &[u32],
        sq_dists: &[T],
        mask: u32,
        excluded: u32,
    ) {
        let (keys, n) = sorted_block(ids, mask, excluded, |j| order::key32(sq_dists[j], ids[j]));
        let m = n.min(row.len());
        row[..m].copy_from_slice(&keys[..m]);
    }
}

/// `f64` neighbours: a network of 32 `u128` keys took 20 instructions a compare-exchange, 3,800
/// a query (callgrind, 77k torus, k = 10), so the block is sorted by `u64` keys of the distance
/// rounded to `f32` and the block position, then put in exact order by insertion. Rounding is
/// monotone: a smaller rounded distance means a smaller distance, so only candidates of equal
/// rounded distance can be out of order, and the `m`-th smallest is among those up to the end
/// of its run of equal rounded distances.
impl RowKey for u128 {
    /// At k = 30 on the 77k torus the row (its first block sorted whole) took 0.81-0.85x the
    /// buffer's time, whose selections and final sort move `u128` keys (docs/speed-log.md,
    /// round 11).
    const ROW_MAX_K: usize = 32;
    #[inline(always)]
    fn index(self) -> u32 {
        self as u32
    }
    #[inline(always)]
    fn first_block<T: Scalar>(
        row: &mut [u128],
        ids: &[u32],
        sq_dists: &[T],
        mask: u32,
        excluded: u32,
    ) {
        let rounded = |j: usize| u64::from((sq_dists[j].to_f64() as f32).to_bits());
        let (keys, n) = sorted_block(ids, mask, excluded, |j| rounded(j) << 32 | j as u64);
        let m = n.min(row.len());
        if m == 0 {
            return;
        }
        let last = keys[m - 1] >> 32;
        let mut end = m;
        while end < n && keys[end] >> 32 == last {
            end += 1;
        }
        if end == m {
            // The usual case: the candidates to order exactly are the row's first `m`, put in
            // order in place (no scratch to clear and copy).
            exact_in_order(&mut row[..m], &keys[..m], ids, sq_dists);
        } else {
            let mut exact = [0u128; 32];
            exact_in_order(&mut exact[..end], &keys[..end], ids, sq_dists);
            row[..m].copy_from_slice(&exact[..m]);
        }
    }
}

/// The exact `u128` keys of the block positions in `rounded` (its low 32 bits, in the order of
/// their rounded distances) into `exact`, in order: by insertion, which only moves a key past
/// others of equal rounded distance.
#[inline(always)]
fn exact_in_order<T: Scalar>(exact: &mut [u128], rounded: &[u64], ids: &[u32], sq_dists: &[T]) {
    for (e, &key) in exact.iter_mut().zip(rounded) {
        let j = key as u32 as usize;
        *e = order::key64(sq_dists[j], ids[j]);
    }
    for i in 1..exact.len() {
        let cand = exact[i];
        let mut j = i;
        while j > 0 && cand < exact[j - 1] {
            exact[j] = exact[j - 1];
            j -= 1;
        }
        exact[j] = cand;
    }
}

/// The k nearest within a radius for one single query with larger `k`: packed keys `K`
/// (`src/query/order.rs`) appended unsorted to a buffer of `2k` while they precede the worst
/// key, which is the `k`-th smallest key at the last compaction (a selection when the buffer is
/// full), or `(sq_radius, u32::MAX)` before `k` keys were held. The worst key may lag behind
/// the true `k`-th nearest held, which only lets a few more candidates in (pruning stays
/// exact); [`KnnBuf::finish`] sorts and keeps `k`. An insertion costs a store instead of a
/// shift by a mispredicted loop.
pub(crate) struct KnnBuf<'a, K> {
    /// Storage of `2k` keys, the first `len` held.
    buf: &'a mut [K],
    len: usize,
    k: usize,
    worst: K,
}

impl<'a, K: RowKey> KnnBuf<'a, K> {
    /// A set of the `k ≥ 1` nearest over `buf` (of length `2k`).
    pub(crate) fn new<T: Scalar>(buf: &'a mut [K], k: usize, sq_radius: T) -> Self
    where
        K: PackedKey<T>,
    {
        debug_assert!(k >= 1 && buf.len() == 2 * k);
        Self {
            buf,
            len: 0,
            k,
            worst: K::of(u32::MAX, sq_radius),
        }
    }

    /// Sorts the held keys and returns the `k` first (fewer if fewer were found).
    pub(crate) fn finish(self) -> &'a [K] {
        let held = &mut self.buf[..self.len];
        held.sort_unstable();
        &held[..self.len.min(self.k)]
    }
}

impl<T: Scalar, K: RowKey + PackedKey<T>> ResultSet<T> for KnnBuf<'_, K> {
    #[inline(always)]
    fn worst_key(&self) -> (T, u32) {
        self.worst.pair()
    }

    #[inline(always)]
    fn insert(&mut self, index: u32, sq_dist: T) {
        self.buf[self.len] = K::of(index, sq_dist);
        self.len += 1;
        if self.len == self.k && self.worst.index() == u32::MAX {
            // Full for the first time: the worst is the largest held.
            self.worst = self.buf[..self.k]
                .iter()
                .copied()
                .max()
                .unwrap_or(self.worst);
        } else if self.len == self.buf.len() {
            let k = self.k;
            self.buf[..self.len].select_nth_unstable(k - 1);
            self.worst = self.buf[k - 1];
            self.len = k;
        }
    }

    #[inline(always)]
    fn offer(&mut self, index: u32, sq_dist: T) {
        if K::of(index, sq_dist) < self.worst {
            <Self as ResultSet<T>>::insert(self, index, sq_dist);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Offers the same candidates (in distance `T`) to the heap and to the packed sets with
    /// keys `K`, one at a time and, for the row, the first 32 as one block, and checks they keep
    /// the same as a brute-force selection.
    fn check_sets<T: Scalar, K: RowKey + PackedKey<T> + std::fmt::Debug>() {
        let cands: Vec<(u32, T)> = (0..200u32)
            .map(|i| {
                let d = ((i * 37) % 23) as f64 * 0.5 + if i % 3 == 0 { 1e-9 } else { 0.0 };
                (i.wrapping_mul(2_654_435_761) % 1000, T::from_f64(d))
            })
            .collect();
        let excluded = cands[5].0;
        for k in [1usize, 3, 8, 50, 300] {
            for r2 in [f64::INFINITY, 4.0, 0.0].map(T::from_f64) {
                let mut heap_out = Vec::new();
                let mut heap = NeighborHeap::new(&mut heap_out, k, r2);
                let mut single_keys = vec![K::default(); k];
                let mut single = KnnRow::new(&mut single_keys[..], r2);
                let mut block_keys = vec![K::default(); k];
                let mut block = KnnRow::new(&mut block_keys[..], r2);
                let mut buf_keys = vec![K::default(); 2 * k];
                let mut buffered = KnnBuf::new(&mut buf_keys[..], k, r2);
                // the first 32 candidates as one block, the excluded index among them
                let (ids, dists): (Vec<u32>, Vec<T>) = cands[..32].iter().copied().unzip();
                let mask = below(&dists, ResultSet::<T>::bound(&block));
                block.offer_block(&ids, &dists, mask, excluded);
                for (n, &(i, d)) in cands.iter().enumerate() {
                    if i != excluded {
                        heap.offer(i, d);
                        single.offer(i, d);
                        buffered.offer(i, d);
                        if n >= 32 {
                            block.offer(i, d);
                        }
                    }
                    // The buffer's worst key never precedes the exact one (it may lag).
                    let (exact, lagging) = (heap.worst_key(), buffered.worst_key());
                    assert!(!order::precedes(lagging, exact), "k {k} r2 {r2}");
                    assert_eq!(heap.worst_key(), single.worst_key());
                }
                assert_eq!(heap.worst_key(), block.worst_key());
                heap.finish();
                let want: Vec<(T, u32)> = heap_out.iter().map(|n| n.key()).collect();
                let got_single: Vec<(T, u32)> = single.held().map(|e| e.pair()).collect();
                assert_eq!(got_single, want, "k {k} r2 {r2}");
                let got_block: Vec<(T, u32)> = block.held().map(|e| e.pair()).collect();
                assert_eq!(got_block, want, "block: k {k} r2 {r2}");
                let got_buffered: Vec<(T, u32)> =
                    buffered.finish().iter().map(|&e| e.pair()).collect();
                assert_eq!(got_buffered, want, "k {k} r2 {r2}");
                // a brute-force reference: sort all within the radius, keep k
                let mut all: Vec<(T, u32)> = cands
                    .iter()
                    .filter(|c| c.1 <= r2 && c.0 != excluded)
                    .map(|&(i, d)| (d, i))
                    .collect();
                all.sort_by(|&a, &b| order::cmp(a, b));
                all.dedup();
                all.truncate(k);
                assert_eq!(want, all);
            }
        }
    }

    /// The bits of the entries of `d` (at most 32) within `bound`.
    fn below<T: Scalar>(d: &[T], bound: T) -> u32 {
        d.iter()
            .enumerate()
            .fold(0, |m, (j, &x)| m | u32::from(x <= bound) << j)
    }

    #[test]
    fn the_k_nearest_sets_agree() {
        check_sets::<f32, u64>();
        check_sets::<f32, u128>();
        check_sets::<f64, u128>();
    }

    #[test]
    fn within_radius_keeps_everything_inside() {
        let mut out = Vec::new();
        let mut set = WithinRadius {
            out: &mut out,
            sq_radius: 1.0f64,
        };
        for (i, d) in [(0u32, 1.0), (1, 1.5), (2, 0.0), (3, 1.0)] {
            set.offer(i, d);
        }
        assert_eq!(set.worst_key(), (1.0, u32::MAX));
        let got: Vec<u32> = out.iter().map(|n| n.index).collect();
        assert_eq!(got, vec![0, 2, 3]);
    }
}
