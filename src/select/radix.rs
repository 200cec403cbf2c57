//! Exact selection across parts that are never gathered: the value of rank `m` among values
//! split over many parts (tiles of a Dask graph, files on disk), found by counting radix
//! digits of the values' order keys.
//!
//! The thesis finds a median as the element of rank `⌊n/2⌋` of a sorted list (Section 3.3.3) or
//! by partitioning against a pivot and continuing on the side that holds the rank (Section
//! 3.3.4, with the randomized select of Algorithm 10, Floyd–Rivest's sampled pivot and the
//! median of medians of Algorithm 11 in Chapter 6; all in `src/select/`). Those algorithms move
//! the elements of one slice. Values that live in parts on different machines cannot be moved
//! together, and a pivot chosen from samples needs a data-dependent number of rounds. Here the
//! "pivot" is a **prefix of the order key** instead, fixed 16 bits per round as in a
//! most-significant-digit radix sort, and the partition is done on counts:
//!
//! 1. Each value maps to its [order key](OrderKey::order_key), an unsigned integer whose order
//!    is the total order of `f64::total_cmp` / `f32::total_cmp` — the order of the library's
//!    medians (the robust mode's noise estimates select with `total_cmp`).
//! 2. A round asks every part for the counts of the next 16-bit digit among its values whose
//!    key starts with the prefix fixed so far ([`RankSearch::digit_counts`]). Counts of parts
//!    add up ([`DigitCounts::merge`], in any tree and order).
//! 3. The driver ([`RankSearch::feed_counts`]) walks the merged counts from the smallest digit
//!    and finds the digit whose bucket holds rank `m`; the ranks before it are subtracted and the
//!    digit joins the prefix: the partition step of Algorithm 10, with 2^16 sides at once.
//! 4. Once all bits of the key are fixed, the bucket holds copies of one value: found. Once the
//!    bucket holding the rank has at most [`GATHER`] values, the parts send the values of that
//!    bucket ([`RankSearch::matching_values`]) and the driver selects among them with the
//!    library's `select_nth`.
//!
//! The answer is exact by construction: the key is a bijection onto the values' bit patterns
//! (every element distinct in the order, as the thesis' compare function of Algorithm 5 makes
//! them), so the value of rank `m` has a unique key, and ties (equal values, also across parts) need no
//! special case — it is bit for bit the element `select_nth_unstable_by(total_cmp)` puts at `m`.
//! An `f64` needs at most four counting rounds and usually two or three, because the gathering
//! round comes early; the bytes of a round are bounded by 65,536 buckets whatever the data, and
//! are in practice a few hundred, because values of one kind share few exponents.
//!
//! **NaN**: keys order NaNs as `total_cmp` does — a NaN with the sign bit set before `−∞`, any
//! other after `+∞` — so a NaN is selected only at the ranks where it sits in that order.
//! Callers that want NaNs out (the robust medians) leave them out of the parts.
//!
//! [`select_in_parts`] runs the rounds in one process over slices; a distributed driver holds a
//! [`RankSearch`] and sends it to the parts each round (it is a few words).

use super::{select_nth, SelectAlgorithm};
use crate::error::{NbhdError, Result};

/// Bits of one radix digit (the counts of one round have at most 2^16 buckets).
pub const DIGIT_BITS: u32 = 16;

/// A bucket of at most this many values is gathered and finished by `select_nth`.
pub const GATHER: u64 = 4096;

/// Parts below this many values count digits by sorting them, not in a 2^16-entry table.
const SPARSE_BELOW: usize = 1 << 13;

/// A value type with an order key: `a.total_cmp(&b) == a.order_key().cmp(&b.order_key())`,
/// and the key is a bijection (`from_order_key(order_key(x))` has the bits of `x`).
pub trait OrderKey: Copy + Send + Sync + 'static {
    /// Bits of the key (32 for `f32`, 64 for `f64`); the key is below `2^BITS`.
    const BITS: u32;
    /// The order key.
    fn order_key(self) -> u64;
    /// The value of a key.
    fn from_order_key(key: u64) -> Self;
}

