#!/usr/bin/env bash
# Dataset generation speed: a simulated session recorded at 30 Hz (stereo
# 960x600 Bayer + depth 640x480 + calibration + ground truth) is turned into
# a dataset by re-running a perception model and the depth monitor offline,
# with the paper's input (left patches, fixed squares) and with the main
# job's (two views, footprint-scaled squares, JPP-C's evidence).
# Side by side: the budget (the recording rate, 30 frames/s: ratio > 1 =
# faster than real time) and the floor (reading and checking the same log
# with ivoa-log-check, no decoding of images).
#   tools/bench/dataset/bench_dataset.sh [--frames N] [--build DIR]
set -euo pipefail
root=$(cd "$(dirname "$0")/../../.." && pwd)
build=$root/build
frames=300
while [ $# -gt 0 ]; do
  case "$1" in
    --frames) frames=$2; shift 2 ;;
    --build) build=$2; shift 2 ;;
    *) echo "usage: $0 [--frames N] [--build DIR]" >&2; exit 2 ;;
  esac
done
B=$build/bin
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
echo "Recording a $frames-frame session of the office scene at 30 Hz session time..."
"$B/ivoa-sim-driver" --scene "$root/libs/sim/scenes/indoor_office.yaml" --seed 9 --rate 30 --frames "$frames" \
  --as-fast-as-possible --start-utime 1700000000000000 --lcm-url "file://$tmp/s.lcmlog?mode=w" --log-level warn
size=$(du -m "$tmp/s.lcmlog" | cut -f1)
printf '\nDataset generation from a %d-frame log (%d MB), one process, OMP/OpenCV default threads:\n' "$frames" "$size"
printf '  %-48s %10s %12s %14s\n' "labels" "seconds" "frames/s" "x real time"
start=$(date +%s.%N)
"$B/ivoa-log-check" "$tmp/s.lcmlog" > /dev/null
end=$(date +%s.%N)
/usr/bin/python3 -c "import sys; s = $end - $start; print(f'  {\"floor: read the log (ivoa-log-check)\":<48} {s:10.1f} {$frames / s:12.1f} {$frames / s / 30:13.1f}x')"
# name | ivoa-dataset build options | description.
runs=(
  "jppc|--labels jppc|re-run JPP-C + depth monitor + Algorithm 1"
  "dense|--labels dense|re-run dense SGBM + depth monitor + Algorithm 1"
  "jppc2|--labels jppc --views 2 --patch-scale 1.6|JPP-C as the main job: two views, scaled"
)
for run in "${runs[@]}"; do
  IFS='|' read -r name options desc <<< "$run"
  start=$(date +%s.%N)
  # shellcheck disable=SC2086  # options are words
  "$B/ivoa-dataset" --log-level warn build --out "$tmp/d_$name" $options "$tmp/s.lcmlog" > "$tmp/$name.txt" 2>&1
  end=$(date +%s.%N)
  /usr/bin/python3 -c "import sys; s = $end - $start; print(f'  {sys.argv[1]:<48} {s:10.1f} {$frames / s:12.1f} {$frames / s / 30:13.1f}x')" "$desc"
  rm -rf "$tmp/d_$name"
done
printf '  %-48s %10s %12.1f %13.1fx\n' "budget: the recording rate" "" 30 1
