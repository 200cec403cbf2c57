//! Views of a caller's point buffer: count, dimension, stride in bytes and scalar type, so that a
//! PCL `PointXYZ` array (16-byte stride), an OpenMesh point array or a plain `[x, y, z, x, ...]`
//! slice is read in place, without the caller copying it.

use crate::error::{NbhdError, Result};
use crate::scalar::{Scalar, ScalarType};

/// The largest number of points a tree holds: indices are `u32`.
pub const MAX_POINTS: usize = u32::MAX as usize;

/// The bytes of one point of dimension `dim` in `scalar`: what every description of points
/// (a view, a growing tree, a saved growing tree) must fit in the address space.
///
/// Errors: [`NbhdError::SizeOverflow`] when `dim × scalar size` exceeds `isize::MAX` bytes.
pub fn point_bytes(dim: usize, scalar: ScalarType) -> Result<usize> {
    dim.checked_mul(scalar.size())
        .filter(|&b| b <= isize::MAX as usize)
        .ok_or_else(|| NbhdError::SizeOverflow {
            what: format!(
                "dim {dim} times {} bytes per coordinate ({:?})",
                scalar.size(),
                scalar
            ),
        })
}

/// A borrowed, validated description of `count` points of dimension `dim` in a byte buffer.
///
/// Point `i` starts at byte `i * stride`; its coordinates are `dim` consecutive values of
/// `scalar`. The view checks the geometry of the buffer (not the values) when it is made.
#[derive(Clone, Copy, Debug)]
pub struct PointsView<'a> {
    bytes: &'a [u8],
    count: usize,
    dim: usize,
    stride: usize,
    scalar: ScalarType,
}

impl<'a> PointsView<'a> {
    /// Describes `count` points of dimension `dim`, `stride` bytes apart, in `bytes`. Zero
    /// points are a valid description (of zero bytes): a tree over them, or a batch of them
    /// as queries, holds or asks nothing.
    ///
    /// Errors: [`NbhdError::ZeroDimension`],
    /// [`NbhdError::StrideTooSmall`], [`NbhdError::TooManyPoints`] and
    /// [`NbhdError::BufferTooSmall`] when `bytes` is shorter than the description.
    pub fn new(
        bytes: &'a [u8],
        count: usize,
        dim: usize,
        stride: usize,
        scalar: ScalarType,
    ) -> Result<Self> {
        let needed = Self::required_bytes(count, dim, stride, scalar).map_err(|e| match e {
            NbhdError::BufferTooSmall { what, needed, .. } => NbhdError::BufferTooSmall {
                what,
                len: bytes.len(),
                needed,
            },
            e => e,
        })?;
        if bytes.len() < needed {
            return Err(NbhdError::BufferTooSmall {
                what: "point buffer (bytes)",
                len: bytes.len(),
                needed,
            });
        }
        Ok(Self {
            bytes,
            count,
            dim,
            stride,
            scalar,
        })
    }

    /// The number of bytes a buffer of `count` points of dimension `dim`, `stride` bytes apart,
    /// must hold: `(count - 1) * stride + dim * scalar.size()` (0 for no point), after the same
    /// geometry checks as [`Self::new`]. Lets a caller that only has a pointer (the C ABI) know
    /// how many bytes it may view before making the view.
    ///
    /// Errors: [`NbhdError::ZeroDimension`], [`NbhdError::StrideTooSmall`],
    /// [`NbhdError::TooManyPoints`], and
    /// [`NbhdError::SizeOverflow`] when `dim × scalar size` or the buffer size overflows the
    /// address space.
    pub fn required_bytes(
        count: usize,
        dim: usize,
        stride: usize,
        scalar: ScalarType,
    ) -> Result<usize> {
        if dim == 0 {
            return Err(NbhdError::ZeroDimension);
        }
        let point_bytes = point_bytes(dim, scalar)?;
        if stride < point_bytes {
            return Err(NbhdError::StrideTooSmall {
                stride,
                point_bytes,
            });
        }
        if count == 0 {
            return Ok(0);
        }
        if count > MAX_POINTS {
            return Err(NbhdError::TooManyPoints {
                count,
                max: MAX_POINTS,
            });
        }
        (count - 1)
            .checked_mul(stride)
            .and_then(|b| b.checked_add(point_bytes))
            .filter(|&b| b <= isize::MAX as usize)
            .ok_or_else(|| NbhdError::SizeOverflow {
                what: format!(
                    "the point buffer of count {count} and stride {stride} \
                     ((count - 1) * stride + {point_bytes} bytes)"
                ),
            })
    }

