//! XYZ text: one point per line, `x y z [more columns]`, separated by whitespace, commas or
//! semicolons.
//!
//! What the columns are is decided, in this order, by
//! 1. the names the caller gives ([`ReadOptions::columns`](super::ReadOptions::columns));
//! 2. a header line before the data: `x y z`, `x,y,z,nx,ny,nz`, `# x y z curvature`,
//!    CloudCompare's `//X,Y,Z,R,G,B` (names in any case, with or without `#`/`//`);
//! 3. without either: 3 columns are `x y z`; 6 columns are `x y z` and a triple that is taken
//!    as a normal `nx ny nz` if every triple has length 1 (± 0.01) or is non-finite, else as a
//!    colour `red green blue` if every value is an integer in 0..=255, and otherwise as the
//!    scalars `field3 field4 field5`; other extra columns are scalars `field3`, `field4`, ...
//!
//! [`TextColumns`](super::TextColumns) says which it was, so that a program can tell its user.
//! Column names are read as: `nx ny nz` or `normal_x ...` normals; `r g b` or
//! `red green blue` colour channels; anything else a scalar field of that name.

use super::assemble::{assign_columns, Builder};
use super::columns::{ColorStyle, Columns};
use super::error::{Fail, PResult};
use super::value::{parse_num, Lines};
use super::{PointCloud, TextColumns};
use std::io::Write;

fn split(line: &str) -> impl Iterator<Item = &str> {
    line.split(|c: char| c.is_ascii_whitespace() || c == ',' || c == ';')
        .filter(|s| !s.is_empty())
}

fn comment(line: &str) -> Option<&str> {
    line.strip_prefix("//").or_else(|| line.strip_prefix('#'))
}

/// A column name as nbhd calls it: coordinates, normals and colour channels in lower case
/// (`X` is `x`, `R` is `red`), any other name as written (`Amplitude` stays `Amplitude`).
fn canonical(name: &str) -> String {
    let n = name.trim().to_ascii_lowercase();
    match n.as_str() {
        "r" => "red".into(),
        "g" => "green".into(),
        "b" => "blue".into(),
        "x" | "y" | "z" | "nx" | "ny" | "nz" | "normal_x" | "normal_y" | "normal_z" | "red"
        | "green" | "blue" => n,
        _ => name.trim().to_string(),
    }
}

/// The names of a header line, if it is one: its first three names are x, y, z.
fn header_names(text: &str) -> Option<Vec<String>> {
    let names: Vec<String> = split(text).map(canonical).collect();
    (names.len() >= 3 && names[..3] == ["x", "y", "z"]).then_some(names)
}

