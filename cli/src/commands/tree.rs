//! `nbhd tree save IN OUT.nbhdtree`: build the k-d tree of a point-cloud file once and save it
//! (docs/tree-file-format.md), so that the neighbourhood commands can load it with `--tree`
//! instead of building it again.

use crate::args::{InputArgs, TreeArgs};
use crate::error::{Context, Result};
use crate::output::{ms, num, Output};
use crate::progress::Progress;
use nbhd::KdTree;
use nbhd::Persist;
use serde_json::json;
use std::path::PathBuf;
use std::time::Instant;

/// Save a built k-d tree, to be loaded by `nbhd knn | radius | neighbors --tree`
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(subcommand)]
    pub what: What,
}

#[derive(clap::Subcommand, Debug)]
pub enum What {
    /// Build the k-d tree of a point-cloud file (f64 coordinates, points with a NaN or
    /// infinite coordinate skipped) and write it to a tree file
    ///
    /// The file holds the tree as built (points in tree order, their indices in the input
    /// file, the nodes), with a versioned, checksummed header: loading it gives the same
    /// tree, and so the same neighbourhoods, bit for bit.
    Save(SaveArgs),
}

#[derive(clap::Args, Debug)]
pub struct SaveArgs {
    #[command(flatten)]
    pub input: InputArgs,

    /// The tree file to write (conventionally .nbhdtree)
    pub output: PathBuf,

    #[command(flatten)]
    pub tree: TreeArgs,
}

pub fn run(a: Args, out: &Output) -> Result<()> {
    match a.what {
        What::Save(s) => save(s, out),
    }
}

fn save(a: SaveArgs, out: &Output) -> Result<()> {
    let cloud = a.input.read()?;
    let name = a.input.input.display().to_string();
    let view = cloud.view().context(&name)?;
    let opts = a.tree.options();
    let t = Instant::now();
    let tree = {
        let _s = Progress::spinner(
            out,
            format!("building the k-d tree of {} points", cloud.len()),
        );
        KdTree::<f64>::build(&view, &opts).context(&name)?
    };
    let build_ms = ms(t);
    let t = Instant::now();
    tree.save_file(&a.output)?;
    let save_ms = ms(t);
    let bytes = std::fs::metadata(&a.output)
        .map(|m| m.len())
        .context(a.output.display())?;
    let stats = tree.stats();
    out.json(&json!({
        "input": name,
        "output": a.output.display().to_string(),
        "points": cloud.len(),
        "skipped_non_finite": cloud.len() - stats.points,
        "tree": {
            "pivot": opts.pivot.name(),
            "median": opts.median.name(),
            "leaf_size": opts.leaf_size,
            "depth": stats.depth,
            "nodes": stats.nodes,
        },
        "file_bytes": bytes,
        "build_ms": num(build_ms),
        "save_ms": num(save_ms),
    }));
    out.text(format!(
        "{name}: tree of {} points ({} skipped as non-finite), {} / {} / leaf {}, depth {}, \
         built in {build_ms:.1} ms\nwrote {} ({bytes} bytes) in {save_ms:.1} ms",
        stats.points,
        cloud.len() - stats.points,
        opts.pivot.name(),
        opts.median.name(),
        opts.leaf_size,
        stats.depth,
        a.output.display(),
    ));
    Ok(())
}
