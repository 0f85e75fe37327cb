#!/usr/bin/env bash
# ivoa-stereo-detector pointed at a recorded log (--lcm-url file://...) ends
# at the log's end as it would at a stop: exit 0, every frame accounted for,
# a final "stopped" state. It used to end with "LCM handle failed", exit 1.
set -euo pipefail
B=${IVOA_BUILD_DIR:?}; S=${IVOA_SOURCE_DIR:?}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
"$B/bin/ivoa-sim-driver" --scene "$S/libs/sim/scenes/indoor_office.yaml" --frames 3 --as-fast-as-possible \
  --lcm-url "file://$out/session.lcmlog?mode=w" --log-level warn
rc=0
"$B/bin/ivoa-stereo-detector" --model jppc --queue-frames 3 --lcm-url "file://$out/session.lcmlog?speed=0" \
  >"$out/detector.log" 2>&1 || rc=$?
cat "$out/detector.log"
[ "$rc" = 0 ] || { echo "FAIL: exit $rc at the end of the log" >&2; exit 1; }
grep -q "stopped: in 3, out 0, dropped 0," "$out/detector.log" || { echo "FAIL: not every frame accounted for" >&2; exit 1; }
! grep -q "LCM handle failed" "$out/detector.log"
echo "OK: the end of the log ends the detector with exit 0"