impl OrderKey for f64 {
    const BITS: u32 = 64;
    /// Sign bit set: all bits flipped (larger magnitudes come first); else the sign bit set.
    #[inline]
    fn order_key(self) -> u64 {
        let bits = self.to_bits();
        if bits >> 63 == 1 {
            !bits
        } else {
            bits | 1 << 63
        }
    }
    #[inline]
    fn from_order_key(key: u64) -> Self {
        f64::from_bits(if key >> 63 == 1 { key ^ 1 << 63 } else { !key })
    }
}

impl OrderKey for f32 {
    const BITS: u32 = 32;
    #[inline]
    fn order_key(self) -> u64 {
        let bits = self.to_bits();
        u64::from(if bits >> 31 == 1 {
            !bits
        } else {
            bits | 1 << 31
        })
    }
    #[inline]
    fn from_order_key(key: u64) -> Self {
        let key = key as u32;
        f32::from_bits(if key >> 31 == 1 { key ^ 1 << 31 } else { !key })
    }
}

/// What a [`RankSearch`] needs next.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RankStep<T> {
    /// Every part's [`RankSearch::digit_counts`], merged, to [`RankSearch::feed_counts`].
    Counts,
    /// Every part's [`RankSearch::matching_values`], concatenated, to
    /// [`RankSearch::feed_values`].
    Values,
    /// The value of the rank.
    Found(T),
}

/// The counts of the next digit among the values whose key has the search's prefix, as a
/// sorted sparse list; merged over parts by addition.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DigitCounts {
    /// The prefix and the number of its bits these counts belong to.
    prefix: u64,
    fixed_bits: u32,
    /// `(digit, count)` by ascending digit, counts > 0.
    counts: Vec<(u16, u64)>,
}

impl DigitCounts {
    /// Adds another part's counts of the same round.
    ///
    /// # Errors
    ///
    /// [`NbhdError::InvalidOption`] when the two belong to different rounds or searches.
    pub fn merge(&mut self, other: &DigitCounts) -> Result<()> {
        if (self.prefix, self.fixed_bits) != (other.prefix, other.fixed_bits) {
            return Err(inconsistent("digit counts of different rounds merged"));
        }
        let mut merged = Vec::with_capacity(self.counts.len().max(other.counts.len()));
        let (mut a, mut b) = (
            self.counts.iter().peekable(),
            other.counts.iter().peekable(),
        );
        loop {
            let next = match (a.peek(), b.peek()) {
                (Some(&&(da, ca)), Some(&&(db, cb))) => match da.cmp(&db) {
                    std::cmp::Ordering::Less => a.next().map(|_| (da, ca)),
                    std::cmp::Ordering::Greater => b.next().map(|_| (db, cb)),
                    std::cmp::Ordering::Equal => {
                        a.next();
                        b.next();
                        Some((da, ca.saturating_add(cb)))
                    }
                },
                (Some(_), None) => a.next().copied(),
                (None, Some(_)) => b.next().copied(),
                (None, None) => None,
            };
            match next {
                Some(x) => merged.push(x),
                None => break,
            }
        }
        self.counts = merged;
        Ok(())
    }

    /// The `(digit, count)` pairs, by ascending digit.
    pub fn counts(&self) -> &[(u16, u64)] {
        &self.counts
    }

    /// How many values these counts cover.
    pub fn total(&self) -> u64 {
        self.counts
            .iter()
            .fold(0u64, |s, &(_, c)| s.saturating_add(c))
    }

