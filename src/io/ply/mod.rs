//! PLY (Stanford polygon format): the `vertex` element is the cloud; other elements (faces,
//! ...) are skipped.
//!
//! `header.rs` reads the header, `decode.rs` reads the vertices in each format, `write.rs`
//! writes them.

mod decode;
mod header;
mod write;

use super::assemble::{assign_columns, Builder};
use super::error::{Fail, PResult};
use super::{PointCloud, Precision};
use header::{Fmt, Header, Prop};
pub(crate) use write::write;

pub(crate) fn read(data: &[u8]) -> PResult<PointCloud> {
    let header = Header::parse(data)?;
    let vertex = header.vertex();
    // Vertex columns: scalar properties; list properties are skipped.
    let names: Vec<String> = vertex
        .props
        .iter()
        .filter(|(_, p)| matches!(p, Prop::Scalar(_)))
        .map(|(s, _)| s.clone())
        .collect();
    let (dest, scalar_names, has_normals) = assign_columns(&names)
        .map_err(|m| Fail::line(header.end_line, format!("vertex element: {m}")))?;
    let mut b = Builder::new(dest, scalar_names, has_normals, vertex.count);
    match header.fmt {
        Fmt::Ascii => decode::ascii(data, &header, &mut b)?,
        Fmt::Le => decode::binary(data, &header, false, &mut b)?,
        Fmt::Be => decode::binary(data, &header, true, &mut b)?,
    }
    let mut cloud = b.finish();
    cloud.source_precision = vertex.props.iter().find_map(|(name, p)| match p {
        Prop::Scalar(t) if name == "x" => Some(Precision::of_type(*t)),
        _ => None,
    });
    Ok(cloud)
}