    /// A view of a tightly packed slice `[x0, y0, z0, x1, ...]` of dimension `dim`.
    pub fn from_flat<T: Scalar>(coords: &'a [T], dim: usize) -> Result<Self> {
        if dim == 0 {
            return Err(NbhdError::ZeroDimension);
        }
        if coords.len() % dim != 0 {
            return Err(NbhdError::BufferTooSmall {
                what: "coordinate slice (values; not a multiple of the dimension)",
                len: coords.len(),
                needed: coords.len().div_ceil(dim) * dim,
            });
        }
        Self::new(
            as_bytes(coords),
            coords.len() / dim,
            dim,
            dim * T::TYPE.size(),
            T::TYPE,
        )
    }

    /// A view of fixed-size points such as `&[[f32; 3]]`.
    pub fn from_rows<T: Scalar, const D: usize>(rows: &'a [[T; D]]) -> Result<Self> {
        Self::from_flat(rows.as_flattened(), D)
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.count
    }

    /// `true` for a view of no point.
    pub fn is_empty(&self) -> bool {
        self.count == 0
    }

    /// Dimension of the points.
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// Bytes from one point to the next.
    pub fn stride(&self) -> usize {
        self.stride
    }

    /// Coordinate type of the buffer.
    pub fn scalar_type(&self) -> ScalarType {
        self.scalar
    }

    /// Coordinate `j` of point `i`, converted to `T`. Panics if out of range (internal use
    /// after validation).
    #[inline]
    pub fn coord<T: Scalar>(&self, i: usize, j: usize) -> T {
        let size = self.scalar.size();
        let at = i * self.stride + j * size;
        let b = &self.bytes[at..at + size];
        match self.scalar {
            ScalarType::F32 => T::from_f64(f32::read_ne(b) as f64),
            ScalarType::F64 => T::from_f64(f64::read_ne(b)),
        }
    }

    /// Point `i` as `D` values of type `S`, which must be the view's own scalar type, with one
    /// bounds check for the point (the bulk read of the build). Panics if out of range.
    #[inline]
    pub(crate) fn row<S: Scalar, const D: usize>(&self, i: usize) -> [S; D] {
        debug_assert!(S::TYPE == self.scalar && D == self.dim);
        let size = std::mem::size_of::<S>();
        let at = i * self.stride;
        let b = &self.bytes[at..at + D * size];
        std::array::from_fn(|j| S::read_ne(&b[j * size..(j + 1) * size]))
    }

    /// Copies point `i` into `out` (length `dim`), converted to `T`.
    #[inline]
    pub fn read_point<T: Scalar>(&self, i: usize, out: &mut [T]) {
        for (j, o) in out.iter_mut().enumerate() {
            *o = self.coord(i, j);
        }
    }

    /// Index and coordinate of the first point with a NaN or infinite coordinate, if any.
    pub fn first_non_finite(&self) -> Option<(usize, usize)> {
        (0..self.count).find_map(|i| {
            (0..self.dim)
                .find(|&j| !self.coord::<f64>(i, j).is_finite())
                .map(|j| (i, j))
        })
    }
}

