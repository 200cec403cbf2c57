//! An exact, order-independent sum of `f64` values: [`ExactSum`].
//!
//! A sum of floating-point values rounds after every addition, so its bits depend on the order
//! of the additions. A run split into tiles (a Dask graph, the tiled robust mode of
//! docs/ARCHITECTURE.md) adds in an order the scheduler picks; to give the same bits as one
//! machine, its sums must not depend on the order at all. `ExactSum` keeps the sum **exactly**
//! and rounds once, when the value is asked for, so every order, every split into parts and
//! every order of merging the parts gives the same bits: the exact sum rounded to nearest, ties
//! to even.
//!
//! # The algorithm: a fixed-point superaccumulator
//!
//! Every finite `f64` is an integer multiple of 2⁻¹⁰⁷⁴ (the smallest subnormal) below 2¹⁰²⁴, so
//! `x · 2¹⁰⁷⁴` is an integer of at most 2098 bits. The accumulator holds the exact sum as one
//! such integer, in [`LIMBS`] signed 64-bit limbs of which each stands for 32 bits
//! (limb `i` weighs 2^(32·i)); this is the "superaccumulator" of the literature on exact and
//! reproducible summation (Kulisch's long accumulator; Neal, "Fast exact summation using small
//! and large superaccumulators"; Collange, Defour, Graillat and Iakymchuk, "Numerical
//! reproducibility for the parallel reduction on multi- and many-core architectures").
//!
//! - **Adding** `x = ±m · 2^(p − 1074)` (`m < 2⁵³`): the 53-bit mantissa shifted by `p mod 32`
//!   spans at most three 32-bit digits, which are added with `x`'s sign to three limbs. No
//!   carry is propagated: a limb has 31 bits of room above its digit, so up to
//!   [`CARRY_ROOM`] additions fit before the limbs must be normalised.
//! - **Normalising** propagates the carries from the lowest limb up: every limb but the top one
//!   ends in `[0, 2³²)` and the top limb holds the signed rest (two's complement over the whole
//!   integer). The sum of fewer than 2⁶⁴ values is below 2¹⁰⁸⁸ in magnitude, so the top limb
//!   (weight 2¹⁰³⁸ in value) never exceeds 2⁵⁰.
//! - **Merging** two accumulators adds their normalised limbs: integer addition is associative
//!   and commutative, so parts merge in any tree and any order to the same integer.
//! - **Rounding** ([`ExactSum::value`]) takes the magnitude, its top 53 bits, the next bit and
//!   whether any lower bit is set, and rounds to nearest, ties to even; an integer below 2⁵³ is
//!   representable as it is (a subnormal or the smallest normals), and a rounded magnitude of
//!   2¹⁰²⁴ or more is infinite, as IEEE 754 rounds an overflow.
//!
//! # Special values
//!
//! - **Zeros**: the sum of values that are all `−0.0` (at least one) is `−0.0`; every other
//!   exact zero, and the empty sum, is `+0.0` — what IEEE addition gives in any order.
//! - **NaN and ±∞** are not added to the integer but remembered: any NaN, or both `+∞` and
//!   `−∞`, make the value NaN (the canonical `f64::NAN`, whatever the inputs' payloads); else
//!   any `+∞` makes it `+∞` and any `−∞` makes it `−∞`. This is what a plain sum gives, except
//!   that a plain sum may also overflow to ∞ part way through a sum whose exact value is finite;
//!   `ExactSum` does not.
//!
//! # Cost
//!
//! About three integer additions and a few bit operations per value, with no branch on the
//! data beyond the rare normalisation; docs/speed-log.md has the measured cost per value
//! against a plain sum. The state is [`LIMBS`] × 8 bytes; [`ExactSum::to_bytes`] writes its
//! normalised form for sending between processes.

use crate::error::{NbhdError, Result};

/// Limbs of the accumulator: 66 hold the 2098 bits of `x · 2¹⁰⁷⁴` and the carries of up to
/// 2⁶⁴ values' sum sit in the last (bits 2112 up, signed).
pub const LIMBS: usize = 67;

/// Additions between normalisations: each adds less than 2³² to a limb that starts below 2³²
/// in magnitude, so 2³⁰ of them keep every limb far inside `i64`.
const CARRY_ROOM: u32 = 1 << 30;

