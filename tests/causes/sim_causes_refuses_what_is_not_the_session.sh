#!/usr/bin/env bash
# ivoa-sim-causes refuses, by name and before rendering anything, what
# would explain a session wrongly: its log given twice (every row twice),
# a scene file of another scene (every frame skipped, an empty CSV, exit
# 0), a --start-utime far from the log's frames (it stepped the trajectory
# billions of frames and hung), an output that is the log, a file of the
# dataset or the scene file, or the other output by another name.
set -euo pipefail
shopt -s inherit_errexit
B=${IVOA_BUILD_DIR:?}; S=${IVOA_SOURCE_DIR:?}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
"$B/bin/ivoa-sim-driver" --scene "$S/libs/sim/scenes/indoor_office.yaml" --frames 1 --as-fast-as-possible \
  --log-level warn --lcm-url "file://$out/office_s5.lcmlog?mode=w"
"$B/bin/ivoa-dataset" build --labels jppc --out "$out/data" "$out/office_s5.lcmlog" >/dev/null  # its failures

# expect CODE TEXT ARGS...: ivoa-sim-causes ARGS exits CODE (in 60 s) saying TEXT.
expect() {
  local code=0
  timeout 60 "$B/bin/ivoa-sim-causes" --no-variants --dataset data --out "$out/c.csv" "${@:3}" >"$out/said.txt" 2>&1 || code=$?
  if [ "$code" != "$1" ] || ! grep -qF -- "$2" "$out/said.txt"; then
    cat "$out/said.txt"
    echo "FAIL: ivoa-sim-causes ${*:3}: exit $code (expected $1), expected to say: $2" >&2
    exit 1
  fi
}
cd "$out"
expect 2 "office_s5.lcmlog and ./office_s5.lcmlog are both session office_s5" office_s5.lcmlog ./office_s5.lcmlog
expect 3 "the log's scene is 'indoor_office', $S/libs/sim/scenes/home.yaml is 'home'" \
  --scene "$S/libs/sim/scenes/home.yaml" office_s5.lcmlog
expect 3 "--start-utime 5 is not the session's first frame" --start-utime 5 office_s5.lcmlog
# Detector settings no detector takes: a flag error before the logs are read (was exit 3 after them).
expect 2 "rect_scale must be in [0.05, 1]" --rect_scale 0 office_s5.lcmlog
# An output that is the log: it was truncated to a CSV header before it was read.
before=$(md5sum <office_s5.lcmlog)
for outputs in "--out office_s5.lcmlog" "--out c.csv --variants-out office_s5.lcmlog"; do
  code=0
  # shellcheck disable=SC2086
  "$B/bin/ivoa-sim-causes" $outputs office_s5.lcmlog >said.txt 2>&1 || code=$?
  [ "$code" = 2 ] && grep -qF "office_s5.lcmlog is the input office_s5.lcmlog (or a file in it): it would be written over" said.txt ||
    { cat said.txt; echo "FAIL: $outputs: exit $code" >&2; exit 1; }
  [ "$(md5sum <office_s5.lcmlog)" = "$before" ] || { echo "FAIL: $outputs changed the log" >&2; exit 1; }
done
# A file of the dataset, or the scene file: cut to a CSV header, they broke the dataset and the scene.
cp "$S/libs/sim/scenes/indoor_office.yaml" scene.yaml
kept=$(cat data/office_s5/samples.csv scene.yaml | md5sum)
for outputs in "--dataset data --out data/office_s5/samples.csv" "--scene scene.yaml --out scene.yaml" \
  "--scene scene.yaml --out c.csv --variants-out ./scene.yaml"; do
  code=0
  # shellcheck disable=SC2086
  "$B/bin/ivoa-sim-causes" --no-variants $outputs office_s5.lcmlog >said.txt 2>&1 || code=$?
  [ "$code" = 2 ] && grep -qF "(or a file in it): it would be written over" said.txt || { cat said.txt; echo "FAIL: $outputs: exit $code" >&2; exit 1; }
done
[ "$(cat data/office_s5/samples.csv scene.yaml | md5sum)" = "$kept" ] || { echo "FAIL: an input was written over" >&2; exit 1; }
code=0
"$B/bin/ivoa-sim-causes" --out c2.csv --variants-out ./c2.csv office_s5.lcmlog >said.txt 2>&1 || code=$?
[ "$code" = 2 ] && grep -qF -- "--out c2.csv and --variants-out ./c2.csv are the same file" said.txt ||
  { cat said.txt; echo "FAIL: --out c2.csv --variants-out ./c2.csv: exit $code" >&2; exit 1; }
# A --rate that is not the log's gives other frame indices, so other noise:
# said, a warning where the frames' times cannot be whole periods of it.
"$B/bin/ivoa-sim-driver" --scene "$S/libs/sim/scenes/indoor_office.yaml" --frames 2 --rate 10 --as-fast-as-possible \
  --log-level warn --lcm-url "file://$out/office_s7.lcmlog?mode=w"
"$B/bin/ivoa-dataset" build --labels jppc --out "$out/data" "$out/office_s7.lcmlog" >/dev/null
for rate_said in "20:info :--rate 20, and its frames' times read as 10 Hz" \
  "15:warning :--rate 15, but its frames' times are not whole periods of it (they read as 10 Hz)" "10:"; do
  rate=${rate_said%%:*} said=${rate_said#*:}
  "$B/bin/ivoa-sim-causes" --no-variants --dataset data --rate "$rate" --out c7.csv office_s7.lcmlog >said.txt 2>&1
  if [ -n "$said" ]; then
    grep -q "${said%%:*}.*office_s7: ${said#*:}" said.txt || { cat said.txt; echo "FAIL: --rate $rate" >&2; exit 1; }
  elif grep -q "rate" said.txt; then
    cat said.txt; echo "FAIL: --rate 10, the log's own, was questioned" >&2; exit 1
  fi
done
# Without its stereo pairs the re-rendering failed as "cannot encode unknown pixel format -1".
mkdir nostereo
"$B/bin/ivoa-log-play" -s 0 -x STEREO_IMAGES --log-level warn --lcm-url "file://$out/nostereo/office_s5.lcmlog?mode=w" \
  office_s5.lcmlog
expect 3 "nostereo/office_s5.lcmlog: no decodable STEREO_IMAGES message" nostereo/office_s5.lcmlog
echo "OK: a log given twice, another scene, a wrong start, no stereo pairs and an output over an input or the other output refused by name; another --rate said"
