#!/bin/sh
# check_typed.sh BINDIR CASE ENGINE -- runs tests/typed/cases/CASE.il over CASE.csv
# on ENGINE and compares the watched values with CASE.expected (written by
# gen_cases.py from MatIEC's definitions).  The engines are those of
# tests/frontend/check_trace.sh, which this mirrors: source and interp (the
# reference interpreter, from the source or from an image written by ldc -O0),
# native, native-O1, native-O2 and c40sim (an image by ldc), and fast, c (the C
# route) and c40interp, which run the source's IL (so that they do not wait for
# the x86-64 backend to compile it).
# On a mismatch, explain.py names each differing case.
set -eu
bindir=$1 case=$2 engine=$3
here=$(cd "$(dirname "$0")" && pwd)
base=$here/cases/$case
src=$base.il
watch=$(head -n 1 "$base.expected" | cut -d, -f2-)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
case "$engine" in
  source) "$bindir/ldrun" "$src" --engine=interp --trace "$base.csv" --watch "$watch" --fault=continue > "$tmp/out" ;;
  fast|c|c40interp) "$bindir/ldrun" "$src" --engine="$engine" --trace "$base.csv" --watch "$watch" --fault=continue > "$tmp/out" ;;
  *)
    case "$engine" in
      c40sim) flags=--target=c40 run=c40sim ;;
      native-O*) flags=-${engine#native-} run=native ;;
      *) flags=-O0 run=$engine ;;
    esac
    "$bindir/ldc" "$src" $flags -o "$tmp/prog.bin"
    "$bindir/ldrun" "$tmp/prog.bin" --engine="$run" --trace "$base.csv" --watch "$watch" --fault=continue > "$tmp/out" ;;
esac
if ! cmp -s "$base.expected" "$tmp/out"; then
  python3 "$here/explain.py" "$src" "$base.expected" "$tmp/out" >&2 || true
  echo "FAIL: $case on $engine differs from MatIEC's values ($base.expected)" >&2
  exit 1
fi