/// Bits of one limb's digit.
const DIGIT: u32 = 32;

/// The size of [`ExactSum::to_bytes`]: magic and version (4), flags (4), count (8), the
/// limbs (8 each).
const BYTES: usize = 16 + 8 * LIMBS;

/// The first bytes of [`ExactSum::to_bytes`] (`"XS"`, format 1).
const MAGIC: [u8; 4] = *b"XS\x01\x00";

/// Flags of the values that are not added to the integer.
const SAW_NAN: u32 = 1;
const SAW_POS_INF: u32 = 2;
const SAW_NEG_INF: u32 = 4;
/// Some value other than `−0.0` was added (a zero sum is then `+0.0`).
const SAW_NOT_NEG_ZERO: u32 = 8;
const FLAGS: u32 = SAW_NAN | SAW_POS_INF | SAW_NEG_INF | SAW_NOT_NEG_ZERO;

/// An exact sum of `f64` values whose value does not depend on the order of the additions or
/// of the merges (see the [module documentation](self)).
///
/// ```
/// use nbhd::ExactSum;
/// let mut a = ExactSum::new();
/// a.add(1e308);
/// a.add(1e-300);
/// let mut b: ExactSum = [-1e308, 0.5].into_iter().collect();
/// b.merge(&a);
/// assert_eq!(b.value(), 0.5); // 0.5 + 1e-300 rounded; a plain sum in this order gives 1e-300
/// assert_eq!(b.count(), 4);
/// ```
#[derive(Clone, Debug)]
pub struct ExactSum {
    /// `Σ x · 2¹⁰⁷⁴ = Σᵢ limbs[i] · 2^(32·i)` over the finite values.
    limbs: [i64; LIMBS],
    /// Additions since the limbs were last normalised.
    pending: u32,
    /// `SAW_*` flags.
    flags: u32,
    /// Values added, finite or not.
    count: u64,
}

impl Default for ExactSum {
    fn default() -> Self {
        Self::new()
    }
}

impl PartialEq for ExactSum {
    /// Two sums are equal when they hold the same exact value, the same special values and the
    /// same count (however they were built).
    fn eq(&self, other: &Self) -> bool {
        let (mut a, mut b) = (self.clone(), other.clone());
        a.normalise();
        b.normalise();
        a.limbs == b.limbs && a.flags == b.flags && a.count == b.count
    }
}

impl Eq for ExactSum {}

impl ExactSum {
    /// The empty sum (its value is `+0.0`).
    pub const fn new() -> Self {
        Self {
            limbs: [0; LIMBS],
            pending: 0,
            flags: 0,
            count: 0,
        }
    }

    /// Adds one value exactly.
    #[inline]
    pub fn add(&mut self, x: f64) {
        self.count += 1;
        let bits = x.to_bits();
        let negative = bits >> 63 == 1;
        let exponent = ((bits >> 52) & 0x7FF) as u32;
        let fraction = bits & ((1 << 52) - 1);
        if exponent == 0x7FF {
            self.flags |= if fraction != 0 {
                SAW_NAN
            } else if negative {
                SAW_NEG_INF
            } else {
                SAW_POS_INF
            };
            return;
        }
        if bits != 1 << 63 {
            self.flags |= SAW_NOT_NEG_ZERO;
        }
        // x = ±m · 2^(p − 1074): a subnormal has p = 0 and no hidden bit
        let (m, p) = if exponent == 0 {
            (fraction, 0)
        } else {
            (fraction | 1 << 52, exponent - 1)
        };
        let shifted = u128::from(m) << (p % DIGIT);
        let i = (p / DIGIT) as usize;
        let pieces = [
            (shifted & 0xFFFF_FFFF) as i64,
            ((shifted >> 32) & 0xFFFF_FFFF) as i64,
            (shifted >> 64) as i64,
        ];
        // p ≤ 2045, so i + 2 ≤ 65 < LIMBS − 1
        let limbs = &mut self.limbs[i..i + 3];
        if negative {
            for (l, d) in limbs.iter_mut().zip(pieces) {
                *l -= d;
            }
        } else {
            for (l, d) in limbs.iter_mut().zip(pieces) {
                *l += d;
            }
        }
        self.pending += 1;
        if self.pending == CARRY_ROOM {
            self.normalise();
        }
    }