    /// The counts as little-endian bytes, for sending a part's counts to the process that
    /// merges them: the prefix (8 bytes), the fixed bits (4), then 10 bytes a digit (2 of the
    /// digit, 8 of its count). [`DigitCounts::from_bytes`] reads them back.
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(12 + 10 * self.counts.len());
        out.extend_from_slice(&self.prefix.to_le_bytes());
        out.extend_from_slice(&self.fixed_bits.to_le_bytes());
        for &(d, c) in &self.counts {
            out.extend_from_slice(&d.to_le_bytes());
            out.extend_from_slice(&c.to_le_bytes());
        }
        out
    }

    /// Reads [`DigitCounts::to_bytes`].
    ///
    /// # Errors
    ///
    /// [`NbhdError::InvalidOption`] for bytes of another length, a prefix wider than its fixed
    /// bits, fixed bits that leave no digit, and digits not ascending or counts of 0.
    pub fn from_bytes(bytes: &[u8]) -> Result<Self> {
        if bytes.len() < 12 || (bytes.len() - 12) % 10 != 0 {
            return Err(inconsistent("digit count bytes of a wrong length"));
        }
        let prefix = u64::from_le_bytes(bytes[..8].try_into().expect("8 bytes"));
        let fixed_bits = u32::from_le_bytes(bytes[8..12].try_into().expect("4 bytes"));
        check_prefix(prefix, fixed_bits)?;
        let counts: Vec<(u16, u64)> = bytes[12..]
            .chunks_exact(10)
            .map(|c| {
                (
                    u16::from_le_bytes(c[..2].try_into().expect("2 bytes")),
                    u64::from_le_bytes(c[2..].try_into().expect("8 bytes")),
                )
            })
            .collect();
        let ascending = counts.windows(2).all(|w| w[0].0 < w[1].0);
        if !ascending || counts.iter().any(|&(_, c)| c == 0) {
            return Err(inconsistent("digit counts not ascending or empty"));
        }
        Ok(Self {
            prefix,
            fixed_bits,
            counts,
        })
    }
}

/// The driver's state of one exact selection across parts: the rank still sought inside the
/// bucket of keys that start with `prefix` (its first `fixed_bits` bits).
#[derive(Clone, Copy, Debug)]
pub struct RankSearch<T: OrderKey> {
    /// The rank among the values of the current bucket.
    rank: u64,
    /// The fixed high bits of the key, right-aligned.
    prefix: u64,
    fixed_bits: u32,
    /// Values in the current bucket (`None` before the first counts).
    bucket: Option<u64>,
    /// Set when the value is found.
    found: Option<u64>,
    _value: std::marker::PhantomData<T>,
}

impl<T: OrderKey> RankSearch<T> {
    /// A search for the value of rank `rank` (0-based, in the keys' order) among all values of
    /// all parts.
    pub fn new(rank: u64) -> Self {
        Self {
            rank,
            prefix: 0,
            fixed_bits: 0,
            bucket: None,
            found: None,
            _value: std::marker::PhantomData,
        }
    }

    /// What the search needs next.
    pub fn step(&self) -> RankStep<T> {
        match (self.found, self.bucket) {
            (Some(key), _) => RankStep::Found(T::from_order_key(key)),
            (None, Some(n)) if n <= GATHER => RankStep::Values,
            _ => RankStep::Counts,
        }
    }

