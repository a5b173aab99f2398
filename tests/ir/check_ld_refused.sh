#!/bin/sh
# check_ld_refused.sh BINDIR SOURCE MESSAGE
# ldc SOURCE --emit=ld -o OUT must fail with MESSAGE on stderr and leave no OUT.
set -eu
bindir=$1 src=$2 msg=$3
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
if "$bindir/ldc" "$src" --emit=ld -o "$tmp/out.ld" 2> "$tmp/err"; then
  echo "FAIL: $src was drawn; expected: $msg" >&2
  exit 1
fi
if ! grep -qF "$msg" "$tmp/err"; then
  echo "FAIL: expected '$msg', got:" >&2
  cat "$tmp/err" >&2
  exit 1
fi
if [ -e "$tmp/out.ld" ]; then echo "FAIL: an output file was left behind" >&2; exit 1; fi
