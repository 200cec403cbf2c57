#!/usr/bin/env bash
# Builds the MeshLab plugin (meshlab_plugin/) against Debian's MeshLab 2020.09 and tests it with
# Debian's own meshlabserver, headless. Idempotent: every download and install is skipped when
# it is already done.
#
#   scripts/meshlab-test.sh            # install what is missing, build, run ctest
#   scripts/meshlab-test.sh -R normals # extra arguments go to ctest
#
# What it needs, and where it comes from:
# - Debian's `meshlab` package (meshlabserver, the plugin directory /usr/lib/x86_64-linux-gnu/meshlab/plugins)
# - MeshLab's plugin interface (common/interfaces.h, vcglib): Debian's source package of the same
#   version, `apt-get source meshlab`, unpacked into target/meshlab/src. Source packages are
#   enabled by copying the machine's own Debian apt source entry with `Types: deb-src`
#   (no mirror address is written here).
# - Qt 5 and GLEW development files (MeshLab's headers include them), PCL for the checker,
#   Xvfb with Mesa's software OpenGL: meshlabserver needs a GL context (Qt's offscreen
#   platform gives none, and MeshLab aborts with "GLEW initialization failed").
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/step.sh
root=$(pwd)
target="${CARGO_TARGET_DIR:-$root/target}"
work="$target/meshlab"
mkdir -p "$work"

sudo=""
[ "$(id -u)" -eq 0 ] || sudo="sudo"

# --- Debian packages ----------------------------------------------------------------------
missing=()
for pkg in meshlab qtbase5-dev libqt5opengl5-dev libglew-dev libeigen3-dev libpcl-dev cmake g++ \
    dpkg-dev xvfb libgl1-mesa-dri; do
    dpkg -s "$pkg" >/dev/null 2>&1 || missing+=("$pkg")
done
if [ "${#missing[@]}" -gt 0 ]; then
    step "installing Debian packages: ${missing[*]}"
    $sudo apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi
meshlab_version=$(dpkg-query -W -f='${Version}' meshlab)

# --- MeshLab's source (its plugin interface), from Debian's source package ---------------
src_stamp="$work/src/.version"
if [ ! -f "$src_stamp" ] || [ "$(cat "$src_stamp")" != "$meshlab_version" ]; then
    # Enable deb-src: a copy of the system's own Debian entry (deb822 or one-line format).
    srcfile=/etc/apt/sources.list.d/nbhd-deb-src.sources
    if ! apt-cache showsrc meshlab 2>/dev/null | grep -q '^Package: meshlab'; then
        step "enabling Debian's source packages: a deb-src copy of the system's apt entry in /etc/apt/sources.list.d/nbhd-deb-src.*"
        if [ -f /etc/apt/sources.list.d/debian.sources ]; then
            sed -e 's/^Types:.*/Types: deb-src/' /etc/apt/sources.list.d/debian.sources \
                | $sudo tee "$srcfile" >/dev/null
        elif grep -qE '^deb ' /etc/apt/sources.list 2>/dev/null; then
            grep -E '^deb ' /etc/apt/sources.list | sed -e 's/^deb /deb-src /' \
                | $sudo tee /etc/apt/sources.list.d/nbhd-deb-src.list >/dev/null
        else
            echo "no Debian apt source entry found to copy as deb-src" >&2
            exit 1
        fi
        $sudo apt-get update -qq
    fi
    rm -rf "$work/src" "$work/apt-source"
    mkdir -p "$work/apt-source"
    step "apt-get source meshlab=$meshlab_version"
    (cd "$work/apt-source" && apt-get source -qq "meshlab=$meshlab_version" >/dev/null)
    dir=$(find "$work/apt-source" -maxdepth 1 -mindepth 1 -type d -name 'meshlab-*' | head -n1)
    mv "$dir" "$work/src"
    echo "$meshlab_version" > "$src_stamp"
fi

# --- nbhd, installed as C/C++ users install it --------------------------------------------
prefix="$target/cpp/prefix"
step "installing nbhd into $prefix"
scripts/install.sh "$prefix" >/dev/null

# --- the plugin -------------------------------------------------------------------------------
# A private MeshLab root laid out as Debian's: MeshLab 2020.09 takes its plugin directory from
# the executable's own place (common/pluginmanager.cpp: <bin>/../lib/<arch>/meshlab/plugins;
# there is no option or environment variable for it), so the tests run a copy of Debian's
# meshlabserver in root/bin with Debian's plugins and ours in root/lib/<arch>/meshlab/plugins,
# and nothing is written into /usr.
arch=$(dpkg-architecture -qDEB_HOST_MULTIARCH)
mlroot="$work/root"
mllib="$mlroot/lib/$arch/meshlab"
build="$work/build"
step "building meshlab_plugin (libfilter_nbhd.so) and its checker"
mkdir -p "$mlroot/bin" "$mllib/plugins"
for exe in meshlabserver meshlab; do
    cmp -s "/usr/bin/$exe" "$mlroot/bin/$exe" || cp "/usr/bin/$exe" "$mlroot/bin/$exe"
done
ln -sf "/usr/lib/$arch/meshlab/libmeshlab-common.so" "$mllib/libmeshlab-common.so"
for so in "/usr/lib/$arch/meshlab/plugins/"*.so; do ln -sf "$so" "$mllib/plugins/"; done
cmake -S meshlab_plugin -B "$build" -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH="$prefix" \
    -DMESHLAB_SOURCE_DIR="$work/src" -DMESHLAB_PLUGIN_DIR="$mllib/plugins" \
    -DNBHD_MESHLAB_TESTS=ON -DMESHLAB_TEST_ROOT="$mlroot" >"$build.configure.log" 2>&1 ||
    { cat "$build.configure.log"; exit 1; }
cmake --build "$build" -j "$(nproc)"
cmake --install "$build" >/dev/null
plugin="$mllib/plugins/libfilter_nbhd.so"
echo "   $(stat -c %s "$plugin") bytes  $plugin"
if readelf -d "$plugin" | grep -q 'libnbhd'; then
    echo "meshlab-test.sh: the plugin must link nbhd statically" >&2; exit 1
fi

# --- meshlabserver under Xvfb ----------------------------------------------------------------
xvfb_pid=""
cleanup() { if [ -n "$xvfb_pid" ]; then kill "$xvfb_pid" 2>/dev/null || true; fi; }
trap cleanup EXIT
if [ -z "${DISPLAY:-}" ]; then
    # -displayfd: Xvfb picks a free display and writes its number once it accepts clients
    # (its socket file appears earlier: a meshlabserver started then aborted, exit 134)
    ready="$work/xvfb.display"
    rm -f "$ready"
    Xvfb -displayfd 3 -screen 0 1280x1024x24 -nolisten tcp 3>"$ready" >"$work/xvfb.log" 2>&1 &
    xvfb_pid=$!
    for _ in $(seq 100); do [ -s "$ready" ] && break; sleep 0.1; done
    if [ -s "$ready" ] && kill -0 "$xvfb_pid" 2>/dev/null; then
        export DISPLAY=":$(head -n 1 "$ready")"
    else
        echo "meshlab-test.sh: could not start Xvfb (see $work/xvfb.log)" >&2; exit 1
    fi
fi
step "ctest: meshlabserver applies every nbhd filter (DISPLAY=$DISPLAY)"
(cd "$build" && ctest --output-on-failure -j "${CTEST_PARALLEL:-$(nproc)}" "$@")
step_end
