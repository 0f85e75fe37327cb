#!/usr/bin/env bash
# End to end: a recorded raw session replayed by ivoa-launch with
# procman_configs/replay.pmd (lcm-logplayer -> stereo detector, depth
# monitor -> logger, viewer) over real UDP multicast LCM, as the README
# shows. Every frame must be replayed, detected, labelled and logged again:
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

timeout 80 "$B/bin/ivoa-launch" "$S/procman_configs/replay.pmd" --script start --plain --status-every 0 \
  --skip introspection --set LOG="$out/raw.lcmlog" --set LOG_DIR="$out" --set LOG_FILE="$out/replay.lcmlog" \
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
assert status["end_reason"] == "--until: done", status["end_reason"]
assert status["exit_code"] == 0
names = {c["name"] for c in status["commands"]}
assert names == {"logplayer", "stereo_detector", "depth_monitor", "logger", "viewer"}, names
channels = json.load(open(f"{out}/check.json"))["channels"]
for c in ("OBSTACLES_STEREO", "OBSTACLES_DEPTH", "INTROSPECTION_LABELS"):
    n = channels.get(c, {}).get("count", 0)
    assert n == frames, f"{c}: {n} messages for {frames} replayed frames"
pngs = [f for f in os.listdir(f"{out}/viewer") if f.endswith(".png")]
assert pngs, "the viewer drew nothing"
print(f"OK: {frames} frames replayed; grids and labels recomputed "
      f"({channels['INTROSPECTION_LABELS']['count']} labelled frames), {len(pngs)} viewer figures")
PY
