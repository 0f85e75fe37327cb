#!/usr/bin/env bash
# lcm-spy with the project's message types, on Java 17.
# Debian's /usr/bin/lcm-spy passes -Xincgc, which Java 9+ rejects, and does
# not pull in jchart2d; this calls the Spy class directly.
#
#   tools/lcm_spy/ivoa-lcm-spy.sh                       # live, $LCM_DEFAULT_URL or the default group
#   tools/lcm_spy/ivoa-lcm-spy.sh -l 'file:///abs/path/session.lcmlog?speed=1'   # a log
#
# Live full-size images: Java LCM 1.3.1 ignores recv_buf_size, so raise the
# host's default socket buffer first (sudo sysctl -w net.core.rmem_default=16777216
# net.core.rmem_max=16777216) or spy on a log.
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
jar=${IVOA_TYPES_JAR:-${IVOA_BUILD_DIR:-$root/build}/share/java/lcmtypes_ivoa.jar}
J=/usr/share/java
for f in "$jar" "$J/lcm.jar" "$J/jchart2d.jar"; do
  [ -f "$f" ] || { echo "ivoa-lcm-spy: missing $f (build the project; apt-get install liblcm-java libjchart2d-java)" >&2; exit 3; }
done
# lcm-spy is a window: without a display Java ends in a HeadlessException trace.
if [ -z "${DISPLAY:-}" ]; then
  echo "ivoa-lcm-spy: no display (DISPLAY is not set): lcm-spy opens a window. Run it in a desktop session," \
    "over 'ssh -X', or under 'xvfb-run -a'; in a terminal, build/bin/ivoa-lcm-stats shows the traffic." >&2
  exit 1
fi
# ClassDiscoverer scans $CLASSPATH for LCM types.
export CLASSPATH="$jar${CLASSPATH:+:$CLASSPATH}"
exec java -Djava.net.preferIPv4Stack=true -Xmx1g -cp "$J/lcm.jar:$J/jchart2d.jar:$jar" lcm.spy.Spy "$@"
