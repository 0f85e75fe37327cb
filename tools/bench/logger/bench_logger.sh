#!/usr/bin/env bash
# Logger benchmark: N seconds (default 60) of 30 Hz stereo pairs
# (2 x 960x600 BGR, 3.5 MB) plus 30 Hz depth (640x480 uint16) and a 1 Hz rig
# calibration over real UDP multicast LCM (a private network namespace on
# loopback), recorded side by side by ivoa-logger and by Debian's
# lcm-logger 1.3.1 (the baseline, with the same receive buffer). Both are
# stopped with SIGINT a short grace after the publisher ends; then every log
# is read back and counted against what was published.
#
#   tools/bench/logger/bench_logger.sh [--seconds 60] [--dir /tmp] [--build build] [--no-baseline]
#                                      [--logger-args "--socket-buffer-mb 0"]
#
# Needs 2 x ~125 MB/s of disk and about 7.5 GB per logger per minute in
# --dir; the logs are deleted after counting.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
src=$(cd "$here/../../.." && pwd)
seconds=60 parent=${TMPDIR:-/tmp} build=${IVOA_BUILD_DIR:-$src/build} baseline=1 grace_s=2 logger_args=""
while [ $# -gt 0 ]; do
  case $1 in
    --seconds) seconds=$2; shift 2 ;;
    --dir) parent=$2; shift 2 ;;
    --build) build=$2; shift 2 ;;
    --no-baseline) baseline=0; shift ;;
    --logger-args) logger_args=$2; shift 2 ;;
    -h|--help) sed -n '2,14p' "$0"; exit 0 ;;
    *) echo "unknown argument $1" >&2; exit 2 ;;
  esac
done
build=$(cd "$build" && pwd)
if [ "${IVOA_IN_NETNS:-0}" != 1 ]; then
  echo "command: $0 $*"
  exec "$src/tests/harness/in_netns.sh" "$0" --seconds "$seconds" --dir "$parent" --build "$build" \
    --logger-args "$logger_args" $([ $baseline = 1 ] || echo --no-baseline)
fi
. "$src/tests/harness/wait_for.sh"

frames=$((30 * seconds))
url="$LCM_DEFAULT_URL&recv_buf_size=16777216"
out=$(mktemp -d "$parent/ivoa-logger-bench.XXXXXX")
trap 'kill $(jobs -p) 2>/dev/null || true; rm -rf "$out"' EXIT
need_mb=$(((1 + baseline) * 130 * seconds))
avail_mb=$(df -Pm "$out" | awk 'NR == 2 { print $4 }')
[ "$avail_mb" -gt "$need_mb" ] || { echo "need ${need_mb} MB free in $parent, have ${avail_mb} MB" >&2; exit 1; }

