//! `nbhd`, the command-line tool of the nbhd library. One module per subcommand under
//! `commands/` of the `nbhd_cli` library; to add one, add a variant to [`Command`], a module,
//! and a line in [`run`]. Every command returns `nbhd_cli::error::Result`; an error is printed
//! as `nbhd: error: …` and the exit status is 1 (2 for a command line clap refuses).

use clap::parser::ValueSource;
use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};
use nbhd_cli::commands;
use nbhd_cli::error::{Context, Result};
use nbhd_cli::output::Output;
use std::process::ExitCode;

const ABOUT: &str = "Exact neighbourhoods in point clouds, and the smoothing that needs them";

const LONG_ABOUT: &str = "\
nbhd computes exact neighbourhoods in point clouds with the k-d trees of M. Skrodzki, \
'Neighborhood Computation of Point Set Surfaces', and uses them to smooth scanned surfaces.

Without a command nbhd runs the demo (nbhd demo): noisy cube, torus and cylinder samples, k-d \
trees with every pivot policy, ε-k neighbourhoods, isotropic and anisotropic smoothing, PLY \
files and PNG pictures in ./nbhd-demo, and a summary of times and errors.

Terms of the neighbourhood and smoothing options, as in the thesis:
  ε (--radius)      influence radius: a neighbourhood holds the points within Euclidean
                    distance ε of the query point (inclusive)
  k (--k)           maximum valence: at most the k nearest of them (the ε-k neighbourhood)
  λ (--lambda)      curvature threshold of anisotropic smoothing
  Q (--quotient)    edge quotient of the feature detection (eq. 2.33)
  τ (--tau)         step size of one smoothing step (eq. 2.18)
  h                 mean spacing: mean distance of a point to its nearest other point;
                    lengths can be given in it (6h), curvatures in 1/h (0.2/h)

Files: PLY (ascii, binary), PCD (ascii, binary, binary_compressed), LAS/LAZ, OBJ (vertices) \
and XYZ text are read; PLY, PCD, LAS/LAZ and XYZ are written, with normals and per-point \
scalar fields (e.g. curvature) that MeshLab and CloudCompare can colour by (in LAS: extra \
bytes NormalX NormalY NormalZ, Curvature, ..., every point record kept). Points with NaN coordinates \
(holes of organized scans) are kept, so point indices are always the file's.";

/// Command line of `nbhd`.
#[derive(Parser, Debug)]
#[command(
    name = "nbhd",
    version,
    about = ABOUT,
    long_about = LONG_ABOUT
)]
struct Cli {
    /// Print the result as one JSON document on standard output, nothing else
    #[arg(long, global = true)]
    json: bool,

    /// Print no messages and no progress bars, only errors and the results that go to
    /// standard output (the JSON document with --json, neighbourhoods without --output)
    #[arg(long, short, global = true)]
    quiet: bool,

    /// Worker threads, 1 to 1024 [default: one per core]
    #[arg(long, global = true)]
    threads: Option<usize>,

    /// Names of the columns of a text (XYZ) input, e.g. x,y,z,r,g,b or x,y,z,nx,ny,nz; without
    /// it a header line names them (x y z / x,y,z / //X,Y,Z,R,G,B), else they are guessed from
    /// the values, and what was read is printed
    #[arg(long, global = true, value_delimiter = ',')]
    columns: Option<Vec<String>>,

    /// What to do [default: demo]
    #[command(subcommand)]
    command: Option<Command>,

    /// Without a command: the options of `nbhd demo`
    #[command(flatten, next_help_heading = "Demo options (without a command)")]
    demo: commands::demo::Args,
}

