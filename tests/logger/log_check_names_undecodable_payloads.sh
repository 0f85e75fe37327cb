#!/usr/bin/env bash
# ivoa-log-check decodes every message of an ivoa type: one whose payload
# was cut short inside an intact log frame (what a reader skips as bad
# input) makes the log DAMAGED (exit 3), named by channel, type, count and
# the byte offset of the first. It used to count as intact. So does a
# message of no ivoa type on a channel of one (its fingerprint damaged: it
# was called intact, blaming the good messages as "of another type").
# Messages of no ivoa type on channels of none are not judged.
set -euo pipefail
B=${IVOA_BUILD_DIR:?}
d=$(mktemp -d)
trap 'rm -rf "$d"' EXIT
"$B/tests/ivoa-test-logger-helper" --lcm-url "file://$d/good.lcmlog?mode=w" --log-level warn \
  publish --calibrations 3 --foreign 2 --rate 1000
"$B/bin/ivoa-log-check" "$d/good.lcmlog" > "$d/good.txt" || { cat "$d/good.txt"; exit 1; }
# The same log with the second calibration's payload 40 bytes short, its
# frame's length field rewritten to match; prints that event's offset.
offset=$(python3 - "$d/good.lcmlog" "$d/cut.lcmlog" <<'PY'
import struct, sys
data, out, at, seen = open(sys.argv[1], "rb").read(), bytearray(), 0, 0
while at < len(data):
    sync, number, utime, chan_len, data_len = struct.unpack_from(">IqqII", data, at)
    channel = data[at + 28:at + 28 + chan_len]
    payload = data[at + 28 + chan_len:at + 28 + chan_len + data_len]
    if channel == b"RIG_CALIBRATION":
        seen += 1
        if seen == 2:
            payload = payload[:-40]
            print(len(out))  # the offset of the cut event
    out += struct.pack(">IqqII", sync, number, utime, chan_len, len(payload)) + channel + payload
    at += 28 + chan_len + data_len
open(sys.argv[2], "wb").write(out)
PY
)
rc=0
"$B/bin/ivoa-log-check" --json "$d/cut.json" "$d/cut.lcmlog" > "$d/cut.txt" || rc=$?
cat "$d/cut.txt"
[ "$rc" = 3 ] || { echo "FAIL: exit $rc, expected 3 (damaged)"; exit 1; }
grep -q "cut.lcmlog: 5 events, .* DAMAGED" "$d/cut.txt"
grep -q "RIG_CALIBRATION: 1 messages do not decode as ivoa.rig_calibration_t (truncated or damaged inside; readers skip them), the first at byte $offset" "$d/cut.txt"
python3 - "$d/cut.json" "$offset" <<'PY'
import json, sys
bad = json.load(open(sys.argv[1]))["files"][0]["undecodable"]
assert bad == {"RIG_CALIBRATION": {"type": "ivoa.rig_calibration_t", "count": 1, "first_offset": int(sys.argv[2]),
                                    "untyped": 0, "first_untyped_offset": 0}}, bad
PY

# The first calibration's fingerprint damaged (its first byte flipped).
fp_offset=$(python3 - "$d/good.lcmlog" "$d/fingerprint.lcmlog" <<'PY'
import struct, sys
data, at = bytearray(open(sys.argv[1], "rb").read()), 0
while at < len(data):
    _, _, _, chan_len, data_len = struct.unpack_from(">IqqII", data, at)
    if data[at + 28:at + 28 + chan_len] == b"RIG_CALIBRATION":
        data[at + 28 + chan_len] ^= 0xFF
        print(at)
        break
    at += 28 + chan_len + data_len
open(sys.argv[2], "wb").write(data)
PY
)
rc=0
"$B/bin/ivoa-log-check" "$d/fingerprint.lcmlog" > "$d/fingerprint.txt" || rc=$?
cat "$d/fingerprint.txt"
[ "$rc" = 3 ] || { echo "FAIL: exit $rc for a damaged fingerprint, expected 3 (damaged)"; exit 1; }
grep -q "RIG_CALIBRATION: 1 messages are of no ivoa type among its ivoa.rig_calibration_t messages (damaged at or before the fingerprint, or another program's type; readers skip them), the first at byte $fp_offset" "$d/fingerprint.txt"
grep -q "RIG_CALIBRATION: 1 of its 3 messages are not ivoa.rig_calibration_t (1 no ivoa type: another program's, or damaged before the fingerprint)" "$d/fingerprint.txt"

# The same log twice read as repeats and a publisher's restart.
rc=0
"$B/bin/ivoa-log-check" "$d/fingerprint.lcmlog" "$d/../$(basename "$d")/fingerprint.lcmlog" > "$d/twice.txt" 2>&1 || rc=$?
[ "$rc" = 2 ] || { cat "$d/twice.txt"; echo "FAIL: exit $rc for a log given twice, expected 2"; exit 1; }
grep -q "is given twice" "$d/twice.txt" || { cat "$d/twice.txt"; exit 1; }
echo "OK: a payload cut inside an intact frame is named; the intact log passes; a log given twice is refused"
