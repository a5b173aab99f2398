#!/bin/sh
# projects_test.sh BINDIR PROJECTS -- ldc --project on every PROJECTS/*.ldp:
# NAME.out is the expected stdout of an accepted project (its configuration
# table), NAME.err the exact stderr of a refused one (exit status 1).
# Run from PROJECTS so the messages name the files as the project does.
# Set LDC_UPDATE=1 to rewrite the expected files after a deliberate change.
set -u
bin=$1 dir=$2
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
cd "$dir" || exit 1
fails=0 checks=0
for p in *.ldp; do
  n=${p%.ldp}
  "$bin/ldc" --project "$p" > "$tmp/out" 2> "$tmp/err"; rc=$?
  checks=$((checks + 1))
  if [ "${LDC_UPDATE:-}" = 1 ]; then
    if [ $rc -eq 0 ]; then cp "$tmp/out" "$n.out"; rm -f "$n.err"; else cp "$tmp/err" "$n.err"; rm -f "$n.out"; fi
    continue
  fi
  if [ -f "$n.err" ]; then
    if [ $rc -ne 1 ]; then echo "FAIL: $p: exit $rc, expected 1" >&2; fails=$((fails + 1)); continue; fi
    if ! diff -u "$n.err" "$tmp/err"; then echo "FAIL: $p: stderr differs from $n.err" >&2; fails=$((fails + 1)); fi
  else
    if [ $rc -ne 0 ]; then echo "FAIL: $p: exit $rc" >&2; cat "$tmp/err" >&2; fails=$((fails + 1)); continue; fi
    if ! diff -u "$n.out" "$tmp/out"; then echo "FAIL: $p: stdout differs from $n.out" >&2; fails=$((fails + 1)); fi
  fi
done

# With -o DIR: one image per task, each with its 'config' section, and a
# project file that runs them; an image project checks the same way.
checks=$((checks + 1))
if "$bin/ldc" --project shared.ldp -o "$tmp/build" 2> "$tmp/err" &&
   [ -f "$tmp/build/fast.bin" ] && [ -f "$tmp/build/belt.bin" ] && [ -f "$tmp/build/slow.bin" ] &&
   [ -f "$tmp/build/plant.ldp" ]; then
  "$bin/ldc" --project "$tmp/build/plant.ldp" > "$tmp/out2" 2>&1 || { echo "FAIL: the built project does not check" >&2; cat "$tmp/out2" >&2; fails=$((fails + 1)); }
  diff -u shared.out "$tmp/out2" > /dev/null || { echo "FAIL: the built project's table differs" >&2; diff -u shared.out "$tmp/out2" >&2; fails=$((fails + 1)); }
  "$bin/ldobjdump" "$tmp/build/fast.bin" > /dev/null || { echo "FAIL: ldobjdump refuses a project image" >&2; fails=$((fails + 1)); }
else
  echo "FAIL: ldc --project -o" >&2; cat "$tmp/err" >&2; fails=$((fails + 1))
fi
checks=$((checks + 1))
if "$bin/ldc" --project conflict.ldp -o "$tmp/refused" 2> /dev/null || [ -e "$tmp/refused" ]; then
  echo "FAIL: a refused project wrote output" >&2; fails=$((fails + 1))
fi
echo "$((checks - fails)) passed, $fails failed"
[ $fails -eq 0 ]
