#!/bin/sh
# check_string_refuses.sh BINDIR ENGINE CASE -- the engines that do not run
# STRING (docs/il.md, "Strings": the C40 and the C40-hosted interpreter) refuse tests/typed/cases/CASE.il by
# name: a non-zero exit below 128 (no signal) and an `error:` message that
# names STRING or the string-argument instruction ARGS (the C40-hosted
# interpreter names the first typed instruction it meets, which may be an
# ARGS.DINT).  Nothing else passes: an engine that ran it, or died, fails.
set -u
bindir=$1 engine=$2 case=$3
src=$(cd "$(dirname "$0")" && pwd)/cases/$case.il
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
case "$engine" in
  c40sim) "$bindir/ldc" "$src" --target=c40 -o "$tmp/prog.bin" > "$tmp/out" 2>&1 ;;
  *) "$bindir/ldrun" "$src" --engine="$engine" --scans 1 > "$tmp/out" 2>&1 ;;
esac
rc=$?
cat "$tmp/out"
if [ $rc -eq 0 ]; then echo "FAIL: $engine accepted $src (STRING)"; exit 1; fi
if [ $rc -ge 128 ]; then echo "FAIL: $engine died (exit $rc) on $src"; exit 1; fi
if ! grep -q 'error' "$tmp/out" || ! grep -Eq '(\<STRING\>|\<ARGS\.)' "$tmp/out"; then
  echo "FAIL: $engine's refusal of $src does not name STRING"; exit 1
fi
