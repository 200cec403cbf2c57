//! The result-set policy every search fills (as nanoflann's `KNNResultSet` and
//! `RadiusResultSet` serve one search): a set is offered candidates `(index, sq_dist)` and
//! says, through its worst admissible key, which candidates can still enter. The searches —
//! the single-query descent (`src/tree/search.rs`), the grouped all-point search
//! (`src/tree/group_search.rs`) and the baselines — only offer; what is kept is decided here:
//!
//! - `NeighborHeap` (`src/query/heap.rs`): the k nearest within a radius, any `k`;
//! - `SortedRow`: the same for small `k`, kept sorted by insertion;
//! - `KnnRow`: the same for one single `f32` query, sorted by insertion (its first leaf
//!   as one sorted block);
//! - `WithinRadius`: every point within a radius.
//!
//! All of them order by `(sq_dist, index)` (`src/query/order.rs`).

use super::{order, Neighbor, NeighborHeap};
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

/// How a [`SortedRow`] holds a neighbour: as a [`Neighbor`], or packed into one integer key
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

/// The k nearest within a radius kept sorted by insertion in a borrowed slice of length `k`
/// (its first `len` entries hold the set): a candidate costs a short shift and the result
/// needs no final sort. For small `k`.
pub(crate) struct SortedRow<'a, T, E> {
    /// Storage of `k` entries.
    pub row: &'a mut [E],
    /// How many are held.
    pub len: &'a mut usize,
    /// The squared radius.
    pub sq_radius: T,
}

impl<T: Scalar, E: RowEntry<T>> ResultSet<T> for SortedRow<'_, T, E> {
    #[inline(always)]
    fn worst_key(&self) -> (T, u32) {
        let k = self.row.len();
        if *self.len < k {
            (self.sq_radius, u32::MAX)
        } else {
            self.row[k - 1].pair()
        }
    }

    #[inline(always)]
    fn insert(&mut self, index: u32, sq_dist: T) {
        let k = self.row.len();
        let cand = E::of(index, sq_dist);
        let held = *self.len;
        // the slot the candidate's entry ends in; the worst entry falls off a full row
        let last = if held < k {
            *self.len += 1;
            held
        } else {
            k - 1
        };
        if last >= LONG_ROW {
            // long rows: a binary search and one block move instead of a compare per entry
            let at = self.row[..last].partition_point(|e| e.precedes(cand));
            self.row.copy_within(at..last, at + 1);
            self.row[at] = cand;
            return;
        }
        let mut j = last;
        while j > 0 && cand.precedes(self.row[j - 1]) {
            self.row[j] = self.row[j - 1];
            j -= 1;
        }
        self.row[j] = cand;
    }
}

/// Held entries from which [`SortedRow`] finds a candidate's place by binary search.
const LONG_ROW: usize = 24;

/// The k nearest within a radius for one single query with small `k`, kept sorted in a
/// borrowed slice of length `k` that [`KnnRow::new`] fills with the sentinel
/// `(sq_radius, u32::MAX)`, packed [`Key32`] entries. The sentinel is the worst admissible key
/// of a set that is not yet full (caller indices are below `u32::MAX`), so the worst key is
/// always the last entry and no count is tested on every offer (cachegrind's branch simulation
/// counted that test among the most mispredicted of a single query, README "Single queries, the
/// floor, and copies of a point"); an insertion shifts the entries that follow the candidate,
/// and the query's first leaf enters as one sorted block ([`ResultSet::offer_block`]).
pub(crate) struct KnnRow<'a> {
    /// Storage of `k ≥ 1` entries, sorted, sentinels last.
    row: &'a mut [Key32],
}

impl<'a> KnnRow<'a> {
    /// A set over `row` (its length is `k`, at least 1), every entry the sentinel.
    pub(crate) fn new<T: Scalar>(row: &'a mut [Key32], sq_radius: T) -> Self {
        row.fill(Key32(order::key32(sq_radius, u32::MAX)));
        Self { row }
    }

