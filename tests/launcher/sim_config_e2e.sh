#!/usr/bin/env bash
# End to end: ivoa-launch runs procman_configs/sim.pmd (simulator driver,
# stereo detector, depth monitor, introspection, logger, viewer) over real
# UDP multicast LCM. The stereo detector is killed with SIGKILL mid-session
# and must come back (auto_respawn) and publish again; the log must hold
# every channel, each frame's images exactly once; the viewer must have
# written its figures; the launcher must stop everything and exit 0.
# The introspection model is the shipped one, or a random-weight model
# written here when none is shipped (its predictions mean nothing).
set -euo pipefail
B=${IVOA_BUILD_DIR:?}; S=${IVOA_SOURCE_DIR:?}
. "$S/tests/harness/wait_for.sh"
out=$(mktemp -d)
launcher=
cleanup() {
  [ -n "$launcher" ] && kill -TERM "$launcher" 2>/dev/null && wait "$launcher" 2>/dev/null
  rm -rf "$out"
}
trap cleanup EXIT
frames=24
rate=2

model="$S/libs/introspection/models/introspection_jppc.pt"
skip=()
if [ ! -f "$model" ]; then
  if [ -x "$B/tests/ivoa-test-random-model" ]; then
    model="$out/random_model.pt"
    "$B/tests/ivoa-test-random-model" "$model"
    echo "no shipped model: introspection runs a random-weight one"
  else
    skip=(--skip introspection)
    echo "no shipped model and no ivoa-test-random-model: running without the introspection command"
  fi
fi

"$B/bin/ivoa-launch" "$S/procman_configs/sim.pmd" "${skip[@]}" --script start --plain --status-every 0 \
  --set FRAMES=$frames --set RATE=$rate --set SEED=3 --set MODEL="$model" \
  --set LOG_DIR="$out" --set LOG_FILE="$out/sim.lcmlog" --set VIEWER_ARGS="--every 1 --max-images 0" \
  --until sim_driver --grace 4 --duration 80 --respawn-delay 0.5 \
  --status-file "$out/status.json" > "$out/launch.txt" 2>&1 &
launcher=$!

# The detector is up once it has published; then kill it mid-session.
"$B/bin/ivoa-lcm-stats" --channels OBSTACLES_STEREO --expect OBSTACLES_STEREO=2 --duration 40 --print-every 0 > /dev/null \
  || { cat "$out/launch.txt"; echo "the stereo detector never published"; exit 1; }
first_pid=$(sed -n 's/^\[launcher\] stereo_detector: started, pid \([0-9]*\)$/\1/p' "$out/launch.txt" | head -1)
[ -n "$first_pid" ] || { cat "$out/launch.txt"; echo "no start line for stereo_detector"; exit 1; }
killed_at=$(date +%s%6N)
kill -KILL "$first_pid"
starts() { grep -c '^\[launcher\] stereo_detector: started, pid' "$out/launch.txt"; }
for _ in $(seq 200); do [ "$(starts)" -ge 2 ] && break; sleep 0.1; done
[ "$(starts)" -ge 2 ] || { cat "$out/launch.txt"; echo "the stereo detector did not come back within 20 s"; exit 1; }
grep -q '^\[launcher\] stereo_detector: ended: signal 9' "$out/launch.txt"

set +e
wait "$launcher"
code=$?
set -e
launcher=
if [ $code -ne 0 ]; then cat "$out/launch.txt"; echo "ivoa-launch exited with $code"; exit 1; fi

# Each frame's raw images exactly once (the logger starts before the driver).
"$B/bin/ivoa-log-check" "$out/sim.lcmlog" --json "$out/check.json" \
  --expect STEREO_IMAGES=$frames DEPTH_IMAGE=$frames SIM_GROUND_TRUTH=$frames \
  || { cat "$out/launch.txt"; exit 1; }

python3 - "$out" "$killed_at" "$frames" "${#skip[@]}" <<'PY'
import json, os, struct, sys
out, killed_at, frames, no_introspection = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), sys.argv[4] != "0"
status = json.load(open(f"{out}/status.json"))
check = json.load(open(f"{out}/check.json"))
cmds = {c["name"]: c for c in status["commands"]}
launch = open(f"{out}/launch.txt").read()
assert status["end_reason"] == "--until: sim_driver ended", status["end_reason"]
processes = {"sim_driver", "stereo_detector", "depth_monitor", "introspection", "logger", "viewer"}
if no_introspection:
    processes.remove("introspection")
