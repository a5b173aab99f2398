#!/bin/sh
# check_iecil_refused.sh BINDIR SOURCE MESSAGE
# ldc SOURCE --emit=iec-il must fail, print MESSAGE (a fixed string) and write nothing.
set -eu
bindir=$1 src=$2 msg=$3
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
if "$bindir/ldc" "$src" --emit=iec-il -o "$tmp/out.il" 2> "$tmp/err"; then
  echo "FAIL: $src was printed as IEC IL" >&2; exit 1
fi
cat "$tmp/err"
grep -qF -- "$msg" "$tmp/err" || { echo "FAIL: expected: $msg" >&2; exit 1; }
[ ! -e "$tmp/out.il" ] || { echo "FAIL: an output file was written" >&2; exit 1; }
