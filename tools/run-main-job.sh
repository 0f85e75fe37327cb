#!/usr/bin/env bash
# The README's main command: installs what is missing, builds, then runs the
# main job on the built-in simulator.
source "$(dirname "$0")/setup/common.sh"
install_packages
build_project
step "Main job"
echo "The simulator and the processing pipeline are not built yet: this command"
echo "only installed the packages and built the foundation (messages, core library,"
echo "tools). What exists now:"
ls "$IVOA_BUILD_DIR/bin"
