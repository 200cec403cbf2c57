//! Rows of a group from one gathered block of candidates: the grouped search's fast path for
//! k-nearest rows up to `rows::SORTED_MAX_K` (`f32` rows up to `rows::KEY_HEAP_MAX_K`) and for
//! radius rows of a tree's own points.
//!
//! The parent's search offers every candidate to a member's row as it is found, nearest cells
//! first, and a row that is not yet full takes whatever comes: the first leaves fill it with
//! points that later ones push out again (about two insertions per neighbour kept, each a
//! shift of a sorted row whose length the branch predictor cannot guess). Here the group first
//! *gathers* every point within a squared radius `r²` of its bounding box — one traversal with
//! a fixed bound, the leaves' points copied into one contiguous block — and each member then
//! computes its squared distances to the whole block in straight-line code, keeps the keys
//! within `r²` and orders them once (by rank, without branches, when there are few).
//!
//! Radius rows gather within the radius itself. For k-nearest rows `r²` is a guess: the
//! previous group's largest k-th squared distance with a margin (groups
//! follow each other in tree order, so the next one lies close by and its points' k-th
//! neighbours are about as far). A member's row is exact as soon as it holds `k` keys within
//! `r²`: every point left out lies in a cell whose lower bound to the group's box — and so to
//! the member — exceeds `r²` (the bounds are exact in floating point, see the parent module),
//! so it cannot precede the k-th key. When a member falls short the group gathers once more
//! within a wider radius; when it falls short again, or the block grows past a cap (clusters
//! of copies of a point, where the parent's tie pruning is the right tool), the group is
//! answered by the parent's search instead. The rows are the same either way, byte for byte:
//! the guess only decides the speed.

#[cfg(all(target_arch = "x86_64", rustc_1_89))]
use super::avx512;
use super::rows::GroupKey;
use super::{box_dist, Members, Search, BLOCK, GROUP};
use crate::scalar::Scalar;
use crate::table::RowsChunk;
use crate::tree::kernel::sq_dists_below_by_dim;
#[cfg(all(target_arch = "x86_64", rustc_1_89))]
use std::any::Any;
use std::ops::Range;

/// The margin of the guess, on squared distances, is `1 + spread / √k`: the k-th squared
/// distance of a point varies from point to point by about `1/√k` of itself (it counts about k
/// points of a random sample; on a volume by `2/3` of that). The spread starts at
/// [`GUESS_SPREAD`] and adapts to the data: each group a gathered block answers shrinks it by
/// [`SHRINK`], each group that falls short grows it by [`GROW`]; in balance one group in
/// `1 + ln GROW / ln(1/SHRINK)` (about 14) falls short. A short group costs a second search, a
/// wide margin larger blocks and more keys to rank in every group. Fixed spreads measured: on
/// the 77k torus 1.5–2 alike and 3 5–10 % slower; on the 1M cube 1.0 10 % faster than 2 but
/// on the torus 4–10 % slower. Adapting takes the cube's kNN table (k = 10) 6 % below the
/// fixed 2 and leaves the surfaces as they were. Under a radius (k nearest within it) the
/// spread stays fixed: rows there may be short because the radius cuts them, and adapting
/// measured 5–10 % slower (1M torus).
const GUESS_SPREAD: f64 = 2.0;

/// The factor on the spread of each group answered from a gathered block.
const SHRINK: f64 = 0.98;

/// The factor on the spread of each group whose block falls short.
const GROW: f64 = 1.3;

/// The range of the spread.
const MIN_SPREAD: f64 = 0.25;
const MAX_SPREAD: f64 = 4.0;

/// The spread of a member's first bound: its predecessor's k-th squared distance times
/// `1 + MEMBER_SPREAD / √k` (a member above it takes its keys within the group's squared
/// radius after all, a second pass over the block).
const MEMBER_SPREAD: f64 = 1.0;

/// Most candidates a group gathers, per neighbour asked for (and at least [`MIN_CAP`]): a
/// larger block means copies of a point or a guess far too wide, and the parent's search
/// answers the group. Volumes need room: in a uniform cube a group of 16 gathers about 250
/// points for k = 10 (12 per neighbour left three quarters of the 1M cube's groups to the
/// parent's search, 1.15 s against 0.85 s with 64; measured alike with 32 on the surface and
/// duplicate-heavy sets). A short group first retries within a wider radius ([`RETRY`]).
const CAP_PER_NEIGHBOUR: usize = 64;

