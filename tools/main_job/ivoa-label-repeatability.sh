#!/usr/bin/env bash
# How much of the labels the sensor noise decides: records the main job's
# test sessions (nine scenes, one seed) once per simulator noise seed (same
# scene, poses and exposures; other camera and depth noise), labels each
# with the stereo detector and the depth monitor offline, and compares the
# labels cell by cell (tools/report/ivoa_label_repeatability.py).
#
# Usage: ivoa-label-repeatability.sh [--realisations K] [--seed S] [--frames N]
#                                    [--scenes A,B,...] [--detector jppc|dense] [--out DIR]
#   defaults: K = 4 noise seeds (0 = the main job's recordings), seed 31,
#   60 frames per session (the full-scale test sessions), the nine scenes, jppc
# Needs the build (./tools/run-main-job.sh or ./tools/run-tests.sh); about
# 20 s per session and realisation on 2 cores; logs are deleted once labelled.
set -euo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
BIN=${IVOA_BUILD_DIR:-$ROOT/build}/bin
PY=/usr/bin/python3
SCENE_NAMES=(indoor_office home corridor polished_lobby warehouse outdoor_campus sidewalk wet_parking_lot night_plaza)
realisations=4
seed=31
frames=60
detector=jppc
out=$ROOT/out/label-repeatability
usage_error() { echo "ivoa-label-repeatability: $*" >&2; exit 2; }
while [ $# -gt 0 ]; do
  case "$1" in --realisations|--seed|--frames|--scenes|--detector|--out)
    [ $# -ge 2 ] && [ -n "$2" ] && [ "${2#--}" = "$2" ] || usage_error "$1 needs a value (see --help)" ;;
  esac
  case "$1" in
    --realisations) realisations=$2; shift 2 ;;
    --seed) seed=$2; shift 2 ;;
    --frames) frames=$2; shift 2 ;;
    --scenes) IFS=, read -r -a SCENE_NAMES <<< "$2"; shift 2 ;;
    --detector) detector=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    -h|--help) sed -n '2,/^set -euo/p' "$0" | sed '$d'; exit 0 ;;
    *) echo "ivoa-label-repeatability: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done
for scene in "${SCENE_NAMES[@]}"; do
  [ -f "$ROOT/libs/sim/scenes/$scene.yaml" ] || { echo "ivoa-label-repeatability: no scene '$scene' in libs/sim/scenes" >&2; exit 2; }
done
# Plain decimal numbers only: a value is used in shell arithmetic, which
# would run a command written into it.
[[ $realisations =~ ^[0-9]{1,3}$ ]] && [ "$realisations" -ge 2 ] ||
  usage_error "--realisations must be 2 to 999, not '$realisations'"
[[ $seed =~ ^[0-9]{1,6}$ ]] || usage_error "--seed must be a whole number 0 to 999999, not '$seed'"
[[ $frames =~ ^[0-9]{1,6}$ ]] && [ "$frames" -ge 1 ] ||
  usage_error "--frames must be a whole number 1 to 999999, not '$frames' (0 would record without end)"
case "$detector" in jppc|dense) ;; *) usage_error "--detector must be jppc or dense, not '$detector'" ;; esac
[ ${#SCENE_NAMES[@]} -gt 0 ] || usage_error "--scenes names no scene"
[ -x "$BIN/ivoa-sim-driver" ] || { echo "ivoa-label-repeatability: no build at $BIN (run ./tools/run-main-job.sh once)" >&2; exit 3; }

# The main job's session timing (RATE 2, a fixed start time per seed), so
# noise seed 0 reproduces its test sessions label for label.
utime=$((1700000000000000 + seed * 10000000000))
mkdir -p "$out"
# Sessions labelled before are kept only if labelled with these settings.
settings="seed $seed, $frames frames, $detector"
if [ -f "$out/settings.txt" ] && [ "$(cat "$out/settings.txt")" != "$settings" ]; then
  echo "  $out was labelled with $(cat "$out/settings.txt"): labelling again with $settings"
  rm -rf "$out"/data_noise*
fi
echo "$settings" > "$out/settings.txt"
datasets=()
for ((n = 0; n < realisations; n++)); do
  data=$out/data_noise$n
  datasets+=("$data")
  for scene in "${SCENE_NAMES[@]}"; do
    name=${scene}_s$seed
    [ -f "$data/$name/samples.csv" ] && continue
    log=$out/$name.noise$n.lcmlog
    LCM_DEFAULT_URL=memq:// "$BIN/ivoa-sim-driver" --log-level warn --scene "$ROOT/libs/sim/scenes/$scene.yaml" \
      --seed "$seed" --rate 2 --frames "$frames" --as-fast-as-possible --start-utime "$utime" --noise-seed "$n" \
      --log "$log"
    "$BIN/ivoa-dataset" --log-level warn build --out "$data" --labels "$detector" --views 1 --session "$name" "$log" |
      tail -1 | sed "s/^/  noise seed $n: /"
    rm -f "$log"
  done
done
"$PY" "$ROOT/tools/report/ivoa_label_repeatability.py" "${datasets[@]}" --json "$out/label_repeatability.json"
