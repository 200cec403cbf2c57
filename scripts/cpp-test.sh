#!/usr/bin/env bash
# Builds nbhd, installs it into a build-local prefix, builds the C++ examples against that
# installation (find_package(nbhd) through CMAKE_PREFIX_PATH) and runs their tests with ctest:
# nbhd's neighbourhoods compared with FLANN's and PCL's on the real data in tests/data, and
# a program linked against the static library.
#
# Needs cmake, g++, libflann-dev, libpcl-dev, libopenmesh-dev, libnanoflann-dev, libeigen3-dev,
# liblz4-dev, libcgal-dev (bench_denoise; scripts/test.sh installs them when missing).
#
# Environment:
#   NBHD_DATA_DIR   the data directory (default: tests/data of the repository)
#   CTEST_PARALLEL  ctest jobs (default: number of cores)
#   Extra arguments are passed to ctest (e.g. scripts/cpp-test.sh -R bunny).
set -euo pipefail
repo="$(cd "$(dirname "$0")/.." && pwd)"
cd "$repo"

target_dir="${CARGO_TARGET_DIR:-$repo/target}"
case "$target_dir" in /*) ;; *) target_dir="$repo/$target_dir" ;; esac
prefix="$target_dir/cpp/prefix"
build="$target_dir/cpp/build"

data="${NBHD_DATA_DIR:-$repo/tests/data}"
if [ ! -d "$data/pcl" ] || [ ! -d "$data/meshes" ]; then
    echo "cpp-test.sh: no data at $data (expected pcl/*.pcd and meshes/*.obj; tests/data is the default)" >&2
    exit 1
fi
data="$(cd "$data" && pwd)"

for tool in cmake c++ pkg-config; do
    command -v "$tool" >/dev/null 2>&1 || { echo "cpp-test.sh: $tool is missing (scripts/test.sh installs it)" >&2; exit 1; }
done

echo "== installing nbhd into $prefix"
scripts/install.sh "$prefix"

# Installs are release-grade (scripts/install.sh): no debug sections in either library, the
# C++ header next to the C header, and the shared library still exporting the C API.
echo "== checking the installed files (stripped, nbhd.hpp present)"
so_file="$(readlink -f "$prefix/lib/libnbhd.so")"
if [ "${NBHD_KEEP_SYMBOLS:-0}" != 1 ]; then
    for lib in "$so_file" "$prefix/lib/libnbhd.a"; do
        if readelf -S "$lib" | grep -q '\.debug'; then
            echo "cpp-test.sh: $lib has debug sections (readelf -S); installs must be stripped" >&2
            exit 1
        fi
    done
    if readelf -S "$so_file" | grep -q '\.symtab'; then
        echo "cpp-test.sh: $so_file still has a symbol table (.symtab)" >&2
        exit 1
    fi
fi
if ! nm -D --defined-only "$so_file" | grep -q ' T nbhd_tree_build$'; then
    echo "cpp-test.sh: $so_file does not export nbhd_tree_build" >&2
    exit 1
fi
for h in nbhd.h nbhd.hpp nbhd_pcl.hpp; do
    if ! cmp -s "include/$h" "$prefix/include/nbhd/$h"; then
        echo "cpp-test.sh: $prefix/include/nbhd/$h is missing or differs from include/$h" >&2
        exit 1
    fi
done
ls -l "$so_file" "$prefix/lib/libnbhd.a" | awk '{ print "   " $5 " bytes  " $NF }'

# The command-line tool writes the files that pcl_loads_nbhd_files loads with PCL.
echo "== building the nbhd command-line tool (release)"
cargo build --release -p nbhd-cli --quiet
nbhd_cli="$target_dir/release/nbhd"

echo "== configuring cpp_examples (Release, -O2, no -march=native)"
cmake -S cpp_examples -B "$build" \
    -DCMAKE_BUILD_TYPE=Release \
    -DCMAKE_PREFIX_PATH="$prefix" \
    -DNBHD_DATA_DIR="$data" \
    -DNBHD_CLI="$nbhd_cli" >"$build.configure.log" 2>&1 || { cat "$build.configure.log"; exit 1; }
grep -E "nbhd [0-9]|Found PCL|Found flann" "$build.configure.log" || true

jobs="$(nproc 2>/dev/null || echo 2)"
echo "== building cpp_examples"
cmake --build "$build" -j "$jobs"

# The pkg-config file must give a working link line too: build a C program with it alone.
echo "== linking a C program with pkg-config --cflags --libs nbhd"
pc_out="$build/pkgconfig_check"
# shellcheck disable=SC2046
cc -O2 -o "$pc_out" cpp_examples/link_check.c \
    $(PKG_CONFIG_PATH="$prefix/lib/pkgconfig" pkg-config --cflags --libs nbhd) \
    -Wl,-rpath,"$prefix/lib"
"$pc_out"
# shellcheck disable=SC2046
cc -O2 -o "$pc_out-static" cpp_examples/link_check.c \
    $(PKG_CONFIG_PATH="$prefix/lib/pkgconfig" pkg-config --cflags --libs nbhd-static)
if readelf -d "$pc_out-static" | grep -q 'libnbhd'; then
    echo "cpp-test.sh: nbhd-static.pc linked libnbhd dynamically" >&2
    exit 1
fi
"$pc_out-static"

# The C++ header compiles with nothing but the pkg-config file's flags.
echo "== compiling <nbhd.hpp> with pkg-config --cflags nbhd (C++14)"
# shellcheck disable=SC2046
printf '#include <nbhd.hpp>\nint main() { nbhdpp::check(nbhd_version() == NBHD_VERSION ? NBHD_STATUS_OK : NBHD_STATUS_INVALID_ARGUMENT, "version"); return 0; }\n' |
    c++ -std=c++14 -Wall -Wextra -Werror -x c++ -o "$pc_out-hpp" - \
        $(PKG_CONFIG_PATH="$prefix/lib/pkgconfig" pkg-config --cflags --libs nbhd) -Wl,-rpath,"$prefix/lib"
"$pc_out-hpp"

# The shared library carries a SONAME (build.rs); programs linked against it, through the CMake
# package or pkg-config, must record that name and not a bare libnbhd.so.
soname="$(readelf -d "$prefix/lib/libnbhd.so" | sed -n 's/.*(SONAME).*\[\(.*\)\].*/\1/p')"
echo "== checking that programs record the SONAME ${soname:-(none)}"
case "$soname" in
    libnbhd.so.?*) ;;
    *) echo "cpp-test.sh: $prefix/lib/libnbhd.so has no versioned SONAME ('$soname')" >&2; exit 1 ;;
esac
for exe in "$build/link_shared" "$build/compare_neighbors" "$pc_out"; do
    needed="$(readelf -d "$exe" | sed -n 's/.*(NEEDED).*\[\(libnbhd[^]]*\)\].*/\1/p')"
    if [ "$needed" != "$soname" ]; then
        echo "cpp-test.sh: $exe needs '$needed', expected the SONAME '$soname'" >&2
        exit 1
    fi
done

echo "== ctest"
cd "$build"
ctest --output-on-failure -j "${CTEST_PARALLEL:-$jobs}" "$@"