/// A group whose block fell short gathers once more within this many times the squared
/// radius before the parent's search answers it. Measured with the AVX-512 loops (one thread,
/// side by side): 1M cube k = 10 447–451 → 419–432 ms, 1M torus k = 10 240–265 → 218–236 ms,
/// k = 30 alike; 1.5 measured the same as 2 within the noise. (Before those loops, when a
/// member's keys cost more, the retry gained nothing.)
const RETRY: f64 = 2.0;

/// The smallest cap of a gathered block.
const MIN_CAP: usize = 256;

/// The largest cap of a gathered block: radius rows double their cap up to this many points
/// (rows of more neighbours are the parent's search's, whose chunk reserves fallibly; the
/// block's scratch — its points, a member's keys and the group's rows, up to [`GROUP`] times
/// the block — stays a few megabytes).
const MAX_CAP: usize = 1 << 16;

/// A member's keys are ordered by rank, without branches, up to this many: `n²` compares, four
/// at a time. Measured (CPU time, 77k torus): 24, 32 and 48 take the same time for `f32`
/// tables, 48 is 5–10 % faster than 32 for `f64` ones (k = 15); 128 is slower than sorting
/// for k = 52 (about 80 keys).
const RANK_MAX: usize = 48;

/// More keys than this many times `k` are first cut to the `k` smallest, then sorted; fewer
/// are sorted whole.
const SELECT_FROM: usize = 4;

/// The scratch of one worker: the gathered block, the members' rows and the guess.
pub(super) struct Gather<T, K, const D: usize> {
    /// Neighbours per row: `k`, or `usize::MAX` for every point within the radius.
    k: usize,
    /// Whether rows are ordered (radius rows may be asked for unordered).
    sorted: bool,
    /// Squared radius of the next gather (k-nearest rows); `None` until a group of this run
    /// was answered.
    guess: Option<T>,
    /// Factor from a group's largest k-th squared distance to the next guess: `1 + spread / √k`.
    margin: T,
    /// The margin's spread (see [`GUESS_SPREAD`]).
    spread: f64,
    /// Factor from a member's k-th squared distance to the next member's first bound:
    /// `1 + MEMBER_SPREAD / √k`.
    member_margin: T,
    /// Most points a block may hold: fixed for k-nearest rows, doubled for radius rows (up to
    /// [`MAX_CAP`]) each time a group's block would pass it.
    cap: usize,
    /// The gathered points by dimension, padded to a multiple of [`BLOCK`] with infinite
    /// coordinates.
    coords: [Vec<T>; D],
    /// Their caller indices.
    ids: Vec<u32>,
    /// The members' rows one after the other, member `i`'s at `starts[i]..starts[i + 1]`.
    rows: Vec<K>,
    starts: [usize; GROUP + 1],
    /// Scratch: a member's keys within `r²`, and the slots of a ranking.
    keys: Vec<K>,
    ranked: Vec<K>,
    stack: Vec<(u32, T)>,
    /// Scratch: the gathered runs of consecutive tree positions (adjacent leaves merged), copied
    /// into the block once the traversal ends.
    runs: Vec<Range<usize>>,
    /// Whether a member's keys come from the AVX-512 loop (`f32` rows on a processor that has
    /// it, see `avx512.rs`).
    avx512: bool,
    /// Whether a member's distances take the AVX loop of `f64` in 3-D (`tree/kernel.rs`) on a
    /// processor that has it.
    avx: bool,
}

impl<T: Scalar, K: GroupKey<T>, const D: usize> Gather<T, K, D> {
    /// The scratch of rows of the `k` nearest (k-nearest rows, with or without a radius).
    pub(super) fn nearest(k: usize) -> Self {
        let mut g = Self::new(k, true);
        g.adapt(1.0);
        g.cap = (CAP_PER_NEIGHBOUR * k).max(MIN_CAP);
        g
    }

    /// The scratch of rows of every point within the search's radius, `sorted` or not.
    pub(super) fn within(sorted: bool) -> Self {
        Self::new(usize::MAX, sorted)
    }

