#!/usr/bin/env bash
# SIGTERM in the middle of heavy traffic: ivoa-logger must write out
# everything it had received, however much is still queued. Its disk rate
# is capped below the traffic (--max-write-mb-s) so that a backlog of over
# 100 MB is waiting when the signal comes; traffic goes on meanwhile.
set -euo pipefail
B=${IVOA_BUILD_DIR:?}
. "$IVOA_SOURCE_DIR/tests/harness/wait_for.sh"
out=$(mktemp -d)
trap 'kill $(jobs -p) 2>/dev/null || true; rm -rf "$out"' EXIT

"$B/bin/ivoa-logger" "$out/drain.lcmlog" --max-write-mb-s 60 --ready-file "$out/ready" 2>"$out/logger.err" &
logger=$!
wait_for_file "$out/ready" 10
"$B/tests/ivoa-test-logger-helper" publish --calibrations 30 --foreign 0 --rate 2 &
"$B/tests/ivoa-test-publish" --count 900 --rate 30 --depth &
publisher=$!
"$B/tests/ivoa-test-logger-helper" wait --pid $logger --counter queue_bytes --min-counter 100000000 --timeout 20
kill -TERM $logger
code=0
wait $logger || code=$?
kill $publisher 2>/dev/null || true
[ $code = 0 ] || { echo "FAIL: ivoa-logger exited $code"; cat "$out/logger.err"; exit 1; }

queued=$(sed -n 's/.*writing the \([0-9]*\) queued messages.*/\1/p' "$out/logger.err")
[ "${queued:-0}" -gt 0 ] || { echo "FAIL: no backlog at the stop"; cat "$out/logger.err"; exit 1; }
"$B/bin/ivoa-log-check" --no-gaps --json "$out/check.json" "$out/drain.lcmlog"
python3 - "$out" "$queued" <<'PY'
import json, sys
out, queued = sys.argv[1], int(sys.argv[2])
check = json.load(open(out + "/check.json"))
session = json.load(open(out + "/drain.lcmlog.json"))["session"]
assert session["dropped"] == 0 and session["received"] == session["written"], session
assert check["events"] == session["written"], (check["events"], session)
stereo = check["channels"]["STEREO_IMAGES"]
print(f"OK: {queued} messages were queued at SIGTERM; received {session['received']} == written "
      f"{session['written']} == events in the log; stereo seq {stereo['first_seq']}..{stereo['last_seq']}, no gaps")
PY
