# Shared set-up for the two README commands (source this file).
# Installs missing Debian packages (with sudo when not root), then
# configures and builds incrementally into build/.
set -euo pipefail

IVOA_ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
IVOA_BUILD_DIR=${IVOA_BUILD_DIR:-$IVOA_ROOT/build}
export IVOA_ROOT IVOA_BUILD_DIR

step() { printf '\n\033[1m==> %s\033[0m\n' "$*"; }

install_packages() {
  local wanted missing=() sudo=""
  wanted=$(grep -vE '^\s*(#|$)' "$IVOA_ROOT/tools/setup/debian-packages.txt")
  for p in $wanted; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  if [ ${#missing[@]} -eq 0 ]; then
    step "Debian packages: all $(echo "$wanted" | wc -w) present"
    return
  fi
  [ "$(id -u)" = 0 ] || sudo=sudo
  step "Installing ${#missing[@]} Debian packages: ${missing[*]}"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get -o DPkg::Lock::Timeout=600 install -y --no-install-recommends \
    "${missing[@]}"
}

build_project() {
  step "Configuring and building (Release) in $IVOA_BUILD_DIR"
  mkdir -p "$IVOA_BUILD_DIR"
  cmake -S "$IVOA_ROOT" -B "$IVOA_BUILD_DIR" -G Ninja -DCMAKE_BUILD_TYPE=Release -DIVOA_WERROR=ON \
    ${IVOA_CMAKE_ARGS:-} > "$IVOA_BUILD_DIR/configure.log" 2>&1 ||
    { cat "$IVOA_BUILD_DIR/configure.log"; return 1; }
  # Two jobs: LibTorch and PCL translation units need ~1.5 GB each.
  cmake --build "$IVOA_BUILD_DIR" -j "${IVOA_JOBS:-2}"
}