    fn new(k: usize, sorted: bool) -> Self {
        Self {
            k,
            sorted,
            guess: None,
            margin: T::ZERO,
            spread: GUESS_SPREAD,
            member_margin: T::from_f64(1.0 + MEMBER_SPREAD / (k as f64).sqrt()),
            cap: MIN_CAP,
            coords: std::array::from_fn(|_| Vec::new()),
            ids: Vec::new(),
            rows: Vec::new(),
            starts: [0; GROUP + 1],
            keys: Vec::new(),
            ranked: vec![K::default(); RANK_MAX + 1],
            stack: Vec::new(),
            runs: Vec::new(),
            avx512: avx512_keys::<T, K>(),
            avx: crate::simd::avx(),
        }
    }

    /// Multiplies the guess's spread by `f` (within its range) and sets the margin from it.
    fn adapt(&mut self, f: f64) {
        self.spread = (self.spread * f).clamp(MIN_SPREAD, MAX_SPREAD);
        self.margin = T::from_f64(1.0 + self.spread / (self.k as f64).sqrt());
    }

    /// Sets the k-nearest guess from a group: `bound` is the largest squared distance of its
    /// rows' last neighbours (the search's `limit` where a row is not full).
    pub(super) fn learn(&mut self, bound: T, limit: T) {
        self.guess = Some((bound * self.margin).min_of(limit));
    }

    /// Answers the group `mb` of `m` members from one gathered block and appends its rows, in
    /// member order, to `out`; `false` (nothing written) when a k-nearest guess is not there yet
    /// or does not settle every row, the block would pass its cap, or the group is copies of
    /// one point with radius rows (the parent's search shares their row).
    pub(super) fn group(
        &mut self,
        search: &Search<'_, T, D>,
        mb: &Members<T, D>,
        m: usize,
        out: &mut RowsChunk<'_, T>,
    ) -> bool {
        let limit = search.sq_radius;
        let r2 = if self.k == usize::MAX {
            if m > 1 && mb.lo == mb.hi {
                return false;
            }
            limit
        } else {
            match self.guess {
                Some(guess) => guess.min_of(limit),
                None => return false,
            }
        };
        // the spread adapts for rows of the k nearest alone: under a radius, rows may be short
        // because the radius cuts them, which a wider guess does not mend
        let adapts = !limit.is_finite();
        let (mut r2, mut retried) = (r2, false);
        let largest = loop {
            // gathered within the search's own limit, a row of fewer than k is whole
            let whole = r2 == limit;
            if !self.collect(search, &mb.lo, &mb.hi, r2) {
                if self.k == usize::MAX {
                    // radius rows hold every point the block would: room for more next time
                    self.cap = (self.cap * 2).min(MAX_CAP);
                }
                return false;
            }
            if !self.reserve_rows(m) {
                return false;
            }
            if let Some(largest) = self.members(mb, m, r2, whole) {
                break largest;
            }
            if adapts {
                self.adapt(GROW);
            }
            if retried {
                return false;
            }
            // short: once more from a block gathered within a wider squared radius
            retried = true;
            r2 = (r2 * T::from_f64(RETRY)).min_of(limit);
        };
        for i in 0..m {
            let row = &self.rows[self.starts[i]..self.starts[i + 1]];
            out.push_row(row.len(), row.iter().map(|&e| e.pair()));
        }
        if self.k != usize::MAX {
            if adapts {
                self.adapt(SHRINK);
            }
            self.learn(largest, limit);
        }
        true
    }

    /// Empties the rows and reserves, fallibly, room for `m` members' rows and one member's keys
    /// from the gathered block; `false` when the memory is not there (the parent's search then
    /// answers the group, and reports the failure through its chunk).
    fn reserve_rows(&mut self, m: usize) -> bool {
        let count = self.ids.len();
        self.rows.clear();
        let keys_more = (count + BLOCK).saturating_sub(self.keys.len());
        self.rows.try_reserve(m * count.min(self.k)).is_ok()
            && self.keys.try_reserve(keys_more).is_ok()
    }

