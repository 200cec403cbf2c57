//! `nbhd knn | radius | neighbors | pairs FILE`: the k nearest, all within radius ε, or the ε-k
//! neighbourhood (the k nearest within ε, thesis Section 2.1.1) of every point of a file, or of
//! the points of a second file, from a k-d tree built with the chosen variant; or the pairs of
//! points within ε (each once).
//!
//! With `--tree FILE` the tree is loaded from a file written by `nbhd tree save` instead of
//! built; it must hold exactly the input's points under their indices.
//!
//! Output: one line per neighbour, `query,rank,index,sq_dist` (caller indices: the points'
//! positions in the file, counted from 0; `sq_dist` is the squared Euclidean distance, written
//! with every digit — under `--metric`, that metric's key: the distance for l1 and linf,
//! Σ|Δ|^p for p=<x>), or a JSON document.

use crate::args::{length_text, parse_boxsize, parse_length, BoxSize, InputArgs, TreeArgs};
use crate::error::{Context, Result};
use crate::output::{ms, num, Output};
use crate::progress::Progress;
use crate::read;
use nbhd::io::PointCloud;
use nbhd::smooth::Length;
use nbhd::NeighborIndex;
use nbhd::Persist;
use nbhd::{
    BuildOptions, KdTree, Metric, NeighborSearch, NeighborTable, Neighborhood, QueryOptions,
    TableOptions, TreeStats,
};
use serde_json::json;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// What every neighbourhood command takes.
#[derive(clap::Args, Debug)]
#[command(mut_arg("input", |a| a.help(
    "Input file (.ply, .pcd, .las/.laz, .obj, .xyz/.txt/.pts/.asc/.csv); points with NaN coordinates are \
     skipped and get empty rows, the others keep their index in the file"
)))]
#[command(mut_arg("from", |a| a.help(
    "Read the input (and the queries) as this format instead of recognising it"
)))]
pub struct Common {
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

    /// Load the k-d tree from this file (written by `nbhd tree save`) instead of building it:
    /// it must hold exactly the input's points, else it is refused; the tree options are the
    /// file's
    #[arg(long = "tree", value_name = "FILE")]
    pub tree_file: Option<PathBuf>,

    /// The distance: l2 (Euclidean, the default), l1 (Manhattan), linf (Chebyshev) or p=<x>
    /// (Minkowski, x ≥ 1). The radius is a distance in it; sq_dist holds its key: squared for
    /// l2, the distance for l1 and linf, Σ|Δ|^p for p=<x>
    #[arg(long, default_value = "l2", value_parser = parse_metric)]
    pub metric: Metric,

    /// Approximate search (≥ 0): each neighbour within (1 + eps) times the exact one's
    /// distance; a radius keeps every point within ε/(1 + eps), none beyond ε·(1 + eps)
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub eps: f64,

    /// The radius is exclusive (‖x − q‖ < ε), as scipy's distance_upper_bound
    #[arg(long)]
    pub strict: bool,

    /// A periodic box (a torus, as scipy's boxsize): the box size L of every axis, comma
    /// separated (x,y,z), or one for all; 0 leaves an axis open. Every point must lie in
    /// [0, L) on a periodic axis; queries are wrapped into the box and each axis difference
    /// counts at its nearest image. A tree loaded with --tree keeps the box it was saved with
    #[arg(long, value_name = "L[,L...]", value_parser = parse_boxsize)]
    pub boxsize: Option<BoxSize>,

    // The input file and its format: here, so that --from is listed after --queries.
    #[command(flatten)]
    pub input: InputArgs,

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

/// Every pair of points within ε of each other
///
/// Each pair once, as row i holding the j > i (scipy's query_pairs), indices ascending; with
/// --queries, each query's row holds the input's points within ε, indices ascending (scipy's
/// sparse_distance_matrix of the queries' tree against the input's). The output's lines are
/// `query,rank,index,sq_dist` as for the other commands: `query` is i (or the query), `rank`
/// the place in its row.
#[derive(clap::Args, Debug)]
pub struct PairsArgs {
    #[command(flatten)]
    pub common: Common,

    /// The pairs' distance ε (inclusive; --strict for < ε): a number in the points' units, or
    /// a multiple of the mean spacing h such as 2h
    #[arg(long, short = 'r', value_parser = parse_length, allow_hyphen_values = true)]
    pub radius: Length,
}

/// Which neighbourhood, before the radius is resolved.
enum Kind {
    Knn(i64),
    Radius(Length),
    KnnRadius(i64, Length),
    Pairs(Length),
}

impl Kind {
    fn name(&self) -> &'static str {
        match self {
            Kind::Knn(_) => "knn",
            Kind::Radius(_) => "radius",
            Kind::KnnRadius(..) => "neighbors",
            Kind::Pairs(_) => "pairs",
        }
    }
}

