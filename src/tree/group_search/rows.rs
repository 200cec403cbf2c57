//! The row collectors of the grouped search: one result set (`src/query/result_set.rs`) per
//! member of a group, kept from tree to tree of a forest, and how their rows are written to a
//! table chunk ([`RowSets`], the one collector trait for a single tree and a forest). Which
//! collector serves which neighbourhood is [`super::run_rows`]'s choice.

use super::GROUP;
use crate::query::order::PackedKey;
use crate::query::result_set::{ResultSet, RowEntry, WithinRadius};
use crate::query::{order, Neighbor, NeighborHeap};
use crate::scalar::{Scalar, ScalarType};
use crate::table::RowsChunk;

/// One result set (`src/query/result_set.rs`) per member of a group, and how their rows are
/// written.
pub(super) trait RowSets<T: Scalar> {
    /// The result set of one member.
    type Set<'a>: ResultSet<T>
    where
        Self: 'a;
    /// Empties the first `m` rows.
    fn clear(&mut self, m: usize);
    /// The result set of member `i`.
    fn set(&mut self, i: usize) -> Self::Set<'_>;
    /// Adds a candidate to member `i`'s set (it must precede the set's worst key, see
    /// [`super::admits`]); returns the set's new worst key.
    #[inline(always)]
    fn insert(&mut self, i: usize, index: u32, sq_dist: T) -> (T, u32) {
        let mut set = self.set(i);
        set.insert(index, sq_dist);
        set.worst_key()
    }
    /// Whether keys change as candidates arrive (k-nearest) or stay the radius (radius).
    const TIGHTENS: bool;

