#!/usr/bin/env bash
# ivoa-logger on a disk that refuses writes, first over a file-size limit
# (RLIMIT_FSIZE, which gives the same short writes and errors a full disk
# does), then on a really full tmpfs where mounting one is permitted, and
# there also stopping short of --min-free-mb (refusing to start below it).
# Each time it must exit with code 4 (kExitIoError) saying why, and leave a log
# that ends with its last whole event: intact for ivoa-log-check and
# replayable by lcm-logplayer, with a sidecar that records the error.
# Input comes from a log (file:// URL), so no network is needed.
set -euo pipefail
B=${IVOA_BUILD_DIR:?}

# check_failed_log DIR WORK REASON: the logger that wrote DIR/out.lcmlog
# (exit code and stderr in WORK) exited 4 and left a good log.
check_failed_log() {
  local dir=$1 work=$2 reason=$3 code
  code=$(cat "$work/code")
  [ "$code" = 4 ] || { echo "FAIL: exit code $code, expected 4"; cat "$work/stderr"; return 1; }
  grep -q "$reason" "$work/stderr" || { echo "FAIL: stderr does not say '$reason'"; cat "$work/stderr"; return 1; }
  "$B/bin/ivoa-log-check" --json "$work/check.json" "$dir/out.lcmlog" >/dev/null
  timeout 20 lcm-logplayer --speed=0 --lcm-url="file://$work/replayed.lcmlog?mode=w" "$dir/out.lcmlog" >/dev/null
  "$B/bin/ivoa-log-check" --json "$work/replayed.json" "$work/replayed.lcmlog" >/dev/null
  python3 - "$dir" "$work" "$reason" <<'PY'
import json, sys
d, work, reason = sys.argv[1:4]
events = json.load(open(work + "/check.json"))["events"]
assert 0 < events < 40, f"expected a partial log, got {events} of 40 events"
assert json.load(open(work + "/replayed.json"))["events"] == events, "lcm-logplayer did not replay every event"
side = json.load(open(d + "/out.lcmlog.json"))
assert side["complete"] is False and reason in side["error"], side
assert side["events"] == events and side["session"]["written"] == events, side
print(f"OK ({reason}): exit 4, {events} whole events kept and replayable, sidecar says: {side['error']}")
PY
}

# run_logger DIR WORK [PREFIX...]: records the input log into DIR/out.lcmlog,
# with $LOGGER_ARGS.
run_logger() {
  local dir=$1 work=$2
  shift 2
  set +e
  # shellcheck disable=SC2086 # LOGGER_ARGS is a list of flags
  "$@" "$B/bin/ivoa-logger" --lcm-url "file://$input?speed=0" ${LOGGER_ARGS:-} "$dir/out.lcmlog" 2>"$work/stderr"
  echo $? >"$work/code"
  set -e
}

if [ "${1:-}" = --on-full-tmpfs ]; then  # the second half, in a private mount namespace
  input=$2 dir=$3 work=$4
  mount -t tmpfs -o size=30m tmpfs "$dir"
  # Without a reserve: filled to the last block.
  LOGGER_ARGS="--min-free-mb 0" run_logger "$dir" "$work"
  check_failed_log "$dir" "$work" "No space left on device"
  # With one (the default 1000 MB is more than this disk): no file at all.
  rm -f "$dir"/out.lcmlog*
  run_logger "$dir" "$work"
  [ "$(cat "$work/code")" = 4 ] && grep -q "under the 1250 MB a start needs (--min-free-mb 1000" "$work/stderr" &&
    [ -z "$(ls -A "$dir")" ] || { echo "FAIL: a disk below the reserve at start"; cat "$work/stderr"; ls "$dir"; exit 1; }
  echo "OK: a disk already below --min-free-mb: exit 4, no file created"
  # A reserve of 12 MB: the log stops whole with about that much still free.
  LOGGER_ARGS="--min-free-mb 12" run_logger "$dir" "$work"
  check_failed_log "$dir" "$work" "event would leave less than --min-free-mb 12"
  free_bytes=$(($(stat -f -c '%a * %S' "$dir")))
  [ "$free_bytes" -ge 12000000 ] || { echo "FAIL: only $free_bytes bytes left free with a 12 MB reserve"; exit 1; }
  echo "OK: stopped with $free_bytes bytes free"
  exit 0
