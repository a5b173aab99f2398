#!/bin/sh
# check_example.sh BINDIR EXAMPLE.ld|EXAMPLE.sfc ENGINE
# Compiles the example to an image with ldc, runs the image over the example's
# trace on ENGINE and compares with EXAMPLE.expected, whose header names the
# watched devices.  ENGINE "source" runs the .ld directly on the interpreter;
# "c" is the C route (ldc --emit=c compiled by the system cc -O2; for a chart,
# the switch form of docs/sfc.md);
# "native-O1", "native-O2" compile at that level; "native-cd" is the
# change-driven image (ldc --change-driven=1 -O2) and "native-cd-plc" the
# same run by the PLC runtime with the trace driver.
set -eu
bindir=$1 src=$2 engine=$3
base=${src%.*}
watch=$(head -n 1 "$base.expected" | cut -d, -f2-)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
if [ "$engine" = source ]; then
  "$bindir/ldrun" "$src" --engine=interp --trace "$base.csv" --watch "$watch" > "$tmp/out"
elif [ "$engine" = native-cd ] || [ "$engine" = native-cd-plc ]; then
  "$bindir/ldc" "$src" -O2 --change-driven=1 -o "$tmp/prog.bin"
  if [ "$engine" = native-cd ]; then
    "$bindir/ldrun" "$tmp/prog.bin" --trace "$base.csv" --watch "$watch" > "$tmp/out"
  else
    "$bindir/ldrun" "$tmp/prog.bin" --io=trace --clock=virtual --free-run --trace "$base.csv" --watch "$watch" > "$tmp/out"
  fi
elif [ "$engine" = c ]; then
  "$bindir/ldrun" "$src" --engine=c --trace "$base.csv" --watch "$watch" > "$tmp/out"
else
  level=-O0
  case $engine in native-O*) level=-${engine#native-}; engine=native;; esac
  "$bindir/ldc" "$src" $level -o "$tmp/prog.bin"
  "$bindir/ldrun" "$tmp/prog.bin" --engine="$engine" --trace "$base.csv" --watch "$watch" > "$tmp/out"
fi
if ! diff -u "$base.expected" "$tmp/out"; then
  echo "FAIL: $src on $engine differs from $base.expected" >&2
  exit 1
fi
