#!/usr/bin/env bash
# Runs every test of nbhd on a fresh machine: installs what is missing (Debian packages), then
# formatting, lints, the Rust tests (which include the C ABI checks: a C program against the
# cdylib, under valgrind, and a threaded C test), the C++ comparisons under ctest, and the C and
# C++ tests again under AddressSanitizer + UndefinedBehaviorSanitizer.
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/step.sh

# --- system packages --------------------------------------------------------------------
apt_install() {
    local sudo=""
    [ "$(id -u)" -eq 0 ] || sudo="sudo"
    step "installing $# Debian packages and what they need: $*"
    $sudo apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "$@" >/dev/null
}
missing=()
command -v cc >/dev/null 2>&1 || missing+=(gcc libc6-dev)
command -v valgrind >/dev/null 2>&1 || missing+=(valgrind)
command -v python3 >/dev/null 2>&1 || missing+=(python3)
python3 -c 'import ensurepip' >/dev/null 2>&1 || missing+=(python3-venv)  # Debian's venv
# cli/tests/cloudcompare.rs: Debian's CloudCompare opens nbhd's files on its command line (Xvfb)
command -v CloudCompare >/dev/null 2>&1 || missing+=(cloudcompare)
command -v xvfb-run >/dev/null 2>&1 || missing+=(xvfb)
if [ -f cpp_examples/CMakeLists.txt ]; then
    command -v cmake >/dev/null 2>&1 || missing+=(cmake)
    command -v c++ >/dev/null 2>&1 || missing+=(g++)
    command -v pkg-config >/dev/null 2>&1 || missing+=(pkg-config)  # cpp-test.sh checks nbhd.pc
    for pkg in libflann-dev libpcl-dev libopenmesh-dev libnanoflann-dev libeigen3-dev liblz4-dev libcgal-dev; do
        dpkg -s "$pkg" >/dev/null 2>&1 || missing+=("$pkg")
    done
fi
if [ "${#missing[@]}" -gt 0 ]; then apt_install "${missing[@]}"; fi

# --- Python: laspy reads nbhd's LAS/LAZ files in tests/io_las.rs -------------------------
# into the venv under target/ that scripts/python-test.sh uses too; NBHD_PYTHON names it
step "the Python environment for laspy (target/pyenv)"
. scripts/python-env.sh
nbhd_python_env "laspy=laspy[lazrs]" lazrs
export NBHD_REQUIRE_LASPY=1

# --- Rust ---------------------------------------------------------------------------------
# Disk: CI's machine has a few GB to spare. Incremental caches and full debug information of
# every test binary took 13 GB of target/debug; line tables keep backtraces' file:line.
export CARGO_INCREMENTAL="${CARGO_INCREMENTAL:-0}"
export CARGO_PROFILE_DEV_DEBUG="${CARGO_PROFILE_DEV_DEBUG:-line-tables-only}"
export CARGO_PROFILE_TEST_DEBUG="${CARGO_PROFILE_TEST_DEBUG:-line-tables-only}"
step "cargo fmt --check"
cargo fmt --all -- --check
step "cargo clippy" "the first time about 1.5 min on 2 free cores"
cargo clippy --workspace --all-targets -- -D warnings
step "cargo test" "the first time about 15 min on 2 free cores (the build of every test binary), then about 12"
# valgrind was installed above: its memcheck runs of the C ABI tests must not be skipped.
export NBHD_REQUIRE_VALGRIND=1
export NBHD_REQUIRE_CLOUDCOMPARE=1  # installed above: its test must not be skipped
# cli/tests/readme.rs runs the README's `cargo install --path cli --profile dist` (the dist
# build of the tool that scripts/cpp-test.sh reuses below)
export NBHD_TEST_INSTALL=1
cargo test --workspace

# --- the Python package (python/): built with maturin, installed by pip, tested by pytest ----
step "the Python package (scripts/python-test.sh)" "about 3 min"
scripts/python-test.sh
step "the wheel: auditwheel, a fresh venv without cargo, stubs (scripts/wheel-test.sh)"
scripts/wheel-test.sh

# --- fuzzing: a few seconds of each reader of nbhd::io and of the C ABI (scripts/fuzz.sh) -----
step "fuzzing the file readers and the C ABI (scripts/fuzz.sh, FUZZ_SECONDS=${FUZZ_SECONDS:-5} each)" "about 3.5 min"
scripts/fuzz.sh

# --- C++ examples under ctest ---------------------------------------------------------------
if [ -f cpp_examples/CMakeLists.txt ]; then
    step "the C and C++ examples (scripts/cpp-test.sh)" "about 3 min"
    scripts/cpp-test.sh
    # The headers' ctests and the C ABI tests once more under AddressSanitizer +
    # UndefinedBehaviorSanitizer (the library cpp-test.sh installed; any report fails).
    step "the C and C++ surfaces under the sanitizers (scripts/sanitize-test.sh)" "about 2.5 min"
    scripts/sanitize-test.sh
fi
step "the MeshLab plugin (scripts/meshlab-test.sh)"
scripts/meshlab-test.sh  # the MeshLab plugin in Debian's meshlabserver (installs what it needs)
step_end
echo "== all tests passed"
