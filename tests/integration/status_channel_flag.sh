#!/usr/bin/env bash
# Every program that publishes a heartbeat takes --status-channel (two
# robots' stacks on one LAN keep their heartbeats apart, as their other
# channels), and a process given one publishes there and not on
# PROCESS_STATUS. No network: the processes write to a log (file://...?mode=w).
set -euo pipefail
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
# it has said something (it is running: 20 s at most), stops it as a user
# would (SIGINT; it publishes a last heartbeat) and prints the log's channels.
heartbeat_channels() {
  local log="$OUT/$1.lcmlog" pid code=0
  "$B/bin/$1" --lcm-url "file://$log?mode=w" "${@:2}" >"$OUT/$1.out" 2>&1 &
  pid=$!
  for _ in $(seq 200); do
    [ -s "$OUT/$1.out" ] && break
    sleep 0.1
  done
  kill -INT "$pid"
  wait "$pid" || code=$?
  if [ "$code" != 0 ]; then
    echo "FAIL: $1 exited $code" >&2
    cat "$OUT/$1.out" >&2
    exit 1
  fi
  "$B/bin/ivoa-log-check" --json "$OUT/$1.json" "$log" >/dev/null
  python3 -c 'import json, sys; print(" ".join(sorted(json.load(open(sys.argv[1]))["channels"])))' "$OUT/$1.json"
}

expect_heartbeats_on_b() {
  local channels
  channels=$(heartbeat_channels "$@" --status-channel ROBOT_B_STATUS)
  if [ "$channels" != "ROBOT_B_STATUS" ]; then
    echo "FAIL: $1 --status-channel ROBOT_B_STATUS wrote channels: '$channels'" >&2
    exit 1
  fi
}
expect_heartbeats_on_b ivoa-depth-monitor
expect_heartbeats_on_b ivoa-logger "$OUT/recorded.lcmlog"
echo "heartbeats on the channel asked for"
