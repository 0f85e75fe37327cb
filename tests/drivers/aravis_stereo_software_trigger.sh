#!/usr/bin/env bash
# Software trigger and Mono8: the driver fires both cameras itself at
# --frame-rate and publishes gray. Each trigger makes one frame per camera and
# the fake stamps its frame count, so pairs show counts that differ by a
# constant: 0, or more after a trigger the fake lost to a starved thread (it
# latches triggers in one bit). Pairs must be taken together (15 Hz: 67 ms
# apart, skew well under that) and the difference may change only rarely.
. "$(dirname "$0")/driver_test_lib.sh"

start rig "$B/bin/ivoa-fake-gige-rig" --ready-file "$OUT/rig.ready"
wait_for_file "$OUT/rig.ready" 10
start check "$B/tests/ivoa-test-check-stereo" --expect 25 --timeout 30 --camera-format Mono8 --stamps frame-count \
  --json "$OUT/summary.json" --ready-file "$OUT/check.ready"
wait_for_file "$OUT/check.ready" 10
start driver "$B/bin/ivoa-aravis-stereo" --left 127.0.0.1 --right 127.0.0.2 --rig "$S/tests/drivers/data/rig_640x480.yaml" \
  --width 640 --height 480 --pixel-format Mono8 --trigger software --frame-rate 15 --packet-size 8192 --output gray

if ! wait_exit check 40; then show driver check rig; exit 1; fi
assert_json "$OUT/summary.json" \
  's["checked"] >= 25' 's["content_mismatch"] == 0' 's["stamp_missing"] == 0' \
  's["count_slips"] <= 2' 's["max_skew_ms"] < 34' 's["off_beat_pairs"] == 0' 's["distinct_ticks"] >= 20' \
  's["pixelformat"] == "GRAY"' '1.5 <= s["rate_hz"] <= 18' 's["utime_regressions"] == 0' \
  || { show driver rig; exit 1; }
grep -q "trigger software" "$OUT/driver.log" || { echo "driver did not report software trigger" >&2; show driver; exit 1; }
echo "OK: $(cat "$OUT/summary.json")"
