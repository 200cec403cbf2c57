//! Writing the results of work done in one order (a tree's) to the places another order (the
//! caller's) gives them, from many threads at once, a block at a time, as the blocks are made
//! — rather than gathered in a pass of their own afterwards. The targets are checked distinct
//! once, before any write, and each block is written once, so that no two threads ever write
//! one slot.

use std::marker::PhantomData;
use std::sync::atomic::{AtomicBool, Ordering};

use rayon::prelude::*;

use crate::error::{NbhdError, Result};

/// Targets checked distinct and each below `len`: the places of the items in a slice of `len`
/// slots (or rows).
pub(crate) struct Targets<'t> {
    to: &'t [u32],
    len: usize,
}

/// Targets checked at once by one task.
const PIECE: usize = 1 << 16;

impl<'t> Targets<'t> {
    /// `to` checked, in parallel: [`NbhdError::IndexOutOfRange`] for the first target at or
    /// beyond `len`, [`NbhdError::DuplicateIndex`] for the first target listed again.
    pub(crate) fn check(to: &'t [u32], len: usize) -> Result<Self> {
        let words = len.div_ceil(64);
        // each task marks its targets in a bitmap of its own; two bitmaps that share a bit
        // share a target
        let marked = to
            .par_chunks(PIECE)
            .try_fold(
                || vec![0u64; words],
                |mut seen, piece| mark(&mut seen, piece, len).map(|()| seen).map_err(|_| ()),
            )
            .try_reduce(
                || vec![0u64; words],
                |mut a, b| {
                    for (x, &y) in a.iter_mut().zip(&b) {
                        if *x & y != 0 {
                            return Err(());
                        }
                        *x |= y;
                    }
                    Ok(a)
                },
            );
        match marked {
            Ok(_) => Ok(Self { to, len }),
            // the first offending target by position, the same for any number of threads
            Err(()) => Err(first_failure(to, len)),
        }
    }
}

/// Marks `targets` in `seen`; `Err` with the position of the first target at or beyond `len`
/// or marked already.
fn mark(seen: &mut [u64], targets: &[u32], len: usize) -> std::result::Result<(), usize> {
    for (p, &t) in targets.iter().enumerate() {
        let t = t as usize;
        if t >= len {
            return Err(p);
        }
        let (word, bit) = (t / 64, 1u64 << (t % 64));
        if seen[word] & bit != 0 {
            return Err(p);
        }
        seen[word] |= bit;
    }
    Ok(())
}

/// The error of the first target of `to` (by position) that is out of range or repeated.
fn first_failure(to: &[u32], len: usize) -> NbhdError {
    match mark(&mut vec![0; len.div_ceil(64)], to, len) {
        Err(p) if to[p] as usize >= len => NbhdError::IndexOutOfRange {
            index: to[p] as usize,
            count: len,
        },
        Err(p) => NbhdError::DuplicateIndex {
            index: to[p] as usize,
        },
        Ok(()) => invalid("targets refused though none is repeated or out of range".into()),
    }
}

/// The slots of a slice, written through a pointer by the blocks of a [`BlockScatter`].
struct Slots<U>(*mut U);

// SAFETY: a `BlockScatter` writes through the pointer only while it borrows the slice
// exclusively, each slot from one block at most and each block once; `U: Send` lets the values
// cross threads.
unsafe impl<U: Send> Send for Slots<U> {}
// SAFETY: as above: shared between the threads writing distinct blocks, never one slot twice.
unsafe impl<U: Send> Sync for Slots<U> {}

/// A slice written a block at a time from any thread: the blocks partition a list of items
/// (block `b` holds items `bounds[b]..bounds[b + 1]`), item `r` is a row of `width` values, and
/// it goes to row `to[r]` of the slice (or, in place, to row `r`). Each block is written at
/// most once, and the targets are distinct, so blocks write disjoint rows.
pub(crate) struct BlockScatter<'o, U> {
    slots: Slots<U>,
    /// Each item's row, `None` for row `r` itself.
    to: Option<&'o [u32]>,
    bounds: &'o [usize],
    width: usize,
    /// Whether each block has been written.
    written: Vec<AtomicBool>,
    _out: PhantomData<&'o mut [U]>,
}

