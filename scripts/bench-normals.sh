#!/usr/bin/env bash
# The normals benchmark in one command (a benchmark, not a test; not run by scripts/test.sh):
# nbhd_estimate_normals against PCL's NormalEstimation / NormalEstimationOMP and
# nbhd_estimate_curvatures against PCL's NormalEstimation + PrincipalCurvaturesEstimation
# (cpp_examples/bench_normals.cpp), and Open3D's estimate_normals (scripts/bench_normals_open3d.py,
# Open3D installed from PyPI into a venv under the target directory, once), on the same torus of
# N points, one thread and T threads, median of R repetitions.
#
#   scripts/bench-normals.sh [N [R [T]]]      (defaults 1000000 3 2)
#
# Needs what scripts/cpp-test.sh needs, plus python3 with venv and pip. If the Open3D wheel
# cannot be installed, its rows say so and the rest still runs.
set -euo pipefail
repo="$(cd "$(dirname "$0")/.." && pwd)"
cd "$repo"
n="${1:-1000000}" reps="${2:-3}" threads="${3:-2}"
target_dir="${CARGO_TARGET_DIR:-$repo/target}"
case "$target_dir" in /*) ;; *) target_dir="$repo/$target_dir" ;; esac
prefix="$target_dir/cpp/prefix"
build="$target_dir/cpp/build"

scripts/install.sh "$prefix" >/dev/null
# NBHD_CLI only registers a ctest (scripts/cpp-test.sh passes the real tool); not built here
cmake -S cpp_examples -B "$build" -DCMAKE_PREFIX_PATH="$prefix" -DCMAKE_BUILD_TYPE=Release \
    -DNBHD_CLI="${NBHD_CLI:-$target_dir/dist/nbhd}" >/dev/null
cmake --build "$build" --target bench_normals -j "$(nproc)" >/dev/null

points="$target_dir/bench-normals-torus.f32"
echo "== $(date -u +%Y-%m-%d) torus of $n points, median of $reps (scripts/bench-normals.sh $n $reps $threads)"
"$build/bench_normals" --generated "$n" --reps "$reps" --threads "$threads" --write "$points"

venv="$target_dir/open3d-venv"
if ! "$venv/bin/python" -c 'import open3d' >/dev/null 2>&1; then
    python3 -m venv "$venv" && "$venv/bin/pip" install --quiet open3d numpy >/dev/null 2>&1 || true
fi
if "$venv/bin/python" -c 'import open3d' >/dev/null 2>&1; then
    version="$("$venv/bin/python" -c 'import open3d; print(open3d.__version__)')"
    for t in 1 "$threads"; do
        ms="$(OMP_NUM_THREADS=$t "$venv/bin/python" scripts/bench_normals_open3d.py "$points" "$reps")"
        echo "| Open3D $version estimate_normals(KNN 16) $t thread(s) | $ms | (wall ms, CPU ms)"
    done
    # Open3D runs more threads than OMP_NUM_THREADS allows (its CPU time is a multiple of its
    # wall time): pinned to one core, its wall time is what one core of it costs.
    if command -v taskset >/dev/null 2>&1; then
        ms="$(OMP_NUM_THREADS=1 taskset -c 0 "$venv/bin/python" scripts/bench_normals_open3d.py "$points" "$reps")"
        echo "| Open3D $version estimate_normals(KNN 16) pinned to one core (taskset -c 0) | $ms | (wall ms, CPU ms)"
    fi
else
    echo "| Open3D estimate_normals | not run: the open3d wheel could not be installed into $venv |"
fi
rm -f "$points"
