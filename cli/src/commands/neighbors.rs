//! `nbhd knn | radius | neighbors FILE`: the k nearest, all within radius ε, or the ε-k
//! neighbourhood (the k nearest within ε, thesis Section 2.1.1) of every point of a file, or of
//! the points of a second file, from a k-d tree built with the chosen variant.
//!
//! Output: one line per neighbour, `query,rank,index,sq_dist` (caller indices: the points'
//! positions in the file, counted from 0; `sq_dist` is the squared Euclidean distance, written
//! with every digit), or a JSON document.

use crate::commands::{length_text, ms, parse_length, read_cloud, FormatArg, TreeArgs};
use crate::output::{num, Output};
use crate::progress::Progress;
use nbhd::smooth::Length;
use nbhd::{KdTree, NeighborTable, Neighborhood, TableOptions};
use serde_json::json;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// What every neighbourhood command takes.
#[derive(clap::Args, Debug)]
pub struct Common {
    /// Input file (.ply, .pcd, .obj, .xyz/.txt/.pts/.asc/.csv); points with NaN coordinates are
    /// skipped and get empty rows, the others keep their index in the file
    pub input: PathBuf,

    /// Write the neighbourhoods to this file (.csv or .txt: query,rank,index,sq_dist lines;
    /// .json: one document) instead of standard output
    #[arg(long, short)]
    pub output: Option<PathBuf>,

    /// Leave each point out of its own neighbourhood (its duplicates at distance 0 stay)
    #[arg(long)]
    pub exclude_self: bool,

    /// Search around the points of this file instead of the input's own points
    #[arg(long)]
    pub queries: Option<PathBuf>,

    /// Read the input (and the queries) as this format instead of recognising it
    #[arg(long, value_enum)]
    pub from: Option<FormatArg>,

    #[command(flatten)]
    pub tree: TreeArgs,
}

/// The k nearest points
#[derive(clap::Args, Debug)]
pub struct KnnArgs {
    #[command(flatten)]
    pub common: Common,

    /// Number of neighbours k (at least 1)
    #[arg(short, long, allow_hyphen_values = true)]
    pub k: i64,
}

/// All points within the influence radius ε (inclusive: ‖x − q‖ ≤ ε)
#[derive(clap::Args, Debug)]
pub struct RadiusArgs {
    #[command(flatten)]
    pub common: Common,

    /// Influence radius ε: a number in the points' units, or a multiple of the mean spacing h
    /// such as 3h
    #[arg(long, short = 'r', value_parser = parse_length, allow_hyphen_values = true)]
    pub radius: Length,
}

/// The ε-k neighbourhood: the k nearest among the points within ε
#[derive(clap::Args, Debug)]
pub struct NeighborsArgs {
    #[command(flatten)]
    pub common: Common,

    /// Maximum valence k (at least 1)
    #[arg(short, long, allow_hyphen_values = true)]
    pub k: i64,

    /// Influence radius ε: a number in the points' units, or a multiple of the mean spacing h
    /// such as 6h
    #[arg(long, short = 'r', value_parser = parse_length, allow_hyphen_values = true)]
    pub radius: Length,
}

/// Which neighbourhood, before the radius is resolved.
enum Kind {
    Knn(i64),
    Radius(Length),
    KnnRadius(i64, Length),
}

pub fn run_knn(a: KnnArgs, out: &Output) -> Result<(), String> {
    run(a.common, Kind::Knn(a.k), out)
}

pub fn run_radius(a: RadiusArgs, out: &Output) -> Result<(), String> {
    run(a.common, Kind::Radius(a.radius), out)
}

pub fn run_neighbors(a: NeighborsArgs, out: &Output) -> Result<(), String> {
    run(a.common, Kind::KnnRadius(a.k, a.radius), out)
}

fn check_k(k: i64) -> Result<usize, String> {
    if k < 1 {
        return Err(format!("k must be at least 1 (got {k})"));
    }
    usize::try_from(k).map_err(|_| format!("k {k} is too large"))
}

