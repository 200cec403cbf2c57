//! The bodies of the C ABI fuzz targets (`abi_build_query`, `abi_tables`, `abi_smoothing`),
//! shared by the cargo-fuzz targets in fuzz/fuzz_targets/ and by tests/abi_fuzz.rs, which
//! replays the seeds and saved crashes on the stable toolchain (both include this file by
//! path).
//!
//! Each body reads its arguments from arbitrary bytes as a hostile C caller would pass them:
//! small point sets with NaN, infinite and huge coordinates, any stride, misaligned data,
//! option structs whose enum fields hold arbitrary integers (written through raw pointers, as
//! C may), absurd k, radii, indices and thread counts. It calls the exports of `nbhd::ffi` and
//! checks that each returns a status its documentation lists, that
//! `nbhd_last_error_message()` is a non-empty C string after every failure, and that results
//! are consistent (counts, ranges, order). Every buffer handed to the library really has the
//! size its description claims, except where the description's own byte size overflows, which
//! the library must refuse before reading.

use std::ffi::{c_int, c_void, CStr};
use std::mem::MaybeUninit;
use std::ptr::{addr_of_mut, null, null_mut};

use nbhd::ffi::*;

/// Arguments read from the fuzzer's bytes; past the end every read gives 0.
pub struct Input<'a>(&'a [u8]);

impl<'a> Input<'a> {
    /// Reads from `data`.
    pub fn new(data: &'a [u8]) -> Self {
        Input(data)
    }

    fn u8(&mut self) -> u8 {
        match self.0.split_first() {
            Some((&b, rest)) => {
                self.0 = rest;
                b
            }
            None => 0,
        }
    }

    fn u16(&mut self) -> u16 {
        u16::from_le_bytes([self.u8(), self.u8()])
    }

    fn u64(&mut self) -> u64 {
        let mut b = [0u8; 8];
        for x in &mut b {
            *x = self.u8();
        }
        u64::from_le_bytes(b)
    }

    fn bool(&mut self) -> bool {
        self.u8() & 1 == 1
    }

    /// A value in `0..n` (`n` at most 65536).
    fn below(&mut self, n: usize) -> usize {
        self.u16() as usize % n.max(1)
    }

    /// A count such as k or an index, near `n` or absurd.
    fn size(&mut self, n: usize) -> usize {
        match self.u8() % 16 {
            0 => 0,
            1 => 1,
            2 => 2,
            3 => n.saturating_sub(1),
            4 => n,
            5 => n + 1,
            6 => usize::MAX,
            7 => usize::MAX / 2 + 1,
            8 => 1 << 32,
            9 => u32::MAX as usize,
            _ => self.below(2 * n + 8),
        }
    }

    /// A real argument (radius, ε, τ, a threshold): ordinary, tiny, huge or not finite.
    fn real(&mut self) -> f64 {
        match self.u8() % 24 {
            0 => 0.0,
            1 => -0.0,
            2 => f64::NAN,
            3 => f64::INFINITY,
            4 => f64::NEG_INFINITY,
            5 => f64::MAX,
            6 => f64::MIN_POSITIVE,
            7 => 5e-324,
            8 => 1e300,
            9 => 1e-300,
            10 => 1e20,
            11 => 1.8e19,
            12 => -1.0,
            13 => f64::from_bits(self.u64()),
            _ => f64::from(self.u16()) / 256.0,
        }
    }

    /// The integer C stores in an enum field with `variants` values: mostly a valid one.
    fn raw_enum(&mut self, variants: c_int) -> c_int {
        match self.u8() % 10 {
            0 => self.u64() as c_int,
            1 => -1,
            2 => variants,
            _ => self.below(variants as usize) as c_int,
        }
    }

    /// A `threads` option: 0 or 1..4 mostly, sometimes above NBHD_MAX_THREADS (refused before
    /// any thread starts).
    fn threads(&mut self) -> usize {
        match self.u8() % 16 {
            0 => NBHD_MAX_THREADS + 1,
            1 => usize::MAX,
            n => usize::from(n % 5),
        }
    }

    /// One coordinate in `mode`: a coarse grid (duplicates), small reals, or anything.
    fn coord(&mut self, mode: u8) -> f64 {
        match mode % 4 {
            0 => f64::from(self.u8() % 8) / 2.0,
            1 => f64::from(self.u16() as i16) / 128.0,
            2 => match self.u8() % 8 {
                0 => self.real(),
                1 => f64::from_bits(self.u64()),
                _ => f64::from(self.u16() as i16) / 128.0,
            },
            _ => f64::from(self.u16() as i16) * 1e-30,
        }
    }
}

/// A point buffer and its `nbhd_points` description (the scalar type written as a raw `int`).
pub struct Points {
    buf: Vec<u8>,
    offset: usize,
    desc: MaybeUninit<nbhd_points>,
    /// The number of points described.
    pub count: usize,
    /// Their dimension.
    pub dim: usize,
    /// Whether the description's scalar type is F64 (else F32 or out of range).
    pub f64: bool,
}

impl Points {
    /// The description to pass to the library (it points into `self.buf`).
    pub fn desc(&mut self) -> *const nbhd_points {
        let data = self.buf.as_ptr().wrapping_add(self.offset).cast::<c_void>();
        let p = self.desc.as_mut_ptr();
        // SAFETY: `p` points to the live, aligned `desc`; its data field is a plain pointer.
        unsafe { addr_of_mut!((*p).data).write(data) };
        p
    }

