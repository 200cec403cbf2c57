//! The `nbhd` command-line tool as a library: its subcommands (`commands`), the arguments,
//! reading, writing and error type they share, its output modes and the built-in point renderer.
//!
//! The modules form layers without a circle: `commands` uses `args` (which reads through
//! `read`), `write` (which draws through `render`), `render`, `progress` and `output`; `read` and
//! `progress` use `output`; every module may use `error`; none uses `commands`, and no command
//! module uses another (`bench` holds its two benchmarks as submodules).

pub mod args;
pub mod commands;
pub mod error;
pub mod output;
pub mod progress;
pub mod read;
pub mod render;
pub mod write;
