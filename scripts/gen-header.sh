#!/bin/sh
# Regenerates include/nbhd.h from src/ffi with cbindgen.toml, using the cbindgen library the
# tests use (so the result is exactly what tests/header.rs checks). The cbindgen CLI of the
# same version gives the same bytes from the ffi module alone:
#   cbindgen --config cbindgen.toml --output include/nbhd.h src/ffi/mod.rs
set -eu
cd "$(dirname "$0")/.."
NBHD_BLESS_HEADER=1 cargo test --quiet --test header header_is_current
echo "include/nbhd.h regenerated"
