//! XYZ text: one point per line, `x y z [nx ny nz] [scalars...]`, separated by whitespace,
//! commas or semicolons. A comment line before the data (`# x y z nx ny nz curvature`, or
//! CloudCompare's `//X Y Z Nx Ny Nz`) names the columns; without one, 6 columns are position
//! and normal and other extra columns become scalars `field3`, `field4`, ...

use super::error::{Fail, PResult};
use super::value::{parse_num, Lines};
use super::{assign_columns, Builder, ColorStyle, Columns, PointCloud};
use std::io::Write;

fn split(line: &str) -> impl Iterator<Item = &str> {
    line.split(|c: char| c.is_ascii_whitespace() || c == ',' || c == ';')
        .filter(|s| !s.is_empty())
}

fn comment(line: &str) -> Option<&str> {
    line.strip_prefix("//").or_else(|| line.strip_prefix('#'))
}

pub(crate) fn read(data: &[u8]) -> PResult<PointCloud> {
    let mut header: Option<Vec<String>> = None;
    let mut b: Option<(Builder, usize)> = None;
    let mut vals = Vec::new();
    for item in Lines::new(data, 0, 1) {
        let (ln, line) = item?;
        let t = line.trim();
        if t.is_empty() {
            continue;
        }
        if let Some(c) = comment(t) {
            if b.is_none() && header.is_none() {
                let names: Vec<String> = split(c).map(|s| s.to_ascii_lowercase()).collect();
                if names.len() >= 3 && names[..3] == ["x", "y", "z"] {
                    header = Some(names);
                }
            }
            continue;
        }
        vals.clear();
        for tok in split(t) {
            vals.push(
                parse_num(tok).ok_or_else(|| Fail::line(ln, format!("'{tok}' is not a number")))?,
            );
        }
        let (builder, ncols) = match &mut b {
            Some(x) => x,
            None => {
                let nc = vals.len();
                if nc < 3 {
                    return Err(Fail::line(
                        ln,
                        format!("a point needs x y z, this line has {nc} values"),
                    ));
                }
                let names: Vec<String> = match &header {
                    Some(h) if h.len() == nc => h.clone(),
                    _ => (0..nc)
                        .map(|j| match (nc, j) {
                            (_, 0..=2) => ["x", "y", "z"][j].to_string(),
                            (6, 3..=5) => ["nx", "ny", "nz"][j - 3].to_string(),
                            _ => format!("field{j}"),
                        })
                        .collect(),
                };
                let (dest, scalars, normals) =
                    assign_columns(&names).map_err(|m| Fail::line(ln, m))?;
                b.insert((Builder::new(dest, scalars, normals, 0), nc))
            }
        };
        if vals.len() != *ncols {
            return Err(Fail::line(
                ln,
                format!("{} values, but the first point had {ncols}", vals.len()),
            ));
        }
        builder.push(vals.iter().copied());
    }
    let mut cloud = match b {
        Some((builder, _)) => builder.finish(),
        None => PointCloud::default(),
    };
    cloud.source_precision = Some(super::Precision::of_text(&cloud.positions));
    Ok(cloud)
}

pub(crate) fn write(w: &mut impl Write, cloud: &PointCloud, single: bool) -> PResult<()> {
    let cols = Columns::new(cloud, ["nx", "ny", "nz"], ColorStyle::Channels);
    writeln!(w, "# {}", cols.names().join(" "))?;
    let mut line = String::new();
    for i in 0..cloud.len() {
        cols.line(&mut line, i, single);
        w.write_all(line.as_bytes())?;
    }
    Ok(())
}