    /// A point set of at most `max_count` points of dimension `dims` (or a hostile one).
    pub fn arbitrary(inp: &mut Input, max_count: usize, dims: &[usize]) -> Points {
        let count = inp.below(max_count + 1);
        let dim = match inp.u8() % 32 {
            0 => 0,
            1 => usize::MAX,
            2 => usize::MAX / 4 + 1,
            _ => dims[inp.below(dims.len())],
        };
        let raw_scalar = inp.raw_enum(2);
        let f64 = raw_scalar == 1;
        let size = if f64 { 8 } else { 4 };
        // A description whose byte size overflows: the library must refuse it unread, so
        // only one point's bytes (or none) are allocated for it.
        let packed = dim.checked_mul(size);
        let (stride, hostile) = match inp.u8() % 12 {
            0 => (0, false),
            1 => (usize::MAX, true),
            2 => (usize::MAX / 2 + 1, true),
            3 => (packed.unwrap_or(1).saturating_sub(1), false),
            _ => (packed.unwrap_or(0) + inp.below(17), false),
        };
        let mode = inp.u8();
        let offset = inp.below(8);
        let (len, real_stride) = match packed {
            Some(p) if p <= 64 => {
                let s = if stride == 0 { p } else { stride.max(p) };
                if hostile {
                    (p, s)
                } else {
                    (count.saturating_sub(1) * s + p, s)
                }
            }
            _ => (0, 0),
        };
        let mut buf = vec![0u8; offset + len];
        if packed.is_some_and(|p| p <= 64) && !(hostile && count > 1) {
            for i in 0..count {
                for c in 0..dim {
                    let at = offset + i * real_stride + c * size;
                    let v = inp.coord(mode);
                    if f64 {
                        buf[at..at + 8].copy_from_slice(&v.to_ne_bytes());
                    } else {
                        buf[at..at + 4].copy_from_slice(&(v as f32).to_ne_bytes());
                    }
                }
            }
        }
        let mut desc = MaybeUninit::<nbhd_points>::zeroed();
        let p = desc.as_mut_ptr();
        // SAFETY: `p` points to the live, aligned `desc`; each field is written through a raw
        // place, the enum as the `int` C may store (never read as a Rust enum here).
        unsafe {
            addr_of_mut!((*p).count).write(count);
            addr_of_mut!((*p).dim).write(dim);
            addr_of_mut!((*p).stride).write(stride);
            addr_of_mut!((*p).scalar_type)
                .cast::<c_int>()
                .write(raw_scalar);
        }
        Points {
            buf,
            offset,
            desc,
            count,
            dim,
            f64,
        }
    }

    /// The bytes of the buffer, from the first point.
    pub fn bytes(&self) -> usize {
        self.buf.len() - self.offset
    }
}

use nbhd_status as S;

/// Statuses every export may return on a hostile pointer or enum.
const COMMON: [nbhd_status; 3] = [S::NullPointer, S::MisalignedPointer, S::InvalidArgument];

/// The statuses of a points description (nbhd_tree_build's documented list; no point is a
/// valid description).
const POINTS: [nbhd_status; 5] = [
    S::ZeroDimension,
    S::StrideTooSmall,
    S::TooManyPoints,
    S::NonFinite,
    S::InvalidArgument,
];

/// Checks `status` of `func`: a value of nbhd_status, one of `allowed` (or OK, or the common
/// pointer statuses), never INTERNAL; after a failure the last error message is a non-empty C
/// string naming the function.
pub fn check(func: &str, status: nbhd_status, allowed: &[nbhd_status]) {
    let raw = status as c_int;
    assert!(
        (0..=S::OutOfMemory as c_int).contains(&raw),
        "{func}: status {raw} is no value of nbhd_status"
    );
    // SAFETY: nbhd_last_error_message returns a valid NUL-terminated string that lives until
    // the next nbhd call on this thread; it is copied at once.
    let message = unsafe { CStr::from_ptr(nbhd_last_error_message()) }
        .to_str()
        .expect("the message is UTF-8")
        .to_owned();
    if status == S::Ok {
        assert!(message.is_empty(), "{func}: OK with message {message:?}");
        return;
    }
    assert_ne!(status, S::Internal, "{func}: {message}");
    assert!(
        allowed.contains(&status) || COMMON.contains(&status),
        "{func}: undocumented status {status:?}: {message}"
    );
    assert!(
        message.starts_with(func) && message.len() > func.len() + 2,
        "{func}: status {status:?} with message {message:?}"
    );
}

