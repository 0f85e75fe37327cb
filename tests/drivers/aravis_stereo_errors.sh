#!/usr/bin/env bash
# Failures a user meets first, each with a clear message and the exit code
# the README documents: a missing rig file (3), a bad flag (2), a pixel
# format the camera lacks (2), cameras that never answer (1).
. "$(dirname "$0")/driver_test_lib.sh"
DRIVER="$B/bin/ivoa-aravis-stereo"
RIG="$S/tests/drivers/data/rig_640x480.yaml"

# expect_exit CODE PATTERN COMMAND...: the command exits with CODE and its output matches PATTERN.
expect_exit() {
  local want=$1 pattern=$2 code=0
  shift 2
  "$@" >"$OUT/run.log" 2>&1 || code=$?
  if [ "$code" != "$want" ] || ! grep -qE -e "$pattern" "$OUT/run.log"; then
    echo "FAILED: '$*' exited $code (want $want), output (want /$pattern/):" >&2
    cat "$OUT/run.log" >&2
    exit 1
  fi
}

expect_exit 3 "/nonexistent/rig.yaml" "$DRIVER" --left 127.0.0.1 --right 127.0.0.2 --rig /nonexistent/rig.yaml
expect_exit 2 "--output" "$DRIVER" --left 127.0.0.1 --right 127.0.0.2 --rig "$RIG" --output jpeg
expect_exit 0 "--packet-size" "$DRIVER" --help
# Values the camera took for others without a word: NaN gain (auto gain),
# 1e300 us (exposure 0), a width alone (ignored), a channel LCM refuses.
expect_exit 2 "--gain: must be a number" "$DRIVER" --left 127.0.0.1 --right 127.0.0.2 --rig "$RIG" --gain nan
expect_exit 2 "--exposure-us: must be in" "$DRIVER" --left 127.0.0.1 --right 127.0.0.2 --rig "$RIG" --exposure-us 1e300
expect_exit 2 "--width and --height set the region together" \
  "$DRIVER" --left 127.0.0.1 --right 127.0.0.2 --rig "$RIG" --width 320
expect_exit 2 "--stereo-channel: must be a channel name of 1 to 63 characters" \
  "$DRIVER" --left 127.0.0.1 --right 127.0.0.2 --rig "$RIG" --stereo-channel "$(printf 'S%.0s' {1..70})"
expect_exit 2 "--reconnect-max: must be in \[0.001, 3600\], not 1e10" \
  "$DRIVER" --left 127.0.0.1 --right 127.0.0.2 --rig "$RIG" --reconnect-max 1e10  # the wait overflowed
expect_exit 2 "--genicam: File does not exist: /nonexistent/camera.xml" \
  "$B/bin/ivoa-fake-gige-rig" --genicam /nonexistent/camera.xml  # it said it was serving, and served nothing
expect_exit 1 "cameras not ready after 1 s \(left NOT open, right NOT open\)" \
  "$DRIVER" --left 127.0.0.1 --right 127.0.0.2 --rig "$RIG" --startup-timeout 1

start rig "$B/bin/ivoa-fake-gige-rig" --ready-file "$OUT/rig.ready"
wait_for_file "$OUT/rig.ready" 10
expect_exit 2 "pixel format 'YUV422Packed' refused.*offers: .*BayerRG8" \
  "$DRIVER" --left 127.0.0.1 --right 127.0.0.2 --rig "$RIG" --pixel-format YUV422Packed
echo "OK: missing rig 3, bad flags 2, absent cameras 1, unsupported pixel format 2"