    /// The entries held, in `(sq_dist, index)` order.
    pub(crate) fn held(&self) -> impl Iterator<Item = Key32> + '_ {
        self.row
            .iter()
            .copied()
            .take_while(|e| e.0 as u32 != u32::MAX)
    }
}

impl<T: Scalar> ResultSet<T> for KnnRow<'_> {
    #[inline(always)]
    fn worst_key(&self) -> (T, u32) {
        order::unkey32(self.row[self.row.len() - 1].0)
    }

    #[inline(always)]
    fn insert(&mut self, index: u32, sq_dist: T) {
        let cand = order::key32(sq_dist, index);
        let row = &mut *self.row;
        let mut j = row.len() - 1;
        while j > 0 && cand < row[j - 1].0 {
            row[j] = row[j - 1];
            j -= 1;
        }
        row[j] = Key32(cand);
    }

    #[inline(always)]
    fn offer(&mut self, index: u32, sq_dist: T) {
        if order::key32(sq_dist, index) < self.row[self.row.len() - 1].0 {
            <Self as ResultSet<T>>::insert(self, index, sq_dist);
        }
    }

    /// An empty row (the query's first leaf) takes the block's candidates at once: their keys
    /// sorted (a sorting network, `src/select/network.rs`) and the first `k` copied in, instead of one insertion
    /// each. Most of a single query's insertions come from its first leaf (every point of it is
    /// within the sentinel bound), each shifting the sentinels behind it; the kept keys are the
    /// same `k` smallest, so the row, its bound and all later pruning are unchanged.
    #[inline(always)]
    fn offer_block(&mut self, ids: &[u32], sq_dists: &[T], mut mask: u32, excluded: u32) {
        if self.row[0].0 as u32 != u32::MAX {
            return offer_each(self, ids, sq_dists, mask, excluded);
        }
        // Every candidate within the bound precedes the sentinel `(sq_radius, u32::MAX)`.
        // Unused entries (and the excluded index's, written at `n` and not counted) hold the
        // largest key, which sorts last.
        let mut keys = [u64::MAX; 33];
        let mut n = 0;
        while mask != 0 {
            let j = mask.trailing_zeros() as usize;
            mask &= mask - 1;
            let id = ids[j];
            keys[n] = order::key32(sq_dists[j], id);
            n += (id != excluded) as usize;
        }
        keys[n] = u64::MAX;
        let sorted: &mut [u64; 32] = (&mut keys[..32]).try_into().unwrap();
        sort32(sorted);
        let m = n.min(self.row.len());
        for (e, &key) in self.row[..m].iter_mut().zip(&keys[..m]) {
            *e = Key32(key);
        }
    }
}

/// The k nearest within a radius for one single `f32` query with larger `k`: packed
/// [`order::key32`] keys appended unsorted to a buffer of `2k` while they precede the worst
/// key, which is the `k`-th smallest key at the last compaction (a selection when the buffer is
/// full), or `(sq_radius, u32::MAX)` before `k` keys were held. The worst key may lag behind
/// the true `k`-th nearest held, which only lets a few more candidates in (pruning stays
/// exact); [`KnnBuf::finish`] sorts and keeps `k`. An insertion costs a store instead of a
/// shift by a mispredicted loop.
pub(crate) struct KnnBuf<'a> {
    /// Storage of `2k` keys, the first `len` held.
    buf: &'a mut [u64],
    len: usize,
    k: usize,
    worst: u64,
}

impl<'a> KnnBuf<'a> {
    /// A set of the `k ≥ 1` nearest over `buf` (of length `2k`).
    pub(crate) fn new<T: Scalar>(buf: &'a mut [u64], k: usize, sq_radius: T) -> Self {
        debug_assert!(k >= 1 && buf.len() == 2 * k);
        Self {
            buf,
            len: 0,
            k,
            worst: order::key32(sq_radius, u32::MAX),
        }
    }

    /// Sorts the held keys and returns the `k` first (fewer if fewer were found).
    pub(crate) fn finish(self) -> &'a [u64] {
        let held = &mut self.buf[..self.len];
        held.sort_unstable();
        &held[..self.len.min(self.k)]
    }
}

