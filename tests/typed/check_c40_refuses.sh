#!/bin/sh
# check_c40_refuses.sh BINDIR ENGINE WHAT -- the C40 (a 32-bit machine) refuses
# a program with a 64-bit type, by the type's name: WHAT is a case file
# (tests/typed/cases/NAME_64.il) or a type name (then the program is
# `MOVE.TYPE D0 D2`, and the message must name that type).  ENGINE c40sim
# compiles with ldc --target=c40; c40interp runs the source's IL on the
# C40-hosted interpreter.  A refusal is a non-zero exit below 128 (no signal)
# and an `error:` message naming a 64-bit type; nothing else passes.
set -u
bindir=$1 engine=$2 what=$3
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
types='LINT|ULINT|LWORD|LREAL|TIME|LTIME|DATE|TOD|DT|LDATE|LTOD|LDT'
case "$what" in
  *.il) src=$what ;;
  *) src=$tmp/$what.il types=$what
     printf '; one %s move\n.rung line 1\n    TRUE\n    MOVE.%s D0 D2\n.end\n' "$what" "$what" > "$src" ;;
esac
# a case without a 64-bit type: the C40-hosted interpreter refuses every typed
# instruction, and the C40 the REAL functions, each naming it (ADD.INT, EXPT.REAL)
case "$engine:$what" in
  c40sim:*_64.il) ;;
  *.il) types="$types|BOOL|SINT|INT|DINT|USINT|UINT|UDINT|BYTE|WORD|DWORD|REAL" ;;
esac
if [ "$engine" = c40sim ]; then
  "$bindir/ldc" "$src" --target=c40 -o "$tmp/prog.bin" > "$tmp/out" 2>&1
  rc=$?
else  # the source's IL, straight to the C40-hosted interpreter (no x86-64 image in between)
  "$bindir/ldrun" "$src" --engine=c40interp --scans 1 > "$tmp/out" 2>&1
  rc=$?
fi
cat "$tmp/out"
if [ $rc -eq 0 ]; then echo "FAIL: $engine accepted $src (a 64-bit type on the C40)"; exit 1; fi
if [ $rc -ge 128 ]; then echo "FAIL: $engine died (exit $rc) on $src"; exit 1; fi
if ! grep -q 'error' "$tmp/out" || ! grep -Eqw "$types" "$tmp/out"; then
  echo "FAIL: $engine's refusal of $src does not name the type ($types)"; exit 1
fi