    /// Appends the first `m` rows, in `(sq_dist, index)` order where asked, to `out`.
    fn write(&mut self, m: usize, out: &mut RowsChunk<'_, T>);
    /// Appends, for every id of `self_ids`, row 0 without that id: the rows of a group of
    /// copies of one point, searched once (radius rows only; see `Search::group_of`).
    fn write_copies(&mut self, _self_ids: &[u32], _out: &mut RowsChunk<'_, T>) {
        unreachable!("only radius rows are shared by copies")
    }
}

/// `k` up to [`SORTED_MAX_K`]: each row sorted by insertion in a fixed slice of `k + 1` entries
/// of a flat buffer, so a candidate costs a short shift and the row needs no final sort. Entries
/// `E` are [`Neighbor`]s, or for `f32` the packed keys [`Key32`], so the insertion compares one
/// integer instead of two floats and an index. Slot 0 of each row is a guard that no candidate precedes
/// (`(0, 0)`: distances are never negative), so the shift stops there without testing the
/// position; the row's entries are slots `1..=len`.
pub(super) struct SortedRows<T, E> {
    k: usize,
    sq_radius: T,
    len: [usize; GROUP],
    buf: Vec<E>,
}

impl<T: Scalar, E: RowEntry<T>> SortedRows<T, E> {
    pub(super) fn new(k: usize, sq_radius: T) -> Self {
        Self {
            k,
            sq_radius,
            len: [0; GROUP],
            buf: vec![E::of(0, T::ZERO); GROUP * (k + 1)],
        }
    }
}

/// Rows up to this `k` are kept sorted by insertion; larger ones in heaps of packed keys
/// ([`KeyHeapRows`]) up to [`KEY_HEAP_MAX_K`], in growing heaps of neighbours beyond. Measured
/// on the 77k torus (README "Single queries, the floor, and copies of a point", round 4): with
/// the guard slot, sorted rows take 17 % fewer instructions than the key heaps for k = 30 and
/// 11 % fewer for k = 52 (each point left out), and 10–20 % less time.
pub(super) const SORTED_MAX_K: usize = 64;

/// Rows up to this `k` are heaps of packed keys: `GROUP · k` keys of scratch per thread.
pub(super) const KEY_HEAP_MAX_K: usize = 4096;

impl<T: Scalar, E: RowEntry<T>> RowSets<T> for SortedRows<T, E> {
    type Set<'a>
        = NoSet
    where
        Self: 'a;
    const TIGHTENS: bool = true;
    #[inline]
    fn clear(&mut self, m: usize) {
        self.len[..m].fill(0);
    }
    fn set(&mut self, _i: usize) -> NoSet {
        NoSet
    }
    #[inline(always)]
    fn insert(&mut self, i: usize, index: u32, sq_dist: T) -> (T, u32) {
        let k = self.k;
        let row = &mut self.buf[i * (k + 1)..(i + 1) * (k + 1)];
        let cand = E::of(index, sq_dist);
        let held = self.len[i];
        // the slot the candidate's entry ends in; the worst entry falls off a full row
        let mut j = if held < k {
            self.len[i] = held + 1;
            held + 1
        } else {
            k
        };
        // SAFETY: `1 ≤ j ≤ k < row.len()` on entry, and no candidate precedes the guard
        // `row[0]`, so the loop leaves at `j = 1` at the latest: `j - 1` and `j` stay in
        // `row`.
        unsafe {
            while cand.precedes(*row.get_unchecked(j - 1)) {
                *row.get_unchecked_mut(j) = *row.get_unchecked(j - 1);
                j -= 1;
            }
            *row.get_unchecked_mut(j) = cand;
        }
        if held + 1 < k {
            (self.sq_radius, u32::MAX)
        } else {
            row[k].pair()
        }
    }
    fn write(&mut self, m: usize, out: &mut RowsChunk<'_, T>) {
        let k = self.k;
        for i in 0..m {
            let row = &self.buf[i * (k + 1) + 1..i * (k + 1) + 1 + self.len[i]];
            out.push_row(row.len(), row.iter().map(|&e| e.pair()));
        }
    }
}

/// A packed key (`src/query/order.rs`, [`PackedKey`]) the grouped search can also rank
/// (`gather.rs`).
pub(super) trait GroupKey<T>: PackedKey<T> + super::gather::Rank + 'static {}

impl<T, K: PackedKey<T> + super::gather::Rank + 'static> GroupKey<T> for K {}

/// Larger `k`: each row a binary max-heap of packed keys in a fixed slice of a flat buffer, so
/// a candidate costs `log k` integer compares and moves (a sorted row shifts or moves about
/// `k / 2` entries) and the worst key is always exact; sorted once, when written.
pub(super) struct KeyHeapRows<T, K> {
    k: usize,
    sq_radius: T,
    len: [usize; GROUP],
    buf: Vec<K>,
}

impl<T: Scalar, K: GroupKey<T>> KeyHeapRows<T, K> {
    pub(super) fn new(k: usize, sq_radius: T) -> Self {
        Self {
            k,
            sq_radius,
            len: [0; GROUP],
            buf: vec![K::default(); GROUP * k],
        }
    }
}

/// [`KeyHeapRows`]' rows are never asked for as [`ResultSet`]s: the search inserts through
/// [`RowSets::insert`]. This set only satisfies the trait.
pub(super) struct NoSet;

impl<T: Scalar> ResultSet<T> for NoSet {
    fn worst_key(&self) -> (T, u32) {
        unreachable!("heap rows insert directly")
    }
    fn insert(&mut self, _index: u32, _sq_dist: T) {
        unreachable!("heap rows insert directly")
    }
}

impl<T: Scalar, K: GroupKey<T>> RowSets<T> for KeyHeapRows<T, K> {
    type Set<'a>
        = NoSet
    where
        Self: 'a;
    const TIGHTENS: bool = true;
    #[inline]
    fn clear(&mut self, m: usize) {
        self.len[..m].fill(0);
    }
    fn set(&mut self, _i: usize) -> NoSet {
        NoSet
    }
    #[inline(always)]
    fn insert(&mut self, i: usize, index: u32, sq_dist: T) -> (T, u32) {
        let k = self.k;
        let heap = &mut self.buf[i * k..i * k + k];
        let key = K::of(index, sq_dist);
        let len = self.len[i];
        if len < k {
            // sift up from the new leaf
            let mut c = len;
            while c > 0 {
                let p = (c - 1) / 2;
                if heap[p] >= key {
                    break;
                }
                heap[c] = heap[p];
                c = p;
            }
            heap[c] = key;
            self.len[i] = len + 1;
            if len + 1 < k {
                return (self.sq_radius, u32::MAX);
            }
        } else {
            // the worst (the root) falls off: sift the candidate down from the root
            let mut c = 0;
            loop {
                let l = 2 * c + 1;
                if l >= k {
                    break;
                }
                let r = l + 1;
                let big = if r < k && heap[r] > heap[l] { r } else { l };
                if heap[big] <= key {
                    break;
                }
                heap[c] = heap[big];
                c = big;
            }
            heap[c] = key;
        }
        heap[0].pair()
    }
    fn write(&mut self, m: usize, out: &mut RowsChunk<'_, T>) {
        let k = self.k;
        for i in 0..m {
            let row = &mut self.buf[i * k..i * k + self.len[i]];
            row.sort_unstable();
            out.push_row(row.len(), row.iter().map(|&e| e.pair()));
        }
    }
}

/// Appends one row of neighbours to the chunk.
#[inline]
fn write_neighbors<T: Scalar>(row: &[Neighbor<T>], out: &mut RowsChunk<'_, T>) {
    out.push_row(row.len(), row.iter().map(|nb| (nb.sq_dist, nb.index)));
}

/// Sorts a row by `(sq_dist, index)` through the packed keys of `src/query/order.rs`; every key
/// is distinct, so an unstable sort gives the one order.
fn sort_row<T: Scalar>(row: &mut [Neighbor<T>], keys: &mut Keys) {
    if T::TYPE == ScalarType::F32 {
        // f32 bits fit in 32: one u64 key (the f64 round trip of an f32 is exact).
        let keys = &mut keys.narrow;
        keys.clear();
        keys.extend(row.iter().map(|nb| order::key32(nb.sq_dist, nb.index)));
        keys.sort_unstable();
        for (nb, &key) in row.iter_mut().zip(keys.iter()) {
            (nb.sq_dist, nb.index) = order::unkey32(key);
        }
    } else {
        let keys = &mut keys.wide;
        keys.clear();
        keys.extend(row.iter().map(|nb| order::key64(nb.sq_dist, nb.index)));
        keys.sort_unstable();
        for (nb, &key) in row.iter_mut().zip(keys.iter()) {
            (nb.sq_dist, nb.index) = order::unkey64(key);
        }
    }
}

/// Scratch keys of [`sort_row`].
#[derive(Default)]
struct Keys {
    narrow: Vec<u64>,
    wide: Vec<u128>,
}

/// Large `k`: a bounded heap per row ([`NeighborHeap`]), sorted at the end.
pub(super) struct HeapRows<T> {
    k: usize,
    sq_radius: T,
    rows: Vec<Vec<Neighbor<T>>>,
    keys: Keys,
}

impl<T: Scalar> RowSets<T> for HeapRows<T> {
    type Set<'a>
        = NeighborHeap<'a, T>
    where
        Self: 'a;
    const TIGHTENS: bool = true;
    #[inline]
    fn clear(&mut self, m: usize) {
        self.rows[..m].iter_mut().for_each(Vec::clear);
    }
    #[inline]
    fn set(&mut self, i: usize) -> NeighborHeap<'_, T> {
        NeighborHeap::resume(&mut self.rows[i], self.k, self.sq_radius)
    }
    fn write(&mut self, m: usize, out: &mut RowsChunk<'_, T>) {
        for r in &mut self.rows[..m] {
            sort_row(r, &mut self.keys);
            write_neighbors(r, out);
        }
    }
}

