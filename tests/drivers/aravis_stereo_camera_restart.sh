#!/usr/bin/env bash
# The right camera is powered off mid-stream, stays off until the driver has
# failed to reopen it, and comes back as a fresh camera (a power cycle). The
# driver must notice the silence, say so, retry with back-off, reopen it
# and publish correct pairs again, counting the reconnect in its heartbeat.
# (Closing an unreachable camera waits for Aravis' own timeouts: ~10 s.)
. "$(dirname "$0")/driver_test_lib.sh"

start rig "$B/bin/ivoa-fake-gige-rig" --power-cycled right --ready-file "$OUT/rig.ready"
wait_for_file "$OUT/rig.ready" 10
start before "$B/tests/ivoa-test-check-stereo" --expect 10 --timeout 30 --json "$OUT/before.json" \
  --ready-file "$OUT/before.ready"
wait_for_file "$OUT/before.ready" 10
start driver "$B/bin/ivoa-aravis-stereo" --left 127.0.0.1 --right 127.0.0.2 --rig "$S/tests/drivers/data/rig_640x480.yaml" \
  --width 640 --height 480 --frame-rate 20 --packet-size 8192 --output raw \
  --frame-timeout 1 --reconnect-initial 0.5 --reconnect-max 2
if ! wait_exit before 40; then show driver before rig; exit 1; fi
assert_json "$OUT/before.json" 's["checked"] >= 10' 's["content_mismatch"] == 0' || { show driver; exit 1; }

kill -USR1 "$PID_rig"  # right camera off
wait_for_line "$OUT/rig.log" "right camera powered off" 10
if ! wait_for_line "$OUT/driver.log" "right camera .*no frame for .*reconnecting" 15; then show driver rig; exit 1; fi
start after "$B/tests/ivoa-test-check-stereo" --expect 10 --timeout 60 --json "$OUT/after.json" \
  --ready-file "$OUT/after.ready"
wait_for_file "$OUT/after.ready" 10
if ! wait_for_line "$OUT/driver.log" "right camera .*cannot open: .*retrying in" 30; then show driver rig; exit 1; fi
kill -USR2 "$PID_rig"  # right camera on again
wait_for_line "$OUT/rig.log" "right camera powered on" 10
if ! wait_for_line "$OUT/driver.log" "right camera .*reconnected, .* after its last frame" 30; then show driver rig; exit 1; fi
if ! wait_exit after 65; then show driver after rig; exit 1; fi
assert_json "$OUT/after.json" \
  's["checked"] >= 10' 's["content_mismatch"] == 0' 's["stamp_mismatch"] == 0' 's["utime_regressions"] == 0' \
  's["status"]["counters"]["disconnects"] >= s["status"]["counters"]["reconnects"] >= 1' 's["status"]["state"] == "running"' \
  || { show driver rig; exit 1; }
echo "OK: $(cat "$OUT/after.json")"