/// Builds a tree (the build options arbitrary, written through raw pointers as C may) and
/// checks the build's status; the tree, or NULL.
fn build(inp: &mut Input, points: &mut Points) -> *mut nbhd_tree {
    let mut opts = MaybeUninit::new(nbhd_build_options_default());
    let o = opts.as_mut_ptr();
    let with_options = inp.u8() % 8 != 0;
    // SAFETY: `o` points to the live, aligned `opts`; the enum fields receive the raw `int`s C
    // may store, and `opts` is only read again by the library, field by field.
    unsafe {
        addr_of_mut!((*o).pivot)
            .cast::<c_int>()
            .write(inp.raw_enum(4));
        addr_of_mut!((*o).median)
            .cast::<c_int>()
            .write(inp.raw_enum(5));
        addr_of_mut!((*o).non_finite)
            .cast::<c_int>()
            .write(inp.raw_enum(2));
        let leaf = match inp.u8() % 8 {
            0 => inp.size(16),
            n => usize::from(n) * 3,
        };
        addr_of_mut!((*o).leaf_size).write(leaf);
        addr_of_mut!((*o).threads).write(inp.threads());
    }
    let mut tree = null_mut();
    let opts_ptr = if with_options { opts.as_ptr() } else { null() };
    let mut allowed = POINTS.to_vec();
    allowed.extend([S::InvalidOption, S::ThreadPool]);
    if inp.u8() % 4 == 0 {
        // Over an index subset: small indices (mostly in range, duplicates possible) and
        // now and then a large one.
        let n = inp.below(48);
        let ids: Vec<u32> = (0..n)
            .map(|_| match inp.u8() % 16 {
                0 => u32::MAX - u32::from(inp.u8()),
                _ => u32::from(inp.u8() % 64),
            })
            .collect();
        // SAFETY: as for nbhd_tree_build below; `ids` holds `ids.len()` readable values.
        let status = unsafe {
            nbhd_tree_build_indices(points.desc(), ids.as_ptr(), ids.len(), opts_ptr, &mut tree)
        };
        allowed.push(S::IndexOutOfRange);
        check("nbhd_tree_build_indices", status, &allowed);
        assert_eq!(status == S::Ok, !tree.is_null());
        return tree;
    }
    // SAFETY: the description is true (or overflows and must be refused unread); `opts_ptr`
    // is NULL or a live options struct; `tree` is writable.
    let status = unsafe { nbhd_tree_build(points.desc(), opts_ptr, &mut tree) };
    check("nbhd_tree_build", status, &allowed);
    assert_eq!(status == S::Ok, !tree.is_null());
    tree
}

/// The stats of a built tree.
fn stats(tree: *const nbhd_tree) -> nbhd_stats {
    let mut s = nbhd_stats::default();
    // SAFETY: `tree` is a live tree; `s` is writable.
    let status = unsafe { nbhd_tree_stats(tree, &mut s) };
    check("nbhd_tree_stats", status, &[]);
    assert_eq!(status, S::Ok);
    s
}

/// Checks one query's results: indices in range, ordered by (squared distance, index) (when
/// the distances were asked for).
fn check_results(idx: &[u32], d: Option<&[f64]>, source_points: usize) {
    for &j in idx {
        assert!((j as usize) < source_points, "index {j} of {source_points}");
    }
    let Some(d) = d else {
        return;
    };
    for (i, &j) in idx.iter().enumerate() {
        assert!(!d[i].is_nan() && d[i] >= 0.0, "sq_dist {}", d[i]);
        if i > 0 {
            assert!(
                (d[i - 1], idx[i - 1]) < (d[i], j),
                "results out of order at {i}: {:?}",
                (&idx[i - 1..=i], &d[i - 1..=i])
            );
        }
    }
}

