//! Any bytes given to the saved-tree loader (see fuzz/tree_bodies.rs): refused with an error,
//! or a tree that answers exactly; never a panic, abort or hang.
#![no_main]

use libfuzzer_sys::fuzz_target;

#[path = "../tree_bodies.rs"]
mod tree_bodies;

fuzz_target!(|data: &[u8]| tree_bodies::load_tree(data));
