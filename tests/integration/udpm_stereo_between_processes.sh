#!/usr/bin/env bash
# One process publishes 60 full-size (960x600 BGR, 3.5 MB) stereo pairs at
# 30 Hz over udpm; another, with the project's default receive buffer,
# must receive every one of them, decoded as ivoa.stereo_image_t, no gaps.
set -euo pipefail
B=${IVOA_BUILD_DIR:?}
out=$(mktemp -d); trap 'rm -rf "$out"; kill $(jobs -p) 2>/dev/null || true' EXIT
"$B/bin/ivoa-lcm-stats" --expect STEREO_IMAGES=60 --duration 30 --print-every 0 --json "$out/stats.json" \
  --ready-file "$out/ready" &
stats=$!
. "$IVOA_SOURCE_DIR/tests/harness/wait_for.sh"
wait_for_file "$out/ready" 10
"$B/tests/ivoa-test-publish" --count 60 --rate 30
wait $stats
python3 - "$out/stats.json" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))["channels"]["STEREO_IMAGES"]
assert s["type"] == "ivoa.stereo_image_t", s
assert s["count"] == 60 and s["seq_gaps"] == 0 and s["utime_regressions"] == 0, s
print("OK: 60/60 stereo pairs over udpm, no gaps:", s)
PY