/// The bytes of a slice of scalars (safe: `f32`/`f64` have no padding and every byte pattern of
/// them is readable as `u8`).
pub(crate) fn as_bytes<T: Scalar>(v: &[T]) -> &[u8] {
    // SAFETY: `T` is `f32` or `f64` (the trait is sealed): plain old data without padding, so
    // viewing its memory as `size_of_val(v)` initialised bytes with the lifetime of `v` is sound.
    unsafe { std::slice::from_raw_parts(v.as_ptr().cast::<u8>(), std::mem::size_of_val(v)) }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn strided_view_reads_pcl_like_layout() {
        // x y z pad, as PCL's PointXYZ.
        let raw: Vec<f32> = vec![1.0, 2.0, 3.0, 0.0, 4.0, 5.0, 6.0, 0.0];
        let v = PointsView::new(as_bytes(&raw), 2, 3, 16, ScalarType::F32).unwrap();
        let mut p = [0.0f64; 3];
        v.read_point(1, &mut p);
        assert_eq!(p, [4.0, 5.0, 6.0]);
    }

    #[test]
    fn geometry_errors() {
        let raw = [0.0f64; 6];
        let b = as_bytes(&raw);
        assert_eq!(
            PointsView::new(b, 2, 0, 24, ScalarType::F64).unwrap_err(),
            NbhdError::ZeroDimension
        );
        let empty = PointsView::new(b, 0, 3, 24, ScalarType::F64).unwrap();
        assert!(empty.is_empty() && empty.dim() == 3);
        assert!(PointsView::new(&[], 0, 3, 24, ScalarType::F64).is_ok());
        assert_eq!(
            PointsView::new(b, 0, 0, 24, ScalarType::F64).unwrap_err(),
            NbhdError::ZeroDimension
        );
        assert!(matches!(
            PointsView::new(b, 2, 3, 16, ScalarType::F64),
            Err(NbhdError::StrideTooSmall {
                stride: 16,
                point_bytes: 24
            })
        ));
        assert!(matches!(
            PointsView::new(b, 3, 3, 24, ScalarType::F64),
            Err(NbhdError::BufferTooSmall { needed: 72, .. })
        ));
        assert!(PointsView::from_flat(&raw[..5], 3).is_err());
    }

    #[test]
    fn required_bytes_matches_new() {
        assert_eq!(
            PointsView::required_bytes(3, 3, 16, ScalarType::F32),
            Ok(2 * 16 + 12)
        );
        assert_eq!(
            PointsView::required_bytes(1, 2, 16, ScalarType::F64),
            Ok(16)
        );
        assert_eq!(PointsView::required_bytes(0, 3, 12, ScalarType::F32), Ok(0));
        assert!(matches!(
            PointsView::required_bytes(0, 3, 11, ScalarType::F32),
            Err(NbhdError::StrideTooSmall { .. })
        ));
        assert_eq!(
            PointsView::required_bytes(2, 0, 12, ScalarType::F32),
            Err(NbhdError::ZeroDimension)
        );
        assert!(matches!(
            PointsView::required_bytes(2, 3, 11, ScalarType::F32),
            Err(NbhdError::StrideTooSmall { .. })
        ));
        assert!(matches!(
            PointsView::required_bytes(1 << 31, 1, usize::MAX / 4, ScalarType::F32),
            Err(NbhdError::SizeOverflow { .. })
        ));
        let e = PointsView::required_bytes(2, usize::MAX / 2, 0, ScalarType::F64).unwrap_err();
        assert!(
            e.to_string()
                .starts_with(&format!("dim {} times 8 bytes", usize::MAX / 2)),
            "{e}"
        );
    }

    #[test]
    fn finds_first_non_finite() {
        let raw = [0.0, 1.0, 2.0, 3.0, f32::NAN, 5.0, f32::INFINITY, 0.0, 0.0];
        let v = PointsView::from_flat(&raw, 3).unwrap();
        assert_eq!(v.first_non_finite(), Some((1, 1)));
    }
}
