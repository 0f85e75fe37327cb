#!/usr/bin/env bash
# The lcm-spy wrapper starts on Java 17 under a virtual display and finds
# every ivoa type in the project's jar (so it can decode every channel);
# without a display it says so.
set -euo pipefail
B=${IVOA_BUILD_DIR:?}
# Without a display it says so in one line (it was a Java HeadlessException trace).
rc=0; msg=$(env -u DISPLAY "$IVOA_SOURCE_DIR/tools/lcm_spy/ivoa-lcm-spy.sh" 2>&1) || rc=$?
[ "$rc" = 1 ] && [ "$(printf '%s\n' "$msg" | wc -l)" = 1 ] && [[ "$msg" == *"no display (DISPLAY is not set)"* ]] ||
  { echo "FAIL: without a display: exit $rc, '$msg'"; exit 1; }
command -v xvfb-run >/dev/null || { echo "SKIPPED: xvfb-run not installed"; exit 77; }
out=$(mktemp -d); trap 'rm -rf "$out"' EXIT
"$B/tests/ivoa-test-publish" --lcm-url "file://$out/spy.lcmlog?mode=w" --count 3 --rate 100 --width 64 --height 48
expected=$("$B/bin/ivoa-lcm-stats" --list-types | wc -l)
. "$IVOA_SOURCE_DIR/tests/harness/wait_for.sh"
IVOA_BUILD_DIR=$B setsid timeout 40 xvfb-run -a "$IVOA_SOURCE_DIR/tools/lcm_spy/ivoa-lcm-spy.sh" \
  -l "file://$out/spy.lcmlog?speed=1" > "$out/spy.out" 2>&1 &
spy=$!
found=0
wait_for_line "$out/spy.out" "Found $expected LCM types" 30 && found=1
kill -- -$spy 2>/dev/null || true
wait $spy 2>/dev/null || true
[ $found = 1 ] || { cat "$out/spy.out"; echo "FAIL: lcm-spy did not load $expected types"; exit 1; }
echo "OK: lcm-spy found $expected ivoa types"
