//! The caller's points validated: what to do with non-finite ones ([`NonFinitePolicy`]), and a
//! compact, validated copy ([`PackedPoints`]): `dim` coordinates per point, packed, with the
//! caller's index of each. Trees and baselines keep one (the tree in its own order). A point
//! *cloud* with its attributes, as files hold it, is the one concept of `io::cloud`.

use crate::error::{NbhdError, Result};
use crate::named_option;
use crate::names::OptionName;
use crate::points::PointsView;
use crate::scalar::Scalar;
use glam::DVec3;
use rayon::prelude::*;

/// What to do with points that have a NaN or infinite coordinate.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum NonFinitePolicy {
    /// Refuse the input with [`NbhdError::NonFinite`] naming the first such point.
    #[default]
    Reject,
    /// Leave such points out (as PCL does); the others keep their original indices.
    Skip,
}

impl NonFinitePolicy {
    /// Both policies.
    pub const ALL: [NonFinitePolicy; 2] = [NonFinitePolicy::Reject, NonFinitePolicy::Skip];
}

impl OptionName for NonFinitePolicy {
    const OPTION: &'static str = "non_finite";
    const WHAT: &'static str = "non-finite policy";
    const NAMES: &'static [(Self, &'static str)] = &[
        (NonFinitePolicy::Reject, "reject"),
        (NonFinitePolicy::Skip, "skip"),
    ];
}
named_option!(NonFinitePolicy);

/// Packed coordinates plus the caller's index of every point.
#[derive(Clone, Debug)]
pub struct PackedPoints<T> {
    /// `dim` coordinates per point, point after point.
    pub coords: Vec<T>,
    /// Caller's index of each point.
    pub ids: Vec<u32>,
    /// Dimension.
    pub dim: usize,
    /// Number of points the caller passed in (skipped ones included).
    pub source_len: usize,
}

impl<T: Scalar> PackedPoints<T> {
    /// Copies the points of `view`, converting to `T` and applying `policy` to non-finite
    /// points. A value that is finite in the source but overflows `T` (an `f64` beyond the
    /// `f32` range) counts as non-finite. The copy may hold no point (none given, or every one
    /// skipped).
    pub fn from_view(view: &PointsView<'_>, policy: NonFinitePolicy) -> Result<Self> {
        Self::from_view_at(view, 0..view.len(), policy)
    }

    /// As [`Self::from_view`], over the points `indices` of `view` only (in range, in the order
    /// given; the caller checks them). Errors name the caller's index.
    pub fn from_view_at(
        view: &PointsView<'_>,
        indices: impl ExactSizeIterator<Item = usize>,
        policy: NonFinitePolicy,
    ) -> Result<Self> {
        let (n, dim) = (indices.len(), view.dim());
        let mut coords = Vec::with_capacity(n * dim);
        let mut ids = Vec::with_capacity(n);
        for i in indices {
            let start = coords.len();
            for j in 0..dim {
                coords.push(view.coord::<T>(i, j));
            }
            if let Some(j) = coords[start..].iter().position(|c| !c.is_finite()) {
                match policy {
                    NonFinitePolicy::Reject => {
                        return Err(NbhdError::NonFinite {
                            index: i,
                            coordinate: j,
                        })
                    }
                    NonFinitePolicy::Skip => coords.truncate(start),
                }
            } else {
                ids.push(i as u32);
            }
        }
        Ok(Self {
            coords,
            ids,
            dim,
            source_len: view.len(),
        })
    }

    /// Number of points held.
    pub fn len(&self) -> usize {
        self.ids.len()
    }

    /// Coordinates of the point in slot `slot`.
    #[inline]
    pub fn point(&self, slot: usize) -> &[T] {
        &self.coords[slot * self.dim..(slot + 1) * self.dim]
    }

    /// For every caller index, the slot holding it (`u32::MAX` for skipped points).
    pub fn slots_by_caller_index(&self) -> Vec<u32> {
        let mut slot_of = vec![u32::MAX; self.source_len];
        for (slot, &id) in self.ids.iter().enumerate() {
            slot_of[id as usize] = slot as u32;
        }
        slot_of
    }
}

/// The finite points of `points` as `policy` asks: `None` when every point is finite (use
/// `points` as they are), otherwise the original index of every finite point and the finite
/// points themselves. [`NonFinitePolicy::Reject`] names the first non-finite point
/// ([`NbhdError::NonFinite`]); an empty set, or one without finite points, is
/// [`NbhdError::EmptyInput`].
pub(crate) fn finite_subset(
    points: &[DVec3],
    policy: NonFinitePolicy,
) -> Result<Option<(Vec<usize>, Vec<DVec3>)>> {
    if points.is_empty() {
        return Err(NbhdError::EmptyInput);
    }
    if all_finite(points) {
        return Ok(None);
    }
    match policy {
        NonFinitePolicy::Reject => check_points(points).map(|_| None),
        NonFinitePolicy::Skip => {
            let index: Vec<usize> = (0..points.len())
                .filter(|&i| points[i].is_finite())
                .collect();
            if index.is_empty() {
                return Err(NbhdError::EmptyInput);
            }
            let finite = index.iter().map(|&i| points[i]).collect();
            Ok(Some((index, finite)))
        }
    }
}

/// Refuses an empty set ([`NbhdError::EmptyInput`]) and names the first point with a NaN or
/// infinite coordinate ([`NbhdError::NonFinite`]).
fn check_points(points: &[DVec3]) -> Result<()> {
    if points.is_empty() {
        return Err(NbhdError::EmptyInput);
    }
    match points.iter().enumerate().find_map(|(i, p)| {
        p.to_array()
            .iter()
            .position(|c| !c.is_finite())
            .map(|c| (i, c))
    }) {
        Some((index, coordinate)) => Err(NbhdError::NonFinite { index, coordinate }),
        None => Ok(()),
    }
}

/// Whether every coordinate of `points` is finite: a parallel scan (a million points are 24 MB
/// to read, and the scan precedes every smoothing and normal estimate).
fn all_finite(points: &[DVec3]) -> bool {
    points
        .par_iter()
        .with_min_len(1 << 14)
        .all(|p| p.is_finite())
}
