# The one Python environment of the tests, shared by scripts/test.sh (laspy for tests/io_las.rs)
# and scripts/python-test.sh (maturin, numpy, scipy, pytest, dask for python/tests). Sourced, not
# run:
#
#   . scripts/python-env.sh
#   nbhd_python_env numpy "dask.array=dask[array]"   # import name=pip requirement, or one name
#
# The environment is a venv under the cargo target directory ($CARGO_TARGET_DIR/pyenv), made once
# with the first `python3` on PATH (or $NBHD_BASE_PYTHON): nothing is installed into the system
# interpreter, which Debian's python3 refuses anyway (externally-managed-environment). Debian
# ships venv's ensurepip apart from python3: python3-venv is installed when it is missing. A venv
# whose interpreter no longer runs (its base was removed) is made anew. Afterwards the venv's bin/
# is first on PATH and NBHD_PYTHON names its interpreter (the Rust tests that call Python use it).

nbhd_python_env() {
    local target="${CARGO_TARGET_DIR:-$PWD/target}"
    case "$target" in /*) ;; *) target="$PWD/$target" ;; esac
    local venv="$target/pyenv" base="${NBHD_BASE_PYTHON:-python3}"
    if ! "$venv/bin/python" -c 'import sys' >/dev/null 2>&1; then
        echo "== creating the Python environment $venv with $(command -v "$base") ($("$base" --version 2>&1))"
        rm -rf "$venv"
        if ! "$base" -m venv "$venv" >/dev/null 2>&1; then
            # Debian splits venv's ensurepip out of python3
            local sudo=""
            [ "$(id -u)" -eq 0 ] || sudo="sudo"
            echo "== installing Debian's python3-venv (apt-get)"
            $sudo apt-get update -qq
            DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends python3-venv >/dev/null
            rm -rf "$venv"
            "$base" -m venv "$venv"
        fi
    fi
    export PATH="$venv/bin:$PATH"
    export NBHD_PYTHON="$venv/bin/python"
    local missing=() pkg
    for pkg in "$@"; do
        "$NBHD_PYTHON" -c "import ${pkg%%=*}" >/dev/null 2>&1 || missing+=("${pkg#*=}")
    done
    if [ "${#missing[@]}" -gt 0 ]; then
        echo "== installing into $venv: ${missing[*]} (pip, a minute or two)"
        "$NBHD_PYTHON" -m pip install --quiet --disable-pip-version-check "${missing[@]}"
    fi
}
