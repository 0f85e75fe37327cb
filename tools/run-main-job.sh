#!/usr/bin/env bash
# The README's main command: installs what is missing, builds, then runs the
# main job on the built-in simulator (record -> label -> dataset -> train ->
# evaluate -> report). Arguments go to the main job, e.g. --scale smoke|default|full,
# --out DIR, --live; see tools/main_job/ivoa-main-job.sh --help.
source "$(dirname "$0")/setup/common.sh"
install_packages
build_project
step "Main job"
exec "$IVOA_ROOT/tools/main_job/ivoa-main-job.sh" "$@"
