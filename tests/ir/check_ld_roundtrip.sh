#!/bin/sh
# check_ld_roundtrip.sh BINDIR SOURCE
# Prints SOURCE (any program ldc reads) as a ladder grid (ldc --emit=ld), reads
# the grid back and compares both programs' IL (ldc --emit=il) with the source
# line numbers taken out (`.rung line N` and the header comment naming the
# file): the grid must give the same instructions, operands, edge slots,
# labels, titles, aliases and retentive words.  A second --emit=ld of the
# grid must print the same grid (the drawing is a fixed point).
set -eu
bindir=$1 src=$2
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
"$bindir/ldc" "$src" --emit=ld -o "$tmp/prog.ld"
"$bindir/ldc" "$src" --emit=il | sed -e 's/^\.rung line [0-9]*/.rung/' -e '1d' > "$tmp/a.il"
"$bindir/ldc" "$tmp/prog.ld" --emit=il | sed -e 's/^\.rung line [0-9]*/.rung/' -e '1d' > "$tmp/b.il"
if ! diff -u "$tmp/a.il" "$tmp/b.il"; then
  echo "FAIL: $src through --emit=ld gives different IL" >&2
  cat "$tmp/prog.ld" >&2
  exit 1
fi
"$bindir/ldc" "$tmp/prog.ld" --emit=ld | sed 1d > "$tmp/again.ld"
if ! sed 1d "$tmp/prog.ld" | diff -u - "$tmp/again.ld"; then
  echo "FAIL: --emit=ld of the grid of $src is not the same grid" >&2
  exit 1
fi
