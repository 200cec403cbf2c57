//! The PCD header: its entries as written (each with its line, for errors), then checked
//! against one another and against the bytes that follow before any point is read.

use crate::io::error::{Fail, PResult};
use crate::io::value::{parse_num, tokens, Lines, Ty};
use crate::io::{Grid, Viewpoint};

/// How the points are stored after the header (`DATA`).
#[derive(Clone, Copy, PartialEq, Eq)]
pub(super) enum Data {
    Ascii,
    Binary,
    Compressed,
}

impl Data {
    fn parse(ln: usize, word: Option<&str>) -> PResult<Data> {
        match word.map(|s| s.to_ascii_lowercase()).as_deref() {
            Some("ascii") => Ok(Data::Ascii),
            Some("binary") => Ok(Data::Binary),
            Some("binary_compressed") => Ok(Data::Compressed),
            other => Err(Fail::line(
                ln,
                format!(
                    "DATA must be ascii, binary or binary_compressed, not '{}'",
                    other.unwrap_or("")
                ),
            )),
        }
    }
}

/// A field of the header: `COUNT` values of one type per point.
pub(super) struct Field {
    pub name: String,
    pub ty: Ty,
    pub count: usize,
}

/// The type of a field of `TYPE` `kind` (`F`, `I`, `U`) and `SIZE` `size`.
fn ty_of(kind: &str, size: usize) -> Option<Ty> {
    Some(match (kind, size) {
        ("F", 4) => Ty::F32,
        ("F", 8) => Ty::F64,
        ("I", 1) => Ty::I8,
        ("I", 2) => Ty::I16,
        ("I", 4) => Ty::I32,
        ("I", 8) => Ty::I64,
        ("U", 1) => Ty::U8,
        ("U", 2) => Ty::U16,
        ("U", 4) => Ty::U32,
        ("U", 8) => Ty::U64,
        _ => return None,
    })
}

/// A header entry as read, with the line it is on.
type Entry<T> = Option<(usize, T)>;

/// The header's entries as written, each with its line; nothing checked across entries yet.
#[derive(Default)]
struct Entries {
    names: Entry<Vec<String>>,
    sizes: Entry<Vec<usize>>,
    kinds: Entry<Vec<String>>,
    counts: Entry<Vec<usize>>,
    width: Entry<usize>,
    height: Entry<usize>,
    points: Entry<usize>,
    data: Entry<Data>,
    viewpoint: Option<Viewpoint>,
    /// `#` lines but PCL's first (`# .PCD v0.7 - Point Cloud Data file format`).
    comments: Vec<String>,
}

/// The numbers of an entry (`SIZE 4 4 4`), each a non-negative integer.
fn numbers(ln: usize, what: &str, rest: &[&str]) -> PResult<Vec<usize>> {
    rest.iter()
        .map(|s| {
            s.parse::<usize>()
                .map_err(|_| Fail::line(ln, format!("{what}: '{s}' is not a non-negative integer")))
        })
        .collect()
}

/// `VIEWPOINT tx ty tz qw qx qy qz`.
fn viewpoint(ln: usize, rest: &[&str]) -> PResult<Viewpoint> {
    let v: Vec<f64> = rest.iter().filter_map(|s| parse_num(s)).collect();
    if rest.len() != 7 || v.len() != 7 {
        return Err(Fail::line(
            ln,
            "VIEWPOINT takes 7 numbers: tx ty tz qw qx qy qz",
        ));
    }
    Ok(Viewpoint {
        origin: [v[0], v[1], v[2]],
        orientation: [v[3], v[4], v[5], v[6]],
    })
}

/// The one number of an entry (`WIDTH 640`).
fn one_number(ln: usize, what: &str, rest: &[&str]) -> PResult<usize> {
    let v = numbers(ln, what, rest)?;
    if v.len() != 1 {
        return Err(Fail::line(ln, format!("{what} takes one number")));
    }
    Ok(v[0])
}

impl Entries {
    /// Reads the header lines up to and including `DATA` (or to the end of the file).
    fn read(lines: &mut Lines<'_>) -> PResult<Entries> {
        let mut e = Entries::default();
        for item in lines.by_ref() {
            let (ln, line) = item?;
            let t = line.trim();
            if let Some(c) = t.strip_prefix('#') {
                let c = c.trim();
                if !c.starts_with(".PCD") {
                    e.comments.push(c.to_string());
                }
                continue;
            }
            if t.is_empty() {
                continue;
            }
            let mut tok = tokens(t);
            let key = tok.next().unwrap_or("").to_ascii_uppercase();
            let rest: Vec<&str> = tok.collect();
            e.take(ln, &key, &rest)?;
            if e.data.is_some() {
                break;
            }
        }
        Ok(e)
    }