    /// Adds every value of a slice.
    pub fn add_slice(&mut self, values: &[f64]) {
        for &x in values {
            self.add(x);
        }
    }

    /// Adds the values of another sum: the result is the same whatever the order of the
    /// merges and additions that built the two.
    pub fn merge(&mut self, other: &ExactSum) {
        let mut other = other.clone();
        other.normalise();
        self.normalise();
        let top = LIMBS - 1;
        for (a, b) in self.limbs[..top].iter_mut().zip(&other.limbs[..top]) {
            *a += b;
        }
        // only sums of 2⁶⁴ values or more (or forged bytes) come near the end of `i64` here;
        // saturating keeps the sign, and the value is ±∞ long before
        self.limbs[top] = self.limbs[top].saturating_add(other.limbs[top]);
        self.pending = 1;
        self.flags |= other.flags;
        self.count = self.count.saturating_add(other.count);
    }

    /// How many values were added (NaN and ±∞ included), over all merged sums.
    pub fn count(&self) -> u64 {
        self.count
    }

    /// The exact sum rounded to the nearest `f64`, ties to even (special values as the
    /// [module documentation](self) says).
    pub fn value(&self) -> f64 {
        if self.flags & SAW_NAN != 0
            || self.flags & (SAW_POS_INF | SAW_NEG_INF) == SAW_POS_INF | SAW_NEG_INF
        {
            return f64::NAN;
        }
        if self.flags & SAW_POS_INF != 0 {
            return f64::INFINITY;
        }
        if self.flags & SAW_NEG_INF != 0 {
            return f64::NEG_INFINITY;
        }
        let mut s = self.clone();
        s.normalise();
        let negative = s.limbs[LIMBS - 1] < 0;
        let magnitude = s.magnitude();
        match rounded_bits(&magnitude) {
            0 if self.flags & SAW_NOT_NEG_ZERO == 0 && self.count > 0 => -0.0,
            bits if negative => -f64::from_bits(bits),
            bits => f64::from_bits(bits),
        }
    }

    /// The normalised state as [`BYTES`] little-endian bytes, for sending a part's sum to the
    /// process that merges it ([`ExactSum::from_bytes`] reads it back).
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut s = self.clone();
        s.normalise();
        let mut out = Vec::with_capacity(BYTES);
        out.extend_from_slice(&MAGIC);
        out.extend_from_slice(&s.flags.to_le_bytes());
        out.extend_from_slice(&s.count.to_le_bytes());
        for l in s.limbs {
            out.extend_from_slice(&l.to_le_bytes());
        }
        out
    }

    /// Reads [`ExactSum::to_bytes`]; refuses bytes of another length, format or version, unknown
    /// flags, and limbs that are not normalised.
    pub fn from_bytes(bytes: &[u8]) -> Result<Self> {
        let bad = |reason: &str| NbhdError::InvalidOption {
            name: "exact sum bytes",
            reason: reason.to_string(),
        };
        if bytes.len() != BYTES {
            return Err(bad(&format!("{} bytes, expected {BYTES}", bytes.len())));
        }
        if bytes[..4] != MAGIC {
            return Err(bad("not an exact sum of format 1"));
        }
        let word = |at: usize| u64::from_le_bytes(bytes[at..at + 8].try_into().expect("8 bytes"));
        let flags = u32::from_le_bytes(bytes[4..8].try_into().expect("4 bytes"));
        if flags & !FLAGS != 0 {
            return Err(bad("unknown flags"));
        }
        let mut limbs = [0i64; LIMBS];
        for (i, l) in limbs.iter_mut().enumerate() {
            *l = word(16 + 8 * i) as i64;
        }
        if limbs[..LIMBS - 1]
            .iter()
            .any(|&l| !(0..1 << DIGIT).contains(&l))
        {
            return Err(bad("limbs not normalised"));
        }
        Ok(Self {
            limbs,
            pending: 0,
            flags,
            count: word(8),
        })
    }

    /// Propagates the carries: every limb but the top one into `[0, 2³²)`.
    fn normalise(&mut self) {
        if self.pending == 0 {
            return;
        }
        let mut carry = 0i64;
        for l in &mut self.limbs[..LIMBS - 1] {
            let v = *l + carry;
            carry = v >> DIGIT; // arithmetic shift: the floor of v / 2³²
            *l = v & 0xFFFF_FFFF;
        }
        let top = LIMBS - 1;
        self.limbs[top] = self.limbs[top].saturating_add(carry);
        self.pending = 0;
    }

    /// The absolute value of the normalised integer as 32-bit digits, lowest first.
    fn magnitude(&self) -> [u32; LIMBS + 1] {
        let mut digits = [0u32; LIMBS + 1];
        let top = self.limbs[LIMBS - 1];
        for (d, &l) in digits.iter_mut().zip(&self.limbs[..LIMBS - 1]) {
            *d = l as u32;
        }
        digits[LIMBS - 1] = top as u32;
        digits[LIMBS] = (top >> 32) as u32;
        if top < 0 {
            // two's complement: invert and add one
            let mut carry = true;
            for d in &mut digits {
                let (v, c) = (!*d).overflowing_add(u32::from(carry));
                *d = v;
                carry = c;
            }
        }
        digits
    }
}