# The kernel's receive buffer (bytes, as it counts them) of PID's socket on the LCM port.
receive_buffer() {
  local port=${LCM_DEFAULT_URL##*:}
  ss -uamnp "sport = :${port%%\?*}" | awk -v pid="pid=$1," '
    index($0, pid) { found = 1; next }
    found && match($0, /rb[0-9]+/) { print substr($0, RSTART + 2, RLENGTH - 2); exit }'
}
cpu_seconds() { awk '{ printf "%.1f", ($14 + $15) / 100 }' "/proc/$1/stat"; }
peak_rss_mb() { awk '/VmHWM/ { printf "%.0f", $2 / 1024 }' "/proc/$1/status"; }
# Datagrams the kernel dropped because PID's UDP receive buffer was full.
socket_drops() {
  local inodes
  inodes=$(ls -l "/proc/$1/fd" 2>/dev/null | sed -n 's/.*socket:\[\([0-9]*\)\]$/\1/p' | tr '\n' ' ')
  awk -v inodes=" $inodes " 'NR > 1 && index(inodes, " " $10 " ") { d += $NF } END { print d + 0 }' /proc/net/udp
}

# shellcheck disable=SC2086 # extra arguments are split on purpose
"$build/bin/ivoa-logger" "$out/ivoa.lcmlog" --lcm-url "$url" --ready-file "$out/ready" $logger_args 2>"$out/ivoa.err" &
ours=$!
wait_for_file "$out/ready" 10
if [ $baseline = 1 ]; then
  lcm-logger --lcm-url="$url" "$out/debian.lcmlog" >"$out/debian.out" 2>&1 &
  theirs=$!
  for _ in $(seq 200); do  # subscribed once its multicast socket is bound
    ss -uanp 2>/dev/null | grep -q "pid=$theirs," && break
    sleep 0.05
  done
fi

echo "ivoa-logger ${logger_args:-(default options)}; $(nproc) CPUs, load average $(cut -d' ' -f1-3 /proc/loadavg)"
echo "publishing $frames stereo pairs + $frames depth images at 30 Hz, $seconds calibrations at 1 Hz ($url)"
"$build/tests/ivoa-test-logger-helper" publish --calibrations "$seconds" --foreign 0 --rate 1 &
extras=$!
start=$(date +%s.%N)
"$build/tests/ivoa-test-publish" --count "$frames" --rate 30 --depth 2>/dev/null
end=$(date +%s.%N)
wait $extras
sleep $grace_s  # the baseline has no other way to tell it has everything

ours_rb=$(receive_buffer $ours)
[ $baseline = 1 ] && theirs_rb=$(receive_buffer $theirs)
ours_cpu=$(cpu_seconds $ours) ours_rss=$(peak_rss_mb $ours) ours_drops=$(socket_drops $ours)
stop=$(date +%s.%N)
kill -INT $ours
if [ $baseline = 1 ]; then
  theirs_cpu=$(cpu_seconds $theirs) theirs_rss=$(peak_rss_mb $theirs) theirs_drops=$(socket_drops $theirs)
  kill -INT $theirs
  wait $theirs || true
fi
wait $ours
ours_exit=$(date +%s.%N)

count() {  # count LOG: per-channel counts and missing sequence numbers, as "CH count missing" lines
  "$build/bin/ivoa-log-check" --json "$out/$1.json" "$out/$1.lcmlog" >/dev/null || true
  python3 - "$out/$1.json" <<'PY'
import json, sys
for name, c in json.load(open(sys.argv[1]))["channels"].items():
    print(name, c["count"], c.get("missing_seq", 0))
PY
}
ours_counts=$(count ivoa)
theirs_counts=$([ $baseline = 1 ] && count debian || true)
size_mb() { stat -c %s "$1" | awk '{ printf "%d", $1 / 1e6 }'; }
ours_mb=$(size_mb "$out/ivoa.lcmlog")
theirs_mb=$([ $baseline = 1 ] && size_mb "$out/debian.lcmlog" || echo 0)

python3 - "$seconds" "$frames" "$start" "$end" "$stop" "$ours_exit" "$ours_mb" "$theirs_mb" \
  "$ours_cpu" "$ours_rss" "${theirs_cpu:-0}" "${theirs_rss:-0}" "$baseline" "$ours_counts" "$theirs_counts" \
  "$ours_drops" "${theirs_drops:-0}" "${ours_rb:-0}" "${theirs_rb:-0}" \
  "$(grep -o 'received.*queue peak [0-9.]* MB' "$out/ivoa.err" | tail -1)" "$(cut -d' ' -f1-3 /proc/loadavg)" <<'PY'
import sys
(seconds, frames, start, end, stop, ours_exit, ours_mb, theirs_mb, ours_cpu, ours_rss, theirs_cpu, theirs_rss,
 baseline, ours_counts, theirs_counts, ours_drops, theirs_drops, ours_rb, theirs_rb, summary, load) = sys.argv[1:]
frames, baseline = int(frames), baseline == "1"
publish_s = float(end) - float(start)
def parse(text):
    return {l.split()[0]: (int(l.split()[1]), int(l.split()[2])) for l in text.splitlines() if l.strip()}
ours, theirs = parse(ours_counts), parse(theirs_counts)
published = {"STEREO_IMAGES": frames, "DEPTH_IMAGE": frames, "RIG_CALIBRATION": int(seconds)}
print(f"\n{'channel':<18}{'published':>10}{'ivoa-logger':>13}{'lost':>7}" +
      (f"{'lcm-logger 1.3.1':>18}{'lost':>7}" if baseline else ""))
lost_ours = lost_theirs = 0
for name, n in published.items():
    o, t = ours.get(name, (0, 0))[0], theirs.get(name, (0, 0))[0]
    lost_ours, lost_theirs = lost_ours + n - o, lost_theirs + n - t
    print(f"{name:<18}{n:>10}{o:>13}{n - o:>7}" + (f"{t:>18}{n - t:>7}" if baseline else ""))
print(f"{'total':<18}{sum(published.values()):>10}{'':>13}{lost_ours:>7}" + (f"{'':>18}{lost_theirs:>7}" if baseline else ""))
gaps = {k: v[1] for k, v in ours.items() if v[1]}
print(f"\nivoa-logger sequence gaps: {gaps or 'none'}")
print(f"publishing took {publish_s:.1f} s; traffic {int(ours_mb) / publish_s:.0f} MB/s; load average at the end {load}")
print(f"ivoa-logger: {int(ours_mb)} MB written, {int(ours_mb) / publish_s:.0f} MB/s sustained while recording; "
      f"exit {float(ours_exit) - float(stop):.2f} s after SIGINT; CPU {ours_cpu} s; peak RSS {ours_rss} MB; "
      f"socket buffer {int(ours_rb) / 1e6:.0f} MB, datagrams dropped by the kernel: {ours_drops}")
print(f"  its summary: {summary}")
if baseline:
    print(f"lcm-logger : {int(theirs_mb)} MB written; CPU {theirs_cpu} s; peak RSS {theirs_rss} MB; "
          f"socket buffer {int(theirs_rb) / 1e6:.0f} MB, datagrams dropped by the kernel: {theirs_drops}")
PY
