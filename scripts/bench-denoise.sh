#!/usr/bin/env bash
# The denoising protocol in one command (a benchmark, not a test; not run by scripts/test.sh):
# the robust mode's defaults against PCL's MovingLeastSquares (radius 5h, order 2) and CGAL's
# jet smoothing (k = 24) on the same clouds in the same run, one thread each, and the table of
# docs/smoothing-results.md ("The denoising protocol").
#
#   scripts/bench-denoise.sh [MESH...]
#
# Meshes: by default eight meshes of Debian's libcgal-demo (none among the PU-Net test shapes
# of the learned denoisers' papers), read from its data archive, and the analytic cube and
# torus of src/shapes. Each is normalised to the unit sphere, sampled by Poisson disk at 10K
# and 50K points (seeded), and given isotropic Gaussian noise of 1, 2 and 3 % of the radius
# (examples/denoise_protocol.rs); cpp_examples/bench_denoise.cpp smooths every cloud with each
# method; denoise_protocol --evaluate measures CD and P2M exactly and prints the table.
#
# Needs what scripts/cpp-test.sh needs, plus libcgal-dev and libcgal-demo (apt-get install).
# Takes about 5 minutes on two cores besides the builds; the work files go to target/denoise.
set -euo pipefail
repo="$(cd "$(dirname "$0")/.." && pwd)"
cd "$repo"
target_dir="${CARGO_TARGET_DIR:-$repo/target}"
case "$target_dir" in /*) ;; *) target_dir="$repo/$target_dir" ;; esac
prefix="$target_dir/cpp/prefix"
build="$target_dir/cpp/build"
work="$target_dir/denoise"

archive=/usr/share/doc/libcgal-dev/data.tar.gz
cgal_meshes="armadillo bunny00 ChineseDragon-10kv bull homer triceratops rotor turbine"
if [ "$#" -gt 0 ]; then
    meshes=("$@")
else
    [ -f "$archive" ] || { echo "bench-denoise.sh: $archive is missing (apt-get install libcgal-demo)" >&2; exit 1; }
    mkdir -p "$work"
    tar -xzf "$archive" -C "$work" $(for m in $cgal_meshes; do echo "data/meshes/$m.off"; done)
    meshes=()
    for m in $cgal_meshes; do meshes+=("$work/data/meshes/$m.off"); done
    meshes+=(cube torus)
fi

echo "== building (nbhd, its C++ benchmark, the protocol's example)"
# the release profile (the same code as the installed dist profile, shared with the example)
NBHD_KEEP_SYMBOLS=1 scripts/install.sh "$prefix" >/dev/null
cmake -S cpp_examples -B "$build" -DCMAKE_PREFIX_PATH="$prefix" -DCMAKE_BUILD_TYPE=Release \
    -DNBHD_CLI="${NBHD_CLI:-$target_dir/release/nbhd}" >/dev/null
cmake --build "$build" --target bench_denoise -j "$(nproc)" >/dev/null
cargo build --release --example denoise_protocol
protocol="$target_dir/release/examples/denoise_protocol"

clouds="$work/clouds"
rm -rf "$clouds"
echo "== sampling and noise ($(date -u '+%Y-%m-%d %H:%M UTC'))"
"$protocol" --prepare "$clouds" "${meshes[@]}" >/dev/null
echo "== smoothing, one thread per method (cpp_examples/bench_denoise)"
names=()
for f in "$clouds"/*.noisy.f64; do names+=("$(basename "$f" .noisy.f64)"); done
LD_LIBRARY_PATH="$prefix/lib" "$build/bench_denoise" "$clouds" "${names[@]}"
echo "== CD and P2M (x 1e4), mean over the meshes"
"$protocol" --evaluate "$clouds" --per-shape "${meshes[@]}"
