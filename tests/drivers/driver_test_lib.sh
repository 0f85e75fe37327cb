# Shared by the driver integration tests (source it; they run inside
# tests/harness/in_netns.sh). Starts processes in the background, remembers
# their PIDs and stops exactly those on exit; bounded waits only.
# Rates: never faster than the camera, and at least a tenth of it (a CI host
# running other tests beside these delivered a third of the 30 Hz once).
set -euo pipefail
B=${IVOA_BUILD_DIR:?}
S=${IVOA_SOURCE_DIR:?}
. "$S/tests/harness/wait_for.sh"
OUT=$(mktemp -d)
PIDS=()

# Stops what this test started, newest first (the driver before the
# simulated cameras it talks to).
# A process that ignores SIGTERM for 15 s is killed (and the test fails).
cleanup() {
  local i j
  for ((i = ${#PIDS[@]} - 1; i >= 0; i--)); do
    kill -TERM "${PIDS[i]}" 2>/dev/null || true
    for ((j = 0; j < 300; j++)); do
      kill -0 "${PIDS[i]}" 2>/dev/null || break
      sleep 0.05
    done
    if kill -0 "${PIDS[i]}" 2>/dev/null; then
      echo "process ${PIDS[i]} ignored SIGTERM for 15 s; killing it" >&2
      kill -KILL "${PIDS[i]}" 2>/dev/null || true
    fi
    wait "${PIDS[i]}" 2>/dev/null || true
  done
  if [ "${KEEP_OUT:-0}" = 1 ]; then echo "outputs kept in $OUT" >&2; else rm -rf "$OUT"; fi
}
trap cleanup EXIT

# start NAME COMMAND...: runs COMMAND in the background, output to $OUT/NAME.log.
start() {
  local name=$1
  shift
  "$@" >"$OUT/$name.log" 2>&1 &
  PIDS+=($!)
  eval "PID_$name=$!"
}

# stop_and_wait NAME SECONDS: SIGTERM, then the exit code (124 if it did not exit in time).
stop_and_wait() {
  local name=$1 limit=$2 pid i
  pid=$(eval echo "\$PID_$name")
  kill -TERM "$pid" 2>/dev/null || true
  for ((i = 0; i < limit * 20; i++)); do
    kill -0 "$pid" 2>/dev/null || break
    sleep 0.05
  done
  if kill -0 "$pid" 2>/dev/null; then
    echo "$name did not exit within ${limit}s of SIGTERM" >&2
    return 124
  fi
  local code=0
  wait "$pid" || code=$?
  return $code
}

# wait_exit NAME SECONDS: the exit code of a process that ends by itself.
wait_exit() {
  local name=$1 limit=$2 pid i
  pid=$(eval echo "\$PID_$name")
  for ((i = 0; i < limit * 20; i++)); do
    kill -0 "$pid" 2>/dev/null || break
    sleep 0.05
  done
  if kill -0 "$pid" 2>/dev/null; then
    echo "$name still running after ${limit}s" >&2
    return 124
  fi
  local code=0
  wait "$pid" || code=$?
  return $code
}

# show NAME...: prints logs (on failure, for the CTest output).
show() {
  local name
  for name in "$@"; do
    echo "----- $name.log" >&2
    tail -n 40 "$OUT/$name.log" >&2 || true
  done
}

# assert_json FILE PYTHON_EXPRESSIONS...: each expression over `s` (the
# summary) must hold; prints the summary and the failed expression otherwise.
assert_json() {
  local file=$1
  shift
  python3 - "$file" "$@" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
failed = [e for e in sys.argv[2:] if not eval(e, {}, {"s": s})]
if failed:
    print("summary:", json.dumps(s, indent=1, sort_keys=True), file=sys.stderr)
    for e in failed:
        print("FAILED:", e, file=sys.stderr)
    sys.exit(1)
PY
}
