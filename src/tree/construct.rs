//! The build driver: from the caller's points to a [`KdTree`]. It reads the points (all of
//! them, or the listed subset of [`KdTree::build_subset`]; straight into compact records for
//! dimensions 1 to 3, through a [`PackedPoints`] otherwise), runs the build the options ask for
//! (`build.rs`, `presorted.rs`) on the thread count asked for, and keeps the coordinates and
//! caller indices in tree order.

use rayon::prelude::*;

use super::build::{build_parallel, build_serial, BuildInput, Subtree};
use super::layout::{BySlot, Inline, Layout, Record};
use super::presorted;
use super::{BuildOptions, KdTree, MedianAlgorithm};
use crate::error::{NbhdError, Result};
use crate::packed::{NonFinitePolicy, PackedPoints};
use crate::parallel::with_threads;
use crate::points::PointsView;
use crate::scalar::{Scalar, ScalarType};
use std::borrow::Cow;
use std::sync::OnceLock;

/// Which points of a view a build reads: all of them, or a validated subset of caller indices
/// (in range, strictly increasing).
#[derive(Clone, Copy)]
enum Selection<'a> {
    All(usize),
    Subset(&'a [u32]),
}

impl Selection<'_> {
    fn len(&self) -> usize {
        match self {
            Selection::All(n) => *n,
            Selection::Subset(s) => s.len(),
        }
    }

    /// The caller's index of the `i`-th selected point.
    #[inline]
    fn at(&self, i: usize) -> usize {
        match self {
            Selection::All(_) => i,
            Selection::Subset(s) => s[i] as usize,
        }
    }
}

impl<T: Scalar> KdTree<T> {
    /// Builds a tree over the points of `view` (converted to `T`). A view of no point, or one
    /// whose every point is skipped, gives a tree of no point: every query finds nothing and
    /// every table row is empty.
    ///
    /// Errors: [`NbhdError::NonFinite`] naming the first point with a NaN or infinite
    /// coordinate (unless `options.non_finite` skips them), [`NbhdError::InvalidOption`] for a
    /// leaf size of 0,
    /// [`NbhdError::ThreadPool`] if a requested pool cannot be created.
    ///
    /// ```
    /// use nbhd::{BuildOptions, KdTree, PivotPolicy, PointsView};
    ///
    /// let rows = [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    /// let options = BuildOptions { pivot: PivotPolicy::CyclicMedian, ..BuildOptions::default() };
    /// let tree = KdTree::<f32>::build(&PointsView::from_rows(&rows)?, &options)?;
    /// assert_eq!((tree.len(), tree.stats().dim), (3, 3));
    /// # Ok::<(), nbhd::NbhdError>(())
    /// ```
    pub fn build(view: &PointsView<'_>, options: &BuildOptions) -> Result<Self> {
        options.validate()?;
        Self::build_selected(view, Selection::All(view.len()), options)
    }

    /// Builds a tree over the points `indices` of `view` only, as PCL's
    /// `setInputCloud(cloud, indices)`: the buffer is read in place (nothing but the listed
    /// points is copied), and every result names the caller's index in `view`, as
    /// [`Self::build`] does. The tree is the one [`Self::build`] makes of the listed points
    /// (identical for any order of `indices`).
    ///
    /// Queries by stored point ([`crate::query::Query::Stored`]) take the caller's index; an
    /// index of `view` that is not listed answers [`NbhdError::SkippedPoint`], as a skipped
    /// non-finite point does. All-point tables ([`crate::NeighborIndex::neighborhoods`]) have
    /// a row for every point of `view` (row `i` for caller index `i`): the listed points' rows
    /// are their neighbourhoods among the listed points, the other rows are empty.
    ///
    /// Errors: as [`Self::build`] (non-finite points among the listed ones are rejected or
    /// skipped as `options.non_finite` says; an empty list gives a tree of no point), plus
    /// [`NbhdError::IndexOutOfRange`] naming the first
    /// index `>= view.len()` and [`NbhdError::DuplicateIndex`] naming the smallest index
    /// listed twice.
    pub fn build_subset(
        view: &PointsView<'_>,
        indices: &[u32],
        options: &BuildOptions,
    ) -> Result<Self> {
        options.validate()?;
        let sorted = checked_subset(indices, view.len())?;
        Self::build_selected(view, Selection::Subset(&sorted), options)
    }

