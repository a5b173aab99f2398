#!/bin/sh
# check_iecil_roundtrip.sh BINDIR SOURCE ENGINE [BASE]
# Prints SOURCE (any program ldc reads) as IEC IL (ldc --emit=iec-il), compiles
# that IEC IL and runs it over BASE.csv (default: SOURCE without .ld) on ENGINE
# (interp or native): the watched values must be BASE.expected, the source's own.
set -eu
bindir=$1 src=$2 engine=$3
base=${4:-${src%.ld}}
watch=$(head -n 1 "$base.expected" | cut -d, -f2-)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
"$bindir/ldc" "$src" --emit=iec-il -o "$tmp/prog.il"
if head -c 200 "$tmp/prog.il" | grep -q '^\.'; then echo "FAIL: not IEC IL" >&2; exit 1; fi
"$bindir/ldc" "$tmp/prog.il" -o "$tmp/prog.bin"
"$bindir/ldrun" "$tmp/prog.bin" --engine="$engine" --trace "$base.csv" --watch "$watch" > "$tmp/out"
if ! diff -u "$base.expected" "$tmp/out"; then
  echo "FAIL: $src through --emit=iec-il on $engine differs from $base.expected" >&2
  exit 1
fi
