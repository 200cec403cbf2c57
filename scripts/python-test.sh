#!/usr/bin/env bash
# Builds and tests the Python package `nbhd` (python/): a virtual environment under the cargo
# target directory (created once, scripts/python-env.sh), maturin, numpy, scipy and pytest
# installed into it only when missing, the binding crate formatted and linted (a workspace of
# its own, see python/Cargo.toml), the package built in release mode and installed with pip exactly as a user
# does (the wheel scripts/wheel-build.sh builds from the sdist), then the pytest
# suite (with nbhd.dask's tests on a LocalCluster) — with the command-line tool built, so
# that the geometry is compared with the Rust results the CLI writes.
#
# Idempotent: a second run reuses the environment and cargo's incremental build.
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/step.sh
root=$PWD
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-$root/target}"
# the venv under the target directory, shared with scripts/test.sh (scripts/python-env.sh);
# import name=pip requirement (dask and distributed: the tests of nbhd.dask on a LocalCluster)
. scripts/python-env.sh
nbhd_python_env maturin numpy scipy pytest "dask.array=dask[array]" distributed
# scipy pinned: python/tests/test_scipy_suite.py runs this version's own k-d tree tests on
# nbhd.spatial (its expected failure is that version's), beside scipy's run of them
scipy_version=1.17.1
if [ "$(python -c 'import scipy; print(scipy.__version__)')" != "$scipy_version" ]; then
    echo "== installing scipy==$scipy_version into the Python environment"
    python -m pip install --quiet --disable-pip-version-check "scipy==$scipy_version"
fi

# python/ is a Cargo workspace of its own, built in a target directory of its own: nbhd is also a
# cdylib, so its release rlib's file name carries no hash (target/release/deps/libnbhd.rlib), and
# in a shared directory the root workspace's build of it (against its own glam) would stand in
# for python/'s whenever the root built last ("expected `DVec3`, found `glam::f64::dvec3::DVec3`").
py_target="$CARGO_TARGET_DIR/python"

step "python/: cargo fmt --check, clippy"
cargo fmt --manifest-path python/Cargo.toml -- --check
CARGO_TARGET_DIR="$py_target" cargo clippy --manifest-path python/Cargo.toml --all-targets -- -D warnings

step "pip install the wheel built from the sdist (scripts/wheel-build.sh: maturin, release)" "the first time about 3 CPU-minutes (docs/setup-costs.md)"
wheel=$(scripts/wheel-build.sh)
python -m pip install --quiet --disable-pip-version-check --force-reinstall --no-deps "$wheel"

step "the command-line tool, for the comparisons with the Rust results"
cargo build --quiet -p nbhd-cli
export NBHD_CLI="$CARGO_TARGET_DIR/debug/nbhd" NBHD_REQUIRE_CLI=1

step "pytest python/tests"
# run from the repository root: python/ itself would shadow the installed package. The tests'
# scratch files (the Dask tests' tiles: about 1 GB) live under the target directory, which
# pytest empties at the start of each run, not in /tmp.
python -m pytest -q -p no:cacheprovider --rootdir python --basetemp "$CARGO_TARGET_DIR/pytest" \
    python/tests

step "scipy's own k-d tree tests on scipy: the baseline of python/tests/test_scipy_suite.py"
(cd "$CARGO_TARGET_DIR" && python -m pytest -q -p no:cacheprovider --pyargs scipy.spatial.tests.test_kdtree)
step_end
