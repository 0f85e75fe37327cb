#!/usr/bin/env bash
# The README's main command: installs what is missing, builds, then runs the
# main job on the built-in simulator (record -> label -> dataset -> train ->
# evaluate -> report). Arguments go to the main job, e.g. --scale smoke|default|full,
# --out DIR, --live; see tools/main_job/ivoa-main-job.sh --help.
# The flags first: --help, or a mistyped one, is answered before minutes
# of installing and building (the main job is a plain script until it runs).
IVOA_MAIN_JOB_CHECK_FLAGS=1 "$(dirname "$0")/main_job/ivoa-main-job.sh" "$@" || exit
case " $* " in *" -h "*|*" --help "*) exit 0 ;; esac
source "$(dirname "$0")/setup/common.sh"
install_packages
build_project
step "Main job"
exec "$IVOA_ROOT/tools/main_job/ivoa-main-job.sh" "$@"