pub fn run_knn(a: KnnArgs, out: &Output) -> Result<()> {
    run(a.common, Kind::Knn(a.k), out)
}

pub fn run_radius(a: RadiusArgs, out: &Output) -> Result<()> {
    run(a.common, Kind::Radius(a.radius), out)
}

pub fn run_neighbors(a: NeighborsArgs, out: &Output) -> Result<()> {
    run(a.common, Kind::KnnRadius(a.k, a.radius), out)
}

pub fn run_pairs(a: PairsArgs, out: &Output) -> Result<()> {
    run(a.common, Kind::Pairs(a.radius), out)
}

fn parse_metric(s: &str) -> std::result::Result<Metric, String> {
    s.parse().map_err(|e: nbhd::NbhdError| e.to_string())
}

fn check_k(k: i64) -> Result<usize> {
    if k < 1 {
        return Err(format!("k must be at least 1 (got {k})").into());
    }
    usize::try_from(k).map_err(|_| format!("k {k} is too large").into())
}

/// Mean distance of a point to its nearest other point, from the tree (the library's one
/// definition, `KdTree::spacing`).
fn mean_spacing(tree: &KdTree<f64>) -> Result<f64> {
    let h = tree.spacing(0).map(|s| s.mean).unwrap_or(0.0);
    if h > 0.0 && h.is_finite() {
        Ok(h)
    } else {
        Err(
            "a radius in units of h needs a mean spacing h > 0 (at least two distinct points)"
                .into(),
        )
    }
}

/// What a neighbourhood command computed, for its summary (JSON and text).
struct Facts {
    name: String,
    queries_file: Option<PathBuf>,
    kind: &'static str,
    k: Option<usize>,
    length: Option<Length>,
    h: Option<f64>,
    radius: Option<f64>,
    query: QueryOptions,
    /// The periodic box's sizes per axis (0 for open), if the tree has one.
    boxsize: Option<Vec<f64>>,
    exclude_self: bool,
    points: usize,
    tree: BuildOptions,
    tree_file: Option<PathBuf>,
    stats: TreeStats,
    table: NeighborTable<f64>,
    build_ms: f64,
    query_ms: f64,
}

fn run(c: Common, kind: Kind, out: &Output) -> Result<()> {
    // Check what can be checked before reading.
    let k = match kind {
        Kind::Knn(k) | Kind::KnnRadius(k, _) => Some(check_k(k)?),
        Kind::Radius(_) | Kind::Pairs(_) => None,
    };
    if c.exclude_self && c.queries.is_some() {
        return Err("--exclude-self applies to the input's own points, not to --queries".into());
    }
    if c.exclude_self && matches!(kind, Kind::Pairs(_)) {
        return Err("--exclude-self does not apply to pairs: a point is never its own pair".into());
    }
    let query = QueryOptions {
        metric: c.metric,
        eps: c.eps,
        strict: c.strict,
    };
    query.validate()?;
    let cloud = c.input.read()?;
    let queries = match &c.queries {
        Some(q) => Some((q, read::cloud(q, c.input.from.map(Into::into))?)),
        None => None,
    };
    let name = c.input.input.display().to_string();
    let boxsize = c.boxsize.as_ref();
    let (tree, build_ms) = match &c.tree_file {
        Some(_) if boxsize.is_some() => {
            return Err(
                "--boxsize builds a periodic tree; a saved tree (--tree) keeps the box \
                        it was saved with (nbhd tree save --boxsize)"
                    .into(),
            )
        }
        Some(file) => load_tree(file, &cloud, &name)?,
        None => build_tree(&cloud, &c.tree.options(), boxsize, &name, out)?,
    };
    let opts = *tree.options();
    let length = match kind {
        Kind::Radius(l) | Kind::KnnRadius(_, l) | Kind::Pairs(l) => Some(l),
        Kind::Knn(_) => None,
    };
    let h = match length {
        Some(Length::Relative(_)) => Some(mean_spacing(&tree).context(&name)?),
        _ => None,
    };
    let radius = length.map(|l| l.resolve(h.unwrap_or(1.0)));
    let search = match (&kind, k, radius) {
        (Kind::Pairs(_), _, Some(radius)) => Search::Pairs(radius),
        (_, Some(k), None) => Search::Table(Neighborhood::Knn { k }),
        (_, None, Some(radius)) => Search::Table(Neighborhood::Radius {
            radius,
            sorted: true,
        }),
        (_, Some(k), Some(radius)) => Search::Table(Neighborhood::KnnRadius { k, radius }),
        (_, None, None) => unreachable!("every kind has k or a radius"),
    };
    let t = Instant::now();
    let table = {
        let _s = Progress::spinner(out, format!("computing {}", kind.name()));
        let queries = queries.as_ref().map(|(path, cloud)| (*path, cloud));
        let opts = TableOptions {
            exclude_self: c.exclude_self,
            threads: 0,
            query,
        };
        table(&tree, search, &opts, queries, &name)?
    };
    let facts = Facts {
        name,
        queries_file: c.queries,
        kind: kind.name(),
        k,
        length,
        h,
        radius,
        query,
        boxsize: tree.period().map(|p| p.sizes()),
        exclude_self: c.exclude_self,
        points: cloud.len(),
        tree: opts,
        tree_file: c.tree_file,
        stats: tree.stats(),
        table,
        build_ms,
        query_ms: ms(t),
    };
    write_result(c.output.as_deref(), &facts, out)
}

