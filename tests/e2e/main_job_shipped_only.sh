#!/usr/bin/env bash
# The main job's --shipped-only run at smoke scale: records only the test
# sessions, trains nothing and reports the shipped model alone, on exactly
# the held-out sessions. Settings the shipped model cannot take are refused.
set -euo pipefail
S=${IVOA_SOURCE_DIR:?}
JOB=$S/tools/main_job/ivoa-main-job.sh
OUT=$(mktemp -d)
trap 'if [ "${KEEP_OUT:-0}" = 1 ]; then echo "outputs kept in $OUT" >&2; else rm -rf "$OUT"; fi' EXIT

# usage_error EXPECTED_TEXT ARGS...: the job must refuse ARGS with exit 2, saying EXPECTED_TEXT.
usage_error() {
  local expected=$1 rc=0
  shift
  "$JOB" "$@" > "$OUT/refused.log" 2>&1 || rc=$?
  if [ $rc != 2 ] || ! grep -q -- "$expected" "$OUT/refused.log"; then
    echo "FAILED: '$*' gave exit $rc, not a usage error naming '$expected':" >&2; cat "$OUT/refused.log" >&2; exit 1
  fi
}
for bad in "--views 1" "--patch-scale 0" "--live"; do
  # shellcheck disable=SC2086
  usage_error "--shipped-only" --scale smoke --shipped-only $bad --out "$OUT/refused"
  [ ! -e "$OUT/refused" ] || { echo "FAILED: --shipped-only $bad started a run" >&2; exit 1; }
done
# Without --out (the default folder is chosen before the scale is checked).
usage_error "--scale must be" --scale no-such-scale
usage_error "--scale must be" --scale no-such-scale --shipped-only
# The model's patch scale written another way passes the check (the scale's error comes after it).
usage_error "--scale must be" --scale no-such-scale --shipped-only --patch-scale 1.60
# Flags checked before anything is recorded (a bad --patch-scale failed
# only once every session was; a value left out was "$2: unbound variable").
usage_error "--scale needs a value" --scale
usage_error "--out needs a value" --out --scale smoke
usage_error "--patch-scale must be a number" --scale smoke --patch-scale abc --out "$OUT/refused"
usage_error "--noise-draws must be 0 (off) or 2 to 999" --scale smoke --noise-draws 1000 --out "$OUT/refused"
usage_error "white space in it is not supported" --scale smoke --out "$OUT/with space"
[ ! -e "$OUT/refused" ] && [ ! -e "$OUT/with space" ] || { echo "FAILED: a refused run made its folder" >&2; exit 1; }
# A full run's folder is not overwritten.
mkdir -p "$OUT/full_run" && echo model > "$OUT/full_run/model_dense.pt"
usage_error "holds a full run" --scale smoke --shipped-only --out "$OUT/full_run"
[ "$(ls "$OUT/full_run")" = model_dense.pt ] || { echo "FAILED: the full run's folder was touched" >&2; exit 1; }

"$JOB" --scale smoke --shipped-only --out "$OUT/run" > "$OUT/main_job.log" 2>&1 ||
  { echo "FAILED: the main job exited non-zero" >&2; tail -40 "$OUT/main_job.log" >&2; exit 1; }
for f in eval_shipped_jppc/eval.json causes_jppc.csv report/report.md report/jppc_eval_shipped_jppc/clusters_tsne.png; do
  [ -s "$OUT/run/$f" ] || { echo "FAILED: $f missing or empty" >&2; tail -40 "$OUT/main_job.log" >&2; exit 1; }
done
for f in model_jppc.pt model_dense.pt data_dense eval_jppc causes_dense.csv; do
  [ ! -e "$OUT/run/$f" ] || { echo "FAILED: $f made by a run that should train nothing" >&2; exit 1; }
done

/usr/bin/python3 - "$OUT/run" <<'PY'
import json, sys, pathlib
out = pathlib.Path(sys.argv[1])
logs = sorted(p.stem for p in (out / "logs").glob("*.lcmlog"))
assert logs == ["indoor_office_s31", "polished_lobby_s31", "wet_parking_lot_s31"], f"recorded {logs}"
models = json.loads((out / "report/metrics.json").read_text())["models"]
assert list(models) == ["jppc_eval_shipped_jppc"], f"the report holds {list(models)}"
ev = json.loads((out / "eval_shipped_jppc/eval.json").read_text())
assert sorted(s["session"] for s in ev["sessions"]) == logs and {s["split"] for s in ev["sessions"]} == {"test"}, ev["sessions"]
assert models["jppc_eval_shipped_jppc"]["overall"]["n"] == ev["samples"] > 0
print(f"shipped model alone on {len(logs)} test sessions, {ev['samples']} cells")
PY
# A rerun keeps whole logs and records again one an earlier run left cut
# short (it was kept as "already recorded").
cut=$OUT/run/logs/polished_lobby_s31.lcmlog
truncate -s $(($(stat -c %s "$cut") / 2)) "$cut"
"$JOB" --scale smoke --shipped-only --out "$OUT/run" > "$OUT/rerun.log" 2>&1 ||
  { echo "FAILED: the rerun exited non-zero" >&2; tail -40 "$OUT/rerun.log" >&2; exit 1; }
grep -q "indoor_office_s31: already recorded" "$OUT/rerun.log" &&
  grep -q "polished_lobby_s31: the log of an earlier run is not 6 whole frames: recorded again" "$OUT/rerun.log" &&
  "${IVOA_BUILD_DIR:?}/bin/ivoa-log-check" "$cut" --expect STEREO_IMAGES=6 > /dev/null ||
  { echo "FAILED: the cut log was kept, or a whole one recorded again" >&2; cat "$OUT/rerun.log" >&2; exit 1; }
echo "OK: main job --shipped-only (smoke) $(grep -o 'Main job done in [0-9ms]*' "$OUT/main_job.log")"
