#!/usr/bin/env bash
# The README's test command: installs what is missing, builds, runs every test.
# Extra arguments go to ctest (e.g. -L unit, -L stereo, -R Jpp, --rerun-failed).
source "$(dirname "$0")/setup/common.sh"
install_packages
build_project
step "Running the tests"
unset IVOA_STATUS_CHANNEL  # a robot's heartbeat channel: the tests expect each program's default
cd "$IVOA_BUILD_DIR"
ctest --output-on-failure --timeout 900 -j "${IVOA_TEST_JOBS:-2}" "$@"
