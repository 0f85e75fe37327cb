#!/usr/bin/env bash
# Runs a command inside a private network namespace whose only interface is
# a multicast-capable loopback with a route for 224.0.0.0/4, so udpm LCM works
# and no test traffic reaches (or comes from) a real network or a live robot.
# A second loopback address, 127.0.0.2, is there for a second GigE camera.
# Exit 77 (CTest's skip code) with the reason when namespaces are forbidden.
set -u
if [ "${IVOA_IN_NETNS:-0}" != 1 ]; then
  if [ "$(id -u)" = 0 ]; then flags=(-n); else flags=(-r -n); fi
  if ! unshare "${flags[@]}" true 2>/dev/null; then
    echo "SKIPPED: cannot create a network namespace here (unshare ${flags[*]} not permitted)." >&2
    echo "Multicast LCM tests need one; the memq:// and file:// tests still ran." >&2
    exit 77
  fi
  exec unshare "${flags[@]}" env IVOA_IN_NETNS=1 "$0" "$@"
fi
ip link set lo up || exit 77
ip link set lo multicast on || exit 77
ip route add 224.0.0.0/4 dev lo || exit 77
ip addr add 127.0.0.2/8 dev lo 2>/dev/null || true
# Tests use a non-default port so they never mix with a live system.
export LCM_DEFAULT_URL="${IVOA_TEST_LCM_URL:-udpm://239.255.76.67:7671?ttl=0}"
unset IVOA_STATUS_CHANNEL  # the tests listen for heartbeats on PROCESS_STATUS
exec "$@"