fi

out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
input=$out/in.lcmlog
"$B/tests/ivoa-test-publish" --lcm-url "file://$input?mode=w" --count 20 --rate 1000 --depth 2>/dev/null

mkdir "$out/limit"
run_logger "$out/limit" "$out/limit" prlimit --fsize=30000000
check_failed_log "$out/limit" "$out/limit" "File too large"

# An existing log is never overwritten without --force.
set +e
"$B/bin/ivoa-logger" --lcm-url "file://$input?speed=0" "$out/limit/out.lcmlog" 2>"$out/exists.err"
code=$?
set -e
[ $code = 4 ] && grep -q -e "--force overwrites it, --increment records to a new NAME-1" "$out/exists.err" || { echo "FAIL: existing file: exit $code"; exit 1; }
echo "OK: an existing log is refused with exit 4"

# With --increment (what record.pmd passes, for a respawned logger given a
# fixed name) the existing log is kept byte for byte and the next free
# numbered name records the whole session, split or not.
kept=$(sha256sum <"$out/limit/out.lcmlog")
for n in 1 2; do
  "$B/bin/ivoa-logger" --lcm-url "file://$input?speed=0" --increment "$out/limit/out.lcmlog" 2>>"$out/increment.err"
done
"$B/bin/ivoa-logger" --lcm-url "file://$input?speed=0" -i --split-mb 1 "$out/limit/out.lcmlog" 2>>"$out/increment.err"
"$B/bin/ivoa-logger" --lcm-url "file://$input?speed=0" -i --split-mb 1 "$out/limit/out.lcmlog" 2>>"$out/increment.err"
[ "$(sha256sum <"$out/limit/out.lcmlog")" = "$kept" ] || { echo "FAIL: --increment changed the existing log"; exit 1; }
grep -q "out.lcmlog exists (a log is never overwritten): logging to .*out-1.lcmlog" "$out/increment.err" ||
  { echo "FAIL: no warning naming the new file"; cat "$out/increment.err"; exit 1; }
grep -q "out.lcmlog.00 exists (a log is never overwritten): logging to .*out-1.lcmlog" "$out/increment.err" ||
  { echo "FAIL: no warning naming the split log's first part"; cat "$out/increment.err"; exit 1; }
for f in out-1.lcmlog out-2.lcmlog; do
  "$B/bin/ivoa-log-check" --json "$out/$f.json" "$out/limit/$f" >/dev/null
  grep -q '"events": 40' "$out/$f.json" || { echo "FAIL: $f does not hold the 40 events"; exit 1; }
done
[ -f "$out/limit/out.lcmlog.00" ] && [ -f "$out/limit/out-1.lcmlog.00" ] || { echo "FAIL: split parts"; ls "$out/limit"; exit 1; }
set +e
"$B/bin/ivoa-logger" --lcm-url "file://$input?speed=0" -i -f "$out/limit/x.lcmlog" 2>/dev/null
code=$?
set -e
[ $code = 2 ] || { echo "FAIL: --increment with --force: exit $code, expected 2"; exit 1; }
echo "OK: --increment keeps the existing logs and records to out-1, out-2 (and out-1.lcmlog.00 when split)"

# A sidecar caught by a glob (out-1.lcmlog*) is named as such, not as a damaged log.
set +e
"$B/bin/ivoa-log-check" "$out/limit/out-1.lcmlog" "$out/limit/out-1.lcmlog.json" >"$out/check_sidecar.txt" 2>&1
code=$?
set -e
[ $code = 3 ] && grep -q "out-1.lcmlog.json: UNREADABLE: not an LCM log.*ivoa-logger's sidecar" "$out/check_sidecar.txt" ||
  { echo "FAIL: a sidecar given to ivoa-log-check: exit $code"; cat "$out/check_sidecar.txt"; exit 1; }
echo "OK: ivoa-log-check names a sidecar given as a log"

mkdir "$out/tmpfs" "$out/work"
if unshare -m true 2>/dev/null; then
  unshare -m "$0" --on-full-tmpfs "$input" "$out/tmpfs" "$out/work"
else
  echo "NOTE: no mount namespace here (unshare -m not permitted); the full-tmpfs case was not run"
fi
