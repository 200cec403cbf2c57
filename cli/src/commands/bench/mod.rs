//! `nbhd bench`: the benchmarks. `thesis` reproduces the computational results of the
//! thesis' Chapter 8; `speed` sets nbhd side by side with the Rust peers.

pub mod speed;
pub mod thesis;

use crate::error::Result;
use crate::output::Output;

pub use speed::SpeedArgs;
pub use thesis::ThesisArgs;

/// Benchmarks
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(subcommand)]
    pub which: Which,
}

#[derive(clap::Subcommand, Debug)]
pub enum Which {
    Thesis(ThesisArgs),
    Speed(SpeedArgs),
}

pub fn run(a: Args, out: &Output) -> Result<()> {
    match a.which {
        Which::Thesis(t) => thesis::run(t, out),
        Which::Speed(s) => speed::run(s, out),
    }
}