    /// Copies every point of the leaves within `r2` of the box `glo..ghi` into the block;
    /// `false` when more than the cap would be gathered.
    fn collect(&mut self, search: &Search<'_, T, D>, glo: &[T; D], ghi: &[T; D], r2: T) -> bool {
        let tree = &search.parts[0];
        let (boxes, soa) = (tree, tree.soa);
        let cap = self.cap;
        for c in &mut self.coords {
            c.clear();
        }
        self.ids.clear();
        let (stack, runs) = (&mut self.stack, &mut self.runs);
        stack.clear();
        runs.clear();
        let mut held = 0;
        stack.push((0, box_dist(glo, ghi, &boxes.lo[0], &boxes.hi[0])));
        while let Some((mut node, lb)) = stack.pop() {
            if lb > r2 {
                continue;
            }
            loop {
                let nd = &tree.nodes[node as usize];
                if nd.is_leaf() {
                    let (a, b) = (nd.a as usize, nd.b as usize);
                    held += b - a;
                    if held > cap {
                        return false;
                    }
                    // leaves come in tree order: a leaf right after the last run extends it
                    match runs.last_mut() {
                        Some(run) if run.end == a => run.end = b,
                        _ => runs.push(a..b),
                    }
                    break;
                }
                let (l, r) = (node + 1, nd.a);
                let lbl = box_dist(glo, ghi, &boxes.lo[l as usize], &boxes.hi[l as usize]);
                let lbr = box_dist(glo, ghi, &boxes.lo[r as usize], &boxes.hi[r as usize]);
                if lbr <= r2 {
                    stack.push((r, lbr));
                }
                if lbl > r2 {
                    break;
                }
                node = l;
            }
        }
        for run in runs.iter() {
            for (j, c) in self.coords.iter_mut().enumerate() {
                c.extend_from_slice(&soa.v[j * soa.stride + run.start..j * soa.stride + run.end]);
            }
            self.ids.extend_from_slice(&tree.ids[run.clone()]);
        }
        let padded = self.ids.len().div_ceil(BLOCK) * BLOCK;
        for c in &mut self.coords {
            c.resize(padded, T::INFINITY);
        }
        true
    }

    /// Appends the rows of the `m` members `mb` from the gathered block within `r2` and
    /// returns the largest squared distance of their last neighbours; `None` when a member's
    /// row falls short of `k` and the block is not `whole` (then the rows are incomplete).
    fn members(&mut self, mb: &Members<T, D>, m: usize, r2: T, whole: bool) -> Option<T> {
        let mut largest = T::ZERO;
        // the first member looks within r², each next one first within its predecessor's k-th
        // squared distance with a margin: members follow each other in tree order
        let mut hint = r2;
        for i in 0..m {
            let held = self.member(&mb.q[i], mb.self_id[i], r2, hint);
            if held < self.k && !whole {
                return None;
            }
            if let Some(last) = self.rows.last().filter(|_| held > 0) {
                let kth = last.pair().0;
                largest = largest.max_of(kth);
                if held == self.k {
                    hint = kth * self.member_margin;
                }
            }
            self.starts[i + 1] = self.rows.len();
        }
        Some(largest)
    }

    /// Appends the row of the member at `qi`: the first `k` keys (all for radius rows), in
    /// `(sq_dist, index)` order unless unsorted rows are asked for, of the gathered points within
    /// `r2` of `qi` other than `self_id`; returns how many it holds.
    ///
    /// The keys are first taken within `hint` (when below `r2`): `k` of them there are the
    /// row, since the block holds every point within `r2` and so within `hint` (fewer keys
    /// to order); with fewer than `k` the member takes its keys within `r2` after all.
    fn member(&mut self, qi: &[T; D], self_id: u32, r2: T, hint: T) -> usize {
        let tight = hint.min_of(r2);
        let mut n = self.keys_within(qi, self_id, tight);
        if n < self.k && tight < r2 {
            n = self.keys_within(qi, self_id, r2);
        }
        let held = n.min(self.k);
        let at = self.rows.len();
        self.rows.resize(at + held, K::default());
        let (keys, row) = (&mut self.keys[..n], &mut self.rows[at..]);
        if self.sorted {
            first_in_order::<T, K>(keys, &mut self.ranked, row);
        } else {
            row.copy_from_slice(keys);
        }
        held
    }

