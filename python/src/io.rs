//! The point-cloud files of `nbhd::io` (PLY, PCD incl. binary_compressed, LAS/LAZ, OBJ read, XYZ):
//! `read` gives a dict of numpy arrays, `write` takes arrays. The file work runs with the GIL
//! released.

use nbhd::io::{self, Encoding, Format, PointCloud, Precision, ReadOptions, WriteOptions};
use numpy::{PyArray1, PyArray2, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::arrays::{float_array, vec1, vec2, Dtype};
use crate::errors::{value_err, OrRaise};

fn format(name: &str) -> PyResult<Format> {
    match name.to_ascii_lowercase().as_str() {
        "ply" => Ok(Format::Ply),
        "pcd" => Ok(Format::Pcd),
        "obj" => Ok(Format::Obj),
        "las" | "laz" => Ok(Format::Las),
        "xyz" | "txt" => Ok(Format::Xyz),
        _ => Err(value_err(format!(
            "unknown format {name:?}; expected ply, pcd, obj, las, laz or xyz"
        ))),
    }
}

fn encoding(name: &str) -> PyResult<Encoding> {
    match name.replace('_', "-").as_str() {
        "ascii" => Ok(Encoding::Ascii),
        "binary" => Ok(Encoding::Binary),
        "binary-big-endian" => Ok(Encoding::BinaryBigEndian),
        "binary-compressed" => Ok(Encoding::BinaryCompressed),
        _ => Err(value_err(format!(
            "unknown encoding {name:?}; expected ascii, binary, binary-big-endian or \
             binary-compressed"
        ))),
    }
}

fn precision(name: &str) -> PyResult<Precision> {
    match name {
        "single" => Ok(Precision::Single),
        "double" => Ok(Precision::Double),
        "keep" => Ok(Precision::Keep),
        _ => Err(value_err(format!(
            "unknown precision {name:?}; expected single, double or keep"
        ))),
    }
}

fn precision_name(p: Precision) -> &'static str {
    match p {
        Precision::Single => "single",
        Precision::Double => "double",
        Precision::Keep => "keep",
    }
}

/// (n, 3) triples as an (n, 3) float64 array.
fn triples<'py>(py: Python<'py>, v: Vec<[f64; 3]>) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let n = v.len();
    vec2(py, v.into_iter().flatten().collect(), n, 3)
}

/// An (n, 3) array of any float type as triples.
fn read_triples(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<[f64; 3]>> {
    let (arr, _) = float_array(obj, Some(Dtype::F64))?;
    let a: PyReadonlyArray2<'_, f64> = arr
        .cast::<PyArray2<f64>>()
        .map_err(|_| value_err(format!("{what} must be a 2-D array (n, 3)")))?
        .readonly();
    let v = a.as_array();
    if v.ncols() != 3 {
        return Err(value_err(format!(
            "{what} must have 3 columns, not {}",
            v.ncols()
        )));
    }
    Ok(v.rows().into_iter().map(|r| [r[0], r[1], r[2]]).collect())
}

/// Reads a point cloud: PLY, PCD (ascii, binary, binary_compressed), LAS/LAZ, OBJ (the `v`
/// lines) or XYZ text, recognised by content and extension unless `format` names it.
///
/// Returns a dict: `positions` (n, 3) float64 in file order (NaN holes of organized scans
/// kept), `normals` (n, 3) or None, `scalars` (dict of name → (n,) float64: `curvature`,
/// `intensity`, `rgb`, ...), `grid` (width, height) or None, `format` ("PLY", ...),
/// `source_precision` ("single", "double" or None), `text_columns` (names read for XYZ files)
/// or None. `columns` names the columns of a text file (e.g. "x y z nx ny nz").
#[pyfunction]
#[pyo3(signature = (path, *, format = None, columns = None))]
pub fn read<'py>(
    py: Python<'py>,
    path: std::path::PathBuf,
    format: Option<&str>,
    columns: Option<&str>,
) -> PyResult<Bound<'py, PyDict>> {
    let opts = ReadOptions {
        format: format.map(self::format).transpose()?,
        columns: columns.map(|c| c.split_whitespace().map(String::from).collect()),
    };
    let (cloud, info) = py.detach(|| io::read_with(&path, &opts)).or_raise()?;
    let d = PyDict::new(py);
    d.set_item("positions", triples(py, cloud.positions)?)?;
    match cloud.normals {
        Some(n) => d.set_item("normals", triples(py, n)?)?,
        None => d.set_item("normals", py.None())?,
    }
    let scalars = PyDict::new(py);
    for s in cloud.scalars {
        scalars.set_item(s.name, vec1(py, s.values))?;
    }
    d.set_item("scalars", scalars)?;
    d.set_item("grid", cloud.grid.map(|g| (g.width, g.height)))?;
    d.set_item("format", info.format.name())?;
    d.set_item(
        "source_precision",
        cloud.source_precision.map(precision_name),
    )?;
    d.set_item("text_columns", info.text_columns.map(|t| t.names))?;
    Ok(d)
}

/// Writes a point cloud: PLY, PCD, LAS/LAZ or XYZ, by `format` or the extension of `path`.
///
/// `positions` (n, 3); `normals` (n, 3) or None; `scalars` a dict of name → (n,) values
/// (`curvature`, `intensity`, colour as `red`/`green`/`blue` or PCL's `rgb`, ...).
/// `encoding`: "binary" (default for PLY and PCD), "ascii", "binary-big-endian" (PLY),
/// "binary-compressed" (PCD). `precision`: "single" (default: what PCL's loaders read),
/// "double", "keep". LAS stores LAS's own fields (`intensity`, `classification`, `gps_time`,
/// ...) in the records and normals (`NormalX NormalY NormalZ`) and other fields as extra bytes
/// (cli/README.md, "LAS and LAZ").
#[pyfunction]
#[pyo3(signature = (path, positions, *, normals = None, scalars = None, format = None,
                    encoding = None, precision = "single"))]
#[allow(clippy::too_many_arguments)]
pub fn write(
    py: Python<'_>,
    path: std::path::PathBuf,
    positions: &Bound<'_, PyAny>,
    normals: Option<&Bound<'_, PyAny>>,
    scalars: Option<&Bound<'_, PyDict>>,
    format: Option<&str>,
    encoding: Option<&str>,
    precision: &str,
) -> PyResult<()> {
    let mut cloud = PointCloud::from_positions(read_triples(positions, "positions")?);
    if let Some(n) = normals {
        cloud.set_normals(read_triples(n, "normals")?).or_raise()?;
    }
    if let Some(s) = scalars {
        for (name, values) in s.iter() {
            let name: String = name.extract()?;
            let (arr, _) = float_array(&values, Some(Dtype::F64))?;
            let a: PyReadonlyArray1<'_, f64> = arr
                .cast::<PyArray1<f64>>()
                .map_err(|_| value_err(format!("scalar {name:?} must be a 1-D array")))?
                .readonly();
            cloud.set_scalar(&name, a.as_array().to_vec()).or_raise()?;
        }
    }
    let opts = WriteOptions {
        format: format.map(self::format).transpose()?,
        encoding: encoding.map(self::encoding).transpose()?,
        precision: self::precision(precision)?,
    };
    py.detach(|| io::write(&path, &cloud, &opts)).or_raise()
}
