#!/bin/sh
# check_trace.sh BINDIR SOURCE BASE ENGINE
# Runs SOURCE (any program ldc reads) over BASE.csv and compares the
# watched values with BASE.expected, whose header names them.  ENGINE interp or
# native runs an image written by ldc (-O0; native-O1, native-O2 at those levels),
# c40sim a C40 image on the simulator; "source" runs the file on the interpreter,
# "c" through the C route (ldc --emit=c and the system cc).
set -eu
bindir=$1 src=$2 base=$3 engine=$4
watch=$(head -n 1 "$base.expected" | cut -d, -f2-)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
if [ "$engine" = source ]; then
  "$bindir/ldrun" "$src" --engine=interp --trace "$base.csv" --watch "$watch" > "$tmp/out"
elif [ "$engine" = c ]; then
  "$bindir/ldrun" "$src" --engine=c --trace "$base.csv" --watch "$watch" > "$tmp/out"
else
  case "$engine" in
    c40sim) flags=--target=c40 run=c40sim ;;
    native-O*) flags=-${engine#native-} run=native ;;
    *) flags=-O0 run=$engine ;;
  esac
  "$bindir/ldc" "$src" $flags -o "$tmp/prog.bin"
  "$bindir/ldrun" "$tmp/prog.bin" --engine="$run" --trace "$base.csv" --watch "$watch" > "$tmp/out"
fi
if ! diff -u "$base.expected" "$tmp/out"; then
  echo "FAIL: $src on $engine differs from $base.expected" >&2
  exit 1
fi