    fn build_selected(
        view: &PointsView<'_>,
        selection: Selection<'_>,
        options: &BuildOptions,
    ) -> Result<Self> {
        let dim = view.dim();
        let (subtree, coords, ids) = match dim {
            1 => build_inline::<T, 1>(view, selection, options)?,
            2 => build_inline::<T, 2>(view, selection, options)?,
            3 => build_inline::<T, 3>(view, selection, options)?,
            _ => {
                let packed = PackedPoints::<T>::from_view_at(
                    view,
                    (0..selection.len()).map(|i| selection.at(i)),
                    options.non_finite,
                )?;
                let n = packed.len();
                let layout = BySlot {
                    coords: &packed.coords,
                    dim,
                };
                let mut slots: Vec<u32> = (0..n as u32).collect();
                let subtree = run_build(layout, options, &mut slots)?;
                let coords = slots
                    .iter()
                    .flat_map(|&s| packed.point(s as usize).iter().copied())
                    .collect();
                let ids = slots.iter().map(|&s| packed.ids[s as usize]).collect();
                (subtree, coords, ids)
            }
        };
        let mut tree = Self {
            dim,
            coords,
            min_id: Vec::new(),
            descent: None,
            ids,
            nodes: subtree.nodes,
            depth: subtree.depth,
            source_len: view.len(),
            options: *options,
            position_of: OnceLock::new(),
            periodic: None,
        };
        tree.derive(options.threads)?;
        Ok(tree)
    }

    /// Builds from packed coordinates `[x0, y0, z0, x1, ...]` of dimension `dim`.
    pub fn from_flat(coords: &[T], dim: usize, options: &BuildOptions) -> Result<Self> {
        Self::build(&PointsView::from_flat(coords, dim)?, options)
    }
}

/// `indices` checked against a view of `count` points and made strictly increasing (borrowed
/// when they already are, the usual case).
fn checked_subset(indices: &[u32], count: usize) -> Result<Cow<'_, [u32]>> {
    if let Some(&bad) = indices.iter().find(|&&i| i as usize >= count) {
        return Err(NbhdError::IndexOutOfRange {
            index: bad as usize,
            count,
        });
    }
    if indices.windows(2).all(|w| w[0] < w[1]) {
        return Ok(Cow::Borrowed(indices));
    }
    let mut sorted = indices.to_vec();
    sorted.sort_unstable();
    if let Some(w) = sorted.windows(2).find(|w| w[0] == w[1]) {
        return Err(NbhdError::DuplicateIndex {
            index: w[0] as usize,
        });
    }
    Ok(Cow::Owned(sorted))
}

