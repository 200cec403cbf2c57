#!/usr/bin/env bash
# Runs Debian's meshlabserver (MeshLab 2020.09) on the X display in $DISPLAY (an Xvfb started
# by scripts/meshlab-test.sh: meshlabserver needs an OpenGL context, which Qt's offscreen
# platform does not give it — GLEW initialization fails).
#
#   run_meshlabserver.sh SERVER --list DUMP
#       dumps MeshLab's filter documentation and fails unless all five nbhd filters and their
#       parameters are in it (MeshLab loaded libfilter_nbhd.so from its plugin directory)
#   run_meshlabserver.sh SERVER IN.ply SCRIPT.mlx OUT.ply
#       loads IN, applies the script's filters, saves OUT as ASCII PLY with vertex normals,
#       quality and colour; fails if meshlabserver fails or OUT is not written
#   run_meshlabserver.sh SERVER --expect-failure IN.ply SCRIPT.mlx OUT.ply MESSAGE
#       the script must fail, with MESSAGE in meshlabserver's log
set -euo pipefail
server="$1"; shift
: "${DISPLAY:?run_meshlabserver.sh needs an X display (scripts/meshlab-test.sh starts Xvfb)}"
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-$(mktemp -d)}"

if [ "$1" = --list ]; then
    dump="$2"
    rm -f "$dump"
    "$server" -d "$dump" >"$dump.log" 2>&1 || { cat "$dump.log"; exit 1; }
    grep -h "Plugins Dir\|filtering actions" "$dump.log" || true
    status=0
    for f in "nbhd: Compute Normals (eps-k neighbourhoods)" "nbhd: Compute Curvatures as Quality" \
        "nbhd: Point Set Smoothing, Isotropic" \
        "nbhd: Point Set Smoothing, Anisotropic Mean Curvature Flow" \
        "nbhd: Point Set Smoothing, Robust (keeps edges)"; do
        if grep -qF "$f" "$dump"; then echo "  ok   MeshLab lists '$f'"; else echo "  FAIL MeshLab does not list '$f'"; status=1; fi
    done
    for p in "k (maximum valence)" "epsilon (influence radius)" "lambda (curvature threshold)" \
        "Feature criterion" "k_plane" "Normal orientation" "Colour by quality"; do
        if grep -qF "$p" "$dump"; then echo "  ok   parameter '$p' in MeshLab's dialog list"; else echo "  FAIL no parameter '$p'"; status=1; fi
    done
    exit $status
fi

expect_failure=0
if [ "$1" = --expect-failure ]; then expect_failure=1; shift; fi
in="$1" script="$2" out="$3" message="${4:-}"
rm -f "$out"
log="$out.log"
set +e
"$server" -i "$in" -o "$out" -m vn vq vc sa -s "$script" >"$log" 2>&1
rc=$?
set -e
grep -h "nbhd\|Problem\|Failed\|saved as" "$log" || true
if [ "$expect_failure" = 1 ]; then
    if [ "$rc" -ne 0 ] && grep -qF "$message" "$log" && [ ! -f "$out" ]; then
        echo "  ok   meshlabserver failed (exit $rc) with '$message' in its log, nothing saved"
        exit 0
    fi
    echo "  FAIL expected meshlabserver to fail with '$message' (exit $rc)"; cat "$log"; exit 1
fi
if [ "$rc" -ne 0 ] || [ ! -s "$out" ]; then
    echo "meshlabserver failed (exit $rc) or wrote no $out:"; cat "$log"; exit 1
fi