impl<'o, U: Copy + Send + Sync> BlockScatter<'o, U> {
    /// Items written to the rows `targets` of `out` (rows of `width`), blocks `bounds`.
    pub(crate) fn to_targets(
        out: &'o mut [U],
        targets: &Targets<'o>,
        bounds: &'o [usize],
        width: usize,
    ) -> Result<Self> {
        Self::new(out, Some(targets.to), targets.len, bounds, width)
    }

    /// Items written to their own rows of `out` (rows of `width`), blocks `bounds`.
    pub(crate) fn in_place(out: &'o mut [U], bounds: &'o [usize], width: usize) -> Result<Self> {
        let rows = bounds.last().copied().unwrap_or(0);
        Self::new(out, None, rows, bounds, width)
    }

    fn new(
        out: &'o mut [U],
        to: Option<&'o [u32]>,
        rows: usize,
        bounds: &'o [usize],
        width: usize,
    ) -> Result<Self> {
        let items = to.map_or(rows, <[u32]>::len);
        let partition = bounds.first() == Some(&0)
            && bounds.last() == Some(&items)
            && bounds.windows(2).all(|w| w[0] <= w[1]);
        if !partition || rows.checked_mul(width) != Some(out.len()) {
            return Err(invalid(format!(
                "{} slots for {rows} rows of {width}, blocks of {items} items bounded by {:?}…",
                out.len(),
                &bounds[..bounds.len().min(4)]
            )));
        }
        Ok(Self {
            slots: Slots(out.as_mut_ptr()),
            to,
            bounds,
            width,
            written: (1..bounds.len()).map(|_| AtomicBool::new(false)).collect(),
            _out: PhantomData,
        })
    }

    /// Writes the items of block `b`, `width` values each, from `values`; refuses (writing
    /// nothing) a block out of range, one written before, or values of another count.
    pub(crate) fn write(&self, b: usize, values: impl ExactSizeIterator<Item = U>) -> Result<()> {
        let Some(flag) = self.written.get(b) else {
            return Err(invalid(format!("block {b} of {}", self.written.len())));
        };
        let items = self.bounds[b]..self.bounds[b + 1];
        if values.len() != items.len() * self.width {
            return Err(invalid(format!(
                "{} values for {} items of {}",
                values.len(),
                items.len(),
                self.width
            )));
        }
        if flag.swap(true, Ordering::Relaxed) {
            return Err(invalid(format!("block {b} written twice")));
        }
        let slots = items
            .map(|r| self.to.map_or(r, |to| to[r] as usize) * self.width)
            .flat_map(|row| row..row + self.width);
        for (slot, v) in slots.zip(values) {
            // SAFETY: `slot` lies in row `to[r]` (or `r`), below the slice's row count (checked
            // by `Targets::check`, or by the bounds for rows in place) and so inside the slice,
            // which `self` borrows exclusively for its lifetime. The rows of distinct items are
            // distinct (the targets are), the blocks hold distinct items, and this block is
            // written this once (its flag was clear): no other write touches this slot.
            unsafe { self.slots.0.add(slot).write(v) };
        }
        Ok(())
    }
}

/// The inverse of the permutation `targets` (refused unless there are as many targets as slots):
/// `inverse(to)[to[r]] == r`, written in parallel.
pub(crate) fn inverse(targets: &Targets<'_>) -> Result<Vec<u32>> {
    let n = targets.to.len();
    if n != targets.len {
        return Err(invalid(format!("{n} targets into {} slots", targets.len)));
    }
    let mut out = vec![0u32; n];
    let bounds: Vec<usize> = (0..n).step_by(PIECE).chain([n]).collect();
    let scatter = BlockScatter::to_targets(&mut out, targets, &bounds, 1)?;
    (0..bounds.len() - 1)
        .into_par_iter()
        .try_for_each(|b| scatter.write(b, (bounds[b]..bounds[b + 1]).map(|r| r as u32)))?;
    Ok(out)
}

