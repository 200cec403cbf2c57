//! Reading point-cloud files, for every command: the global `--columns` of text files, the note
//! on how a text file's columns were read, and the finite points of a cloud.

use crate::error::Result;
use crate::output::Output;
use nbhd::io::{Format, PointCloud, ReadInfo, ReadOptions};
use std::path::Path;
use std::sync::OnceLock;

/// What every command reads input files with: the output mode (for the note on text
/// columns) and the global `--columns`.
static READ_CONTEXT: OnceLock<(Output, Option<Vec<String>>)> = OnceLock::new();

/// Sets the output mode and `--columns` for [`cloud`] (once, from `main`).
pub fn set_context(out: Output, columns: Option<Vec<String>>) {
    let _ = READ_CONTEXT.set((out, columns));
}

/// Reads a cloud (in `format`, or the one recognised) with the global `--columns`, and tells what was read; errors name the file.
pub fn cloud_info(path: &Path, format: Option<Format>) -> Result<(PointCloud, ReadInfo)> {
    let opts = ReadOptions {
        format,
        columns: READ_CONTEXT.get().and_then(|c| c.1.clone()),
    };
    Ok(nbhd::io::read_with(path, &opts)?)
}

/// `columns x y z red green blue (the header on line 1)` for a text input.
pub fn columns_note(info: &ReadInfo) -> Option<String> {
    info.text_columns
        .as_ref()
        .map(|t| format!("columns {} ({})", t.names.join(" "), t.from))
}

/// `not carried: 1200 face element(s)`: what the input holds that the cloud does not carry.
pub fn not_carried_note(info: &ReadInfo) -> Option<String> {
    (!info.not_carried.is_empty()).then(|| format!("not carried: {}", info.not_carried.join(", ")))
}

/// Prints a note on standard error unless --quiet or --json.
pub fn note(s: impl AsRef<str>) {
    if let Some((out, _)) = READ_CONTEXT.get() {
        out.note(s);
    }
}

/// Reads a cloud; errors name the file. Says on standard error (unless --quiet or --json) what
/// a text input's columns were read as, and what the file holds that the cloud does not carry.
pub fn cloud(path: &Path, format: Option<Format>) -> Result<PointCloud> {
    let (cloud, info) = cloud_info(path, format)?;
    for n in [columns_note(&info), not_carried_note(&info)]
        .into_iter()
        .flatten()
    {
        note(format!("{}: {n}", path.display()));
    }
    Ok(cloud)
}

/// The finite points of a cloud as `DVec3` and their indices in the file.
pub fn finite_points(cloud: &PointCloud) -> (Vec<glam::DVec3>, Vec<usize>) {
    cloud
        .positions
        .iter()
        .enumerate()
        .filter(|(_, p)| p.iter().all(|c| c.is_finite()))
        .map(|(i, p)| (glam::DVec3::from_array(*p), i))
        .unzip()
}