    /// Takes the entry `key` with its values `rest`, on line `ln`.
    fn take(&mut self, ln: usize, key: &str, rest: &[&str]) -> PResult<()> {
        match key {
            "VERSION" => {}
            // PCL's default, the identity, is as good as none.
            "VIEWPOINT" => {
                self.viewpoint = Some(viewpoint(ln, rest)?).filter(|v| *v != Viewpoint::IDENTITY)
            }
            "FIELDS" | "COLUMNS" => {
                self.names = Some((ln, rest.iter().map(|s| s.to_string()).collect()))
            }
            "SIZE" => self.sizes = Some((ln, numbers(ln, "SIZE", rest)?)),
            "TYPE" => {
                self.kinds = Some((ln, rest.iter().map(|s| s.to_ascii_uppercase()).collect()))
            }
            "COUNT" => self.counts = Some((ln, numbers(ln, "COUNT", rest)?)),
            "WIDTH" => self.width = Some((ln, one_number(ln, "WIDTH", rest)?)),
            "HEIGHT" => self.height = Some((ln, one_number(ln, "HEIGHT", rest)?)),
            "POINTS" => self.points = Some((ln, one_number(ln, "POINTS", rest)?)),
            "DATA" => self.data = Some((ln, Data::parse(ln, rest.first().copied())?)),
            _ => {
                return Err(Fail::line(
                    ln,
                    format!("unknown PCD header entry '{}' (is this a PCD file?)", key),
                ))
            }
        }
        Ok(())
    }

    /// The fields named on line `fields_line`, with their types and counts (`SIZE`, `TYPE` and
    /// `COUNT` default to 4, `F` and 1), and the line of `COUNT`.
    fn fields(&mut self, fields_line: usize, names: Vec<String>) -> PResult<(Vec<Field>, usize)> {
        let nf = names.len();
        let (sl, sizes) = self.sizes.take().unwrap_or((fields_line, vec![4; nf]));
        let (tl, kinds) = self
            .kinds
            .take()
            .unwrap_or((fields_line, vec!["F".to_string(); nf]));
        let (cl, counts) = self.counts.take().unwrap_or((fields_line, vec![1; nf]));
        for (l, len, what) in [
            (sl, sizes.len(), "SIZE"),
            (tl, kinds.len(), "TYPE"),
            (cl, counts.len(), "COUNT"),
        ] {
            if len != nf {
                return Err(Fail::line(
                    l,
                    format!("{what} has {len} entries but FIELDS names {nf}"),
                ));
            }
        }
        let mut fields = Vec::with_capacity(nf);
        for (i, name) in names.into_iter().enumerate() {
            let ty = ty_of(&kinds[i], sizes[i]).ok_or_else(|| {
                Fail::line(
                    tl,
                    format!(
                        "field '{}' has TYPE {} with SIZE {}, which PCD does not define",
                        name, kinds[i], sizes[i]
                    ),
                )
            })?;
            fields.push(Field {
                name,
                ty,
                count: counts[i],
            });
        }
        Ok((fields, cl))
    }

    /// WIDTH x HEIGHT if both are given, checked for overflow.
    fn grid_points(&self) -> PResult<Option<usize>> {
        match (self.width, self.height) {
            (Some((_, w)), Some((hl, h))) => Ok(Some(w.checked_mul(h).ok_or_else(|| {
                Fail::line(
                    hl,
                    format!("WIDTH x HEIGHT = {w} x {h} overflows: no file holds that many points"),
                )
            })?)),
            _ => Ok(None),
        }
    }

    /// The number of points and the line that declares it: `POINTS` (which must agree with
    /// WIDTH x HEIGHT), else WIDTH x HEIGHT, else `WIDTH` (v0.5 headers).
    fn point_count(&self, grid_points: Option<usize>, data_line: usize) -> PResult<(usize, usize)> {
        match (self.points, self.width, grid_points) {
            (Some((pl, p)), Some((_, w)), Some(wh)) if wh != p => {
                let h = self.height.map_or(0, |h| h.1);
                Err(Fail::line(
                    pl,
                    format!("POINTS {p} differs from WIDTH x HEIGHT = {w} x {h}"),
                ))
            }
            (Some((pl, p)), _, _) => Ok((p, pl)),
            (None, Some((wl, _)), Some(wh)) => Ok((wh, wl)),
            (None, Some((wl, w)), None) => Ok((w, wl)),
            _ => Err(Fail::line(
                data_line,
                "the PCD header gives neither POINTS nor WIDTH",
            )),
        }
    }

