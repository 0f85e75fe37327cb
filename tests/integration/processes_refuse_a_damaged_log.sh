#!/usr/bin/env bash
# A process replaying a log (--lcm-url file://LOG) reads it through LCM's
# own reader, which crashed every live process (SIGSEGV) on an event header
# claiming 2^31-1 bytes, and stopped at other damage with one line, losing
# what came after it. Each refuses a damaged log before LCM opens it: exit
# 3, naming the byte, and pointing at ivoa-log-play, which skips damage.
# A log whose last event is cut short (a recording stopped mid-write) is
# played up to the cut, with a warning: LCM's reader ends there safely.
set -euo pipefail
shopt -s inherit_errexit
B=${IVOA_BUILD_DIR:?}; S=${IVOA_SOURCE_DIR:?}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
"$B/bin/ivoa-sim-driver" --scene "$S/libs/sim/scenes/indoor_office.yaml" --frames 2 --as-fast-as-possible \
  --lcm-url "file://$out/clean.lcmlog?mode=w" --log-level warn
# The header that crashed them, at the end; and garbage between good events.
python3 - "$out" <<'PY'
import struct, sys
out = sys.argv[1]
clean = open(out + "/clean.lcmlog", "rb").read()
crash = struct.pack(">IqqII", 0xEDA1DA01, 99, 0, 13, 0x7FFFFFFF) + b"STEREO_IMAGES" + bytes(100)
open(out + "/crash.lcmlog", "wb").write(clean + crash)
open(out + "/middle.lcmlog", "wb").write(clean + b"garbage" * 10 + clean)
open(out + "/cut.lcmlog", "wb").write(clean[:-100])
PY
size=$(stat -c %s "$out/clean.lcmlog")

# expect LOG TEXT PROGRAM ARGS...: PROGRAM on LOG exits 3 (in 60 s) saying TEXT.
expect() {
  local code=0
  timeout 60 "$B/bin/$3" "${@:4}" --lcm-url "file://$out/$1?speed=0" >"$out/said.txt" 2>&1 || code=$?
  if [ "$code" != 3 ] || ! grep -qF -- "$2" "$out/said.txt"; then
    cat "$out/said.txt"
    echo "FAIL: $3 on $1: exit $code (expected 3), expected to say: $2" >&2
    exit 1
  fi
}
for program in ivoa-stereo-detector ivoa-depth-monitor ivoa-introspection "ivoa-viewer --out-dir $out/figures" \
  "ivoa-logger $out/recorded.lcmlog" "ivoa-lcm-stats --duration 5"; do
  # shellcheck disable=SC2086
  expect crash.lcmlog "crash.lcmlog: damaged at byte $size: " $program
  # shellcheck disable=SC2086
  expect middle.lcmlog "good events after it would not be read. ivoa-log-play plays the log, skipping the damage" \
    $program
done
[ ! -e "$out/recorded.lcmlog" ] || { echo "FAIL: the logger recorded from a log it refused" >&2; exit 1; }
"$B/bin/ivoa-stereo-detector" --lcm-url "file://$out/clean.lcmlog?speed=0" --log-level warn  # a clean one plays

for program in ivoa-stereo-detector ivoa-depth-monitor ivoa-introspection "ivoa-viewer --out-dir $out/figures" \
  "ivoa-logger $out/recorded.lcmlog" "ivoa-lcm-stats --duration 5"; do
  code=0
  # shellcheck disable=SC2086
  timeout 60 "$B/bin/"$program --lcm-url "file://$out/cut.lcmlog?speed=0" >"$out/said.txt" 2>&1 || code=$?
  if [ "$code" != 0 ] || ! grep -qF "cut.lcmlog: its last event, at byte " "$out/said.txt"; then
    cat "$out/said.txt"
    echo "FAIL: $program on a log cut at its last event: exit $code (expected 0, with a warning)" >&2
    exit 1
  fi
done
# What the logger recorded from it is every event before the cut, whole.
"$B/bin/ivoa-log-check" "$out/recorded.lcmlog" >"$out/check.txt" || { cat "$out/check.txt"; exit 1; }
grep -q "STEREO_IMAGES" "$out/check.txt" || { cat "$out/check.txt"; echo "FAIL: nothing recorded" >&2; exit 1; }
echo "OK: every process refuses a damaged log by byte, plays a clean one, and one cut in its last event"
