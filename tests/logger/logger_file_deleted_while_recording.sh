#!/usr/bin/env bash
# The log file deleted while ivoa-logger writes it (by hand, a clean-up
# script): what was in it is gone, but the logger must say so, count it,
# and keep recording into a new file of that name (it used to write on into
# the deleted file and report every message written, exit 0).
set -euo pipefail
B=${IVOA_BUILD_DIR:?}
. "$IVOA_SOURCE_DIR/tests/harness/wait_for.sh"
out=$(mktemp -d)
trap 'kill $(jobs -p) 2>/dev/null || true; rm -rf "$out"' EXIT

"$B/bin/ivoa-logger" "$out/del.lcmlog" --channels STEREO_IMAGES --ready-file "$out/ready" 2>"$out/logger.err" &
logger=$!
wait_for_file "$out/ready" 10
"$B/tests/ivoa-test-publish" --count 10 --rate 10
# all 10 written (each pair is 3456000 bytes of pixels and more), then the file goes
"$B/tests/ivoa-test-logger-helper" wait --pid $logger --counter bytes_written --min-counter 34560000 --timeout 15
rm "$out/del.lcmlog"
"$B/tests/ivoa-test-publish" --count 20 --rate 10
"$B/tests/ivoa-test-logger-helper" wait --pid $logger --min-in 30 --timeout 15
kill -TERM $logger
code=0
wait $logger || code=$?
# the recording has a hole: exit 4, as for any message LOST (it was 0)
[ $code = 4 ] || { echo "FAIL: ivoa-logger exited $code, expected 4"; cat "$out/logger.err"; exit 1; }
grep -q "del.lcmlog was deleted while recording: its 10 messages are lost" "$out/logger.err" ||
  { echo "FAIL: the deletion was not reported"; cat "$out/logger.err"; exit 1; }
grep -q "LOST 10 messages written to a log file deleted while recording" "$out/logger.err" ||
  { echo "FAIL: the loss is not in the summary"; cat "$out/logger.err"; exit 1; }
"$B/bin/ivoa-log-check" --json "$out/check.json" "$out/del.lcmlog" >/dev/null
python3 - "$out" <<'PY'
import json, sys
out = sys.argv[1]
events = json.load(open(out + "/check.json"))["events"]
session = json.load(open(out + "/del.lcmlog.json"))["session"]
assert events == 20, f"the new file holds {events} events, expected the 20 sent after the deletion"
assert session["written"] == 30 and session["deleted"] == 10, session
print(f"OK: 10 messages lost with the deleted file were reported; the 20 after it are in the new file")
PY
