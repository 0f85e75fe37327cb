#!/usr/bin/env bash
# End to end: a recorded raw session, cut into two split files as
# ivoa-logger --split-mb leaves it, replayed by ivoa-launch with
# procman_configs/replay.pmd (ivoa-log-play -> stereo detector, depth
# monitor -> logger, viewer) over real UDP multicast LCM, as the README
# shows. Every frame of both files must be replayed, detected, labelled and
# logged again:
# the launcher starts the player only once the consumers have announced
# themselves, the detector queues the frames, which this log (recorded as
# fast as possible) replays in bursts tens of milliseconds apart, and the
# monitor keeps the depth frames until the detector's late grids arrive.
set -euo pipefail
B=${IVOA_BUILD_DIR:?}; S=${IVOA_SOURCE_DIR:?}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
frames=8

"$B/bin/ivoa-sim-driver" --frames $frames --rate 2 --seed 11 --as-fast-as-possible \
  --lcm-url "file://$out/raw.lcmlog?mode=w" --log-level warn
# Cut it in two at an event boundary (LCM log events: sync word, event
# number, time, channel and data lengths, channel, data).
python3 - "$out/raw.lcmlog" <<'PY'
import struct, sys
path = sys.argv[1]
raw, events, pos = open(path, "rb").read(), [], 0
while pos < len(raw):
    _, _, _, channel_len, data_len = struct.unpack(">IqqII", raw[pos:pos + 28])
    events.append(raw[pos:pos + 28 + channel_len + data_len])
    pos += 28 + channel_len + data_len
half = len(events) // 2
open(path + ".00", "wb").write(b"".join(events[:half]))
open(path + ".01", "wb").write(b"".join(events[half:]))
PY

timeout 80 "$B/bin/ivoa-launch" "$S/procman_configs/replay.pmd" --script start --plain --status-every 0 \
  --skip introspection --set LOG="$out/raw.lcmlog.00 $out/raw.lcmlog.01" --set LOG_DIR="$out" --set LOG_FILE="$out/replay.lcmlog" \
  --set VIEWER_ARGS="--every 1" --set DETECTOR_ARGS="--queue-frames $frames" \
  --set MONITOR_ARGS="--depth-history-us 10000000" --until logplayer --grace 3 --duration 60 \
  --status-file "$out/status.json" > "$out/launch.txt" 2>&1 \
  || { cat "$out/launch.txt"; echo "ivoa-launch failed"; exit 1; }

"$B/bin/ivoa-log-check" "$out/replay.lcmlog" --json "$out/check.json" \
  --expect STEREO_IMAGES=$frames DEPTH_IMAGE=$frames > /dev/null || { cat "$out/launch.txt"; exit 1; }
python3 - "$out" $frames <<'PY' || { cat "$out/launch.txt" "$out/status.json"; exit 1; }
import json, os, sys
out, frames = sys.argv[1], int(sys.argv[2])
status = json.load(open(f"{out}/status.json"))
assert status["end_reason"] == "--until: logplayer ended", status["end_reason"]
assert status["exit_code"] == 0
names = {c["name"] for c in status["commands"]}
assert names == {"logplayer", "stereo_detector", "depth_monitor", "logger", "viewer"}, names
channels = json.load(open(f"{out}/check.json"))["channels"]
for c in ("OBSTACLES_STEREO", "OBSTACLES_DEPTH", "INTROSPECTION_LABELS"):
    n = channels.get(c, {}).get("count", 0)
    assert n == frames, f"{c}: {n} messages for {frames} replayed frames"
# replay.pmd's stop script: the player, the detector, the monitor, the
# viewer, each waited for, then the logger: their final heartbeats are logged.
logged = json.load(open(f"{out}/check.json"))["processes"]
assert logged.get("log_play", {}).get("state") == "finished", logged.get("log_play")
for name in ("stereo_detector", "depth_monitor", "viewer"):
    assert logged.get(name, {}).get("state") == "stopped", f"{name}: last heartbeat in the log {logged.get(name)}"
pngs = [f for f in os.listdir(f"{out}/viewer") if f.endswith(".png")]
assert pngs, "the viewer drew nothing"
player = next(c for c in status["commands"] if c["name"] == "logplayer")["heartbeat"]
assert player["counters"]["files_done"] == 2 and player["bad_input"] == 0, player
print(f"OK: {frames} frames replayed from two split files; grids and labels recomputed "
      f"({channels['INTROSPECTION_LABELS']['count']} labelled frames), {len(pngs)} viewer figures")
PY