    /// Writes into `keys` the keys of the gathered points within `bound` of `qi` other than
    /// `self_id`, in block order; returns how many.
    fn keys_within(&mut self, qi: &[T; D], self_id: u32, bound: T) -> usize {
        // room for every gathered point and a block more: the keys are written without a
        // capacity test
        self.keys.resize(self.ids.len() + BLOCK, K::default());
        if let Some(n) = self.keys_within_avx512(qi, self_id, bound) {
            return n;
        }
        #[cfg(target_arch = "x86_64")]
        if self.avx {
            // SAFETY: `avx` is set only where the processor has AVX (`crate::simd::avx`).
            return unsafe { self.keys_within_avx(qi, self_id, bound) };
        }
        self.keys_by_blocks(qi, self_id, bound, false)
    }

    /// [`Gather::keys_by_blocks`] compiled for AVX, so that the AVX distances of `f64` in 3-D
    /// (`tree/kernel.rs`) inline into its loop instead of being a call per block (a call per
    /// block cost the 1M cube's `f64` k = 10 table a billion instructions, docs/speed-log.md
    /// round 14).
    ///
    /// # Safety
    /// The processor must support AVX.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx")]
    unsafe fn keys_within_avx(&mut self, qi: &[T; D], self_id: u32, bound: T) -> usize {
        self.keys_by_blocks(qi, self_id, bound, true)
    }

    /// [`Gather::keys_within`] a block of [`BLOCK`] gathered points at a time (`avx`: the
    /// distances of `f64` in 3-D in AVX lanes, set only where the processor has AVX).
    #[inline(always)]
    fn keys_by_blocks(&mut self, qi: &[T; D], self_id: u32, bound: T, avx: bool) -> usize {
        let (mut n, count, sse) = (0, self.ids.len(), crate::simd::sse());
        for start in (0..count).step_by(BLOCK) {
            let (d, mut hits) = sq_dists_below_by_dim::<T, D, BLOCK>(
                qi,
                |j| &self.coords[j][start..start + BLOCK],
                bound,
                sse,
                avx,
            );
            if count - start < BLOCK {
                // the padding is infinitely far, yet within an infinite bound
                hits &= (1 << (count - start)) - 1;
            }
            while hits != 0 {
                let p = hits.trailing_zeros() as usize;
                hits &= hits - 1;
                let id = self.ids[start + p];
                self.keys[n] = K::of(id, d[p]);
                n += usize::from(id != self_id);
            }
        }
        n
    }

    /// [`Gather::keys_within`] by the AVX-512 loop (`avx512.rs`) when `self.avx512` says it
    /// runs here; `None` otherwise.
    fn keys_within_avx512(&mut self, qi: &[T; D], self_id: u32, bound: T) -> Option<usize> {
        if !self.avx512 {
            return None;
        }
        #[cfg(all(target_arch = "x86_64", rustc_1_89))]
        if let (Some(coords), Some(q), Some(&b), Some(keys)) = (
            (&self.coords as &dyn Any).downcast_ref::<[Vec<f32>; D]>(),
            (qi as &dyn Any).downcast_ref::<[f32; D]>(),
            (&bound as &dyn Any).downcast_ref::<f32>(),
            (&mut self.keys as &mut dyn Any).downcast_mut::<Vec<u64>>(),
        ) {
            // SAFETY: `avx512` (checked above) is set only where the processor has AVX-512 F
            // and VL.
            return Some(unsafe { avx512::keys_within(coords, &self.ids, q, self_id, b, keys) });
        }
        let _ = (qi, self_id, bound);
        None
    }
}

/// Whether [`Gather::keys_within`] takes the AVX-512 loop: `f32` coordinates, 64-bit keys and
/// a processor with AVX-512 F and VL.
fn avx512_keys<T: Scalar, K: 'static>() -> bool {
    use std::any::TypeId;
    TypeId::of::<T>() == TypeId::of::<f32>()
        && TypeId::of::<K>() == TypeId::of::<u64>()
        && avx512_here()
}

/// Whether the AVX-512 loops run here: built (x86-64, Rust 1.89 or later), a processor with
/// AVX-512 F and VL, and the portable forms not forced (`crate::simd`).
fn avx512_here() -> bool {
    #[cfg(all(target_arch = "x86_64", rustc_1_89))]
    return crate::simd::avx512();
    #[cfg(not(all(target_arch = "x86_64", rustc_1_89)))]
    false
}

