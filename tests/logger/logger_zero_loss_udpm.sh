#!/usr/bin/env bash
# Zero loss over real UDP multicast: 30 Hz stereo pairs (2 x 960x600 BGR,
# 3.5 MB) plus 30 Hz depth (640x480 uint16), rig calibrations and a channel
# of no ivoa type, recorded by ivoa-logger into 100 MB split files. Every
# published message must be in the log in order (no sequence gap, no utime
# going back), and every split file after the first must start with the
# rig calibration. LOGGER_TEST_FRAMES sets the length (default 240 = 8 s).
set -euo pipefail
B=${IVOA_BUILD_DIR:?}
. "$IVOA_SOURCE_DIR/tests/harness/wait_for.sh"
frames=${LOGGER_TEST_FRAMES:-240}
out=$(mktemp -d)
trap 'kill $(jobs -p) 2>/dev/null || true; [ -n "${KEEP:-}" ] || rm -rf "$out"' EXIT

# Its own heartbeat is left out so that "received" counts only what the test sent.
"$B/bin/ivoa-logger" "$out/zl.lcmlog" --split-mb 100 --exclude 'PROCESS_STATUS|LCM_SELF_TEST' --ready-file "$out/ready" \
  2>"$out/logger.err" &
logger=$!
wait_for_file "$out/ready" 10
"$B/tests/ivoa-test-logger-helper" publish --calibrations 8 --foreign 8 --rate 2 &
extras=$!
"$B/tests/ivoa-test-publish" --count "$frames" --rate 30 --depth
wait $extras
# Bounded wait until the logger's heartbeat has counted every message sent.
"$B/tests/ivoa-test-logger-helper" wait --pid $logger --min-in $((2 * frames + 16)) --timeout 15
kill -INT $logger
code=0
wait $logger || code=$?
[ $code = 0 ] || { echo "FAIL: ivoa-logger exited $code"; cat "$out/logger.err"; exit 1; }

"$B/bin/ivoa-log-check" --no-gaps --expect "STEREO_IMAGES=$frames,DEPTH_IMAGE=$frames,FOREIGN_DATA=8" \
  --json "$out/check.json" "$out"/zl.lcmlog.[0-9][0-9]
python3 - "$out" "$frames" <<'PY'
import glob, json, sys
out, frames = sys.argv[1], int(sys.argv[2])
check = json.load(open(out + "/check.json"))
files, ch = check["files"], check["channels"]
assert len(files) >= 2, f"expected split files, got {len(files)}"
for f in files[1:]:
    assert f["first_channel"] == "RIG_CALIBRATION", f
for name in ("STEREO_IMAGES", "DEPTH_IMAGE"):
    c = ch[name]
    assert (c["first_seq"], c["last_seq"], c["missing_seq"]) == (0, frames - 1, 0), c
    assert c["utime_regressions"] == 0 and c["seq_regressions"] == 0, c
assert ch["RIG_CALIBRATION"]["count"] == 8 + len(files) - 1, ch["RIG_CALIBRATION"]  # 8 sent + a copy per new file
assert ch["FOREIGN_DATA"]["type"] == "unknown", ch["FOREIGN_DATA"]
last = json.load(open(sorted(glob.glob(out + "/zl.lcmlog.[0-9][0-9].json"))[-1]))
session = last["session"]
assert session["received"] == session["written"] == 2 * frames + 16 and session["dropped"] == 0, session
print(f"OK: {frames}/{frames} stereo pairs and depth images, 8/8 calibrations, 8/8 foreign messages in "
      f"{len(files)} files, no gaps; logger received {session['received']}, wrote {session['written']}, dropped 0")
PY
