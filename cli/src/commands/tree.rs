//! `nbhd tree save IN OUT.nbhdtree`: build the k-d tree of a point-cloud file once and save it
//! (docs/tree-file-format.md), so that the neighbourhood commands can load it with `--tree`
//! instead of building it again.

use crate::args::{parse_boxsize, BoxSize, InputArgs, TreeArgs};
use crate::commands::neighbors::build_tree;
use crate::error::{Context, Result};
use crate::output::{ms, num, Output};
use nbhd::Persist;
use serde_json::json;
use std::path::PathBuf;
use std::time::Instant;

/// Save a built k-d tree, to be loaded by `nbhd knn | radius | neighbors | pairs --tree`
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

    /// Build a periodic tree (a torus, as scipy's boxsize; see `nbhd knn --help`): the box
    /// size L of every axis, comma separated, or one for all; 0 leaves an axis open. The file
    /// keeps the box: the commands that load the tree search it periodically
    #[arg(long, value_name = "L[,L...]", value_parser = parse_boxsize)]
    pub boxsize: Option<BoxSize>,
}

pub fn run(a: Args, out: &Output) -> Result<()> {
    match a.what {
        What::Save(s) => save(s, out),
    }
}

fn save(a: SaveArgs, out: &Output) -> Result<()> {
    let cloud = a.input.read()?;
    let name = a.input.input.display().to_string();
    let opts = a.tree.options();
    let (tree, build_ms) = build_tree(&cloud, &opts, a.boxsize.as_ref(), &name, out)?;
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
        "boxsize": tree.period().map(|p| p.sizes()),
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