fn invalid(reason: String) -> NbhdError {
    NbhdError::InvalidOption {
        name: "scatter",
        reason,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blocks_land_on_their_targets_from_any_thread() {
        let n = 150_000;
        // a permutation: i ↦ 7i mod n (7 and n coprime)
        let to: Vec<u32> = (0..n).map(|i| (7 * i % n) as u32).collect();
        let bounds: Vec<usize> = (0..n).step_by(4096).chain([n]).collect();
        let targets = Targets::check(&to, n).unwrap();
        let mut out = vec![[0u64; 2]; n];
        let mut flat = vec![0u64; 2 * n];
        let mut own = vec![0u64; n];
        {
            let rows = BlockScatter::to_targets(&mut out, &targets, &bounds, 1).unwrap();
            let wide = BlockScatter::to_targets(&mut flat, &targets, &bounds, 2).unwrap();
            let in_place = BlockScatter::in_place(&mut own, &bounds, 1).unwrap();
            (0..bounds.len() - 1).into_par_iter().rev().for_each(|b| {
                let items = bounds[b]..bounds[b + 1];
                let pair = |i: usize| [i as u64, (i * i) as u64];
                rows.write(b, items.clone().map(pair)).unwrap();
                let flat: Vec<u64> = items.clone().flat_map(pair).collect();
                wide.write(b, flat.into_iter()).unwrap();
                in_place.write(b, items.map(|i| i as u64 + 1)).unwrap();
                // a second write of the block is refused
                assert!(in_place
                    .write(b, std::iter::repeat_n(0, bounds[b + 1] - bounds[b]))
                    .is_err());
            });
        }
        for i in 0..n {
            let t = to[i] as usize;
            assert_eq!(out[t], [i as u64, (i * i) as u64]);
            assert_eq!(flat[2 * t..2 * t + 2], [i as u64, (i * i) as u64]);
            assert_eq!(own[i], i as u64 + 1);
        }
    }

    #[test]
    fn inverse_undoes_the_permutation() {
        let n = 150_000;
        let to: Vec<u32> = (0..n).map(|i| (7 * i % n) as u32).collect();
        let inv = inverse(&Targets::check(&to, n).unwrap()).unwrap();
        assert!((0..n).all(|i| inv[to[i] as usize] as usize == i));
        // targets into more slots than items are no permutation
        assert!(inverse(&Targets::check(&to, n + 1).unwrap()).is_err());
    }

    #[test]
    fn repeated_or_outside_targets_are_refused() {
        let n = 200_000;
        let mut to: Vec<u32> = (0..n as u32).collect();
        assert!(Targets::check(&to, n).is_ok());
        // a repeat far from its first (in another task's piece), and a nearer one after it
        to[150_000] = 7;
        to[170_001] = 170_000;
        assert!(matches!(
            Targets::check(&to, n),
            Err(NbhdError::DuplicateIndex { index: 7 })
        ));
        to[10] = n as u32;
        assert!(matches!(
            Targets::check(&to, n),
            Err(NbhdError::IndexOutOfRange { index, count }) if index == n && count == n
        ));
        assert!(matches!(
            Targets::check(&[3, 9, 3], 100),
            Err(NbhdError::DuplicateIndex { index: 3 })
        ));
    }

    #[test]
    fn bad_blocks_and_counts_write_nothing() {
        let to = [3u32, 9, 99];
        let targets = Targets::check(&to, 100).unwrap();
        let mut out = vec![0u8; 100];
        // bounds that do not partition the three items, or slots of another count
        assert!(BlockScatter::to_targets(&mut out, &targets, &[0, 2], 1).is_err());
        assert!(BlockScatter::to_targets(&mut out, &targets, &[0, 2, 1, 3], 1).is_err());
        assert!(BlockScatter::to_targets(&mut out, &targets, &[0, 3], 2).is_err());
        let mut other = vec![0u8; 101];
        assert!(BlockScatter::to_targets(&mut other, &targets, &[0, 3], 1).is_err());
        let bounds = [0, 1, 3];
        let s = BlockScatter::to_targets(&mut out, &targets, &bounds, 1).unwrap();
        assert!(s.write(2, [1u8].into_iter()).is_err());
        assert!(s.write(1, [1u8].into_iter()).is_err());
        assert!(s.write(1, [1u8, 2, 3].into_iter()).is_err());
        s.write(1, [1u8, 2].into_iter()).unwrap();
        drop(s);
        assert_eq!((out[3], out[9], out[99]), (0, 1, 2));
        assert_eq!(out.iter().map(|&x| u32::from(x)).sum::<u32>(), 3);
    }
}
