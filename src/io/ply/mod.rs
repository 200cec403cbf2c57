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

/// Reads the vertices of a PLY file; also returns what else it holds, which the cloud does
/// not carry (other elements such as faces, list properties of the vertices).
pub(crate) fn read(data: &[u8]) -> PResult<(PointCloud, Vec<String>)> {
    let header = Header::parse(data)?;
    let mut not_carried: Vec<String> = header
        .elements
        .iter()
        .filter(|e| e.name != "vertex" && e.count > 0)
        .map(|e| format!("{} {} element(s)", e.count, e.name))
        .collect();
    let vertex = header.vertex();
    not_carried.extend(
        vertex
            .props
            .iter()
            .filter(|(_, p)| matches!(p, Prop::List(..)))
            .map(|(name, _)| format!("the vertices' list property '{name}'")),
    );
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
    cloud.metadata.comments = header.comments.clone();
    // The scalar fields' types.
    let types = vertex
        .props
        .iter()
        .filter_map(|(name, p)| match p {
            Prop::Scalar(t) if cloud.scalar(name).is_some() => Some((name.clone(), *t)),
            _ => None,
        })
        .collect();
    cloud.metadata.field_types = types;
    cloud.source_precision = vertex.props.iter().find_map(|(name, p)| match p {
        Prop::Scalar(t) if name == "x" => Some(Precision::of_type(*t)),
        _ => None,
    });
    Ok((cloud, not_carried))
}