/// `abi_build_query`: a build with arbitrary points and options, then single queries of every
/// kind with arbitrary k, radii, indices and buffer capacities.
pub fn build_query(data: &[u8]) {
    let mut inp = Input::new(data);
    let mut points = Points::arbitrary(&mut inp, 300, &[1, 2, 3, 4]);
    let tree = build(&mut inp, &mut points);
    if tree.is_null() {
        return;
    }
    let st = stats(tree);
    assert!(st.points <= points.count); // 0: no point given, or every one skipped
    assert_eq!(st.source_points, points.count);
    assert_eq!(st.dim, points.dim);
    let tree_f64 = st.scalar_type == nbhd_scalar_type::F64;
    assert_eq!(tree_f64, points.f64);
    let n = st.points;
    for _ in 0..1 + inp.below(8) {
        let op = inp.u8() % 6;
        let k = inp.size(n);
        let radius = inp.real();
        let index = inp.size(st.source_points);
        let exclude_self = inp.bool();
        let capacity = match inp.u8() % 4 {
            0 => 0,
            1 => k.min(600),
            _ => inp.below(2 * n + 2),
        };
        let query: Vec<f64> = (0..st.dim).map(|_| inp.coord(inp_mode(op))).collect();
        let query32: Vec<f32> = query.iter().map(|&v| v as f32).collect();
        let q: *const c_void = if tree_f64 {
            query.as_ptr().cast()
        } else {
            query32.as_ptr().cast()
        };
        let null_indices = capacity == 0 && inp.bool();
        let with_dists = inp.u8() % 4 != 0;
        let mut idx = vec![u32::MAX; capacity];
        let mut d64 = vec![f64::NAN; capacity];
        let mut d32 = vec![f32::NAN; capacity];
        let ip = if null_indices {
            null_mut()
        } else {
            idx.as_mut_ptr()
        };
        let dp: *mut c_void = match (with_dists, tree_f64) {
            (false, _) => null_mut(),
            (true, true) => d64.as_mut_ptr().cast(),
            (true, false) => d32.as_mut_ptr().cast(),
        };
        let mut count = usize::MAX;
        let (func, allowed): (&str, &[nbhd_status]) = match op {
            0 => (
                "nbhd_tree_knn",
                &[S::NonFiniteQuery, S::InvalidK, S::BufferTooSmall],
            ),
            1 => (
                "nbhd_tree_radius",
                &[S::NonFiniteQuery, S::InvalidRadius, S::BufferTooSmall],
            ),
            2 => (
                "nbhd_tree_knn_radius",
                &[
                    S::NonFiniteQuery,
                    S::InvalidK,
                    S::InvalidRadius,
                    S::BufferTooSmall,
                ],
            ),
            3 => (
                "nbhd_tree_knn_index",
                &[
                    S::InvalidK,
                    S::BufferTooSmall,
                    S::IndexOutOfRange,
                    S::SkippedPoint,
                ],
            ),
            4 => (
                "nbhd_tree_radius_index",
                &[
                    S::InvalidRadius,
                    S::BufferTooSmall,
                    S::IndexOutOfRange,
                    S::SkippedPoint,
                ],
            ),
            _ => (
                "nbhd_tree_knn_radius_index",
                &[
                    S::InvalidK,
                    S::InvalidRadius,
                    S::BufferTooSmall,
                    S::IndexOutOfRange,
                    S::SkippedPoint,
                ],
            ),
        };
        // SAFETY: `tree` is live; `q` holds `dim` values of the tree's scalar type, aligned;
        // `ip` and `dp` are NULL or writable for `capacity` values of their types; `count`
        // is writable.
        let status = unsafe {
            match op {
                0 => nbhd_tree_knn(tree, q, k, ip, dp, capacity, &mut count),
                1 => nbhd_tree_radius(tree, q, radius, ip, dp, capacity, &mut count),
                2 => nbhd_tree_knn_radius(tree, q, k, radius, ip, dp, capacity, &mut count),
                3 => {
                    nbhd_tree_knn_index(tree, index, exclude_self, k, ip, dp, capacity, &mut count)
                }
                4 => nbhd_tree_radius_index(
                    tree,
                    index,
                    exclude_self,
                    radius,
                    ip,
                    dp,
                    capacity,
                    &mut count,
                ),
                _ => nbhd_tree_knn_radius_index(
                    tree,
                    index,
                    exclude_self,
                    k,
                    radius,
                    ip,
                    dp,
                    capacity,
                    &mut count,
                ),
            }
        };
        check(func, status, allowed);
        match status {
            S::Ok => {
                assert!(
                    count <= capacity,
                    "{func}: count {count} > capacity {capacity}"
                );
                let d: Vec<f64> = if tree_f64 {
                    d64[..count].to_vec()
                } else {
                    d32[..count].iter().map(|&v| f64::from(v)).collect()
                };
                let d = with_dists.then_some(&d[..]);
                check_results(&idx[..count], d, st.source_points);
                if op == 0 {
                    assert_eq!(count, k.min(n), "{func}: k {k}, {n} points");
                }
                if op == 3 {
                    let others = if exclude_self { n - 1 } else { n };
                    assert_eq!(count, k.min(others), "{func}: k {k}, {n} points");
                }
                if op >= 3 && exclude_self {
                    assert!(!idx[..count].contains(&(index as u32)), "{func}: self");
                }
            }
            S::BufferTooSmall => assert!(count > capacity, "{func}: {count} <= {capacity}"),
            _ => assert_eq!(count, 0, "{func}: count after an error"),
        }
    }
    // (after the queries above, so that the inputs found before keep their paths)
    search_with_options(&mut inp, tree, &st);
    // SAFETY: `tree` came from nbhd_tree_build and is freed once.
    unsafe { nbhd_tree_free(tree) };
}

/// nbhd_tree_search with arbitrary query options (metric enum values out of range, any p and
/// eps, strict) and neighbourhood specs: a documented status, or ordered results of the
/// tree's points.
fn search_with_options(inp: &mut Input, tree: *mut nbhd_tree, st: &nbhd_stats) {
    let tree_f64 = st.scalar_type == nbhd_scalar_type::F64;
    for _ in 0..inp.below(4) {
        let mode = inp.u8();
        let query: Vec<f64> = (0..st.dim).map(|_| inp.coord(mode)).collect();
        let query32: Vec<f32> = query.iter().map(|&v| v as f32).collect();
        let q: *const c_void = if tree_f64 {
            query.as_ptr().cast()
        } else {
            query32.as_ptr().cast()
        };
        let mut spec = MaybeUninit::new(nbhd_neighborhood_spec {
            kind: nbhd_neighborhood_kind::Knn,
            k: inp.size(st.points),
            radius: inp.real(),
        });
        let mut o = MaybeUninit::new(nbhd_query_options_default());
        let (sp, op) = (spec.as_mut_ptr(), o.as_mut_ptr());
        // SAFETY: `sp` and `op` point to live, aligned structs; the enums receive any int and
        // the bool any byte C may store.
        unsafe {
            addr_of_mut!((*sp).kind)
                .cast::<c_int>()
                .write(inp.raw_enum(3));
            addr_of_mut!((*op).metric)
                .cast::<c_int>()
                .write(inp.raw_enum(4));
            addr_of_mut!((*op).p).write(inp.real());
            addr_of_mut!((*op).eps).write(inp.real());
            addr_of_mut!((*op).strict).cast::<u8>().write(inp.u8());
        }
        let capacity = inp.below(2 * st.points + 2);
        let mut idx = vec![u32::MAX; capacity];
        let mut d64 = vec![f64::NAN; capacity];
        let mut d32 = vec![f32::NAN; capacity];
        let dp: *mut c_void = if tree_f64 {
            d64.as_mut_ptr().cast()
        } else {
            d32.as_mut_ptr().cast()
        };
        let mut count = usize::MAX;
        // SAFETY: `tree` is live; `q` holds `dim` values of the tree's type; the structs are
        // live; the buffers are writable for `capacity` values; `count` is writable.
        let status = unsafe {
            nbhd_tree_search(
                tree,
                q,
                spec.as_ptr(),
                o.as_ptr(),
                idx.as_mut_ptr(),
                dp,
                capacity,
                &mut count,
            )
        };
        let allowed = [
            S::NonFiniteQuery,
            S::InvalidK,
            S::InvalidRadius,
            S::InvalidOption,
            S::InvalidArgument,
            S::BufferTooSmall,
        ];
        check("nbhd_tree_search", status, &allowed);
        match status {
            S::Ok => {
                assert!(count <= capacity, "nbhd_tree_search: {count} > {capacity}");
                let d: Vec<f64> = if tree_f64 {
                    d64[..count].to_vec()
                } else {
                    d32[..count].iter().map(|&v| f64::from(v)).collect()
                };
                check_results(&idx[..count], Some(&d), st.source_points);
            }
            S::BufferTooSmall => assert!(count > capacity),
            _ => assert_eq!(count, 0, "nbhd_tree_search: count after an error"),
        }
    }
}

