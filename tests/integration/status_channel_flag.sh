#!/usr/bin/env bash
# Every program that publishes a heartbeat takes --status-channel (two
# robots' stacks on one LAN keep their heartbeats apart, as their other
# channels), and a process given one publishes there and not on
# PROCESS_STATUS; so does one whose environment's IVOA_STATUS_CHANNEL names
# one (ivoa-launch sets it for its commands). No network: the processes write to a log (file://...?mode=w).
set -euo pipefail
shopt -s inherit_errexit
B=${IVOA_BUILD_DIR:?}
OUT=$(mktemp -d)
trap 'rm -rf "$OUT"' EXIT
cd "$OUT"  # whatever a program writes by default stays in here

for program in ivoa-sim-driver ivoa-aravis-stereo ivoa-openni2-kinect ivoa-stereo-detector ivoa-depth-monitor \
  ivoa-introspection ivoa-logger ivoa-viewer ivoa-log-play ivoa-launch; do
  "$B/bin/$program" --help >"$OUT/help.txt"
  if ! grep -q -e "--status-channel" "$OUT/help.txt"; then
    echo "FAIL: $program --help lists no --status-channel" >&2
    exit 1
  fi
done

# heartbeat_channels PROGRAM ARGS...: runs the program writing to a log until
# it has said something (it is running: 20 s at most) or ended, stops it as a
# user would (SIGINT; it publishes a last heartbeat) and prints the channels
# its heartbeats went to (those of type ivoa.process_status_t). With
# LET_IT_END=1 it is not stopped but waited for: a log player ends at the
# end of its log, and one stopped at its first line had played nothing yet.
heartbeat_channels() {
  local log="$OUT/$1.lcmlog" pid code=0
  "$B/bin/$1" --lcm-url "file://$log?mode=w" "${@:2}" >"$OUT/$1.out" 2>&1 &
  pid=$!
  if [ "${LET_IT_END:-0}" != 1 ]; then
    for _ in $(seq 200); do
      [ -s "$OUT/$1.out" ] && break
      sleep 0.1
    done
    kill -INT "$pid" 2>/dev/null || true
  fi
  wait "$pid" || code=$?
  if [ "$code" != 0 ]; then
    echo "FAIL: $1 exited $code" >&2
    cat "$OUT/$1.out" >&2
    exit 1
  fi
  if ! "$B/bin/ivoa-log-check" --json "$OUT/$1.json" "$log" >"$OUT/$1.check" 2>&1; then
    echo "FAIL: ivoa-log-check could not read the log $1 wrote:" >&2
    cat "$OUT/$1.check" "$OUT/$1.out" >&2
    exit 1
  fi
  python3 -c 'import json, sys
channels = json.load(open(sys.argv[1]))["channels"]
print(" ".join(sorted(c for c, v in channels.items() if v["type"] == "ivoa.process_status_t")))' "$OUT/$1.json"
}

# expect_heartbeats_on CHANNEL PROGRAM ARGS...
expect_heartbeats_on() {
  local channels
  channels=$(heartbeat_channels "${@:2}" --status-channel "$1")
  if [ "$channels" != "$1" ]; then
    echo "FAIL: $2 --status-channel $1 sent heartbeats to: '$channels'" >&2
    cat "$OUT/$2.out" "$OUT/$2.check" >&2
    exit 1
  fi
}
expect_heartbeats_on ROBOT_B_STATUS ivoa-depth-monitor
expect_heartbeats_on ROBOT_B_STATUS ivoa-logger "$OUT/recorded.lcmlog"
expect_heartbeats_on ROBOT_B_STATUS ivoa-viewer --out-dir "$OUT/figures"
expect_heartbeats_on ROBOT_B_STATUS ivoa-introspection
expect_heartbeats_on ROBOT_B_STATUS ivoa-sim-driver --rate 2
# The player's own heartbeats, beside the monitor's it replays from its log.
channels=$(LET_IT_END=1 heartbeat_channels ivoa-log-play --speed 0 --status-channel ROBOT_C_STATUS \
  "$OUT/ivoa-depth-monitor.lcmlog")
if [ "$channels" != "ROBOT_B_STATUS ROBOT_C_STATUS" ]; then
  echo "FAIL: ivoa-log-play --status-channel ROBOT_C_STATUS: heartbeats on '$channels'" >&2
  cat "$OUT/ivoa-log-play.out" "$OUT/ivoa-log-play.check" >&2  # what it said it played, what the log holds
  ls -l "$OUT" >&2
  exit 1
fi
# $IVOA_STATUS_CHANNEL (what ivoa-launch hands its commands) replaces the
# default; the flag still beats it.
channels=$(IVOA_STATUS_CHANNEL=ROBOT_D_STATUS heartbeat_channels ivoa-depth-monitor)  # after the player read its log
[ "$channels" = ROBOT_D_STATUS ] || { echo "FAIL: IVOA_STATUS_CHANNEL=ROBOT_D_STATUS: heartbeats on '$channels'" >&2; exit 1; }
export IVOA_STATUS_CHANNEL=ROBOT_D_STATUS
expect_heartbeats_on ROBOT_B_STATUS ivoa-viewer --out-dir "$OUT/figures"
unset IVOA_STATUS_CHANNEL
echo "heartbeats on the channel asked for"
