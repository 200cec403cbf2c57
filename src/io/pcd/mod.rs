//! PCD, the Point Cloud Library's format (v0.7; v0.5/0.6 headers without WIDTH/HEIGHT too).
//!
//! `header.rs` reads and checks the header, `decode.rs` reads the points in each `DATA`
//! encoding, `lzf.rs` is the compression of `binary_compressed`, `write.rs` writes all three.

mod decode;
mod header;
mod lzf;
mod write;

use super::assemble::{assign_columns, Builder};
use super::cloud::is_packed_name;
use super::error::{Fail, PResult};
use super::{PointCloud, Precision};
use decode::PointColumns;
use header::{Data, Header};
pub(crate) use write::write;

pub(crate) fn read(data: &[u8]) -> PResult<PointCloud> {
    let header = Header::parse(data)?;
    let cols = PointColumns::of(&header.fields);
    let (dest, scalar_names, has_normals) =
        assign_columns(&cols.names).map_err(|m| Fail::line(header.fields_line, m))?;
    let mut b = Builder::new(dest, scalar_names, has_normals, header.points);
    match header.data {
        Data::Ascii => decode::ascii(data, &header, &cols, &mut b)?,
        Data::Binary => decode::binary(data, &header, &cols, &mut b)?,
        Data::Compressed => decode::compressed(data, &header, &cols, &mut b)?,
    }
    let mut cloud = b.finish();
    cloud.source_precision = header
        .fields
        .iter()
        .find(|f| f.name == "x")
        .map(|f| Precision::of_type(f.ty));
    cloud.grid = header.grid;
    cloud.metadata.viewpoint = header.viewpoint;
    cloud.metadata.comments = header.comments;
    // The scalar fields' types (a packed colour is a colour, stored PCL's way).
    let types = cols
        .names
        .iter()
        .zip(&cols.types)
        .filter(|(n, _)| cloud.scalar(n).is_some() && !is_packed_name(n))
        .map(|(n, &t)| (n.clone(), t))
        .collect();
    cloud.metadata.field_types = types;
    Ok(cloud)
}