/// Builds the k-d tree of `cloud` (periodic over `boxsize` if given) under a spinner; returns
/// it and the milliseconds taken.
pub(crate) fn build_tree(
    cloud: &PointCloud,
    opts: &BuildOptions,
    boxsize: Option<&BoxSize>,
    name: &str,
    out: &Output,
) -> Result<(KdTree<f64>, f64)> {
    let view = cloud.view().context(name)?;
    let t = Instant::now();
    let tree = {
        let _s = Progress::spinner(
            out,
            format!("building the k-d tree of {} points", cloud.len()),
        );
        match boxsize {
            Some(boxsize) => {
                KdTree::<f64>::build_periodic(&view, opts, &boxsize.0).context(name)?
            }
            None => KdTree::<f64>::build(&view, opts).context(name)?,
        }
    };
    Ok((tree, ms(t)))
}

/// Loads the tree saved in `file` and checks that it holds exactly the points of `cloud` (read
/// from `name`) under their indices, bit for bit; returns it and the milliseconds taken.
fn load_tree(file: &Path, cloud: &PointCloud, name: &str) -> Result<(KdTree<f64>, f64)> {
    let t = Instant::now();
    let fname = file.display().to_string();
    let tree = KdTree::<f64>::load_file(file).context(&fname)?;
    let view = cloud.view().context(name)?;
    let refuse = |what: String| -> Result<(KdTree<f64>, f64)> {
        Err(format!("{fname}: the saved tree is not the tree of {name}: {what}").into())
    };
    if tree.dim() != view.dim() {
        return refuse(format!(
            "it is {}-dimensional, the input {}-dimensional",
            tree.dim(),
            view.dim()
        ));
    }
    if tree.source_len() != view.len() {
        return refuse(format!(
            "it was built over {} points, the input has {}",
            tree.source_len(),
            view.len()
        ));
    }
    let mut p = vec![0.0f64; view.dim()];
    for i in 0..view.len() {
        view.read_point(i, &mut p);
        let finite = p.iter().all(|c| c.is_finite());
        let same = match tree.point(i as u32) {
            Some(q) => finite && q.iter().zip(&p).all(|(a, b)| a.to_bits() == b.to_bits()),
            None => !finite,
        };
        if !same {
            return refuse(format!("point {i} differs"));
        }
    }
    Ok((tree, ms(t)))
}

/// What a command searches: a neighbourhood per point, or the pairs within a distance.
enum Search {
    Table(Neighborhood<f64>),
    Pairs(f64),
}

/// The neighbourhoods (or pairs) of the tree's own points, or of the points of the query file
/// (which must all be finite); errors of the search name the input file `name`.
fn table(
    tree: &KdTree<f64>,
    search: Search,
    opts: &TableOptions,
    queries: Option<(&PathBuf, &PointCloud)>,
    name: &str,
) -> Result<NeighborTable<f64>> {
    let Some((path, q)) = queries else {
        return match search {
            Search::Table(nbhd) => tree.neighborhoods(nbhd, opts).context(name),
            Search::Pairs(radius) => tree.pairs(radius, opts).context(name),
        };
    };
    let qname = path.display().to_string();
    let qv = q.view().context(&qname)?;
    if let Some((i, _)) = qv.first_non_finite() {
        return Err(format!("{qname}: query point {i} has a NaN or infinite coordinate").into());
    }
    match search {
        Search::Table(nbhd) => tree.neighborhoods_of(&qv, nbhd, opts).context(name),
        Search::Pairs(radius) => {
            // The queries' tree measures the pairs (its metric under `opts`, the input's box).
            let qtree = match tree.period() {
                Some(p) => KdTree::<f64>::build_periodic(&qv, tree.options(), &p.sizes()),
                None => KdTree::<f64>::build(&qv, tree.options()),
            }
            .context(&qname)?;
            qtree.pairs_with(tree, radius, opts).context(name)
        }
    }
}