pub(crate) fn read(data: &[u8], given: Option<&[String]>) -> PResult<(PointCloud, TextColumns)> {
    let mut header: Option<(usize, Vec<String>)> = None;
    let mut ncols: Option<(usize, usize)> = None; // (columns, line of the first point)
    let mut values: Vec<f64> = Vec::new();
    let mut rows = 0usize;
    for item in Lines::new(data, 0, 1) {
        let (ln, line) = item?;
        let t = line.trim();
        if t.is_empty() {
            continue;
        }
        if let Some(c) = comment(t) {
            if ncols.is_none() && header.is_none() {
                header = header_names(c).map(|h| (ln, h));
            }
            continue;
        }
        if ncols.is_none() && header.is_none() {
            if let Some(h) = header_names(t) {
                header = Some((ln, h));
                continue;
            }
        }
        let before = values.len();
        for tok in split(t) {
            values.push(
                parse_num(tok).ok_or_else(|| Fail::line(ln, format!("'{tok}' is not a number")))?,
            );
        }
        let nc = values.len() - before;
        match ncols {
            None => {
                if nc < 3 {
                    return Err(Fail::line(
                        ln,
                        format!("a point needs x y z, this line has {nc} values"),
                    ));
                }
                ncols = Some((nc, ln));
            }
            Some((n0, _)) if n0 != nc => {
                return Err(Fail::line(
                    ln,
                    format!("{nc} values, but the first point had {n0}"),
                ))
            }
            _ => {}
        }
        rows += 1;
    }
    let Some((nc, first_line)) = ncols else {
        let cloud = PointCloud {
            source_precision: Some(super::Precision::Single),
            ..PointCloud::default()
        };
        let (names, from) = match (given, header) {
            (Some(g), _) => (g.to_vec(), "the caller's column names".to_string()),
            (None, Some((ln, h))) => (h, format!("the header on line {ln}")),
            (None, None) => (vec!["x".into(), "y".into(), "z".into()], "no data".into()),
        };
        return Ok((cloud, TextColumns { names, from }));
    };
    let (names, from) = if let Some(g) = given {
        let names: Vec<String> = g.iter().map(|s| canonical(s)).collect();
        if names.len() != nc {
            return Err(Fail::line(
                first_line,
                format!(
                    "{} column names were given ({}), the data has {nc} columns",
                    names.len(),
                    names.join(" ")
                ),
            ));
        }
        (names, "the column names given".to_string())
    } else if let Some((ln, h)) = header {
        if h.len() != nc {
            return Err(Fail::line(
                ln,
                format!(
                    "the header names {} columns ({}), the data on line {first_line} has {nc}",
                    h.len(),
                    h.join(" ")
                ),
            ));
        }
        (h, format!("the header on line {ln}"))
    } else {
        guess(&values, nc)
    };
    let (dest, scalars, normals) = assign_columns(&names).map_err(|m| Fail::line(first_line, m))?;
    let mut b = Builder::new(dest, scalars, normals, rows);
    for row in values.chunks_exact(nc) {
        b.push(row.iter().copied());
    }
    let mut cloud = b.finish();
    cloud.source_precision = Some(super::Precision::of_text(&cloud.positions));
    Ok((cloud, TextColumns { names, from }))
}

/// Column names of a file without header or given names (see the module docs).
fn guess(values: &[f64], nc: usize) -> (Vec<String>, String) {
    let mut names: Vec<String> = (0..nc)
        .map(|j| match j {
            0..=2 => ["x", "y", "z"][j].to_string(),
            _ => format!("field{j}"),
        })
        .collect();
    if nc == 3 {
        return (names, "three columns, read as x y z".into());
    }
    if nc != 6 {
        return (
            names,
            format!(
                "no header: {nc} columns read as x y z and scalars field3..field{}",
                nc - 1
            ),
        );
    }
    let triples = || values.chunks_exact(6).map(|r| [r[3], r[4], r[5]]);
    let is_color = triples().all(|t| {
        t.iter()
            .all(|&v| (0.0..=255.0).contains(&v) && v.fract() == 0.0)
    });
    let is_normal = triples().all(|t| {
        let l = (t[0] * t[0] + t[1] * t[1] + t[2] * t[2]).sqrt();
        !l.is_finite() || (l - 1.0).abs() <= 0.01
    });
    // Unit vectors first: an axis-aligned normal (0 0 1) is also three small integers.
    let (extra, why) = if is_normal {
        (
            ["nx", "ny", "nz"],
            "no header: columns 4-6 are unit vectors, read as normals nx ny nz",
        )
    } else if is_color {
        (
            ["red", "green", "blue"],
            "no header: columns 4-6 are integers in 0..255, read as colour red green blue",
        )
    } else {
        (
            ["field3", "field4", "field5"],
            "no header: columns 4-6 are neither colours (0..255 integers) nor unit normals, read as scalars field3 field4 field5",
        )
    };
    for (k, e) in extra.iter().enumerate() {
        names[3 + k] = e.to_string();
    }
    (names, why.to_string())
}

pub(crate) fn write(w: &mut impl Write, cloud: &PointCloud, single: bool) -> PResult<()> {
    let cols = Columns::new(cloud, ["nx", "ny", "nz"], ColorStyle::Channels, 8);
    // CloudCompare's header (`//X Y Z ...`): its text reader takes a `#` as a column and
    // reads no point of a file with a `# x y z` line.
    writeln!(w, "//{}", cols.names().join(" "))?;
    let mut line = String::new();
    for i in 0..cloud.len() {
        cols.line(&mut line, i, single);
        w.write_all(line.as_bytes())?;
    }
    Ok(())
}