/// The coordinate mode of query points: mostly ordinary, sometimes anything.
fn inp_mode(op: u8) -> u8 {
    if op % 3 == 0 {
        2
    } else {
        1
    }
}

/// Writes an arbitrary neighbourhood spec (its kind a raw `int`).
fn spec(inp: &mut Input, n: usize) -> MaybeUninit<nbhd_neighborhood_spec> {
    let mut s = MaybeUninit::<nbhd_neighborhood_spec>::zeroed();
    let p = s.as_mut_ptr();
    let radius = inp.real();
    // SAFETY: `p` points to the live, aligned `s`; the kind receives a raw `int` as C may
    // store it.
    unsafe {
        addr_of_mut!((*p).kind)
            .cast::<c_int>()
            .write(inp.raw_enum(3));
        addr_of_mut!((*p).k).write(inp.size(n));
        addr_of_mut!((*p).radius).write(radius);
    }
    s
}

/// Writes arbitrary table options (the bool a raw byte).
fn table_options(inp: &mut Input) -> MaybeUninit<nbhd_table_options> {
    let mut o = MaybeUninit::new(nbhd_table_options_default());
    let p = o.as_mut_ptr();
    // SAFETY: `p` points to the live, aligned `o`; the bool receives any byte C may store.
    unsafe {
        addr_of_mut!((*p).exclude_self).cast::<u8>().write(inp.u8());
        addr_of_mut!((*p).threads).write(inp.threads());
    }
    o
}

/// Checks a table made by the library and frees it.
fn check_table(table: *mut nbhd_neighborhoods, rows: usize, source_points: usize, f64: bool) {
    // SAFETY: `table` is a live table until freed at the end; its arrays hold `rows + 1`
    // offsets and `total` indices and squared distances of the tree's type, as documented.
    unsafe {
        assert_eq!(nbhd_neighborhoods_rows(table), rows);
        let total = nbhd_neighborhoods_total(table);
        let offsets = std::slice::from_raw_parts(nbhd_neighborhoods_offsets(table), rows + 1);
        assert_eq!(offsets[0], 0);
        assert_eq!(offsets[rows], total);
        let idx = if total == 0 {
            &[][..]
        } else {
            std::slice::from_raw_parts(nbhd_neighborhoods_indices(table), total)
        };
        let d: Vec<f64> = if total == 0 {
            Vec::new()
        } else if f64 {
            std::slice::from_raw_parts(nbhd_neighborhoods_sq_dists(table).cast::<f64>(), total)
                .to_vec()
        } else {
            std::slice::from_raw_parts(nbhd_neighborhoods_sq_dists(table).cast::<f32>(), total)
                .iter()
                .map(|&v| f64::from(v))
                .collect()
        };
        for r in 0..rows {
            assert!(offsets[r] <= offsets[r + 1], "offsets fall at row {r}");
            let (a, b) = (offsets[r], offsets[r + 1]);
            check_results(&idx[a..b], Some(&d[a..b]), source_points);
        }
        for row in [0, rows.saturating_sub(1), rows, usize::MAX] {
            let (mut ri, mut rd, mut len) = (null(), null(), usize::MAX);
            let status = nbhd_neighborhoods_row(table, row, &mut ri, &mut rd, &mut len);
            check("nbhd_neighborhoods_row", status, &[]);
            if row < rows {
                assert_eq!(status, S::Ok);
                assert_eq!(len, offsets[row + 1] - offsets[row]);
            } else {
                assert_eq!(status, S::InvalidArgument);
                assert_eq!(len, 0);
            }
        }
        nbhd_neighborhoods_free(table);
    }
}

/// Points enough that a k-nearest table of k = SIZE_MAX over them needs more than 1.2 TB:
/// the library must refuse it with OUT_OF_MEMORY before any search.
const BIG: usize = 400_000;

