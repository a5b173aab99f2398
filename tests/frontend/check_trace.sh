#!/bin/sh
# check_trace.sh BINDIR SOURCE BASE ENGINE [EXPECTED]
# Runs SOURCE (any program ldc reads) over BASE.csv and compares the
# watched values with EXPECTED (default BASE.expected), whose header names them.
# ENGINE interp or native runs an image written by ldc (-O0; native-O1, native-O2
# at those levels), c40sim a C40 image on the simulator, c40interp the IL on the
# C40-hosted interpreter; "source" runs the file on the interpreter, "c" through
# the C route (ldc --emit=c and the system cc), "fast-source" the file on the fast
# interpreter (no image).
# LDC_TRACE_FLAGS: more ldrun options (--fault=continue for a trace that runs
# on past an index fault).
set -eu
bindir=$1 src=$2 base=$3 engine=$4
flags_run=${LDC_TRACE_FLAGS:-}
expected=${5:-$base.expected}
# The C40 divides REALs by a reciprocal and two Newton steps, never above the
# exact quotient (docs/c40.md, "Division"): where a watched REAL shows that
# (it prints exactly, docs/format.md), BASE.c40.expected holds the C40's values.
case "$engine" in c40*) [ $# -lt 5 ] && [ -f "$base.c40.expected" ] && expected=$base.c40.expected ;; esac
watch=$(head -n 1 "$expected" | cut -d, -f2-)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
if [ "$engine" = source ]; then
  "$bindir/ldrun" "$src" --engine=interp --trace "$base.csv" --watch "$watch" $flags_run > "$tmp/out"
elif [ "$engine" = c ]; then
  "$bindir/ldrun" "$src" --engine=c --trace "$base.csv" --watch "$watch" $flags_run > "$tmp/out"
elif [ "$engine" = fast-source ]; then  # the source on the fast interpreter, no image
  "$bindir/ldrun" "$src" --engine=fast --trace "$base.csv" --watch "$watch" $flags_run > "$tmp/out"
else
  case "$engine" in
    c40sim) flags=--target=c40 run=c40sim ;;
    c40interp) flags=-O0 run=c40interp ;;
    native-O*) flags=-${engine#native-} run=native ;;
    *) flags=-O0 run=$engine ;;
  esac
  "$bindir/ldc" "$src" $flags -o "$tmp/prog.bin"
  "$bindir/ldrun" "$tmp/prog.bin" --engine="$run" --trace "$base.csv" --watch "$watch" $flags_run > "$tmp/out"
fi
if ! diff -u "$expected" "$tmp/out"; then
  echo "FAIL: $src on $engine differs from $expected" >&2
  exit 1
fi
