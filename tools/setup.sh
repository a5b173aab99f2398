#!/bin/sh
# tools/setup.sh build|test -- installs the Debian packages ldc needs, if any
# is missing (README's two set-up commands and .ci/run call it).
#   build: the compiler, CMake and GoogleTest (the build configures the tests)
#   test:  also binutils and binutils-source (GNU as, objdump, tic4x built by
#          the c40_tools test), mbpoll and python3-pymodbus (the Modbus tests),
#          chromium (the monitor's browser test)
# It runs apt-get as root, or through sudo; it changes nothing when every
# package is there.
set -eu
case "${1:-}" in
  build) pkgs="cmake make g++ libgtest-dev" ;;
  test) pkgs="cmake make g++ libgtest-dev binutils binutils-source xz-utils mbpoll python3-pymodbus chromium" ;;
  *) echo "usage: tools/setup.sh build|test" >&2; exit 2 ;;
esac
need=""
for p in $pkgs; do
  dpkg -s "$p" >/dev/null 2>&1 || need="$need $p"
done
[ -z "$need" ] && exit 0
if [ "$(id -u)" -eq 0 ]; then
  as_root=""
elif command -v sudo >/dev/null 2>&1; then
  as_root="sudo"
else
  echo "tools/setup.sh: missing Debian packages:$need (run this script as root, or install them)" >&2
  exit 1
fi
echo "tools/setup.sh: installing$need" >&2
export DEBIAN_FRONTEND=noninteractive
$as_root apt-get update -qq
$as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq $need