/// The bits of the non-negative `f64` nearest to `I · 2⁻¹⁰⁷⁴` (ties to even), `I` given as
/// 32-bit digits lowest first; `+∞`'s bits when it rounds to 2¹⁰²⁴ or more.
fn rounded_bits(digits: &[u32]) -> u64 {
    let Some(top) = digits.iter().rposition(|&d| d != 0) else {
        return 0;
    };
    let length = DIGIT as usize * top + (DIGIT - digits[top].leading_zeros()) as usize;
    if length <= 53 {
        // below 2⁵³: the bits of I · 2⁻¹⁰⁷⁴ are I itself (subnormal, or the first binade)
        return u64::from(digits[0]) | u64::from(digits.get(1).copied().unwrap_or(0)) << 32;
    }
    let shift = length - 53;
    let mut m = bits_from(digits, shift, 53);
    let half = bits_from(digits, shift - 1, 1) == 1;
    let sticky = any_below(digits, shift - 1);
    if half && (sticky || m & 1 == 1) {
        m += 1; // may carry to 2⁵³, which the exponent field below absorbs
    }
    // value = m · 2^(shift − 1074): biased exponent shift + 1 and the hidden bit of m
    let bits = ((shift as u64) << 52) + m;
    bits.min(f64::INFINITY.to_bits())
}

/// Whether any bit of the integer below bit `at` is set.
fn any_below(digits: &[u32], at: usize) -> bool {
    let (d, b) = (at / DIGIT as usize, at % DIGIT as usize);
    digits[..d].iter().any(|&x| x != 0) || (b > 0 && digits[d] & ((1u32 << b) - 1) != 0)
}

/// `len ≤ 64` bits of the integer starting at bit `at`.
fn bits_from(digits: &[u32], at: usize, len: usize) -> u64 {
    let mut out = 0u64;
    let mut got = 0;
    let mut pos = at;
    while got < len {
        let (d, b) = (pos / DIGIT as usize, pos % DIGIT as usize);
        let take = (DIGIT as usize - b).min(len - got);
        let digit = u64::from(digits.get(d).copied().unwrap_or(0));
        out |= ((digit >> b) & ((1u64 << take) - 1)) << got;
        got += take;
        pos += take;
    }
    out
}

impl Extend<f64> for ExactSum {
    fn extend<I: IntoIterator<Item = f64>>(&mut self, values: I) {
        for x in values {
            self.add(x);
        }
    }
}

impl Extend<f32> for ExactSum {
    /// `f32` values are added exactly (through their exact `f64` value).
    fn extend<I: IntoIterator<Item = f32>>(&mut self, values: I) {
        for x in values {
            self.add(f64::from(x));
        }
    }
}

impl FromIterator<f64> for ExactSum {
    fn from_iter<I: IntoIterator<Item = f64>>(values: I) -> Self {
        let mut s = ExactSum::new();
        s.extend(values);
        s
    }
}

#[cfg(test)]
mod tests;