#[derive(Subcommand, Debug)]
enum Command {
    Demo(commands::demo::Args),
    Knn(commands::neighbors::KnnArgs),
    Radius(commands::neighbors::RadiusArgs),
    Neighbors(commands::neighbors::NeighborsArgs),
    Pairs(commands::neighbors::PairsArgs),
    /// PCA normals of every point over its ε-k neighbourhood (thesis eq. 2.8–2.10)
    ///
    /// Writes the input with normals (nx ny nz; normal_x normal_y normal_z in PCD) and curvature,
    /// PCL's surface variation λ0/(λ0+λ1+λ2) of the covariance, as float32 (--precision).
    Normals(commands::geometry::Args),
    /// Normals and curvatures of every point over its ε-k neighbourhood (thesis Section 2.2)
    ///
    /// Writes the input with normals and the scalar properties curvature (PCL's surface
    /// variation λ0/(λ0+λ1+λ2)), k1, k2 (principal curvatures, Weingarten estimate eq. 2.25,
    /// signed against the normal), mean_curvature ((k1+k2)/2) and max_abs_curvature
    /// (max(|k1|,|k2|), 'Max Princ'), which MeshLab and CloudCompare colour by.
    Curvature(commands::geometry::Args),
    Smooth(commands::smooth::Args),
    Tiles(commands::tiles::Args),
    Bench(commands::bench::Args),
    Info(commands::info::Args),
    Convert(commands::convert::Args),
    Render(commands::render::Args),
    Crop(commands::filter::CropArgs),
    Sor(commands::filter::SorArgs),
    Ror(commands::filter::RorArgs),
    Voxel(commands::filter::VoxelArgs),
    Tree(commands::tree::Args),
}

fn run(cli: Cli) -> Result<()> {
    let out = Output::new(cli.json, cli.quiet);
    nbhd_cli::read::set_context(out, cli.columns.clone());
    if let Some(t) = cli.threads {
        if t == 0 {
            return Err("--threads must be at least 1".into());
        }
        if t > nbhd::MAX_THREADS {
            return Err(format!(
                "--threads {t} is above the maximum of {} worker threads",
                nbhd::MAX_THREADS
            )
            .into());
        }
        rayon_threads(t)?;
    }
    use commands::geometry::What;
    match cli.command {
        None => commands::demo::run(cli.demo, &out),
        Some(Command::Demo(a)) => commands::demo::run(a, &out),
        Some(Command::Knn(a)) => commands::neighbors::run_knn(a, &out),
        Some(Command::Radius(a)) => commands::neighbors::run_radius(a, &out),
        Some(Command::Neighbors(a)) => commands::neighbors::run_neighbors(a, &out),
        Some(Command::Pairs(a)) => commands::neighbors::run_pairs(a, &out),
        Some(Command::Normals(a)) => commands::geometry::run(a, What::Normals, &out),
        Some(Command::Curvature(a)) => commands::geometry::run(a, What::Curvature, &out),
        Some(Command::Smooth(a)) => commands::smooth::run(a, &out),
        Some(Command::Tiles(a)) => commands::tiles::run(a, &out),
        Some(Command::Bench(a)) => commands::bench::run(a, &out),
        Some(Command::Info(a)) => commands::info::run(a, &out),
        Some(Command::Convert(a)) => commands::convert::run(a, &out),
        Some(Command::Render(a)) => commands::render::run(a, &out),
        Some(Command::Crop(a)) => commands::filter::run_crop(a, &out),
        Some(Command::Sor(a)) => commands::filter::run_sor(a, &out),
        Some(Command::Ror(a)) => commands::filter::run_ror(a, &out),
        Some(Command::Voxel(a)) => commands::filter::run_voxel(a, &out),
        Some(Command::Tree(a)) => commands::tree::run(a, &out),
    }
}

/// Sizes the global rayon pool that the library's parallel loops run on.
fn rayon_threads(n: usize) -> Result<()> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .build_global()
        .context(format!("could not create {n} threads"))
}

/// Parses the command line; the demo's options are refused after a command.
fn parse() -> Cli {
    let matches = Cli::command().get_matches();
    let cli = Cli::from_arg_matches(&matches).unwrap_or_else(|e| e.exit());
    if cli.command.is_some() {
        let demo = <commands::demo::Args as clap::Args>::augment_args(clap::Command::new("demo"));
        for arg in demo.get_arguments() {
            if matches.value_source(arg.get_id().as_str()) == Some(ValueSource::CommandLine) {
                let name = arg.get_long().unwrap_or(arg.get_id().as_str());
                Cli::command()
                    .error(
                        clap::error::ErrorKind::ArgumentConflict,
                        format!("--{name} is an option of the demo: put it after `nbhd demo`, or leave out the command"),
                    )
                    .exit();
            }
        }
    }
    cli
}

fn main() -> ExitCode {
    let cli = parse();
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("nbhd: error: {e}");
            ExitCode::FAILURE
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn command_line_definition_is_consistent() {
        Cli::command().debug_assert();
    }
}