/// The first `row.len()` of the distinct `keys` in order into `row` (`keys` may be reordered;
/// `ranked` is scratch of [`RANK_MAX`] + 1 slots).
fn first_in_order<T, K: GroupKey<T>>(keys: &mut [K], ranked: &mut [K], row: &mut [K]) {
    let held = row.len();
    if keys.len() <= RANK_MAX {
        let slots = &mut ranked[..keys.len().min(held) + 1];
        rank(keys, slots);
        row.copy_from_slice(&slots[..held]);
        return;
    }
    if keys.len() > SELECT_FROM * held && held > 0 {
        keys.select_nth_unstable(held - 1);
        keys[..held].sort_unstable();
    } else {
        keys.sort_unstable();
    }
    row.copy_from_slice(&keys[..held]);
}

/// Each of the distinct `keys` into `slots` at its rank, the number of keys below it, the
/// ranks from the last slot on sharing it: the first `slots.len() - 1` keys in order, without
/// a data-dependent branch (a sort of a few keys mispredicts about once per key).
fn rank<K: Copy + Ord + Rank>(keys: &[K], slots: &mut [K]) {
    #[cfg(target_arch = "x86_64")]
    {
        #[cfg(rustc_1_89)]
        if avx512_here() {
            // SAFETY: the processor supports AVX-512 F and VL (checked just above).
            return unsafe { rank_avx512(keys, slots) };
        }
        if crate::simd::avx2() {
            // SAFETY: the processor supports AVX2 (checked just above).
            return unsafe { rank_avx2(keys, slots) };
        }
    }
    rank_portable(keys, slots)
}

/// [`rank`] compiled for AVX-512: eight 64-bit compares at a time, into mask registers.
#[cfg(all(target_arch = "x86_64", rustc_1_89))]
#[target_feature(enable = "avx512f,avx512vl")]
fn rank_avx512<K: Copy + Ord + Rank>(keys: &[K], slots: &mut [K]) {
    // SAFETY: this function runs only where AVX-512 F and VL are (its own target features).
    place_by_rank(keys, slots, |k, below| unsafe {
        K::count_below_avx512(k, below)
    });
}

/// [`rank`] compiled for AVX2: the counts of smaller keys four 64-bit compares at a time.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn rank_avx2<K: Copy + Ord + Rank>(keys: &[K], slots: &mut [K]) {
    rank_portable(keys, slots)
}

/// The loop of [`rank`], inlined into each instruction set's version.
#[inline(always)]
fn rank_portable<K: Copy + Ord + Rank>(keys: &[K], slots: &mut [K]) {
    place_by_rank(keys, slots, K::count_below);
}

/// Each key into `slots` at its rank as `count_below` counts it (a form of
/// [`Rank::count_below`]), the ranks from the last slot on sharing it.
#[inline(always)]
fn place_by_rank<K: Copy>(keys: &[K], slots: &mut [K], count_below: impl FnOnce(&[K], &mut [u32])) {
    let last = slots.len() - 1;
    let mut below = [0u32; RANK_MAX];
    count_below(keys, &mut below[..keys.len()]);
    for (&a, &b) in keys.iter().zip(&below) {
        slots[(b as usize).min(last)] = a;
    }
}

/// Counting, for each key, the keys below it, in a form that vectorises.
pub(super) trait Rank: Sized {
    /// `below[i]` = how many of `keys` are less than `keys[i]`.
    fn count_below(keys: &[Self], below: &mut [u32]);

    /// [`Rank::count_below`] on a processor with AVX-512 F and VL.
    ///
    /// # Safety
    /// The processor must support AVX-512 F and VL.
    #[cfg(all(target_arch = "x86_64", rustc_1_89))]
    #[target_feature(enable = "avx512f,avx512vl")]
    unsafe fn count_below_avx512(keys: &[Self], below: &mut [u32]) {
        Self::count_below(keys, below)
    }
}

impl Rank for u64 {
    #[inline(always)]
    fn count_below(keys: &[u64], below: &mut [u32]) {
        for (c, &a) in below.iter_mut().zip(keys) {
            *c = keys.iter().map(|&b| u32::from(b < a)).sum();
        }
    }

    #[cfg(all(target_arch = "x86_64", rustc_1_89))]
    #[target_feature(enable = "avx512f,avx512vl")]
    unsafe fn count_below_avx512(keys: &[u64], below: &mut [u32]) {
        // SAFETY: the processor has AVX-512 F and VL (this function's own contract).
        unsafe { super::avx512::count_below(keys, below) }
    }
}