/// Builds with compact records of dimension `D`, read straight from the caller's buffer;
/// returns the nodes, the coordinates and the caller indices in tree order. A record's slot is
/// the caller's index itself: it orders ties exactly as the slots of a [`PackedPoints`] would
/// (both increase with the caller's index), and needs no map back.
fn build_inline<T: Scalar, const D: usize>(
    view: &PointsView<'_>,
    sel: Selection<'_>,
    options: &BuildOptions,
) -> Result<(Subtree<T>, Vec<T>, Vec<u32>)> {
    // Reading the points and copying the result out are a fifth of a fast build: on more than
    // one thread they would cap its speed-up, so for large clouds they run in parallel too.
    let parallel = options.threads != 1 && sel.len() >= PARALLEL_COPY_MIN;
    let work = || {
        let policy = options.non_finite;
        let mut records = match (view.scalar_type(), parallel) {
            (ScalarType::F32, false) => read_records::<T, f32, D>(view, sel, policy)?,
            (ScalarType::F64, false) => read_records::<T, f64, D>(view, sel, policy)?,
            (ScalarType::F32, true) => read_records_parallel::<T, f32, D>(view, sel, policy)?,
            (ScalarType::F64, true) => read_records_parallel::<T, f64, D>(view, sel, policy)?,
        };
        let subtree = run_build(Inline::<D>, options, &mut records)?;
        let mut coords = vec![T::ZERO; records.len() * D];
        let mut ids = Vec::new();
        if parallel {
            coords
                .par_chunks_mut(D)
                .zip(records.par_iter())
                .with_min_len(4096)
                .for_each(|(c, r)| c.copy_from_slice(&r.p));
            records
                .par_iter()
                .with_min_len(4096)
                .map(|r| r.slot)
                .collect_into_vec(&mut ids);
        } else {
            for (c, r) in coords.chunks_exact_mut(D).zip(&records) {
                c.copy_from_slice(&r.p);
            }
            ids.extend(records.iter().map(|r| r.slot));
        }
        Ok((subtree, coords, ids))
    };
    if parallel {
        with_threads(options.threads, work)?
    } else {
        work()
    }
}

/// Points from which a build on more than one thread reads and writes its copies in parallel.
const PARALLEL_COPY_MIN: usize = 256 * 1024;

/// [`read_records`] on the current rayon pool: every selected point converted in parallel, in order;
/// if any is not finite, the serial reader decides (the error names the first such point, or
/// the skipped points are left out).
fn read_records_parallel<T: Scalar, S: Scalar, const D: usize>(
    view: &PointsView<'_>,
    sel: Selection<'_>,
    policy: NonFinitePolicy,
) -> Result<Vec<Record<T, D>>> {
    let mut records = Vec::new();
    (0..sel.len())
        .into_par_iter()
        .with_min_len(4096)
        .map(|i| {
            let i = sel.at(i);
            Record {
                p: view.row::<S, D>(i).map(|c| T::from_f64(c.to_f64())),
                slot: i as u32,
            }
        })
        .collect_into_vec(&mut records);
    if records
        .par_iter()
        .any(|r| r.p.iter().any(|c| !c.is_finite()))
    {
        return read_records::<T, S, D>(view, sel, policy);
    }
    Ok(records)
}

/// The finite selected points of `view` (stored as `S`) as records of `T` coordinates, applying
/// `policy` to the others (a value finite in `S` that overflows `T` counts as non-finite, as
/// in [`PackedPoints::from_view`]).
fn read_records<T: Scalar, S: Scalar, const D: usize>(
    view: &PointsView<'_>,
    sel: Selection<'_>,
    policy: NonFinitePolicy,
) -> Result<Vec<Record<T, D>>> {
    let n = sel.len();
    let mut records = Vec::with_capacity(n);
    for i in (0..n).map(|i| sel.at(i)) {
        let p = view.row::<S, D>(i).map(|c| T::from_f64(c.to_f64()));
        if p.iter().all(|c| c.is_finite()) {
            records.push(Record { p, slot: i as u32 });
        } else if policy == NonFinitePolicy::Reject {
            let coordinate = p.iter().position(|c| !c.is_finite()).unwrap_or(0);
            return Err(NbhdError::NonFinite {
                index: i,
                coordinate,
            });
        }
    }
    Ok(records)
}

/// Runs the build the options ask for over `items` (given in slot order, left in tree order).
fn run_build<T: Scalar, L: Layout<T>>(
    layout: L,
    options: &BuildOptions,
    items: &mut [L::Item],
) -> Result<Subtree<T>> {
    let input = BuildInput {
        layout,
        options: *options,
        guard: super::max_unbalanced_depth(items.len()),
    };
    if options.median == MedianAlgorithm::Presorted {
        return Ok(presorted::build_presorted(&input, items));
    }
    match options.threads {
        1 => Ok(build_serial(&input, items, 0, 0)),
        t => with_threads(t, || build_parallel(&input, items, 0, 0)),
    }
}
