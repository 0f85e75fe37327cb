#!/usr/bin/env bash
# ivoa-log-play into a log (file://PATH?mode=w or a): it refuses to write over
# one of the logs it is to play (opening it would empty it), leaving that
# log as it was; into another file it plays every event; an output LCM
# cannot publish to (a file:// URL without mode=w) is named in its summary.
set -euo pipefail
shopt -s inherit_errexit
B=${IVOA_BUILD_DIR:?}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
"$B/bin/ivoa-sim-driver" --frames 2 --as-fast-as-possible --lcm-url "file://$out/in.lcmlog?mode=w" --log-level warn
before=$(md5sum <"$out/in.lcmlog")

# mode=a appended the log to itself (it doubled)
for mode in w a; do
  code=0
  (cd "$out" && "$B/bin/ivoa-log-play" -s 0 --lcm-url "file://$out/./in.lcmlog?mode=$mode" in.lcmlog) >"$out/same.txt" 2>&1 ||
    code=$?
  [ "$code" = 2 ] || { cat "$out/same.txt"; echo "FAIL: mode=$mode into the input exited $code, expected 2" >&2; exit 1; }
  grep -q "would write over in.lcmlog, one of the logs to play" "$out/same.txt" || { cat "$out/same.txt"; exit 1; }
  [ "$(md5sum <"$out/in.lcmlog")" = "$before" ] || { echo "FAIL: mode=$mode changed the input log" >&2; exit 1; }
done

"$B/bin/ivoa-log-play" -s 0 --lcm-url "file://$out/copy.lcmlog?mode=w" "$out/in.lcmlog" >"$out/copy.txt" 2>&1
"$B/bin/ivoa-log-check" --json "$out/in.json" "$out/in.lcmlog" >/dev/null
"$B/bin/ivoa-log-check" --json "$out/copy.json" "$out/copy.lcmlog" >/dev/null
python3 - "$out/in.json" "$out/copy.json" <<'PY'
import json, sys
played, copied = (json.load(open(p))["channels"] for p in sys.argv[1:])
for channel, c in played.items():
    if channel == "PROCESS_STATUS":
        continue  # the player's own heartbeats are added
    assert copied[channel]["count"] == c["count"], (channel, c["count"], copied[channel]["count"])
PY

code=0
"$B/bin/ivoa-log-play" -s 0 --lcm-url "file://$out/copy.lcmlog" "$out/in.lcmlog" >"$out/read_only.txt" 2>&1 || code=$?
[ "$code" = 1 ] || { cat "$out/read_only.txt"; echo "FAIL: an output LCM refused exited $code, expected 1" >&2; exit 1; }
grep -q "refused by LCM: not published" "$out/read_only.txt" || { cat "$out/read_only.txt"; exit 1; }
# A disk that fills (here a file size limit, SIGXFSZ ignored so the write
# fails as on a full disk): LCM writes through stdio and reports nothing, so
# the play ended "finished", exit 0, over a cut log.
code=0
(trap '' XFSZ && ulimit -f 200 && "$B/bin/ivoa-log-play" -s 0 --lcm-url "file://$out/cut.lcmlog?mode=w" "$out/in.lcmlog") \
  >"$out/cut.txt" 2>&1 || code=$?
[ "$code" = 4 ] || { cat "$out/cut.txt"; echo "FAIL: a cut output log exited $code, expected 4" >&2; exit 1; }
grep -q "the output log is not whole: $out/cut.lcmlog holds" "$out/cut.txt" || { cat "$out/cut.txt"; exit 1; }

code=0
"$B/bin/ivoa-log-play" -s 0 --lcm-url memq:// "$out/in.lcmlog" "$out/./in.lcmlog" >"$out/twice.txt" 2>&1 || code=$?
[ "$code" = 2 ] || { cat "$out/twice.txt"; echo "FAIL: a log given twice exited $code, expected 2" >&2; exit 1; }
grep -q "is given twice" "$out/twice.txt" || { cat "$out/twice.txt"; exit 1; }
echo "OK: the input log kept, a copy played, refusals named, a cut output and a log given twice refused"