    /// The grid of an organized cloud: WIDTH x HEIGHT with more than one row, holding the
    /// `points` declared.
    fn grid(&self, grid_points: Option<usize>, points: usize) -> Option<Grid> {
        match (self.width, self.height, grid_points) {
            (Some((_, width)), Some((_, height)), Some(wh)) if height > 1 && wh == points => {
                Some(Grid { width, height })
            }
            _ => None,
        }
    }
}

/// A checked PCD header.
pub(super) struct Header {
    /// How the points are stored.
    pub data: Data,
    /// The fields, in order.
    pub fields: Vec<Field>,
    /// Line of `FIELDS`, for errors about the fields' names.
    pub fields_line: usize,
    /// Number of points declared.
    pub points: usize,
    /// Bytes per point in binary data.
    pub record: usize,
    /// The grid of an organized cloud.
    pub grid: Option<Grid>,
    /// Byte offset of the data, just after the `DATA` line.
    pub end: usize,
    /// Line number of the `DATA` line.
    pub end_line: usize,
    /// `VIEWPOINT`, if given.
    pub viewpoint: Option<Viewpoint>,
    /// Comment lines (`#`) but the format's first.
    pub comments: Vec<String>,
}

impl Header {
    /// Reads and checks the header of the PCD file `data`: entries consistent with one another,
    /// and sizes and counts that the bytes after the header can hold.
    pub fn parse(data: &[u8]) -> PResult<Header> {
        let mut lines = Lines::new(data, 0, 1);
        let mut e = Entries::read(&mut lines)?;
        let end = lines.offset();
        let end_line = lines.line_no();
        let Some((data_line, kind)) = e.data else {
            return Err(Fail::line(
                end_line.max(1),
                "the PCD header has no DATA line",
            ));
        };
        let Some((fields_line, names)) = e.names.take() else {
            return Err(Fail::line(data_line, "the PCD header has no FIELDS line"));
        };
        let (fields, counts_line) = e.fields(fields_line, names)?;
        let grid_points = e.grid_points()?;
        let (points, points_line) = e.point_count(grid_points, data_line)?;
        let (values_per_point, record) = point_size(&fields, counts_line, data.len())?;
        let body_len = data.len() - end;
        check_body_size(kind, points, record, values_per_point, body_len)
            .map_err(|m| Fail::line(points_line, m))?;
        Ok(Header {
            data: kind,
            fields,
            fields_line,
            points,
            record,
            grid: e.grid(grid_points, points),
            end,
            end_line,
            viewpoint: e.viewpoint,
            comments: std::mem::take(&mut e.comments),
        })
    }
}

/// Values per point and bytes per point, checked for overflow and against the file: a point
/// cannot have more values than the file (of `file_len` bytes) has bytes.
fn point_size(fields: &[Field], counts_line: usize, file_len: usize) -> PResult<(usize, usize)> {
    let mut values_per_point = 0usize;
    let mut record = 0usize;
    for f in fields {
        values_per_point = values_per_point
            .checked_add(f.count)
            .filter(|&v| v <= file_len)
            .ok_or_else(|| {
                Fail::line(
                    counts_line,
                    format!(
                        "COUNT {} of field '{}' gives more values per point than the file has \
                         bytes ({})",
                        f.count, f.name, file_len
                    ),
                )
            })?;
        // Cannot overflow: count <= file_len and size <= 8.
        record += f.ty.size() * f.count;
    }
    Ok((values_per_point, record))
}

/// Whether `points` points of `record` bytes (binary) or `values_per_point` values (text) can
/// be in the `body_len` bytes after the header; the message says why not.
fn check_body_size(
    kind: Data,
    points: usize,
    record: usize,
    values_per_point: usize,
    body_len: usize,
) -> Result<(), String> {
    let n = points;
    let rec = record;
    match kind {
        Data::Binary => {
            if n.checked_mul(rec).is_none_or(|need| need > body_len) {
                return Err(format!(
                    "the header declares {n} points of {rec} bytes, but only {body_len} bytes \
                     follow it"
                ));
            }
        }
        Data::Compressed => {
            if n.checked_mul(rec)
                .is_none_or(|need| need > u32::MAX as usize)
            {
                return Err(format!(
                    "the header declares {n} points of {rec} bytes, more than binary_compressed \
                     data can hold (4 GiB)"
                ));
            }
        }
        // A point takes at least 2 bytes of text per value ("0 ").
        Data::Ascii => {
            if n.checked_mul(values_per_point.max(1))
                .is_none_or(|need| need > body_len)
            {
                return Err(format!(
                    "the header declares {n} points of {values_per_point} values, but only \
                     {body_len} bytes of text follow it"
                ));
            }
        }
    }
    Ok(())
}