/// `abi_tables`: nbhd_tree_neighborhoods and nbhd_tree_neighborhoods_of with an arbitrary
/// spec and options over a small tree; and, for some inputs, a k-nearest table far too large
/// for any memory, which must be refused with OUT_OF_MEMORY.
pub fn tables(data: &[u8]) {
    let mut inp = Input::new(data);
    if inp.u8() == 0xB1 {
        return big_table(&mut inp);
    }
    let mut points = Points::arbitrary(&mut inp, 200, &[1, 2, 3, 4]);
    let tree = build(&mut inp, &mut points);
    if tree.is_null() {
        return;
    }
    let st = stats(tree);
    let tree_f64 = st.scalar_type == nbhd_scalar_type::F64;
    let table_allowed = [
        S::InvalidK,
        S::InvalidRadius,
        S::InvalidOption,
        S::OutOfMemory,
        S::ThreadPool,
    ];
    let mut of_allowed = table_allowed.to_vec();
    of_allowed.extend(POINTS);
    of_allowed.extend([S::DimensionMismatch, S::NonFiniteQuery]);
    for _ in 0..1 + inp.below(3) {
        let s = spec(&mut inp, st.points);
        let o = table_options(&mut inp);
        let opts = if inp.u8() % 4 == 0 {
            null()
        } else {
            o.as_ptr()
        };
        let mut table = null_mut();
        if inp.bool() {
            // SAFETY: `tree` is live; `s` and `opts` are live structs (or NULL); `table` is
            // writable.
            let status = unsafe { nbhd_tree_neighborhoods(tree, s.as_ptr(), opts, &mut table) };
            check("nbhd_tree_neighborhoods", status, &table_allowed);
            assert_eq!(status == S::Ok, !table.is_null());
            if status == S::Ok {
                check_table(table, st.source_points, st.source_points, tree_f64);
            }
        } else {
            let dims = [st.dim, st.dim, st.dim, st.dim + 1];
            let mut queries = Points::arbitrary(&mut inp, 64, &dims);
            // SAFETY: as above; the queries' description is true (or overflows and must be
            // refused unread).
            let status = unsafe {
                nbhd_tree_neighborhoods_of(tree, queries.desc(), s.as_ptr(), opts, &mut table)
            };
            check("nbhd_tree_neighborhoods_of", status, &of_allowed);
            assert_eq!(status == S::Ok, !table.is_null());
            if status == S::Ok {
                check_table(table, queries.count, st.source_points, tree_f64);
            }
        }
    }
    // SAFETY: `tree` came from nbhd_tree_build and is freed once.
    unsafe { nbhd_tree_free(tree) };
}

/// A k-nearest table over [`BIG`] points with k near SIZE_MAX: OUT_OF_MEMORY, at once.
fn big_table(inp: &mut Input) {
    let side = 100usize;
    let coords: Vec<f32> = (0..BIG)
        .flat_map(|i| {
            [
                (i % side) as f32,
                ((i / side) % side) as f32,
                (i / (side * side)) as f32,
            ]
        })
        .collect();
    let desc = nbhd_points {
        data: coords.as_ptr().cast(),
        count: BIG,
        dim: 3,
        stride: 0,
        scalar_type: nbhd_scalar_type::F32,
    };
    let mut opts = nbhd_build_options_default();
    opts.threads = 1;
    let mut tree = null_mut();
    // SAFETY: `desc` describes `coords`; `opts` and `tree` are live.
    let status = unsafe { nbhd_tree_build(&desc, &opts, &mut tree) };
    check("nbhd_tree_build", status, &[]);
    assert_eq!(status, S::Ok);
    let k = match inp.u8() % 4 {
        0 => usize::MAX,
        1 => BIG,
        2 => 1 << 40,
        _ => BIG - 1,
    };
    let s = nbhd_neighborhood_spec {
        kind: nbhd_neighborhood_kind::Knn,
        k,
        radius: 0.0,
    };
    let mut o = MaybeUninit::new(nbhd_table_options_default());
    let p = o.as_mut_ptr();
    // SAFETY: `p` points to the live, aligned `o`; the bool receives any byte C may store.
    unsafe {
        addr_of_mut!((*p).exclude_self).cast::<u8>().write(inp.u8());
        addr_of_mut!((*p).threads).write(usize::from(inp.u8() % 3));
    }
    let mut table = null_mut();
    let start = std::time::Instant::now();
    // SAFETY: `tree` is live; `s` and `o` are live structs; `table` is writable.
    let status = unsafe { nbhd_tree_neighborhoods(tree, &s, o.as_ptr(), &mut table) };
    check("nbhd_tree_neighborhoods", status, &[S::OutOfMemory]);
    assert_eq!(status, S::OutOfMemory);
    assert!(table.is_null());
    assert!(
        start.elapsed().as_secs() < 2,
        "refused after {:?}",
        start.elapsed()
    );
    // SAFETY: `tree` came from nbhd_tree_build and is freed once.
    unsafe { nbhd_tree_free(tree) };
}

/// A progress callback that stops the run once the counter behind `user_data` (if any)
/// reaches 0.
unsafe extern "C" fn progress(fraction: f64, _stage: nbhd_stage, user_data: *mut c_void) -> bool {
    assert!((0.0..=1.0).contains(&fraction), "progress {fraction}");
    if user_data.is_null() {
        return true;
    }
    // SAFETY: `user_data` is the `u32` counter the fuzz body passed, alive during the call,
    // and the callback is never called from two threads at once (documented).
    let left = unsafe { &mut *user_data.cast::<u32>() };
    if *left == 0 {
        return false;
    }
    *left -= 1;
    true
}

