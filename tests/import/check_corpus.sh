#!/bin/sh
# check_corpus.sh BINDIR SOURCE [EXPECTED_ERROR]
# Without EXPECTED_ERROR: SOURCE compiles to an image, which runs 300 scans on
# the interpreter and on native code with the same values for every alias.
# With it: ldc refuses SOURCE with exactly that message (the file named as in
# its own directory) and leaves no output behind.
set -eu
bindir=$1 src=$2
dir=$(dirname "$src") file=$(basename "$src")
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
if [ $# -ge 3 ]; then
  status=0
  (cd "$dir" && "$bindir/ldc" "$file" -o "$tmp/prog.bin") 2> "$tmp/err" || status=$?
  if [ "$status" -ne 1 ]; then echo "FAIL: $src: exit status $status, expected 1" >&2; exit 1; fi
  if [ -e "$tmp/prog.bin" ]; then echo "FAIL: $src: an output file was left behind" >&2; exit 1; fi
  if ! diff -u "$3" "$tmp/err"; then echo "FAIL: $src: message differs from $3" >&2; exit 1; fi
  exit 0
fi
"$bindir/ldc" "$src" -o "$tmp/prog.bin"
watch=$("$bindir/ldc" "$src" --emit=il | sed -n 's/^\.alias \([^ ]*\) .*/\1/p' | paste -sd, -)
for engine in interp native; do
  if [ -n "$watch" ]; then
    "$bindir/ldrun" "$tmp/prog.bin" --engine=$engine --scans 300 --watch "$watch" > "$tmp/$engine"
  else
    "$bindir/ldrun" "$tmp/prog.bin" --engine=$engine --scans 300 > "$tmp/$engine"
  fi
done
if [ "$(wc -l < "$tmp/interp")" -ne 301 ]; then echo "FAIL: $src: expected 300 scans" >&2; exit 1; fi
if ! diff -u "$tmp/interp" "$tmp/native"; then echo "FAIL: $src: native code differs from the interpreter" >&2; exit 1; fi
