#!/usr/bin/env bash
# The viewer on a recorded session (file:// replay at real speed) with
# --window on a virtual display (Xvfb): the window opens, every frame is
# also drawn to a PNG, and the viewer exits 0 at the end of the log.
set -euo pipefail
B=${IVOA_BUILD_DIR:?}
command -v Xvfb > /dev/null || { echo "SKIPPED: Xvfb is not installed (apt-get install xvfb)"; exit 77; }
out=$(mktemp -d)
xvfb=
cleanup() { [ -n "$xvfb" ] && kill "$xvfb" 2>/dev/null; wait 2>/dev/null || true; rm -rf "$out"; }
trap cleanup EXIT
frames=4

"$B/bin/ivoa-sim-driver" --frames $frames --rate 2 --as-fast-as-possible --pixel-format jpeg \
  --lcm-url "file://$out/session.lcmlog?mode=w" --log-level warn

# -displayfd: Xvfb picks a free display and writes its number when ready.
exec 3> "$out/display"
Xvfb -displayfd 3 -screen 0 1600x900x24 -nolisten tcp > "$out/xvfb.txt" 2>&1 &
xvfb=$!
exec 3>&-
for _ in $(seq 100); do [ -s "$out/display" ] && break; sleep 0.1; done
[ -s "$out/display" ] || { cat "$out/xvfb.txt"; echo "Xvfb did not start"; exit 1; }
export DISPLAY=":$(cat "$out/display")" XDG_RUNTIME_DIR="$out"

timeout 60 "$B/bin/ivoa-viewer" --window --lcm-url "file://$out/session.lcmlog?speed=1" --out-dir "$out/png" \
  > "$out/viewer.txt" 2>&1 || { cat "$out/viewer.txt"; echo "ivoa-viewer failed"; exit 1; }
grep -q "window open" "$out/viewer.txt" || { cat "$out/viewer.txt"; echo "no window was opened"; exit 1; }
n=$(ls "$out/png" | grep -c '\.png$')
[ "$n" -eq $frames ] || { cat "$out/viewer.txt"; echo "$n figures for $frames frames"; exit 1; }
echo "OK: window on $DISPLAY, $n figures"
