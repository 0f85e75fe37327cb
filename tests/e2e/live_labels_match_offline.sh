#!/usr/bin/env bash
# End to end over real UDP multicast LCM, each part its own process:
#   simulator driver (live)  or  lcm-logplayer of a recorded raw log (replay)
#     -> ivoa-stereo-detector -> ivoa-depth-monitor -> labels
#     -> ivoa-logger records everything
# Then the labels the processes published (ivoa-dataset --labels recorded)
# must equal the labels computed offline from the same log's raw frames
# (ivoa-dataset --labels jppc): same cells, same labels, same patches.
# Usage: live_labels_match_offline.sh live|replay
set -euo pipefail
mode=${1:?live or replay}
B=${IVOA_BUILD_DIR:?}; S=${IVOA_SOURCE_DIR:?}
. "$S/tests/harness/wait_for.sh"
out=$(mktemp -d)
pids=()
cleanup() { for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done; wait 2>/dev/null || true; rm -rf "$out"; }
trap cleanup EXIT
frames=16
sim_args=(--scene "$S/libs/sim/scenes/indoor_office.yaml" --seed 21 --rate 4 --frames $frames --pixel-format bgr
          --start-utime 1700000000000000 --log-level warn)

if [ "$mode" = replay ]; then  # record the raw session first, as a robot would
  "$B/bin/ivoa-sim-driver" "${sim_args[@]}" --as-fast-as-possible --lcm-url "file://$out/raw.lcmlog?mode=w"
fi

"$B/bin/ivoa-logger" "$out/live.lcmlog" -x 'LCM_SELF_TEST|PROCESS_STATUS' --ready-file "$out/logger.ready" \
  --log-level warn & pids+=($!)
# Every frame must be labelled: the detector queues the frames it cannot
# take at once (a log recorded as fast as possible replays in bursts, and a
# busy machine can stall it live), and the monitor keeps the depth frames
# until the late grids arrive (16 frames at 4 Hz: 3.75 s of stream time).
"$B/bin/ivoa-stereo-detector" --model jppc --queue-frames $frames --log-level warn & pids+=($!)
"$B/bin/ivoa-depth-monitor" --depth-history-us 10000000 --log-level warn & pids+=($!)
wait_for_file "$out/logger.ready" 20
# Both processes are up once each has sent two heartbeats.
"$B/bin/ivoa-lcm-stats" --channels PROCESS_STATUS --expect PROCESS_STATUS=4 --duration 20 --print-every 0 > /dev/null

if [ "$mode" = live ]; then
  "$B/bin/ivoa-sim-driver" "${sim_args[@]}" --realtime
else
  lcm-logplayer --speed=1 --lcm-url="$LCM_DEFAULT_URL" "$out/raw.lcmlog"
fi

# Wait (bounded) until the labels of every frame are on disk.
for _ in $(seq 100); do
  "$B/bin/ivoa-log-check" "$out/live.lcmlog" --expect INTROSPECTION_LABELS=$frames > /dev/null 2>&1 && break
  sleep 0.2
done
for p in "${pids[@]}"; do kill -INT "$p"; done
for p in "${pids[@]}"; do wait "$p"; done
pids=()
"$B/bin/ivoa-log-check" "$out/live.lcmlog" || true

"$B/bin/ivoa-dataset" --log-level warn build --out "$out/data" --session live --labels recorded "$out/live.lcmlog"
"$B/bin/ivoa-dataset" --log-level warn build --out "$out/data" --session offline --labels jppc "$out/live.lcmlog"
python3 - "$out/data" $frames <<'PY'
import csv, sys
root, frames = sys.argv[1], int(sys.argv[2])
def load(name):
    rows = list(csv.DictReader(open(f"{root}/{name}/samples.csv")))
    return {(r["utime"], r["cell"]): r for r in rows}, open(f"{root}/{name}/patches.bin", "rb").read()
live, live_patches = load("live")
offline, offline_patches = load("offline")
live_frames = {k[0] for k in live}
assert len(live_frames) >= frames - 1, f"only {len(live_frames)} of {frames} frames were labelled live"
common = [k for k in offline if k[0] in live_frames]
missing = [k for k in common if k not in live]
extra = [k for k in live if k not in offline]
wrong = [k for k in common if k in live and live[k]["label"] != offline[k]["label"]]
assert not missing and not extra, f"cells differ: {len(missing)} only offline, {len(extra)} only live"
def show(k):
    l, o = live[k], offline[k]
    return (f"frame {k[0]} cell {k[1]}: live label {l['label']} (stereo {l['stereo_state']}, depth {l['depth_state']}), "
            f"offline {o['label']} (stereo {o['stereo_state']}, depth {o['depth_state']})")
assert not wrong, f"{len(wrong)} of {len(common)} labels differ:\n" + "\n".join(show(k) for k in wrong[:8])
size = 100 * 100 * 3
for k in common:
    a, b = int(live[k]["sample"]), int(offline[k]["sample"])
    assert live_patches[a*size:(a+1)*size] == offline_patches[b*size:(b+1)*size], f"patch differs at {k}"
counts = {}
for k in common: counts[live[k]["label"]] = counts.get(live[k]["label"], 0) + 1
print(f"OK: {len(live_frames)}/{frames} frames, {len(common)} samples: live labels == offline labels, patches equal; "
      f"labels (0 TP, 1 TN, 2 FP, 3 FN): {dict(sorted(counts.items()))}")
PY

# The failure causes of the same log: without --rate the frames' times give
# the driver's 4 Hz, and every frame is re-rendered with the verdict the live
# detector gave (at the tool's default 2 Hz, half would be skipped).
"$B/bin/ivoa-sim-causes" --out "$out/causes.csv" "$out/live.lcmlog" > "$out/causes.txt" 2>&1 ||
  { cat "$out/causes.txt"; exit 1; }
grep -q "live: recorded at 4 Hz" "$out/causes.txt" &&
  grep -qE "failure cells in $frames frames \(0 frames skipped\); re-rendered verdict matches the recorded one for [0-9]+ \(100.0 %\)" \
    "$out/causes.txt" || { echo "FAIL: ivoa-sim-causes did not reproduce every frame"; cat "$out/causes.txt"; exit 1; }
echo "OK: ivoa-sim-causes found the 4 Hz rate and reproduced the live verdicts of all $frames frames"
