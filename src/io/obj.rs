//! Wavefront OBJ: the `v x y z [w | r g b]` lines are the points, in file order; faces,
//! normals (`vn`, indexed per face corner, not per vertex) and the rest are ignored.

use super::error::{Fail, PResult};
use super::value::{parse_num, tokens, Lines};
use super::PointCloud;

pub(crate) fn read(data: &[u8]) -> PResult<PointCloud> {
    let mut positions = Vec::new();
    for item in Lines::new(data, 0, 1) {
        let (ln, line) = item?;
        let mut tok = tokens(line);
        if tok.next() != Some("v") {
            continue;
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
        positions.push(p);
    }
    let mut cloud = PointCloud::from_positions(positions);
    cloud.source_precision = Some(super::Precision::of_text(&cloud.positions));
    Ok(cloud)
}
