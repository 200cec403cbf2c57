//! The `nbhd` command-line tool as a library: its subcommands (`commands`), the arguments,
//! reading, writing and error type they share, its output modes and the built-in point renderer.
//!
//! Layers, each using only those below it: `commands` → `args`, `read`, `write` → `render`,
//! `progress`, `output`, `error` → the nbhd library.

pub mod args;
pub mod commands;
pub mod error;
pub mod output;
pub mod progress;
pub mod read;
pub mod render;
pub mod write;
