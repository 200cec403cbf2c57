//! The coordinate types nbhd computes in: `f32` and `f64`, both first-class.

use std::fmt::{Debug, Display};
use std::ops::{Add, Mul, Rem, Sub};

/// The run-time tag of a coordinate type, used where the type is only known from a buffer
/// description (the C ABI, files).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ScalarType {
    /// 32-bit IEEE 754 floats.
    F32,
    /// 64-bit IEEE 754 floats.
    F64,
}

impl ScalarType {
    /// Size of one coordinate in bytes.
    pub const fn size(self) -> usize {
        match self {
            ScalarType::F32 => 4,
            ScalarType::F64 => 8,
        }
    }
}

/// A floating-point coordinate type (implemented for `f32` and `f64`).
///
/// Sealed: the trees, queries and smoothing rely on IEEE semantics of exactly these two types.
pub trait Scalar:
    Copy
    + Send
    + Sync
    + PartialOrd
    + Debug
    + Display
    + Default
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Rem<Output = Self>
    + sealed::Sealed
    + 'static
{
    /// The run-time tag of this type.
    const TYPE: ScalarType;
    /// Zero.
    const ZERO: Self;
    /// Positive infinity.
    const INFINITY: Self;
    /// Converts from `f64` (rounding to nearest for `f32`).
    fn from_f64(v: f64) -> Self;
    /// Converts to `f64` (exact).
    fn to_f64(self) -> f64;
    /// Reads one native-endian value from exactly `Self::TYPE.size()` bytes.
    fn read_ne(bytes: &[u8]) -> Self;
    /// `true` unless NaN or infinite.
    fn is_finite(self) -> bool;
    /// A value whose bits carry `i < 2^30` (an index stored in a value slot, only moved, never
    /// computed with): `f32` the bits themselves (exponent at most 127, so never a NaN),
    /// `f64` the bits as a subnormal. [`Scalar::index_bits`] gives `i` back. Plumbing of the
    /// tree's compact descent (`src/tree/node.rs`), not for callers.
    #[doc(hidden)]
    fn from_index_bits(i: u32) -> Self;
    /// The index stored by [`Scalar::from_index_bits`].
    #[doc(hidden)]
    fn index_bits(self) -> u32;
    /// Absolute value.
    fn abs(self) -> Self;
    /// `self` to the power `p` (the platform's `pow`).
    fn powf(self, p: Self) -> Self;
    /// Square root.
    fn sqrt(self) -> Self;
    /// The largest value below `self` (`x < self` ⇔ `x ≤ self.next_down()` for every `x`).
    fn next_down(self) -> Self;
    /// Machine epsilon (the distance from 1 to the next value).
    const EPSILON: Self;
    /// The largest finite value.
    const MAX: Self;
    /// Larger of two non-NaN values.
    #[inline]
    fn max_of(self, other: Self) -> Self {
        if other > self {
            other
        } else {
            self
        }
    }
    /// Smaller of two non-NaN values.
    #[inline]
    fn min_of(self, other: Self) -> Self {
        if other < self {
            other
        } else {
            self
        }
    }
}

mod sealed {
    pub trait Sealed {}
    impl Sealed for f32 {}
    impl Sealed for f64 {}
}

impl Scalar for f32 {
    const TYPE: ScalarType = ScalarType::F32;
    const ZERO: Self = 0.0;
    const INFINITY: Self = f32::INFINITY;
    const EPSILON: Self = f32::EPSILON;
    const MAX: Self = f32::MAX;
    #[inline(always)]
    fn abs(self) -> Self {
        f32::abs(self)
    }
    #[inline]
    fn powf(self, p: Self) -> Self {
        f32::powf(self, p)
    }
    #[inline]
    fn sqrt(self) -> Self {
        f32::sqrt(self)
    }
    #[inline]
    fn next_down(self) -> Self {
        // (`f32::next_down` needs Rust 1.86, above the crate's rust-version)
        if self.is_nan() || self == f32::NEG_INFINITY {
            self
        } else if self == 0.0 {
            -f32::from_bits(1)
        } else if self > 0.0 {
            f32::from_bits(self.to_bits() - 1)
        } else {
            f32::from_bits(self.to_bits() + 1)
        }
    }
    #[inline]
    fn from_f64(v: f64) -> Self {
        v as f32
    }
    #[inline]
    fn to_f64(self) -> f64 {
        self as f64
    }
    #[inline]
    fn read_ne(bytes: &[u8]) -> Self {
        let mut b = [0u8; 4];
        b.copy_from_slice(bytes);
        f32::from_ne_bytes(b)
    }
    #[inline]
    fn is_finite(self) -> bool {
        f32::is_finite(self)
    }
    #[inline(always)]
    fn from_index_bits(i: u32) -> Self {
        f32::from_bits(i)
    }
    #[inline(always)]
    fn index_bits(self) -> u32 {
        self.to_bits()
    }
}

impl Scalar for f64 {
    const TYPE: ScalarType = ScalarType::F64;
    const ZERO: Self = 0.0;
    const INFINITY: Self = f64::INFINITY;
    const EPSILON: Self = f64::EPSILON;
    const MAX: Self = f64::MAX;
    #[inline(always)]
    fn abs(self) -> Self {
        f64::abs(self)
    }
    #[inline]
    fn powf(self, p: Self) -> Self {
        f64::powf(self, p)
    }
    #[inline]
    fn sqrt(self) -> Self {
        f64::sqrt(self)
    }
    #[inline]
    fn next_down(self) -> Self {
        // (`f64::next_down` needs Rust 1.86, above the crate's rust-version)
        if self.is_nan() || self == f64::NEG_INFINITY {
            self
        } else if self == 0.0 {
            -f64::from_bits(1)
        } else if self > 0.0 {
            f64::from_bits(self.to_bits() - 1)
        } else {
            f64::from_bits(self.to_bits() + 1)
        }
    }
    #[inline]
    fn from_f64(v: f64) -> Self {
        v
    }
    #[inline]
    fn to_f64(self) -> f64 {
        self
    }
    #[inline]
    fn read_ne(bytes: &[u8]) -> Self {
        let mut b = [0u8; 8];
        b.copy_from_slice(bytes);
        f64::from_ne_bytes(b)
    }
    #[inline]
    fn is_finite(self) -> bool {
        f64::is_finite(self)
    }
    #[inline(always)]
    fn from_index_bits(i: u32) -> Self {
        f64::from_bits(i as u64)
    }
    #[inline(always)]
    fn index_bits(self) -> u32 {
        self.to_bits() as u32
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn next_down_is_the_predecessor() {
        assert_eq!(Scalar::next_down(1.0f64), 1.0 - f64::EPSILON / 2.0);
        assert_eq!(Scalar::next_down(1.0f32), 1.0 - f32::EPSILON / 2.0);
        assert_eq!(Scalar::next_down(0.0f64), -f64::from_bits(1));
        assert_eq!(Scalar::next_down(-1.0f32), -1.0 - f32::EPSILON);
        assert_eq!(Scalar::next_down(f32::INFINITY), f32::MAX);
        assert_eq!(Scalar::next_down(f64::NEG_INFINITY), f64::NEG_INFINITY);
    }
}
