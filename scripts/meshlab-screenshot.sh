#!/usr/bin/env bash
# Takes docs/meshlab-plugin.png: Debian's MeshLab 2020.09 GUI under Xvfb with nbhd's robust
# smoothing dialog open, after "Apply" on the noisy fandisk of the meshlabserver tests. Run
# scripts/meshlab-test.sh first (it builds the plugin into target/meshlab/root). Not part of
# scripts/test.sh: it documents, it does not test.
#
# The dialog is a separate top-level window; without a window manager or compositor Xvfb's
# root window does not show its contents (xwd -root gives a black rectangle), so the picture is
# the root window with the dialog's own capture (xwd -id) put at the dialog's place on screen.
set -euo pipefail
cd "$(dirname "$0")/.."
target="${CARGO_TARGET_DIR:-$(pwd)/target}"
work="$target/meshlab"
meshlab="$work/root/bin/meshlab"
input="$work/build/work/fandisk_noisy.ply"
out="docs/meshlab-plugin.png"
[ -x "$meshlab" ] && [ -f "$input" ] || { echo "run scripts/meshlab-test.sh first" >&2; exit 1; }

missing=()
for pkg in xdotool x11-apps imagemagick; do dpkg -s "$pkg" >/dev/null 2>&1 || missing+=("$pkg"); done
if [ "${#missing[@]}" -gt 0 ]; then
    sudo=""; [ "$(id -u)" -eq 0 ] || sudo="sudo"
    $sudo apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi
convert=/usr/bin/convert   # ImageMagick's, whatever else is first in PATH

pids=()
cleanup() { for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done; }
trap cleanup EXIT
for d in $(seq 140 180); do
    [ -e "/tmp/.X11-unix/X$d" ] || [ -e "/tmp/.X$d-lock" ] || break
done
Xvfb ":$d" -screen 0 1400x950x24 -nolisten tcp >/dev/null 2>&1 &
pids+=($!)
export DISPLAY=":$d" XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-$(mktemp -d)}"
sleep 1
"$meshlab" "$input" >"$work/gui.log" 2>&1 &
pids+=($!)

wait_window() {  # name pattern -> window id
    for _ in $(seq 100); do
        w=$(xdotool search --onlyvisible --name "$1" 2>/dev/null | head -n1 || true)
        [ -n "$w" ] && { echo "$w"; return; }
        sleep 0.2
    done
    echo "no window '$1'" >&2; exit 1
}
main=$(wait_window '^MeshLab 2020')
sleep 3
xdotool windowsize "$main" 1400 950
sleep 1
# MeshLab's filter search (Ctrl+F), the first match, Return: the filter's parameter dialog.
xdotool windowfocus "$main"
xdotool key --window "$main" ctrl+f
sleep 1
xdotool type --delay 80 "Robust (keeps"
sleep 1
xdotool key Down Return
dialog=$(wait_window '^nbhd: Point Set Smoothing, Robust')
sleep 1
dx=835 dy=75
xdotool windowmove "$dialog" $dx $dy
sleep 1
read -r dw dh < <(xdotool getwindowgeometry "$dialog" | sed -n 's/.*Geometry: \([0-9]*\)x\([0-9]*\).*/\1 \2/p')
# "Apply" is the lower right button of the dialog.
xdotool mousemove $((dx + dw * 3 / 4)) $((dy + dh - 23)) click 1
for _ in $(seq 100); do grep -q "Applied filter nbhd" "$work/gui.log" && break; sleep 0.2; done
grep "nbhd" "$work/gui.log" || { echo "the filter was not applied" >&2; exit 1; }
# Turn the model a little so that its edges show (MeshLab's trackball: drag in the view).
xdotool mousemove 400 500 mousedown 1
for i in $(seq 1 12); do xdotool mousemove $((400 + i * 6)) $((500 - i * 9)); sleep 0.05; done
xdotool mouseup 1
sleep 2
xwd -root -silent > "$work/root.xwd"
xwd -id "$dialog" -silent > "$work/dialog.xwd"
$convert "xwd:$work/root.xwd" "xwd:$work/dialog.xwd" -geometry "+$dx+$dy" -composite "$out"
echo "wrote $out"