impl Facts {
    /// The summary as JSON (without the rows).
    fn json(&self) -> serde_json::Value {
        json!({
            "input": self.name,
            "queries_file": self.queries_file.as_ref().map(|q| q.display().to_string()),
            "kind": self.kind,
            "k": self.k,
            "radius": self.radius.map(num),
            "radius_given": self.length.map(length_text),
            "spacing_h": self.h.map(num),
            "metric": self.query.metric.to_string(),
            "eps": num(self.query.eps),
            "strict": self.query.strict,
            "boxsize": self.boxsize,
            "exclude_self": self.exclude_self,
            "points": self.points,
            "skipped_non_finite": self.points - self.stats.points,
            "queries": self.table.len(),
            "tree": {
                "pivot": self.tree.pivot.name(),
                "median": self.tree.median.name(),
                "leaf_size": self.tree.leaf_size,
                "depth": self.stats.depth,
                "nodes": self.stats.nodes,
                "leaves": self.stats.leaves,
                "bytes": self.stats.bytes,
            },
            "tree_file": self.tree_file.as_ref().map(|f| f.display().to_string()),
            "build_ms": self.tree_file.is_none().then(|| num(self.build_ms)),
            "load_ms": self.tree_file.is_some().then(|| num(self.build_ms)),
            "query_ms": num(self.query_ms),
            "rows": {
                "min": self.table.min_row_len(),
                "mean": num(self.table.mean_row_len()),
                "max": self.table.max_row_len(),
                "total": self.table.total(),
            },
        })
    }

    /// The summary as text.
    fn text(&self) -> String {
        format!(
            "{}: {} of {} queries over {} points ({} skipped as non-finite){}{}: \
             neighbours per row min {} / mean {:.2} / max {}, total {}\n\
             tree {} / {} / leaf {}: depth {}, {} nodes, {} leaves, {} KiB, {} in {:.1} ms; \
             queries {:.1} ms",
            self.name,
            self.kind,
            self.table.len(),
            self.points,
            self.points - self.stats.points,
            self.k.map_or(String::new(), |k| format!(", k = {k}")),
            self.radius.map_or(String::new(), |r| format!(
                ", ε = {r}{}",
                self.h.map_or(String::new(), |h| format!(
                    " ({} with h = {h})",
                    length_text(self.length.unwrap())
                ))
            )),
            self.table.min_row_len(),
            self.table.mean_row_len(),
            self.table.max_row_len(),
            self.table.total(),
            self.tree.pivot.name(),
            self.tree.median.name(),
            self.tree.leaf_size,
            self.stats.depth,
            self.stats.nodes,
            self.stats.leaves,
            self.stats.bytes / 1024,
            self.tree_file
                .as_ref()
                .map_or("built".to_string(), |f| format!(
                    "loaded from {}",
                    f.display()
                )),
            self.build_ms,
            self.query_ms,
        )
    }
}

/// Writes the rows to `output` (CSV or JSON by its extension) or standard output, and the
/// summary as text or JSON.
fn write_result(output: Option<&Path>, facts: &Facts, out: &Output) -> Result<()> {
    let table = &facts.table;
    let summary = facts.json();
    let text = facts.text();
    match output {
        Some(path) => {
            let json_file = path
                .extension()
                .is_some_and(|e| e.eq_ignore_ascii_case("json"));
            let bar = Progress::bar(out, table.len() as u64, "writing");
            let res = if json_file {
                let mut doc = summary.clone();
                doc["neighbors"] = rows_json(table);
                std::fs::write(path, serde_json::to_string(&doc).expect("plain values"))
            } else {
                write_csv(path, table, &bar)
            };
            res.context(path.display())?;
            drop(bar);
            let mut doc = summary;
            doc["output"] = json!(path.display().to_string());
            out.json(&doc);
            out.text(format!("{text}\nwrote {}", path.display()));
        }
        None if out.json => {
            let mut doc = summary;
            doc["neighbors"] = rows_json(table);
            out.json(&doc);
        }
        None => {
            let stdout = std::io::stdout();
            let mut w = std::io::BufWriter::new(stdout.lock());
            // A closed pipe (`nbhd knn ... | head`) ends the output quietly.
            if write_rows(&mut w, table, &Progress::hidden()).is_ok() {
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
