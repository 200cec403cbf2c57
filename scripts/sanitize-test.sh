#!/usr/bin/env bash
# The C and C++ surfaces under AddressSanitizer + UndefinedBehaviorSanitizer: the ctests of the
# headers (<nbhd.hpp>, <nbhd_pcl.hpp>) and the C ABI tests (tests/c/*.c) are built once more
# with -fsanitize=address,undefined and run; any report fails (the first error aborts the
# program: -fno-sanitize-recover=all, abort_on_error=1, halt_on_error=1; leaks are reported at
# exit: detect_leaks=1). scripts/test.sh runs it after scripts/cpp-test.sh.
#
# The Rust library itself is not instrumented (that needs a nightly compiler); the programs are
# linked with -fsanitize=address, so the ASan runtime is loaded first and its allocator serves
# the library's allocations too: a program reading past a buffer nbhd made (a table's offsets,
# a result), or nbhd reading the caller's memory after it was freed, is reported. No LD_PRELOAD
# is needed.
#
# Environment:
#   CARGO_TARGET_DIR   as for cargo (default: target/); the build goes to <target>/cpp/sanitize
#   Extra arguments are passed to ctest (e.g. scripts/sanitize-test.sh -R pcl_safety).
set -euo pipefail
repo="$(cd "$(dirname "$0")/.." && pwd)"
cd "$repo"

target_dir="${CARGO_TARGET_DIR:-$repo/target}"
case "$target_dir" in /*) ;; *) target_dir="$repo/$target_dir" ;; esac
prefix="$target_dir/cpp/prefix"   # scripts/cpp-test.sh installs there too
build="$target_dir/cpp/sanitize"
data="$repo/tests/data"

for tool in cmake c++ cc; do
    command -v "$tool" >/dev/null 2>&1 || { echo "sanitize-test.sh: $tool is missing (scripts/test.sh installs it)" >&2; exit 1; }
done

san=(-fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer -g)
# Eigen's allocation must match Debian's (uninstrumented, C++14) PCL, which allocates and frees
# point clouds across the library boundary: under AddressSanitizer Eigen stops trusting glibc's
# malloc alignment and allocates with an offset of its own (PCL then frees the block with plain
# free(): "bad-free" in MovingLeastSquares), and under C++17 it drops the class operators
# new/delete that PCL's build uses (PCL's malloc, our global delete: "alloc-dealloc-mismatch").
# Both are told to do as in PCL's build, so the reports that remain are real.
eigen=(-DEIGEN_MALLOC_ALREADY_ALIGNED=1 -DEIGEN_HAS_CXX17_OVERALIGN=0)
export ASAN_OPTIONS="detect_leaks=1:abort_on_error=1:strict_string_checks=1:detect_stack_use_after_return=1:check_initialization_order=1"
export UBSAN_OPTIONS="halt_on_error=1:abort_on_error=1:print_stacktrace=1"

echo "== installing nbhd into $prefix (no-op when current)"
scripts/install.sh "$prefix" >/dev/null

# --- the headers' ctests ------------------------------------------------------------------------
# Programs with ctests that include <nbhd.hpp> or <nbhd_pcl.hpp>: the two written for this
# (test_pcl_safety, test_nbhd_hpp), nbhd::PclSearch under PCL's algorithms (test_pcl_backend:
# NormalEstimationOMP and FPFHEstimationOMP on threads, MLS, clusters, regions; a window of an
# organized scan with NaN holes and a torus), <nbhd.hpp> with OpenMesh (smooth_mesh) and
# against FLANN and PCL (compare_neighbors, one file; cpp-test.sh runs all of them unsanitized).
# The benchmarks' smoke runs add no path of the headers.
programs=(test_pcl_safety test_nbhd_hpp test_pcl_backend smooth_mesh compare_neighbors)
tests='^(pcl_safety|nbhd_hpp|pcl_backend_torus|pcl_backend_office1|smooth_mesh_fandisk|compare_bunny_(knn|radius|knn-radius))$'

echo "== configuring cpp_examples with -fsanitize=address,undefined"
cmake -S cpp_examples -B "$build" \
    -DCMAKE_BUILD_TYPE=Release \
    -DCMAKE_C_FLAGS="${san[*]}" \
    -DCMAKE_CXX_FLAGS="${san[*]} ${eigen[*]}" \
    -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=address,undefined" \
    -DCMAKE_PREFIX_PATH="$prefix" \
    -DNBHD_DATA_DIR="$data" \
    -DNBHD_CLI="$target_dir/release/nbhd" >"$build.configure.log" 2>&1 ||
    { cat "$build.configure.log"; exit 1; }
jobs="$(nproc 2>/dev/null || echo 2)"
echo "== building ${programs[*]}"
cmake --build "$build" -j "$jobs" --target "${programs[@]}"
echo "== ctest under the sanitizers"
(cd "$build" && ctest --output-on-failure -j "$jobs" -R "$tests" "$@")

# --- the C ABI tests ------------------------------------------------------------------------------
echo "== the C ABI tests (tests/c) under the sanitizers"
cdir="$build/c"
mkdir -p "$cdir/scratch"
for src in tests/c/*.c; do
    name="$(basename "$src" .c)"
    # As tests/c_abi.rs compiles them (no fused multiply-adds: the brute forces round as nbhd).
    cc -std=c99 -Wall -Wextra -Werror -pedantic -ffp-contract=off -O1 -pthread "${san[@]}" \
        -Iinclude "$src" -o "$cdir/$name" -L"$prefix/lib" -Wl,-rpath,"$prefix/lib" -lnbhd -lm
    case "$name" in
        dynamic_test | persist_test) args=("$cdir/scratch") ;;
        *) args=() ;;
    esac
    echo "   $name"
    "$cdir/$name" "${args[@]}" >"$cdir/$name.log" 2>&1 || {
        cat "$cdir/$name.log" >&2
        echo "sanitize-test.sh: tests/c/$name failed under the sanitizers (log $cdir/$name.log)" >&2
        exit 1
    }
done
echo "== sanitizers found nothing"
