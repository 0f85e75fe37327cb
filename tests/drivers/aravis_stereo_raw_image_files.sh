#!/usr/bin/env bash
# The simulated rig serves a sequence of real stereo images from files (the
# Middlebury "Aloe" pair and a chessboard pair, from opencv-doc); the driver
# publishes raw BayerRG8 (--output raw, a third the size of BGR): every pair
# must carry the camera's Bayer bytes exactly, labelled BAYER_RGGB.
. "$(dirname "$0")/driver_test_lib.sh"
D=/usr/share/doc/opencv-doc/examples/data
for f in aloeL.jpg aloeR.jpg left01.jpg right01.jpg; do
  [ -r "$D/$f" ] || { echo "SKIPPED: $D/$f missing (package opencv-doc)"; exit 77; }
done
LEFT=("$D/aloeL.jpg" "$D/left01.jpg")
RIGHT=("$D/aloeR.jpg" "$D/right01.jpg")

start rig "$B/bin/ivoa-fake-gige-rig" --left-images "${LEFT[@]}" --right-images "${RIGHT[@]}" --ready-file "$OUT/rig.ready"
wait_for_file "$OUT/rig.ready" 10
start check "$B/tests/ivoa-test-check-stereo" --expect 30 --timeout 30 --camera-format BayerRG8 \
  --left-images "${LEFT[@]}" --right-images "${RIGHT[@]}" --json "$OUT/summary.json" --ready-file "$OUT/check.ready"
wait_for_file "$OUT/check.ready" 10
start driver "$B/bin/ivoa-aravis-stereo" --left 127.0.0.1 --right 127.0.0.2 --rig "$S/tests/drivers/data/rig_640x480.yaml" \
  --width 640 --height 480 --frame-rate 20 --packet-size 8192 --output raw

if ! wait_exit check 40; then show driver check rig; exit 1; fi
assert_json "$OUT/summary.json" \
  's["checked"] >= 30' 's["content_mismatch"] == 0' 's["content_ok"] == s["checked"]' \
  's["stamp_missing"] == 0' 's["stamp_mismatch"] == 0' 's["checked"] - s["off_beat_pairs"] >= 10' \
  's["pixelformat"] == "BAYER_RGGB"' 's["width"] == 640 and s["height"] == 480' 's["utime_regressions"] == 0' \
  || { show driver rig; exit 1; }
echo "OK: $(cat "$OUT/summary.json")"