/// Radius: every candidate within the radius ([`WithinRadius`]), sorted at the end if asked.
pub(super) struct RadiusRows<T> {
    sq_radius: T,
    sorted: bool,
    rows: Vec<Vec<Neighbor<T>>>,
    keys: Keys,
}

impl<T: Scalar> RowSets<T> for RadiusRows<T> {
    type Set<'a>
        = WithinRadius<'a, T>
    where
        Self: 'a;
    const TIGHTENS: bool = false;
    #[inline]
    fn clear(&mut self, m: usize) {
        self.rows[..m].iter_mut().for_each(Vec::clear);
    }
    #[inline(always)]
    fn set(&mut self, i: usize) -> WithinRadius<'_, T> {
        WithinRadius {
            out: &mut self.rows[i],
            sq_radius: self.sq_radius,
        }
    }
    fn write(&mut self, m: usize, out: &mut RowsChunk<'_, T>) {
        for r in &mut self.rows[..m] {
            if self.sorted {
                sort_row(r, &mut self.keys);
            }
            write_neighbors(r, out);
        }
    }
    fn write_copies(&mut self, self_ids: &[u32], out: &mut RowsChunk<'_, T>) {
        let r = &mut self.rows[0];
        if self.sorted {
            sort_row(r, &mut self.keys);
        }
        // The shared row as two flat arrays, stored once; each member's row (the shared one
        // less the member itself) is written only into the final table.
        let ids: Vec<u32> = r.iter().map(|nb| nb.index).collect();
        let dists: Vec<T> = r.iter().map(|nb| nb.sq_dist).collect();
        out.push_shared(&ids, &dists, self_ids);
    }
}

impl<T: Scalar> HeapRows<T> {
    pub(super) fn new(k: usize, sq_radius: T) -> Self {
        Self {
            k,
            sq_radius,
            rows: (0..GROUP).map(|_| Vec::new()).collect(),
            keys: Keys::default(),
        }
    }
}

impl<T: Scalar> RadiusRows<T> {
    pub(super) fn new(sq_radius: T, sorted: bool) -> Self {
        Self {
            sq_radius,
            sorted,
            rows: (0..GROUP).map(|_| Vec::new()).collect(),
            keys: Keys::default(),
        }
    }
}