/// Statuses of the smoothing, curvature and normal exports.
const SMOOTHING: [nbhd_status; 13] = [
    S::ZeroDimension,
    S::EmptyInput,
    S::StrideTooSmall,
    S::TooManyPoints,
    S::NonFinite,
    S::InvalidK,
    S::InvalidOption,
    S::Degenerate,
    S::OutOfMemory,
    S::ThreadPool,
    S::Cancelled,
    S::InvalidArgument,
    S::NullPointer,
];

/// Writes the progress callback fields: none, one that always goes on, or one that stops
/// after `counter` calls.
fn progress_fields(inp: &mut Input, counter: &mut u32) -> (nbhd_progress_fn, *mut c_void) {
    match inp.u8() % 4 {
        0 => (Some(progress), null_mut()),
        1 => {
            *counter = u32::from(inp.u8() % 8);
            (Some(progress), (counter as *mut u32).cast())
        }
        _ => (None, null_mut()),
    }
}

/// `abi_smoothing`: nbhd_smooth, nbhd_smooth_robust, nbhd_estimate_curvatures and
/// nbhd_estimate_normals on arbitrary small point sets with arbitrary option structs (k,
/// steps and iterations capped small so one run stays fast).
pub fn smoothing(data: &[u8]) {
    let mut inp = Input::new(data);
    let mut points = Points::arbitrary(&mut inp, 48, &[3, 3, 3, 2]);
    let op = inp.u8() % 4;
    let k = match inp.u8() % 4 {
        0 => inp.size(points.count),
        _ => inp.below(33),
    };
    let epsilon = inp.real();
    let mut counter = 0u32;
    let (prog, user) = progress_fields(&mut inp, &mut counter);
    let with_options = inp.u8() % 8 != 0;
    let mut out = vec![0u8; points.bytes()];
    let mut geometry = vec![nbhd_point_geometry::default(); points.count];
    let geo = if inp.bool() {
        geometry.as_mut_ptr()
    } else {
        null_mut()
    };
    let mut summary = nbhd_smooth_summary::default();
    let out_coords: *mut c_void = out.as_mut_ptr().cast();
    let desc = points.desc();
    let (func, status) = match op {
        0 | 1 => {
            let mut o = MaybeUninit::new(nbhd_smooth_options_default());
            let p = o.as_mut_ptr();
            // SAFETY: `p` points to the live, aligned `o`; enum fields receive raw `int`s and
            // bools raw bytes, as C may store them; the callback and its counter outlive the
            // call.
            unsafe {
                addr_of_mut!((*p).k).write(k);
                addr_of_mut!((*p).epsilon).write(epsilon);
                addr_of_mut!((*p).epsilon_units)
                    .cast::<c_int>()
                    .write(inp.raw_enum(2));
                addr_of_mut!((*p).steps).write(inp.below(4));
                addr_of_mut!((*p).tau).write(inp.real());
                addr_of_mut!((*p).weighting)
                    .cast::<c_int>()
                    .write(inp.raw_enum(3));
                addr_of_mut!((*p).lambda).write(inp.real());
                addr_of_mut!((*p).lambda_units)
                    .cast::<c_int>()
                    .write(inp.raw_enum(2));
                addr_of_mut!((*p).feature)
                    .cast::<c_int>()
                    .write(inp.raw_enum(4));
                addr_of_mut!((*p).feature_threshold).write(inp.real());
                addr_of_mut!((*p).feature_units)
                    .cast::<c_int>()
                    .write(inp.raw_enum(2));
                addr_of_mut!((*p).constrain_interior)
                    .cast::<u8>()
                    .write(inp.u8());
                addr_of_mut!((*p).interior_threshold).write(inp.real());
                addr_of_mut!((*p).update_neighbors)
                    .cast::<u8>()
                    .write(inp.u8());
                addr_of_mut!((*p).orientation)
                    .cast::<c_int>()
                    .write(inp.raw_enum(4));
                addr_of_mut!((*p).orientation_point).write([inp.real(), inp.real(), inp.real()]);
                addr_of_mut!((*p).threads).write(inp.threads());
                addr_of_mut!((*p).progress).write(prog);
                addr_of_mut!((*p).progress_user_data).write(user);
                addr_of_mut!((*p).non_finite)
                    .cast::<c_int>()
                    .write(inp.raw_enum(2));
            }
            let opts = if with_options { o.as_ptr() } else { null() };
            if op == 0 {
                // SAFETY: the description is true (or must be refused unread); `out_coords`
                // has the input's layout; `geo` is NULL or holds `count` elements; `summary`
                // and `opts` are live.
                let s = unsafe { nbhd_smooth(desc, opts, out_coords, geo, &mut summary) };
                ("nbhd_smooth", s)
            } else {
                let geo = geometry.as_mut_ptr();
                // SAFETY: as above; `geo` holds `count` elements.
                let s = unsafe { nbhd_estimate_curvatures(desc, opts, geo, &mut summary) };
                ("nbhd_estimate_curvatures", s)
            }
        }
        2 => {
            let mut o = MaybeUninit::new(nbhd_robust_options_default());
            let p = o.as_mut_ptr();
            let k_plane = match inp.u8() % 4 {
                0 => inp.size(points.count),
                _ => k.saturating_add(inp.below(16)).min(64),
            };
            // SAFETY: as for the smooth options.
            unsafe {
                addr_of_mut!((*p).k).write(k);
                addr_of_mut!((*p).k_plane).write(k_plane);
                addr_of_mut!((*p).epsilon).write(epsilon);
                addr_of_mut!((*p).epsilon_units)
                    .cast::<c_int>()
                    .write(inp.raw_enum(2));
                addr_of_mut!((*p).max_iterations).write(inp.below(4));
                addr_of_mut!((*p).tolerance).write(inp.real());
                addr_of_mut!((*p).inlier_width).write(inp.real());
                addr_of_mut!((*p).feature_angle).write(inp.real());
                addr_of_mut!((*p).tau).write(inp.real());
                addr_of_mut!((*p).orientation)
                    .cast::<c_int>()
                    .write(inp.raw_enum(4));
                addr_of_mut!((*p).orientation_point).write([inp.real(), inp.real(), inp.real()]);
                addr_of_mut!((*p).threads).write(inp.threads());
                addr_of_mut!((*p).progress).write(prog);
                addr_of_mut!((*p).progress_user_data).write(user);
                addr_of_mut!((*p).non_finite)
                    .cast::<c_int>()
                    .write(inp.raw_enum(2));
                addr_of_mut!((*p).noise_scale).cast::<u8>().write(inp.u8());
            }
            let opts = if with_options { o.as_ptr() } else { null() };
            // SAFETY: as for nbhd_smooth.
            let s = unsafe { nbhd_smooth_robust(desc, opts, out_coords, geo, &mut summary) };
            ("nbhd_smooth_robust", s)
        }
        _ => {
            let mut o = MaybeUninit::new(nbhd_normal_options_default());
            let p = o.as_mut_ptr();
            // SAFETY: as for the smooth options.
            unsafe {
                addr_of_mut!((*p).k).write(k);
                addr_of_mut!((*p).epsilon).write(epsilon);
                addr_of_mut!((*p).epsilon_units)
                    .cast::<c_int>()
                    .write(inp.raw_enum(2));
                addr_of_mut!((*p).orientation)
                    .cast::<c_int>()
                    .write(inp.raw_enum(4));
                addr_of_mut!((*p).orientation_point).write([inp.real(), inp.real(), inp.real()]);
                addr_of_mut!((*p).non_finite)
                    .cast::<c_int>()
                    .write(inp.raw_enum(2));
                addr_of_mut!((*p).threads).write(inp.threads());
                addr_of_mut!((*p).progress).write(prog);
                addr_of_mut!((*p).progress_user_data).write(user);
            }
            // The output layout: strides of 0 (packed), exact, padded or too small.
            let raw_scalar = inp.raw_enum(2);
            let size = if raw_scalar == 1 { 8 } else { 4 };
            let stride = |inp: &mut Input, values: usize| match inp.u8() % 6 {
                0 => values * size - 1,
                1 => usize::MAX,
                2 => values * size,
                3 => values * size + inp.below(16),
                _ => 0,
            };
            let ns = stride(&mut inp, 3);
            let cs = stride(&mut inp, 1);
            // Enough bytes for every stride that does not overflow (those must be refused).
            let room = |s: usize, values: usize| {
                if s == usize::MAX {
                    values * 8 + 8
                } else {
                    points.count * s.max(values * 8) + 8
                }
            };
            let mut normals = vec![0f64; room(ns, 3) / 8 + 1];
            let mut curv = vec![0f64; room(cs, 1) / 8 + 1];
            let mut flags = vec![0u8; points.count];
            let with_curv = inp.bool();
            let with_flags = inp.bool();
            let mut out = MaybeUninit::<nbhd_normals_output>::zeroed();
            let q = out.as_mut_ptr();
            // SAFETY: `q` points to the live, aligned `out`; the scalar type receives a raw
            // `int` as C may store it; the buffers outlive the call.
            unsafe {
                addr_of_mut!((*q).normals).write(normals.as_mut_ptr().cast());
                addr_of_mut!((*q).normals_stride).write(ns);
                addr_of_mut!((*q).scalar_type)
                    .cast::<c_int>()
                    .write(raw_scalar);
                addr_of_mut!((*q).curvature).write(if with_curv {
                    curv.as_mut_ptr().cast()
                } else {
                    null_mut()
                });
                addr_of_mut!((*q).curvature_stride).write(cs);
                addr_of_mut!((*q).flags).write(if with_flags {
                    flags.as_mut_ptr()
                } else {
                    null_mut()
                });
            }
            let opts = if with_options { o.as_ptr() } else { null() };
            // SAFETY: the description is true (or must be refused unread); the output
            // buffers are writable for `count` points in every layout not refused (a stride
            // of SIZE_MAX overflows and must be refused); `opts` is live.
            let s = unsafe { nbhd_estimate_normals(desc, opts, out.as_ptr()) };
            ("nbhd_estimate_normals", s)
        }
    };
    check(func, status, &SMOOTHING);
    if status == S::Ok {
        assert!(points.count >= 1);
        if op != 3 {
            // ε may resolve to 0 (a relative ε of 1e-308 times a spacing of 1e-27) or to
            // infinity; the result is then that of a radius of 0 (duplicates) or of k alone.
            assert!(
                summary.spacing >= 0.0 && summary.epsilon >= 0.0,
                "{func}: OK with {summary:?}, epsilon {epsilon}, k {k}, {} points",
                points.count
            );
        }
    }
}