/// Mean distance of a point to its nearest other point, from the tree.
fn mean_spacing(tree: &KdTree<f64>) -> Result<f64, String> {
    let t = tree
        .neighborhoods(Neighborhood::Knn { k: 1 }, &TableOptions::default())
        .map_err(|e| e.to_string())?;
    let d: Vec<f64> = (0..t.len())
        .filter_map(|i| t.sq_dists_of(i).first().map(|d| d.sqrt()))
        .collect();
    let h = d.iter().sum::<f64>() / d.len().max(1) as f64;
    if h > 0.0 && h.is_finite() {
        Ok(h)
    } else {
        Err(
            "a radius in units of h needs a mean spacing h > 0 (at least two distinct points)"
                .into(),
        )
    }
}

fn run(c: Common, kind: Kind, out: &Output) -> Result<(), String> {
    // Check what can be checked before reading.
    let k = match kind {
        Kind::Knn(k) | Kind::KnnRadius(k, _) => Some(check_k(k)?),
        Kind::Radius(_) => None,
    };
    if c.exclude_self && c.queries.is_some() {
        return Err("--exclude-self applies to the input's own points, not to --queries".into());
    }
    let cloud = read_cloud(&c.input, c.from)?;
    let queries = match &c.queries {
        Some(q) => Some(read_cloud(q, c.from)?),
        None => None,
    };
    let opts = c.tree.options();
    let name = c.input.display().to_string();
    let view = cloud.view().map_err(|e| format!("{name}: {e}"))?;
    let t = Instant::now();
    let tree = {
        let _s = Progress::spinner(
            out,
            format!("building the k-d tree of {} points", cloud.len()),
        );
        KdTree::<f64>::build(&view, &opts).map_err(|e| format!("{name}: {e}"))?
    };
    let build_ms = ms(t);
    let length = match kind {
        Kind::Radius(l) | Kind::KnnRadius(_, l) => Some(l),
        Kind::Knn(_) => None,
    };
    let h = match length {
        Some(Length::Relative(_)) => Some(mean_spacing(&tree).map_err(|e| format!("{name}: {e}"))?),
        _ => None,
    };
    let radius = length.map(|l| l.resolve(h.unwrap_or(1.0)));
    let nbhd = match (k, radius) {
        (Some(k), None) => Neighborhood::Knn { k },
        (None, Some(radius)) => Neighborhood::Radius {
            radius,
            sorted: true,
        },
        (Some(k), Some(radius)) => Neighborhood::KnnRadius { k, radius },
        (None, None) => unreachable!("every kind has k or a radius"),
    };
    nbhd.validate().map_err(|e| e.to_string())?;
    let t = Instant::now();
    let table = {
        let _s = Progress::spinner(out, "computing neighbourhoods");
        match &queries {
            None => tree.neighborhoods(
                nbhd,
                &TableOptions {
                    exclude_self: c.exclude_self,
                    threads: 0,
                },
            ),
            Some(q) => {
                let qname = c.queries.as_ref().unwrap().display().to_string();
                let qv = q.view().map_err(|e| format!("{qname}: {e}"))?;
                if let Some((i, _)) = qv.first_non_finite() {
                    return Err(format!(
                        "{qname}: query point {i} has a NaN or infinite coordinate"
                    ));
                }
                tree.neighborhoods_of(&qv, nbhd, &TableOptions::default())
            }
        }
        .map_err(|e| format!("{name}: {e}"))?
    };
    let query_ms = ms(t);
    let stats = tree.stats();
    let kind_name = match nbhd {
        Neighborhood::Knn { .. } => "knn",
        Neighborhood::Radius { .. } => "radius",
        Neighborhood::KnnRadius { .. } => "neighbors",
    };
    let summary = json!({
        "input": name,
        "queries_file": c.queries.as_ref().map(|q| q.display().to_string()),
        "kind": kind_name,
        "k": k,
        "radius": radius.map(num),
        "radius_given": length.map(length_text),
        "spacing_h": h.map(num),
        "exclude_self": c.exclude_self,
        "points": cloud.len(),
        "skipped_non_finite": cloud.len() - stats.points,
        "queries": table.len(),
        "tree": {
            "pivot": opts.pivot.name(),
            "median": opts.median.name(),
            "leaf_size": opts.leaf_size,
            "depth": stats.depth,
            "nodes": stats.nodes,
            "leaves": stats.leaves,
            "bytes": stats.bytes,
        },
        "build_ms": num(build_ms),
        "query_ms": num(query_ms),
        "rows": {
            "min": table.min_row_len(),
            "mean": num(table.mean_row_len()),
            "max": table.max_row_len(),
            "total": table.total(),
        },
    });
    let text = format!(
        "{name}: {kind_name} of {} queries over {} points ({} skipped as non-finite){}{}: \
         neighbours per row min {} / mean {:.2} / max {}, total {}\n\
         tree {} / {} / leaf {}: depth {}, {} nodes, {} leaves, {} KiB, built in {:.1} ms; \
         queries {:.1} ms",
        table.len(),
        cloud.len(),
        cloud.len() - stats.points,
        k.map_or(String::new(), |k| format!(", k = {k}")),
        radius.map_or(String::new(), |r| format!(
            ", ε = {r}{}",
            h.map_or(String::new(), |h| format!(
                " ({} with h = {h})",
                length_text(length.unwrap())
            ))
        )),
        table.min_row_len(),
        table.mean_row_len(),
        table.max_row_len(),
        table.total(),
        opts.pivot.name(),
        opts.median.name(),
        opts.leaf_size,
        stats.depth,
        stats.nodes,
        stats.leaves,
        stats.bytes / 1024,
        build_ms,
        query_ms,
    );
    match &c.output {
        Some(path) => {
            let json_file = path
                .extension()
                .is_some_and(|e| e.eq_ignore_ascii_case("json"));
            let bar = Progress::bar(out, table.len() as u64, "writing");
            let res = if json_file {
                let mut doc = summary.clone();
                doc["neighbors"] = rows_json(&table);
                std::fs::write(path, serde_json::to_string(&doc).expect("plain values"))
            } else {
                write_csv(path, &table, &bar)
            };
            res.map_err(|e| format!("{}: {e}", path.display()))?;
            drop(bar);
            let mut doc = summary;
            doc["output"] = json!(path.display().to_string());
            out.json(&doc);
            out.text(format!("{text}\nwrote {}", path.display()));
        }
        None if out.json => {
            let mut doc = summary;
            doc["neighbors"] = rows_json(&table);
            out.json(&doc);
        }
        None => {
            let stdout = std::io::stdout();
            let mut w = std::io::BufWriter::new(stdout.lock());
            // A closed pipe (`nbhd knn ... | head`) ends the output quietly.
            if write_rows(&mut w, &table, &Progress::hidden()).is_ok() {
                let _ = w.flush();
            }
            drop(w);
            out.note(text);
        }
    }
    Ok(())
}

fn rows_json(table: &NeighborTable<f64>) -> serde_json::Value {
    (0..table.len())
        .map(|i| {
            json!({
                "indices": table.indices_of(i),
                "sq_dists": table.sq_dists_of(i).iter().map(|&d| num(d)).collect::<Vec<_>>(),
            })
        })
        .collect()
}

fn write_csv(path: &Path, table: &NeighborTable<f64>, bar: &Progress) -> std::io::Result<()> {
    let mut w = std::io::BufWriter::new(std::fs::File::create(path)?);
    write_rows(&mut w, table, bar)?;
    w.flush()
}

fn write_rows(
    w: &mut impl Write,
    table: &NeighborTable<f64>,
    bar: &Progress,
) -> std::io::Result<()> {
    writeln!(w, "query,rank,index,sq_dist")?;
    for i in 0..table.len() {
        for (r, (j, d)) in table
            .indices_of(i)
            .iter()
            .zip(table.sq_dists_of(i))
            .enumerate()
        {
            writeln!(w, "{i},{r},{j},{d:?}")?;
        }
        if i % 4096 == 0 {
            bar.set(i as u64);
        }
    }
    Ok(())
}
