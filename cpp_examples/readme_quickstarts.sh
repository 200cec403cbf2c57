#!/usr/bin/env bash
# ctest readme_quickstarts: the C and C++ quick starts of README.md and the PCL program of
# cpp_examples/README.md, exactly as they are shown. The marked code blocks
# (scripts/readme-snippet.sh) are written to the files the READMEs name, their build lines —
# pkg-config for C, the CMake package for C++ and PCL — run as they stand against the nbhd
# installed in PREFIX, with PREFIX and NBHD (the clone) set as the README's install step sets
# them, and each program's output must end with the output block printed after it. The
# README's one-line PCL example must be lines of that PCL program. So an edit that breaks a
# quick start, or changes what it prints, fails this test.
#
# Usage: readme_quickstarts.sh PREFIX WORKDIR     (WORKDIR is emptied first)
set -euo pipefail
if [ "$#" -ne 2 ]; then
    echo "usage: $0 PREFIX WORKDIR" >&2
    exit 2
fi
repo="$(cd "$(dirname "$0")/.." && pwd)"
export PREFIX="$1" NBHD="$repo"
rm -rf "$2"
mkdir -p "$2"
cd "$2"

readme="$repo/README.md"
snippet() { "$repo/scripts/readme-snippet.sh" "$readme" "$1"; }

# run BLOCK EXPECTED: runs the shell block BLOCK with bash (stopping at the first failing line)
# and checks that what it printed ends with the block EXPECTED.
run() {
    local script want got
    script="$(snippet "$1")"
    want="$(snippet "$2")"
    echo "== ${readme#"$repo"/}, block $1:"
    echo "$script" | sed 's/^/   /'
    if ! got="$(bash -euo pipefail -c "$script" 2>&1)"; then
        echo "$got"
        echo "readme_quickstarts: the README's block $1 failed" >&2
        exit 1
    fi
    if [[ "$got" != *"$want" ]]; then
        echo "$got"
        echo "readme_quickstarts: the output above does not end with the README's block $2:" >&2
        echo "$want" >&2
        exit 1
    fi
    echo "$want" | sed 's/^/   > /'
}

snippet c-quickstart >quickstart.c
run c-build c-output

snippet cpp-quickstart >quickstart.cpp
snippet cmake-quickstart >CMakeLists.txt
run cmake-build cpp-output

pcl_line="$(snippet pcl-line)"
readme="$repo/cpp_examples/README.md"
snippet pcl-quickstart >pcl_normals.cpp
snippet cmake-pcl >>CMakeLists.txt
run pcl-build pcl-output
while IFS= read -r line; do
    line="${line#"${line%%[![:space:]]*}"}"
    if [ -n "$line" ] && ! grep -qF -- "$line" pcl_normals.cpp; then
        echo "readme_quickstarts: README.md's PCL line is not in cpp_examples/README.md's program: $line" >&2
        exit 1
    fi
done <<<"$pcl_line"
echo "== the quick starts build and print what the READMEs say"
