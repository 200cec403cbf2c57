#!/usr/bin/env bash
# Fuzzes each reader of nbhd::io (PLY, PCD, PCD binary_compressed data, OBJ, XYZ, LAS/LAZ),
# the saved-tree loader (load_tree, fuzz/tree_bodies.rs) and
# the C ABI's build/query, table and smoothing entry points (abi_*, fuzz/abi_bodies.rs) and the
# SIMD forms of the dispatched loops against their portable forms and brute force (simd_*,
# fuzz/simd_bodies.rs) with cargo-fuzz (libFuzzer) for a few seconds each: scripts/test.sh runs
# it so.
#
#   scripts/fuzz.sh                 every target, FUZZ_SECONDS (default 5) each
#   FUZZ_SECONDS=600 scripts/fuzz.sh read_pcd     a longer run of one target
#
# cargo-fuzz needs nightly rustc flags; on the machine's stable toolchain RUSTC_BOOTSTRAP=1
# enables them (only for these builds). Sanitizers are off (-s none): the readers are safe
# Rust, and what the fuzzer looks for is a panic (a failed check of an abi_* body included), an
# abort (allocation failure) or a hang (-timeout). Seeds are tests/data/fuzz-seeds/<format> or
# <abi_target>; the growing corpus lives under the target directory; a crash is written to
# fuzz/artifacts/<target>/ and fails the run: keep it as a regression case in
# tests/data/fuzz-regressions/<format or abi_target>/ (tests/io_fuzz.rs and tests/abi_fuzz.rs
# read them).
set -euo pipefail
repo="$(cd "$(dirname "$0")/.." && pwd)"
cd "$repo"

if ! cargo fuzz --version >/dev/null 2>&1; then
    echo "== installing cargo-fuzz"
    cargo install --locked cargo-fuzz
fi

seconds="${FUZZ_SECONDS:-5}"
target_dir="${CARGO_TARGET_DIR:-$repo/target}"
case "$target_dir" in /*) ;; *) target_dir="$repo/$target_dir" ;; esac
export CARGO_TARGET_DIR="$target_dir/fuzz"
targets=("$@")
if [ "${#targets[@]}" -eq 0 ]; then
    targets=(read_ply read_pcd read_pcd_compressed read_obj read_xyz read_las
        abi_build_query abi_tables abi_smoothing load_tree simd_search simd_robust)
fi

echo "== building the fuzz targets"
RUSTC_BOOTSTRAP=1 cargo fuzz build --fuzz-dir fuzz -s none >/dev/null

for t in "${targets[@]}"; do
    seeds="tests/data/fuzz-seeds/${t#read_}"
    corpus="$target_dir/fuzz-corpus/$t"
    mkdir -p "$corpus"
    echo "== fuzzing $t for ${seconds}s (seeds $seeds)"
    log="$target_dir/fuzz-$t.log"
    if ! RUSTC_BOOTSTRAP=1 cargo fuzz run --fuzz-dir fuzz -s none "$t" "$corpus" "$seeds" -- \
        -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -max_len=65536 \
        -print_final_stats=1 >"$log" 2>&1; then
        tail -40 "$log" >&2
        echo "fuzz.sh: $t failed (a crash is in fuzz/artifacts/$t/; log $log)" >&2
        exit 1
    fi
    grep -E "^Done|stat::number_of_executed_units|stat::peak_rss_mb" "$log" || true
done
echo "== fuzzing passed"
