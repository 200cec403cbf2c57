//! The writers' shared code: the columns a cloud is written as, with their names, storage and
//! values in text or binary.

use super::cloud::PointCloud;
use super::value::{self, Ty};

/// A property or field name usable in a PLY or PCD header: whitespace replaced by `_`.
pub(crate) fn header_name(name: &str) -> String {
    let s: String = name
        .chars()
        .map(|c| if c.is_whitespace() { '_' } else { c })
        .collect();
    if s.is_empty() {
        "unnamed".into()
    } else {
        s
    }
}

/// How a writer lays out colours.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum ColorStyle {
    /// `red green blue` as 8-bit unsigned integers (PLY `uchar`, XYZ integers): what MeshLab,
    /// CloudCompare and PCL's PLY reader take as colour.
    Channels,
    /// One `rgb` field holding `0x00RRGGBB` in the bits of a 32-bit float (PCD `F 4`), as
    /// PCL's `PointXYZRGB` stores it.
    PackedFloat,
}

/// How a column is stored.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Store {
    /// `float` or `double` by the precision asked for.
    Float,
    /// 8-bit unsigned integer (colour channels).
    U8,
    /// A packed colour: the 32 bits of a PCD `F 4` field (text: the unsigned integer).
    RgbBits,
    /// An integer type the file read stored the field as (its values fit it).
    Int(Ty),
}

#[derive(Clone, Copy)]
enum Col<'a> {
    Pos(usize),
    Normal(usize),
    Scalar(&'a [f64]),
    Int(&'a [f64], Ty),
    Channel(usize),
    Rgb,
}

/// The columns a writer emits, with their names and storage.
pub(crate) struct Columns<'a> {
    cloud: &'a PointCloud,
    names: Vec<String>,
    cols: Vec<Col<'a>>,
    colors: Vec<[u8; 3]>,
    packed: Vec<u32>,
}

impl<'a> Columns<'a> {
    /// `x y z`, the normals under `normal_names`, the colour (if the cloud has one, in
    /// `style`), then the other scalar fields in order: in the integer type the file read
    /// stored them as ([`Metadata::field_types`](super::Metadata::field_types)) while their
    /// values fit it and it is at most `max_int` bytes, else as floats.
    pub fn new(
        cloud: &'a PointCloud,
        normal_names: [&str; 3],
        style: ColorStyle,
        max_int: usize,
    ) -> Self {
        let mut c = Columns {
            cloud,
            names: Vec::new(),
            cols: Vec::new(),
            colors: Vec::new(),
            packed: Vec::new(),
        };
        for (j, n) in ["x", "y", "z"].iter().enumerate() {
            c.push(n, Col::Pos(j));
        }
        if cloud.normals.is_some() {
            for (j, n) in normal_names.iter().enumerate() {
                c.push(n, Col::Normal(j));
            }
        }
        let colors = cloud.colors();
        if let Some(colors) = colors.clone() {
            match style {
                ColorStyle::Channels => {
                    for (k, n) in ["red", "green", "blue"].iter().enumerate() {
                        c.push(n, Col::Channel(k));
                    }
                    c.colors = colors;
                }
                ColorStyle::PackedFloat => {
                    // A packed field read from a file keeps its 32 bits (alpha included);
                    // channels are packed as 0x00RRGGBB.
                    c.packed = match cloud.packed_color_field() {
                        Some(v) => v.iter().map(|&x| x as u32).collect(),
                        None => colors
                            .iter()
                            .map(|[r, g, b]| (*r as u32) << 16 | (*g as u32) << 8 | *b as u32)
                            .collect(),
                    };
                    c.push("rgb", Col::Rgb);
                }
            }
        }
        for s in &cloud.scalars {
            if colors.is_some() && is_color_name(&s.name) {
                continue;
            }
            let int = cloud
                .metadata
                .field_type(&s.name)
                .filter(|t| t.size() <= max_int && t.holds_all(&s.values));
            let col = match int {
                Some(t) => Col::Int(&s.values, t),
                None => Col::Scalar(&s.values),
            };
            c.push(&header_name(&s.name), col);
        }
        c
    }

    fn push(&mut self, name: &str, col: Col<'a>) {
        self.names.push(name.to_string());
        self.cols.push(col);
    }

    /// Column names, in order.
    pub fn names(&self) -> &[String] {
        &self.names
    }

    /// Number of columns.
    pub fn len(&self) -> usize {
        self.cols.len()
    }

    /// How column `c` is stored.
    pub fn store(&self, c: usize) -> Store {
        match self.cols[c] {
            Col::Channel(_) => Store::U8,
            Col::Rgb => Store::RgbBits,
            Col::Int(_, t) => Store::Int(t),
            _ => Store::Float,
        }
    }

    /// The value of column `c` at point `i`.
    pub fn get(&self, c: usize, i: usize) -> f64 {
        match self.cols[c] {
            Col::Pos(j) => self.cloud.positions[i][j],
            Col::Normal(j) => self.cloud.normals.as_ref().map_or(0.0, |n| n[i][j]),
            Col::Scalar(v) | Col::Int(v, _) => v[i],
            Col::Channel(k) => self.colors[i][k] as f64,
            Col::Rgb => self.packed[i] as f64,
        }
    }

    /// Column `c` of point `i` as text: floats as the shortest form that reads back exactly
    /// at the precision, colours as unsigned integers (PCL writes `rgb` so in ascii PCD).
    pub fn text(&self, c: usize, i: usize, single: bool) -> String {
        match self.cols[c] {
            Col::Channel(k) => self.colors[i][k].to_string(),
            Col::Rgb => self.packed[i].to_string(),
            Col::Int(v, _) => format!("{}", v[i] as i64),
            _ => value::fmt_num(self.get(c, i), single),
        }
    }

    /// Appends column `c` of point `i` in binary.
    pub fn put(&self, buf: &mut Vec<u8>, c: usize, i: usize, single: bool, big_endian: bool) {
        let (v, ty) = match self.cols[c] {
            Col::Channel(k) => (f64::from(self.colors[i][k]), Ty::U8),
            Col::Rgb => (f64::from(self.packed[i]), Ty::U32),
            Col::Int(v, t) => (v[i], t),
            _ if single => (self.get(c, i), Ty::F32),
            _ => (self.get(c, i), Ty::F64),
        };
        ty.put(v, buf, big_endian);
    }

    /// One text line of point `i`, columns separated by a space.
    pub fn line(&self, out: &mut String, i: usize, single: bool) {
        out.clear();
        for c in 0..self.len() {
            if c > 0 {
                out.push(' ');
            }
            out.push_str(&self.text(c, i, single));
        }
        out.push('\n');
    }
}

/// Scalar fields that hold a colour: a packed `rgb`/`rgba`, or `red`/`green`/`blue`.
fn is_color_name(name: &str) -> bool {
    matches!(name, "rgb" | "rgba" | "red" | "green" | "blue")
}
