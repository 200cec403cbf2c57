//! numpy arrays in and out: an (n, d) array of float32 or float64 becomes a `PointsView` of its
//! own memory when its rows are laid out as the view describes (coordinates of a point adjacent,
//! points a positive stride apart: C-contiguous arrays, row slices `a[::2]`, column-prefix
//! slices `a[:, :3]` of wider records), and a packed copy otherwise (Fortran order, negative or
//! zero strides, transposes). Outputs are numpy arrays that take over the Rust vectors without
//! a copy.

use nbhd::{NbhdError, PointsView, Scalar};
use numpy::ndarray::{Array2, ArrayView2};
use numpy::{
    Element, IntoPyArray, PyArray1, PyArray2, PyArrayDyn, PyArrayMethods, PyReadonlyArray2,
};
use pyo3::prelude::*;

use crate::errors::value_err;

/// The two scalar types of the library, as numpy sees them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Dtype {
    F32,
    F64,
}

impl Dtype {
    pub fn numpy_name(self) -> &'static str {
        match self {
            Dtype::F32 => "float32",
            Dtype::F64 => "float64",
        }
    }
}

/// `obj` as a numpy array of float32 or float64: an array of either type as it is (no copy),
/// anything else (lists, integer, boolean or float16 arrays) converted by `numpy.asarray` to
/// `want` (float64 when `None`). With `want` given, an array of the other float type is
/// converted too. Complex, object, string and other non-numeric arrays raise NbhdValueError.
pub fn float_array<'py>(
    obj: &Bound<'py, PyAny>,
    want: Option<Dtype>,
) -> PyResult<(Bound<'py, PyAny>, Dtype)> {
    let is32 = obj.cast::<PyArrayDyn<f32>>().is_ok();
    let is64 = obj.cast::<PyArrayDyn<f64>>().is_ok();
    let have = if is32 {
        Some(Dtype::F32)
    } else if is64 {
        Some(Dtype::F64)
    } else {
        None
    };
    match (have, want) {
        (Some(h), None) => Ok((obj.clone(), h)),
        (Some(h), Some(w)) if h == w => Ok((obj.clone(), h)),
        (_, w) => {
            let w = w.unwrap_or(Dtype::F64);
            let np = obj.py().import("numpy")?;
            let given = np.call_method1("asarray", (obj,))?;
            refuse_non_real(&given)?;
            let arr = np.call_method1("asarray", (given, w.numpy_name()))?;
            Ok((arr, w))
        }
    }
}

/// Refuses arrays whose values are not real numbers: complex (converting drops the imaginary
/// part, which numpy only warns about), object (anything, converted one element at a time),
/// strings, bytes, records, dates and durations.
fn refuse_non_real(arr: &Bound<'_, PyAny>) -> PyResult<()> {
    let dtype = arr.getattr("dtype")?;
    let kind: String = dtype.getattr("kind")?.extract()?;
    if matches!(kind.as_str(), "b" | "i" | "u" | "f") {
        return Ok(());
    }
    let what = match kind.as_str() {
        "c" => "complex numbers (their imaginary part would be dropped)",
        "O" => "Python objects",
        "U" | "S" => "strings",
        "M" | "m" => "dates or durations",
        _ => "records or raw bytes",
    };
    Err(value_err(format!(
        "nbhd takes real numbers; got a {} array of {what}",
        dtype.str()?
    )))
}

/// The rank of a numpy array.
pub fn ndim(arr: &Bound<'_, PyAny>) -> PyResult<usize> {
    arr.getattr("ndim")?.extract()
}

/// Refuses `arr` unless it is 2-D: points as rows, (n, `d`) (`d` names the columns asked for).
pub fn check_rows(arr: &Bound<'_, PyAny>, d: &str) -> PyResult<()> {
    match ndim(arr)? {
        2 => Ok(()),
        n => Err(value_err(format!(
            "points must be a 2-D array (n, {d}), not {n}-D"
        ))),
    }
}

/// An (n, d) array made 2-D: a 1-D array of d values is one point (1, d).
pub fn as_rows<'py>(arr: &Bound<'py, PyAny>, what: &str) -> PyResult<(Bound<'py, PyAny>, bool)> {
    match ndim(arr)? {
        2 => Ok((arr.clone(), false)),
        1 => Ok((arr.call_method1("reshape", (1, -1))?, true)),
        n => Err(value_err(format!(
            "{what} must be a 1-D array (one point) or a 2-D array (n, d), not {n}-D"
        ))),
    }
}

/// Points of an (n, d) numpy array read in place where the layout allows, else a packed copy.
pub struct Points<'py, T: Element> {
    array: PyReadonlyArray2<'py, T>,
    packed: Option<Vec<T>>,
}

impl<'py, T: Element + Scalar> Points<'py, T> {
    /// Borrows the (n, d) array `arr` of `T` (read-only while the borrow lives).
    pub fn new(arr: &Bound<'py, PyAny>) -> PyResult<Self> {
        let array: PyReadonlyArray2<'py, T> = arr
            .cast::<PyArray2<T>>()
            .map_err(|e| value_err(format!("expected a 2-D float array: {e}")))?
            .try_readonly()
            .map_err(|e| value_err(format!("the array is being written elsewhere: {e}")))?;
        let packed =
            (!in_place(&array.as_array())).then(|| array.as_array().iter().copied().collect());
        Ok(Self { array, packed })
    }

