//! The `nbhd` command-line tool as a library: its subcommands, output modes and the built-in
//! point renderer, so that other commands (and tests) can reuse them.

pub mod commands;
pub mod output;
pub mod progress;
pub mod render;