impl<T: Scalar> ResultSet<T> for KnnBuf<'_> {
    #[inline(always)]
    fn worst_key(&self) -> (T, u32) {
        order::unkey32(self.worst)
    }

    #[inline(always)]
    fn insert(&mut self, index: u32, sq_dist: T) {
        self.buf[self.len] = order::key32(sq_dist, index);
        self.len += 1;
        if self.len == self.k && self.worst as u32 == u32::MAX {
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
        if order::key32(sq_dist, index) < self.worst {
            <Self as ResultSet<T>>::insert(self, index, sq_dist);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Offers the same candidates to every k-nearest set and checks they keep the same.
    #[test]
    fn the_k_nearest_sets_agree() {
        let cands: Vec<(u32, f32)> = (0..200u32)
            .map(|i| {
                (
                    i.wrapping_mul(2_654_435_761) % 1000,
                    ((i * 37) % 23) as f32 * 0.5,
                )
            })
            .collect();
        for k in [1usize, 3, 8, 50, 300] {
            for r2 in [f32::INFINITY, 4.0, 0.0] {
                let mut heap_out = Vec::new();
                let mut heap = NeighborHeap::new(&mut heap_out, k, r2);
                let mut nb = vec![Neighbor::<f32>::default(); k];
                let mut keys = vec![Key32::default(); k];
                let (mut nb_len, mut key_len) = (0, 0);
                let mut sorted = SortedRow {
                    row: &mut nb[..],
                    len: &mut nb_len,
                    sq_radius: r2,
                };
                let mut packed = SortedRow {
                    row: &mut keys[..],
                    len: &mut key_len,
                    sq_radius: r2,
                };
                let mut single_keys = vec![Key32::default(); k];
                let mut single = KnnRow::new(&mut single_keys[..], r2);
                let mut buf_keys = vec![0u64; 2 * k];
                let mut buffered = KnnBuf::new(&mut buf_keys[..], k, r2);
                for &(i, d) in &cands {
                    heap.offer(i, d);
                    sorted.offer(i, d);
                    packed.offer(i, d);
                    single.offer(i, d);
                    buffered.offer(i, d);
                    // The buffer's worst key never precedes the exact one (it may lag).
                    let (exact, lagging) = (heap.worst_key(), buffered.worst_key());
                    assert!(!order::precedes(lagging, exact), "k {k} r2 {r2}");
                    assert_eq!(heap.worst_key(), sorted.worst_key());
                    assert_eq!(heap.worst_key(), packed.worst_key());
                    assert_eq!(heap.worst_key(), single.worst_key());
                }
                heap.finish();
                let want: Vec<(f32, u32)> = heap_out.iter().map(|n| n.key()).collect();
                let got: Vec<(f32, u32)> = nb[..nb_len].iter().map(|n| n.key()).collect();
                let got_packed: Vec<(f32, u32)> =
                    keys[..key_len].iter().map(|&e| e.pair()).collect();
                let got_single: Vec<(f32, u32)> = single.held().map(|e| e.pair()).collect();
                assert_eq!(got_single, want, "k {k} r2 {r2}");
                let got_buffered: Vec<(f32, u32)> = buffered
                    .finish()
                    .iter()
                    .map(|&e| order::unkey32(e))
                    .collect();
                assert_eq!(got_buffered, want, "k {k} r2 {r2}");
                assert_eq!(got, want, "k {k} r2 {r2}");
                assert_eq!(got_packed, want, "k {k} r2 {r2}");
                // a brute-force reference: sort all within the radius, keep k
                let mut all: Vec<(f32, u32)> = cands
                    .iter()
                    .filter(|c| c.1 <= r2)
                    .map(|&(i, d)| (d, i))
                    .collect();
                all.sort_by(|&a, &b| order::cmp(a, b));
                all.dedup();
                all.truncate(k);
                assert_eq!(want, all);
            }
        }
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
