//! One module per subcommand: each has `Args` (clap) and `run(args, &Output)`. Commands depend on
//! the shared modules (`args`, `read`, `write`, `output`, `progress`, `render`, `error`), never
//! on each other; `bench` holds its two benchmarks as submodules.

pub mod bench;
pub mod convert;
pub mod demo;
pub mod filter;
pub mod geometry;
pub mod info;
pub mod neighbors;
pub mod render;
pub mod smooth;
pub mod tiles;
pub mod tree;
