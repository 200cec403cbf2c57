//! `nbhd`, the command-line tool of the nbhd library. One module per subcommand under
//! `commands/` of the `nbhd_cli` library; to add one, add a variant to [`Command`], a module,
//! and a line in [`run`].

use clap::{Parser, Subcommand};
use nbhd_cli::commands;
use nbhd_cli::output::Output;
use std::process::ExitCode;

const ABOUT: &str = "Exact neighbourhoods in point clouds, and the smoothing that needs them";

const LONG_ABOUT: &str = "\
nbhd computes exact neighbourhoods in point clouds with the k-d trees of M. Skrodzki, \
'Neighborhood Computation of Point Set Surfaces', and uses them to smooth scanned surfaces.

Terms of the neighbourhood and smoothing options, as in the thesis:
  ε (--radius)      influence radius: a neighbourhood holds the points within Euclidean
                    distance ε of the query point (inclusive)
  k (--k)           maximum valence: at most the k nearest of them (the ε-k neighbourhood)
  λ (--lambda)      curvature threshold of anisotropic smoothing
  Q (--quotient)    edge quotient of the feature detection

Files: PLY (ascii, binary), PCD (ascii, binary, binary_compressed), OBJ (vertices) and XYZ \
text are read; PLY, PCD and XYZ are written, with normals and per-point scalar fields \
(e.g. curvature) that MeshLab and CloudCompare can colour by. Points with NaN coordinates \
(holes of organized scans) are kept, so point indices are always the file's.";

/// Command line of `nbhd`.
#[derive(Parser, Debug)]
#[command(name = "nbhd", version, about = ABOUT, long_about = LONG_ABOUT)]
struct Cli {
    /// Print the result as one JSON document on standard output, nothing else
    #[arg(long, global = true)]
    json: bool,

    /// Print nothing but errors (and the JSON document if --json is given)
    #[arg(long, short, global = true)]
    quiet: bool,

    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    Info(commands::info::Args),
    Convert(commands::convert::Args),
    Render(commands::render::Args),
}

fn run(cli: Cli) -> Result<(), String> {
    let out = Output::new(cli.json, cli.quiet);
    match cli.command {
        Command::Info(a) => commands::info::run(a, &out),
        Command::Convert(a) => commands::convert::run(a, &out),
        Command::Render(a) => commands::render::run(a, &out),
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
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
    use clap::CommandFactory;

    #[test]
    fn command_line_definition_is_consistent() {
        Cli::command().debug_assert();
    }
}
