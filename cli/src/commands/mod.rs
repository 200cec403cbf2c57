//! One module per subcommand: each has `Args` (clap) and `run(args, &Output)`.

pub mod convert;
pub mod info;
pub mod render;

use nbhd::io::Format;

/// Input format named on the command line.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum FormatArg {
    Ply,
    Pcd,
    Obj,
    Xyz,
}

impl From<FormatArg> for Format {
    fn from(f: FormatArg) -> Self {
        match f {
            FormatArg::Ply => Format::Ply,
            FormatArg::Pcd => Format::Pcd,
            FormatArg::Obj => Format::Obj,
            FormatArg::Xyz => Format::Xyz,
        }
    }
}

/// Parses `x,y,z`.
pub fn parse_vec3(s: &str) -> Result<[f64; 3], String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|t| t.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("'{s}' is not three numbers x,y,z"))?;
    <[f64; 3]>::try_from(v).map_err(|_| format!("'{s}' is not three numbers x,y,z"))
}