assert set(cmds) == processes, cmds.keys()
for name, c in cmds.items():
    assert c["state"] == "stopped" and not c["failed"] and not c["killed"], (name, c)
det = cmds["stereo_detector"]
assert det["restarts"] == 1, f"stereo_detector restarts {det['restarts']}, expected 1 (killed once)"
# The killed instance's counts stay in the status (its last heartbeat's),
# beside the respawned one's; the other commands ran once.
assert det["earlier_instances"]["instances"] == 1, det["earlier_instances"]
assert all(cmds[n]["earlier_instances"]["instances"] == 0 for n in processes - {"stereo_detector"}), cmds
for name in processes - {"sim_driver", "stereo_detector"}:
    assert cmds[name]["restarts"] == 0, (name, cmds[name])
assert cmds["sim_driver"]["exit_code"] == 0
# Heartbeats reached the launcher's table.
for name in processes:
    assert cmds[name]["heartbeat"] is not None, f"no heartbeat from {name}"
assert cmds["viewer"]["heartbeat"]["messages_out"] >= 1

channels = check["channels"]
expected = ["STEREO_IMAGES", "DEPTH_IMAGE", "RIG_CALIBRATION", "SIM_GROUND_TRUTH", "OBSTACLES_STEREO",
            "OBSTACLES_DEPTH", "INTROSPECTION_LABELS", "INTROSPECTION", "PROCESS_STATUS"]
if no_introspection:
    expected.remove("INTROSPECTION")
missing = [c for c in expected if channels.get(c, {}).get("count", 0) == 0]
assert not missing, f"channels missing from the log: {missing}"
# The respawned detector worked on frames captured after the kill.
last = channels["OBSTACLES_STEREO"]["last_utime"]
assert last > killed_at, f"no OBSTACLES_STEREO after the kill (last {last}, kill at {killed_at})"

pngs = sorted(f for f in os.listdir(f"{out}/viewer") if f.endswith(".png"))
assert len(pngs) >= frames // 3, f"the viewer wrote {len(pngs)} figures for {frames} frames"
with open(f"{out}/viewer/{pngs[-1]}", "rb") as f:
    head = f.read(24)
assert head[:8] == b"\x89PNG\r\n\x1a\n", "not a PNG"
width, height = struct.unpack(">II", head[16:24])
assert (width, height) == (3 * 480, 300), f"figure is {width}x{height}, expected three 480x300 panels"
# The stop script stops the simulator, then the detector, the other
# consumers and the viewer, each waited for, and the logger last: every
# process's final heartbeat ("stopped", its final counts) is in the log.
logged = check["processes"]
for name in processes - {"logger"}:
    final = logged.get(name, {})
    assert final.get("state") == "stopped", f"{name}: last heartbeat in the log {final}, not its final one"
    table = cmds[name]["heartbeat"]
    assert (final["messages_in"], final["messages_out"]) == (table["messages_in"], table["messages_out"]), (name, final, table)
counts = {c: channels[c]["count"] for c in expected}
print(f"OK: detector killed and respawned (restarts 1), log channels {counts}, {len(pngs)} viewer figures")
PY

# What the introspection published scores against the monitor's labels of
# the same frames: every labelled cell of a predicted frame that the
# introspection looks at (its patch inside the image) has a prediction.
if [ ${#skip[@]} -eq 0 ]; then
  "$B/bin/ivoa-live-score" "$out/sim.lcmlog" --json "$out/score.json" > "$out/score.txt" 2>&1 ||
    { cat "$out/score.txt"; echo "ivoa-live-score failed on the session's log"; exit 1; }
  python3 - "$out/score.json" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
assert s["scored_frames"] >= 1 and s["labelled_cells"] > 0, s
assert s["unmatched_cells"] == 0, f"{s['unmatched_cells']} labelled cells in view without a prediction"
assert s["image"]["all"]["cells"] == s["labelled_cells"] - s["outside_view_cells"] - s["no_grid_cells"], s
assert s["compute_ms"]["frames"] == s["predicted_frames"] and s["compute_ms"]["median"] > 0, s["compute_ms"]
print(f"live score: {s['scored_frames']} frames, {s['labelled_cells']} labelled cells, mean per-class "
      f"{s['image']['all']['mean_per_class']} from the image, {s['given_verdict']['all']['mean_per_class']} given the verdict")
PY
fi
