#!/bin/sh
# Builds GNU as, objdump and objcopy for the TMS320C4x (tic4x) from the
# binutils source that Debian ships in the package `binutils-source`
# (/usr/src/binutils/binutils-<version>.tar.xz). Debian's binutils-multiarch
# does not include the tic4x target, so the C40 cross-checks need these.
#
#   tests/assembler/build_tic4x_tools.sh [DIR]
#
# Installs DIR/bin/tic4x-as, tic4x-objdump and tic4x-objcopy (DIR defaults to
# $LDC_TIC4X_DIR, else $HOME/.cache/ldc-tic4x). Does nothing if they exist.
# Needs: binutils-source, a C compiler, make, xz. Takes about a minute on
# 2 cores. No network access.
set -eu
dir=${1:-${LDC_TIC4X_DIR:-${HOME:-/tmp}/.cache/ldc-tic4x}}
if [ -x "$dir/bin/tic4x-as" ] && [ -x "$dir/bin/tic4x-objdump" ] && [ -x "$dir/bin/tic4x-objcopy" ]; then
  echo "tic4x tools in $dir/bin"
  exit 0
fi
src=$(ls /usr/src/binutils/binutils-*.tar.xz 2>/dev/null | head -n 1 || true)
if [ -z "$src" ]; then
  echo "build_tic4x_tools: /usr/src/binutils/binutils-*.tar.xz not found;" \
       "install it with: apt-get install -y binutils-source" >&2
  exit 1
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
tar -xJf "$src" -C "$work"
cd "$work"/binutils-*
mkdir build
cd build
jobs=$(nproc 2>/dev/null || echo 2)
log=$work/build.log
../configure --target=tic4x-none-coff --disable-nls --disable-werror \
  --disable-gdb --disable-gdbserver --disable-sim --disable-gprof \
  --disable-gprofng --disable-ld --without-zstd MAKEINFO=true >"$log" 2>&1 ||
  { tail -n 30 "$log" >&2; exit 1; }
make -j"$jobs" MAKEINFO=true configure-binutils all-bfd all-opcodes all-libiberty \
  all-libsframe all-libctf all-gas >>"$log" 2>&1 || { tail -n 40 "$log" >&2; exit 1; }
make -C binutils -j"$jobs" MAKEINFO=true objdump objcopy >>"$log" 2>&1 ||
  { tail -n 40 "$log" >&2; exit 1; }
mkdir -p "$dir/bin"
for t in as:gas/as-new objdump:binutils/objdump objcopy:binutils/objcopy; do
  cp "${t#*:}" "$dir/bin/tic4x-${t%%:*}.tmp.$$"
  mv "$dir/bin/tic4x-${t%%:*}.tmp.$$" "$dir/bin/tic4x-${t%%:*}"
done
echo "tic4x tools in $dir/bin"
