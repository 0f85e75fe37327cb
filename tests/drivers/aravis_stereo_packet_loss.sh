#!/usr/bin/env bash
# The fake cameras lose 1 % of their GVSP packets and never resend: many
# frames arrive incomplete. The driver must drop and count them (heartbeat
# counters) and never publish a corrupt pair: every published pixel must
# still equal what the cameras served.
. "$(dirname "$0")/driver_test_lib.sh"

start rig "$B/bin/ivoa-fake-gige-rig" --packet-loss 0.01 --ready-file "$OUT/rig.ready"
wait_for_file "$OUT/rig.ready" 10
start check "$B/tests/ivoa-test-check-stereo" --expect 20 --timeout 40 --camera-format BayerRG8 \
  --json "$OUT/summary.json" --ready-file "$OUT/check.ready"
wait_for_file "$OUT/check.ready" 10
start driver "$B/bin/ivoa-aravis-stereo" --left 127.0.0.1 --right 127.0.0.2 --rig "$S/tests/drivers/data/rig_640x480.yaml" \
  --width 640 --height 480 --frame-rate 20 --packet-size 8192 --output raw

if ! wait_exit check 50; then show driver check rig; exit 1; fi
assert_json "$OUT/summary.json" \
  's["checked"] >= 20' 's["content_mismatch"] == 0' 's["content_ok"] == s["checked"]' 's["stamp_missing"] == 0' \
  's["stamp_mismatch"] == 0' \
  's["status"]["counters"]["incomplete"] > 0' 's["status"]["bad_input"] > 0' \
  's["status"]["counters"]["unpaired"] > 0' 's["status"]["counters"]["reconnects"] == 0' \
  || { show driver rig; exit 1; }
grep -q "dropped" "$OUT/driver.log" || { echo "no log line about dropped incomplete frames" >&2; show driver; exit 1; }
echo "OK: $(cat "$OUT/summary.json")"