    /// Whether the key of `v` lies in the current bucket.
    /// The search's state as 45 little-endian bytes, for sending it to the parts (they count
    /// and match with it) or saving a driver: the key's bits (1 byte), the rank, the prefix, the
    /// fixed bits (4), the bucket's size and the found key (each a flag byte and 8 bytes, 0
    /// when unset). [`RankSearch::from_bytes`] reads them back.
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(SEARCH_BYTES);
        out.push(T::BITS as u8);
        out.extend_from_slice(&self.rank.to_le_bytes());
        out.extend_from_slice(&self.prefix.to_le_bytes());
        out.extend_from_slice(&self.fixed_bits.to_le_bytes());
        for v in [self.bucket, self.found] {
            out.push(u8::from(v.is_some()));
            out.extend_from_slice(&v.unwrap_or(0).to_le_bytes());
        }
        out
    }

    /// Reads [`RankSearch::to_bytes`].
    ///
    /// # Errors
    ///
    /// [`NbhdError::InvalidOption`] for bytes of another length or value type, and a state no
    /// search reaches (a prefix wider than its bits, a rank outside the bucket).
    pub fn from_bytes(bytes: &[u8]) -> Result<Self> {
        if bytes.len() != SEARCH_BYTES || u32::from(bytes[0]) != T::BITS {
            return Err(inconsistent("rank search bytes of another length or type"));
        }
        let word = |at: usize| u64::from_le_bytes(bytes[at..at + 8].try_into().expect("8 bytes"));
        let option = |at: usize| match bytes[at] {
            0 => Ok(None),
            1 => Ok(Some(word(at + 1))),
            _ => Err(inconsistent("rank search bytes with a bad flag")),
        };
        let fixed_bits = u32::from_le_bytes(bytes[17..21].try_into().expect("4 bytes"));
        let (prefix, bucket, found) = (word(9), option(21)?, option(30)?);
        if fixed_bits > T::BITS
            || (fixed_bits < T::BITS && check_prefix(prefix, fixed_bits).is_err())
        {
            return Err(inconsistent("rank search bytes with a bad prefix"));
        }
        let rank = word(1);
        if bucket.is_some_and(|n| rank >= n) || (fixed_bits > 0) != bucket.is_some() {
            return Err(inconsistent(
                "rank search bytes with a rank outside its bucket",
            ));
        }
        Ok(Self {
            rank,
            prefix,
            fixed_bits,
            bucket,
            found,
            _value: std::marker::PhantomData,
        })
    }

    #[inline]
    fn in_bucket(&self, key: u64) -> bool {
        self.fixed_bits == 0 || key >> (T::BITS - self.fixed_bits) == self.prefix
    }

    /// One part's counts of the next digit among its values in the current bucket.
    pub fn digit_counts(&self, values: &[T]) -> DigitCounts {
        if values.len() >= SPARSE_BELOW {
            let mut table = vec![0u64; 1 << DIGIT_BITS];
            self.count_into(values, &mut table);
            return self.counts_of_table(&table);
        }
        let shift = T::BITS - self.fixed_bits - DIGIT_BITS;
        let mut digits: Vec<u16> = values
            .iter()
            .map(|v| v.order_key())
            .filter(|&k| self.in_bucket(k))
            .map(|k| (k >> shift) as u16)
            .collect();
        digits.sort_unstable();
        let mut counts: Vec<(u16, u64)> = Vec::new();
        for d in digits {
            match counts.last_mut() {
                Some((last, c)) if *last == d => *c += 1,
                _ => counts.push((d, 1)),
            }
        }
        DigitCounts {
            prefix: self.prefix,
            fixed_bits: self.fixed_bits,
            counts,
        }
    }

    /// Adds the digits of `values` in the current bucket to a table of 2^16 counts.
    fn count_into(&self, values: &[T], table: &mut [u64]) {
        let shift = T::BITS - self.fixed_bits - DIGIT_BITS;
        for v in values {
            let key = v.order_key();
            if self.in_bucket(key) {
                table[((key >> shift) & 0xFFFF) as usize] += 1;
            }
        }
    }

    /// The sparse counts of a table of 2^16 counts.
    fn counts_of_table(&self, table: &[u64]) -> DigitCounts {
        DigitCounts {
            prefix: self.prefix,
            fixed_bits: self.fixed_bits,
            counts: (0..=u16::MAX)
                .zip(table.iter().copied())
                .filter(|&(_, c)| c > 0)
                .collect(),
        }
    }

    /// One part's values in the current bucket (the gathering round).
    pub fn matching_values(&self, values: &[T]) -> Vec<T> {
        values
            .iter()
            .copied()
            .filter(|v| self.in_bucket(v.order_key()))
            .collect()
    }

    /// Takes the merged counts of all parts: fixes the next digit.
    ///
    /// # Errors
    ///
    /// [`NbhdError::InvalidOption`] when the rank is not below the number of values (first
    /// round), when the counts belong to another round, or when they do not add up to the
    /// bucket the previous round found (a part changed or was left out).
    pub fn feed_counts(&mut self, counts: &DigitCounts) -> Result<()> {
        if !matches!(self.step(), RankStep::Counts) {
            return Err(inconsistent("digit counts fed when none were asked for"));
        }
        if (counts.prefix, counts.fixed_bits) != (self.prefix, self.fixed_bits) {
            return Err(inconsistent("digit counts of another round"));
        }
        self.check_bucket(counts.total())?;
        let mut below = 0u64;
        for &(digit, count) in &counts.counts {
            if self.rank - below < count {
                self.rank -= below;
                self.prefix = self.prefix << DIGIT_BITS | u64::from(digit);
                self.fixed_bits += DIGIT_BITS;
                self.bucket = Some(count);
                if self.fixed_bits == T::BITS {
                    // every bit fixed: the bucket holds copies of one value
                    self.found = Some(self.prefix);
                }
                return Ok(());
            }
            below += count;
        }
        // only counts whose total saturated `u64` get here
        Err(inconsistent("digit counts that overflow"))
    }

    /// Takes the values of the current bucket from all parts, in any order: selects the rank
    /// among them.
    ///
    /// # Errors
    ///
    /// [`NbhdError::InvalidOption`] when values were not asked for, when one lies outside the
    /// bucket, or when their number is not the bucket's.
    pub fn feed_values(&mut self, values: &[T]) -> Result<()> {
        if !matches!(self.step(), RankStep::Values) {
            return Err(inconsistent("values fed when none were asked for"));
        }
        self.check_bucket(values.len() as u64)?;
        let mut keys: Vec<u64> = values.iter().map(|v| v.order_key()).collect();
        if keys.iter().any(|&k| !self.in_bucket(k)) {
            return Err(inconsistent("a value outside the bucket"));
        }
        let m = self.rank as usize;
        select_nth(
            &mut keys,
            m,
            &mut |a, b| a < b,
            SelectAlgorithm::FloydRivest,
        );
        self.found = Some(keys[m]);
        Ok(())
    }

    /// Checks that a round covers the values the previous one counted (and, in the first
    /// round, that the rank exists).
    fn check_bucket(&self, total: u64) -> Result<()> {
        match self.bucket {
            None if self.rank >= total => Err(NbhdError::InvalidOption {
                name: "rank",
                reason: format!("rank {} of {total} values", self.rank),
            }),
            Some(n) if n != total => Err(inconsistent(&format!(
                "{total} values in a bucket of {n} (a part changed or is missing)"
            ))),
            _ => Ok(()),
        }
    }
}