impl Rank for u128 {
    /// Compared as two 64-bit halves (`(hi, lo)` in lexicographic order), which SIMD compares
    /// where it has no 128-bit compare.
    #[inline(always)]
    fn count_below(keys: &[u128], below: &mut [u32]) {
        let (mut hi, mut lo) = ([0u64; RANK_MAX], [0u64; RANK_MAX]);
        for ((h, l), &k) in hi.iter_mut().zip(&mut lo).zip(keys) {
            (*h, *l) = ((k >> 64) as u64, k as u64);
        }
        let (hi, lo) = (&hi[..keys.len()], &lo[..keys.len()]);
        for ((c, &ha), &la) in below.iter_mut().zip(hi).zip(lo) {
            *c = hi
                .iter()
                .zip(lo)
                .map(|(&hb, &lb)| u32::from((hb < ha) | ((hb == ha) & (lb < la))))
                .sum();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Ranking gives the sorted order, whichever instruction set runs it, for every count of
    /// keys up to [`RANK_MAX`], rows shorter and longer than the keys, and both key widths.
    #[test]
    fn ranks_order_the_first_keys() {
        let mut state = 99u64;
        for n in 0..=RANK_MAX {
            for held in [0, 1, 5, 10, 16, 40] {
                let keys: Vec<u64> = (0..n)
                    .map(|i| {
                        state = state
                            .wrapping_mul(6_364_136_223_846_793_005)
                            .wrapping_add(1);
                        // few distinct distances: ties broken by the index in the low bits
                        ((state >> 60) << 32) | i as u64
                    })
                    .collect();
                check_ranks(&keys, held);
                // wide keys: the halves tie, or differ only in the low one
                let wide: Vec<u128> = keys
                    .iter()
                    .map(|&k| (u128::from(k >> 40) << 64) | u128::from(k) << 20)
                    .collect();
                check_ranks(&wide, held);
            }
        }
    }

    /// The AVX-512 loop of a member's keys gives the portable loop's keys, in the same order,
    /// for blocks of every length around the register's sixteen lanes, bounds that fall
    /// exactly on points, an infinite bound (the padding stays out) and the member inside or
    /// outside the block. Where the processor has no AVX-512 there is one loop and nothing to
    /// compare: the test says so and passes.
    #[test]
    fn avx512_keys_match_the_portable_loop() {
        if !avx512_keys::<f32, u64>() {
            eprintln!("no AVX-512 here: only the portable loop runs");
            return;
        }
        let mut g = Gather::<f32, u64, 3>::within(true);
        let mut state = 7u64;
        let mut next = || {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1);
            // a coarse grid, so that distances tie and fall exactly on a bound
            ((state >> 59) as f32) * 0.25
        };
        for count in [0usize, 1, 7, 8, 9, 15, 16, 17, 31, 33, 100] {
            for c in &mut g.coords {
                c.clear();
            }
            g.ids = (0..count as u32).map(|i| 3 * i + 1).collect();
            for _ in 0..count {
                for c in &mut g.coords {
                    c.push(next());
                }
            }
            for c in &mut g.coords {
                c.resize(count.div_ceil(BLOCK) * BLOCK, f32::INFINITY);
            }
            let q = [next(), next(), next()];
            for bound in [0.0, 0.0625, 1.0, 2.25, 16.0, f32::INFINITY] {
                for self_id in [1, 3 * (count as u32 / 2) + 1, 2] {
                    let mut got = Vec::new();
                    for fast in [true, false] {
                        g.avx512 = fast;
                        let n = g.keys_within(&q, self_id, bound);
                        got.push(g.keys[..n].to_vec());
                    }
                    assert_eq!(got[0], got[1], "count {count} bound {bound} self {self_id}");
                }
            }
        }
    }

    fn check_ranks<K: Copy + Ord + Default + Rank + std::fmt::Debug>(keys: &[K], held: usize) {
        let mut want = keys.to_vec();
        want.sort_unstable();
        want.truncate(held);
        let mut slots = vec![K::default(); held + 1];
        rank(keys, &mut slots);
        assert_eq!(
            &slots[..want.len()],
            &want[..],
            "n {} held {held}",
            keys.len()
        );
        let mut portable = vec![K::default(); held + 1];
        rank_portable(keys, &mut portable);
        assert_eq!(portable, slots);
    }
}
