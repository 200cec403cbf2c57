//! Writing items to the places a list of targets gives them, from many threads at once: the
//! results of work done in one order (a tree's) put into another (the caller's) as they are
//! made, rather than gathered in a pass of their own afterwards. The targets are checked
//! distinct before any write, so that no two threads ever write one slot.

use rayon::prelude::*;

use crate::error::{NbhdError, Result};

/// Items written per task: enough that a task is worth its scheduling, few enough for two
/// threads to share a block of 8192.
const CHUNK: usize = 1024;

/// Checks lists of targets into slices of `len` slots, remembering nothing between checks but
/// its buffer.
pub(crate) struct TargetCheck {
    len: usize,
    /// One bit per slot, all clear between checks.
    seen: Vec<u64>,
}

/// Targets checked by a [`TargetCheck`]: distinct, and each below its `len`.
pub(crate) struct Targets<'t> {
    to: &'t [u32],
    len: usize,
}

impl TargetCheck {
    /// A check of targets into `len` slots.
    pub(crate) fn new(len: usize) -> Self {
        Self {
            len,
            seen: vec![0; len.div_ceil(64)],
        }
    }

    /// `to` as [`Targets`], or [`NbhdError::IndexOutOfRange`] for a target at or beyond `len`
    /// and [`NbhdError::DuplicateIndex`] for one listed twice.
    pub(crate) fn check<'t>(&mut self, to: &'t [u32]) -> Result<Targets<'t>> {
        let mut failed = None;
        let mut marked = 0;
        for &t in to {
            let t = t as usize;
            if t >= self.len {
                failed = Some(NbhdError::IndexOutOfRange {
                    index: t,
                    count: self.len,
                });
                break;
            }
            let (word, bit) = (t / 64, 1u64 << (t % 64));
            if self.seen[word] & bit != 0 {
                failed = Some(NbhdError::DuplicateIndex { index: t });
                break;
            }
            self.seen[word] |= bit;
            marked += 1;
        }
        for &t in &to[..marked] {
            self.seen[t as usize / 64] = 0;
        }
        match failed {
            Some(e) => Err(e),
            None => Ok(Targets { to, len: self.len }),
        }
    }
}

/// The slots of a slice, written through a pointer by the tasks of [`scatter`].
struct Slots<U>(*mut U);

// SAFETY: `scatter` writes through the pointer only while it holds the slice exclusively, each
// slot from one task at most (its targets are distinct); `U: Send` lets the values cross threads.
unsafe impl<U: Send> Send for Slots<U> {}
// SAFETY: as above: shared between the tasks of one `scatter`, which never write one slot twice.
unsafe impl<U: Send> Sync for Slots<U> {}

/// Writes `items[r]` to `out[targets[r]]` for every `r`, in parallel. Refuses with
/// [`NbhdError::InvalidOption`] (writing nothing) when `items` and the targets differ in length
/// or the targets were checked for another length of `out`.
pub(crate) fn scatter<U: Copy + Send + Sync>(
    out: &mut [U],
    targets: &Targets<'_>,
    items: &[U],
) -> Result<()> {
    if targets.len != out.len() || targets.to.len() != items.len() {
        return Err(NbhdError::InvalidOption {
            name: "scatter",
            reason: format!(
                "{} items to {} targets into {} slots (checked for {})",
                items.len(),
                targets.to.len(),
                out.len(),
                targets.len
            ),
        });
    }
    let slots = Slots(out.as_mut_ptr());
    items
        .par_chunks(CHUNK)
        .zip(targets.to.par_chunks(CHUNK))
        .for_each(|(items, to)| {
            let slots = &slots;
            for (&item, &t) in items.iter().zip(to) {
                // SAFETY: `t < out.len()` (checked by `TargetCheck::check` for this length,
                // compared above), so the slot lies inside `out`, which this call borrows
                // exclusively; the targets are distinct, so no other task writes this slot.
                unsafe { slots.0.add(t as usize).write(item) };
            }
        });
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn items_land_on_their_targets() {
        let n = 5000;
        // a permutation: i ↦ 7i mod n (7 and 5000 coprime)
        let to: Vec<u32> = (0..n).map(|i| (7 * i % n) as u32).collect();
        let items: Vec<u64> = (0..n as u64).map(|i| i * i).collect();
        let mut check = TargetCheck::new(n);
        let mut out = vec![0u64; n];
        // in two parts, as blocks come
        for part in [0..3000, 3000..n] {
            let targets = check.check(&to[part.clone()]).unwrap();
            scatter(&mut out, &targets, &items[part]).unwrap();
        }
        for i in 0..n {
            assert_eq!(out[to[i] as usize], items[i]);
        }
    }

    #[test]
    fn repeated_or_outside_targets_are_refused_and_forgotten() {
        let mut check = TargetCheck::new(100);
        assert!(matches!(
            check.check(&[3, 9, 3]),
            Err(NbhdError::DuplicateIndex { index: 3 })
        ));
        assert!(matches!(
            check.check(&[3, 100]),
            Err(NbhdError::IndexOutOfRange {
                index: 100,
                count: 100
            })
        ));
        // the failed checks left no mark: the same targets pass now
        let targets = check.check(&[3, 9, 99]).unwrap();
        let mut out = vec![0u8; 100];
        scatter(&mut out, &targets, &[1, 2, 3]).unwrap();
        assert_eq!((out[3], out[9], out[99]), (1, 2, 3));
        // items of another length, or another length of slots: nothing written
        assert!(scatter(&mut out, &targets, &[7, 7]).is_err());
        let mut other = vec![0u8; 101];
        assert!(scatter(&mut other, &targets, &[7, 7, 7]).is_err());
        assert!(other.iter().all(|&x| x == 0));
    }
}
