#!/usr/bin/env bash
# The real ivoa-stereo-detector over real udpm LCM (inside a private network
# namespace): frames before calibration are counted and skipped, calibrated
# frames give OBSTACLES_STEREO grids, bad input (wrong size, garbage) is
# counted in PROCESS_STATUS and the process keeps running, a changed
# calibration is picked up, and SIGTERM ends it cleanly (exit 0).
set -euo pipefail
B=${IVOA_BUILD_DIR:?}
out=$(mktemp -d)
detector=
cleanup() {
  [ -n "$detector" ] && kill "$detector" 2>/dev/null || true
  rm -rf "$out"
}
trap cleanup EXIT
"$B/bin/ivoa-stereo-detector" --model jppc >"$out/detector.log" 2>&1 &
detector=$!
if ! "$B/tests/ivoa-test-stereo-feed" --timeout 20; then
  echo "--- detector log" >&2; cat "$out/detector.log" >&2
  exit 1
fi
kill -0 "$detector" || { echo "the detector died" >&2; cat "$out/detector.log" >&2; exit 1; }
kill -TERM "$detector"
rc=0; wait "$detector" || rc=$?
detector=
[ "$rc" = 0 ] || { echo "detector exited $rc after SIGTERM" >&2; cat "$out/detector.log" >&2; exit 1; }
grep -q "no calibration yet" "$out/detector.log"
grep -q "bad input (skipped)" "$out/detector.log"
echo "OK: ivoa-stereo-detector over udpm, bad input counted, clean exit"