/// Bytes of [`RankSearch::to_bytes`].
const SEARCH_BYTES: usize = 1 + 8 + 8 + 4 + 9 + 9;

/// Refuses a prefix of more bits than `fixed_bits`, or fixed bits that leave no 16-bit digit of
/// a 64-bit key (or are not whole digits).
fn check_prefix(prefix: u64, fixed_bits: u32) -> Result<()> {
    if fixed_bits % DIGIT_BITS != 0
        || fixed_bits + DIGIT_BITS > 64
        || (fixed_bits < 64 && prefix >> fixed_bits != 0)
    {
        return Err(inconsistent("a prefix wider than its bits"));
    }
    Ok(())
}

fn inconsistent(reason: &str) -> NbhdError {
    NbhdError::InvalidOption {
        name: "rank search",
        reason: reason.to_string(),
    }
}

/// The value of rank `rank` (0-based, in `total_cmp` order) among the values of all `parts`,
/// which are read, never copied together: the rounds of [`RankSearch`] run in this process.
/// Bit for bit the element `select_nth_unstable_by(rank, total_cmp)` puts at `rank` in the
/// concatenation.
///
/// # Errors
///
/// [`NbhdError::InvalidOption`] when `rank` is not below the number of values.
pub fn select_in_parts<T: OrderKey>(parts: &[&[T]], rank: u64) -> Result<T> {
    let mut search = RankSearch::<T>::new(rank);
    let total: usize = parts.iter().map(|p| p.len()).sum();
    // a shared table of counts pays off from a few thousand values on
    let mut table = vec![
        0u64;
        if total >= SPARSE_BELOW {
            1 << DIGIT_BITS
        } else {
            0
        }
    ];
    loop {
        match search.step() {
            RankStep::Found(v) => return Ok(v),
            RankStep::Counts if table.is_empty() => {
                let mut counts = search.digit_counts(&[]);
                for part in parts {
                    counts.merge(&search.digit_counts(part))?;
                }
                search.feed_counts(&counts)?;
            }
            RankStep::Counts => {
                // in one process the parts share one table of counts
                table.fill(0);
                for part in parts {
                    search.count_into(part, &mut table);
                }
                search.feed_counts(&search.counts_of_table(&table))?;
            }
            RankStep::Values => {
                let values: Vec<T> = parts
                    .iter()
                    .flat_map(|p| search.matching_values(p))
                    .collect();
                search.feed_values(&values)?;
            }
        }
    }
}

#[cfg(test)]
mod tests;
