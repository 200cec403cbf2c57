#!/usr/bin/env bash
# Builds the release artefacts of the Python package `nbhd`: the source distribution (maturin
# sdist of pyproject.toml at the repository root) and, FROM that sdist, the binary wheel — so the
# one release compile proves both that the sdist builds and what the wheel holds. Prints the
# wheel's path on stdout (messages go to stderr). Used by scripts/python-test.sh (which installs
# the wheel) and scripts/wheel-test.sh (which checks it in a fresh environment).
#
# Out: $CARGO_TARGET_DIR/wheel/dist/nbhd-<version>.tar.gz and nbhd-<version>-cp39-abi3-<platform>.whl
# (abi3: the extension uses CPython's stable ABI from 3.9 on, PyO3's feature abi3-py39 in
# python/Cargo.toml, so the one wheel serves every CPython >= 3.9).
#
# The sdist is unpacked into a fixed directory and only files whose content changed are
# rewritten: its members all carry the same old timestamp, and cargo decides what to rebuild by
# timestamps, so a plain unpack would either rebuild everything each run (new timestamps) or
# nothing (the old ones). The cargo target directory is python/'s own ($CARGO_TARGET_DIR/python,
# see scripts/python-test.sh), so the dependencies' release builds are shared.
#
# Needs the environment of scripts/python-env.sh (maturin and pip on PATH).
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
target="${CARGO_TARGET_DIR:-$root/target}"
case "$target" in /*) ;; *) target="$root/$target" ;; esac
export CARGO_TARGET_DIR="$target"  # maturin sdist runs cargo too: not into python/target
out="$target/wheel"
dist="$out/dist"
rm -rf "$dist" "$out/unpacked"
mkdir -p "$dist" "$out/unpacked" "$out/src"

echo "== maturin sdist" >&2
maturin sdist --out "$dist" >&2
sdist=$(ls "$dist"/nbhd-*.tar.gz)
tar -xzf "$sdist" -C "$out/unpacked"
name=$(basename "$sdist" .tar.gz)
# $out/src/$name mirrors the sdist; unchanged files keep the timestamps of their first unpack
python - "$out/unpacked/$name" "$out/src/$name" <<'EOF'
import filecmp, os, shutil, sys
new, old = sys.argv[1], sys.argv[2]
keep = set()
for dirpath, _, files in os.walk(new):
    rel = os.path.relpath(dirpath, new)
    os.makedirs(os.path.join(old, rel), exist_ok=True)
    for f in files:
        src, dst = os.path.join(dirpath, f), os.path.join(old, rel, f)
        keep.add(os.path.normpath(os.path.join(rel, f)))
        if not (os.path.isfile(dst) and filecmp.cmp(src, dst, shallow=False)):
            shutil.copyfile(src, dst)  # copyfile: the timestamp becomes now
for dirpath, _, files in os.walk(old):
    for f in files:
        rel = os.path.normpath(os.path.relpath(os.path.join(dirpath, f), old))
        if rel not in keep:
            os.remove(os.path.join(old, rel))
EOF
rm -rf "$out/unpacked"

echo "== the wheel, built from the sdist (pip wheel: PEP 517, maturin, release)" >&2
CARGO_TARGET_DIR="$target/python" python -m pip wheel --quiet --disable-pip-version-check \
    --no-deps --no-build-isolation --wheel-dir "$dist" "$out/src/$name" >&2
ls "$dist"/nbhd-*.whl