    /// Whether the points are read in place (no copy).
    pub fn is_in_place(&self) -> bool {
        self.packed.is_none()
    }

    /// The points as the library's view: of the array's memory, or of the packed copy.
    pub fn view(&self) -> Result<PointsView<'_>, NbhdError> {
        let a = self.array.as_array();
        let (n, d) = a.dim();
        let size = std::mem::size_of::<T>();
        if let Some(p) = &self.packed {
            let bytes = as_bytes(p);
            return PointsView::new(bytes, n, d, d * size, T::TYPE);
        }
        if n == 0 || d == 0 {
            return PointsView::new(&[], n, d, d * size, T::TYPE);
        }
        let stride = if n == 1 {
            d * size
        } else {
            a.strides()[0] as usize * size
        };
        let len = (n - 1) * stride + d * size;
        // SAFETY: `in_place` checked that point i's d coordinates are the d consecutive `T`s at
        // element offset i * strides[0] from `a.as_ptr()` with strides[0] ≥ d (or n = 1), all
        // inside the array's memory, which the read-only borrow `self.array` keeps alive and
        // unchanged by Rust for the lifetime of the returned view; the last point ends at
        // byte (n - 1) * stride + d * size from the start. Bytes have no alignment needs.
        let bytes = unsafe { std::slice::from_raw_parts(a.as_ptr().cast::<u8>(), len) };
        PointsView::new(bytes, n, d, stride, T::TYPE)
    }
}

/// Whether `a` can be viewed in place: coordinates adjacent, rows a positive stride of at least
/// one point apart (non-overlapping).
fn in_place<T>(a: &ArrayView2<'_, T>) -> bool {
    let (n, d) = a.dim();
    let s = a.strides();
    if n == 0 || d == 0 {
        return true;
    }
    (d == 1 || s[1] == 1) && (n == 1 || s[0] >= d as isize)
}

fn as_bytes<T: Scalar>(v: &[T]) -> &[u8] {
    // SAFETY: `T` is f32 or f64 (the library's `Scalar`), plain data without padding; the slice
    // covers exactly the vector's initialised values and lives as long as `v`.
    unsafe { std::slice::from_raw_parts(v.as_ptr().cast::<u8>(), std::mem::size_of_val(v)) }
}

/// The points of an (n, 3) array (any float type) as `f64` triples: the input of the geometry
/// and the smoothing, which compute in `f64`.
pub fn dvec3s(obj: &Bound<'_, PyAny>) -> PyResult<Vec<glam::DVec3>> {
    let (arr, _) = float_array(obj, Some(Dtype::F64))?;
    check_rows(&arr, "3")?;
    let ro: PyReadonlyArray2<'_, f64> = arr
        .cast::<PyArray2<f64>>()
        .map_err(|e| value_err(e.to_string()))?
        .try_readonly()
        .map_err(|e| value_err(e.to_string()))?;
    let a = ro.as_array();
    let (n, d) = a.dim();
    if d != 3 {
        return Err(crate::errors::nbhd_err(NbhdError::DimensionMismatch {
            expected: 3,
            got: d,
        }));
    }
    Ok((0..n)
        .map(|i| glam::DVec3::new(a[[i, 0]], a[[i, 1]], a[[i, 2]]))
        .collect())
}

/// The flags of a 1-D array or sequence (anything numpy converts to `bool`), read as one
/// array rather than one Python object at a time.
pub fn bools(obj: &Bound<'_, PyAny>) -> PyResult<Vec<bool>> {
    vector_of(obj, "bool", "flags must be a 1-D array of booleans")
}

/// The values of a 1-D array or sequence converted by numpy to `dtype` (the element type
/// `T`), copied; `refusal` is the message when it is not one-dimensional.
pub fn vector_of<T: Element + Copy>(
    obj: &Bound<'_, PyAny>,
    dtype: &str,
    refusal: &str,
) -> PyResult<Vec<T>> {
    let np = obj.py().import("numpy")?;
    let arr = np.call_method1("ascontiguousarray", (obj, dtype))?;
    let ro: numpy::PyReadonlyArray1<'_, T> = arr.extract().map_err(|_| value_err(refusal))?;
    Ok(ro
        .as_slice()
        .map_err(|e| value_err(e.to_string()))?
        .to_vec())
}

/// A vector as a 1-D numpy array, without a copy.
pub fn vec1<'py, T: Element>(py: Python<'py>, v: Vec<T>) -> Bound<'py, PyArray1<T>> {
    v.into_pyarray(py)
}

/// `rows × cols` values, row after row, as a 2-D numpy array, without a copy.
pub fn vec2<'py, T: Element>(
    py: Python<'py>,
    v: Vec<T>,
    rows: usize,
    cols: usize,
) -> PyResult<Bound<'py, PyArray2<T>>> {
    Array2::from_shape_vec((rows, cols), v)
        .map(|a| a.into_pyarray(py))
        .map_err(|e| value_err(format!("internal shape error: {e}")))
}

/// f64 triples as an (n, 3) numpy array.
pub fn dvec3_array<'py>(py: Python<'py>, v: &[glam::DVec3]) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let flat: Vec<f64> = v.iter().flat_map(|p| p.to_array()).collect();
    vec2(py, flat, v.len(), 3)
}
