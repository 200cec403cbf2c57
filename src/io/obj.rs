//! Wavefront OBJ: the `v x y z [w | r g b]` lines are the points, in file order; faces,
//! normals (`vn`, indexed per face corner, not per vertex), the `w` or colour of a `v` line
//! and the rest are not read, and the reader says which of them the file had.

use super::error::{Fail, PResult};
use super::value::{parse_num, tokens, Lines};
use super::PointCloud;

/// Reads the vertices of an OBJ file; also returns, in words, what else it holds.
pub(crate) fn read(data: &[u8]) -> PResult<(PointCloud, Vec<String>)> {
    let mut positions = Vec::new();
    // Lines of each other kind, and `v` lines with more than x y z.
    let mut others: Vec<(String, usize)> = Vec::new();
    let mut more = 0usize;
    for item in Lines::new(data, 0, 1) {
        let (ln, line) = item?;
        let mut tok = tokens(line);
        match tok.next() {
            Some("v") => {}
            Some(k) if !k.starts_with('#') => {
                match others.iter_mut().find(|(o, _)| o == k) {
                    Some((_, c)) => *c += 1,
                    None => others.push((k.to_string(), 1)),
                }
                continue;
            }
            _ => continue,
        }
        let mut p = [0.0; 3];
        for (j, c) in p.iter_mut().enumerate() {
            let t = tok.next().ok_or_else(|| {
                Fail::line(
                    ln,
                    format!(
                        "vertex {}: missing {} coordinate",
                        positions.len() + 1,
                        ["x", "y", "z"][j]
                    ),
                )
            })?;
            *c = parse_num(t).ok_or_else(|| {
                Fail::line(
                    ln,
                    format!("vertex {}: '{t}' is not a number", positions.len() + 1),
                )
            })?;
        }
        more += usize::from(tok.next().is_some());
        positions.push(p);
    }
    let mut cloud = PointCloud::from_positions(positions);
    cloud.source_precision = Some(super::Precision::of_text(&cloud.positions));
    let mut not_carried: Vec<String> = others
        .into_iter()
        .map(|(k, c)| format!("{c} '{k}' line(s)"))
        .collect();
    if more > 0 {
        not_carried.push(format!("the w or colour values of {more} 'v' line(s)"));
    }
    Ok((cloud, not_carried))
}
