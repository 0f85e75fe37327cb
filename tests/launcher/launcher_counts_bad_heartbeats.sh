#!/usr/bin/env bash
# ivoa-launch over real UDP multicast LCM: a message on the heartbeat
# channel that is not a heartbeat (another program's type, a damaged
# packet) is counted as the launcher's own bad input, named in its
# heartbeat's last_error, and the launcher keeps running and stops cleanly.
# A log player sends it; the logger records the launcher's heartbeats.
set -euo pipefail
shopt -s inherit_errexit
B=${IVOA_BUILD_DIR:?}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT

# A log of one 8-byte message on PROCESS_STATUS (LCM log event: sync word,
# event number, time, channel and data lengths, channel, data).
python3 - "$out/not_a_heartbeat.lcmlog" <<'PY'
import struct, sys
channel, data = b"PROCESS_STATUS", b"\x01\x02\x03\x04\x05\x06\x07\x08"
event = struct.pack(">IqqII", 0xEDA1DA01, 0, 1_700_000_000_000_000, len(channel), len(data)) + channel + data
open(sys.argv[1], "wb").write(event)
PY

cat > "$out/run.pmd" <<PMD
cmd "logger" { exec = "$B/bin/ivoa-logger $out/recorded.lcmlog"; }
cmd "player" { exec = "$B/bin/ivoa-log-play --speed 0 $out/not_a_heartbeat.lcmlog"; }
script "start" {
  start cmd "logger" wait "running";
  start cmd "player";
}
PMD
timeout 60 "$B/bin/ivoa-launch" "$out/run.pmd" --script start --plain --status-every 0 --until player --grace 2.5 --duration 30 \
  --status-file "$out/status.json" >"$out/launch.txt" 2>&1 || { cat "$out/launch.txt"; echo "FAIL: ivoa-launch failed" >&2; exit 1; }

# The logger records the message as it came; ivoa-log-check names it (no
# ivoa type on a channel of one: readers skip it) and exits 3.
code=0
"$B/bin/ivoa-log-check" --json "$out/check.json" "$out/recorded.lcmlog" >"$out/check.txt" || code=$?
grep -q "PROCESS_STATUS: 1 messages are of no ivoa type among its ivoa.process_status_t messages" "$out/check.txt" &&
  [ "$code" = 3 ] || { cat "$out/check.txt"; echo "FAIL: ivoa-log-check exit $code, expected 3 naming it" >&2; exit 1; }
python3 - "$out/check.json" <<'PY' || { cat "$out/launch.txt"; exit 1; }
import json, sys
launcher = json.load(open(sys.argv[1]))["processes"].get("launcher")
assert launcher, "no heartbeat of the launcher was logged"
assert launcher["bad_input"] == 1, f"launcher heartbeat counts bad_input {launcher['bad_input']}, expected 1"
expected = "channel PROCESS_STATUS: 8-byte message does not decode as"
assert expected in launcher["last_error"], f"last_error: {launcher['last_error']!r}"
print(f"OK: the launcher counted the message that is not a heartbeat: {launcher['last_error']}")
PY
