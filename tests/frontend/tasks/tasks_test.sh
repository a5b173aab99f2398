#!/bin/sh
# tasks_test.sh BINDIR -- PLCopen and ST configurations of several tasks
# (docs/plcopen.md, "Configurations of several tasks"; docs/st.md), from this directory:
# NAME.xml or NAME.st with NAME.out is accepted and `ldc NAME.xml` prints that
# configuration table; NAME.xml with NAME.err is refused with exactly that
# message and no output.  plcopen_tasks.xml also: `ldc -o DIR` writes an image
# per task and a project that checks the same; `ldrun FILE --io=stdio` runs the
# tasks together (plcopen_tasks.cmds -> plcopen_tasks.expected); each task's
# program alone agrees on every engine (check_corpus.sh with TASK).
# UPDATE=1 rewrites the expected files.
set -u
bin=$(cd "$1" && pwd)
here=$(cd "$(dirname "$0")" && pwd)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
cd "$here" || exit 1
fails=0
fail() { echo "FAIL: $*" >&2; fails=$((fails + 1)); }
for x in *.xml *.st; do
  n=${x%.*}
  "$bin/ldc" "$x" > "$tmp/out" 2> "$tmp/err"; rc=$?
  if [ "${UPDATE:-}" = 1 ]; then
    if [ $rc -eq 0 ]; then cp "$tmp/out" "$n.out"; else cp "$tmp/err" "$n.err"; fi
    continue
  fi
  if [ -f "$n.err" ]; then
    [ $rc -eq 1 ] || fail "$x: exit $rc, expected 1"
    diff -u "$n.err" "$tmp/err" || fail "$x: message differs from $n.err"
    "$bin/ldc" "$x" -o "$tmp/refused" 2> /dev/null && fail "$x: ldc -o accepted it"
    [ -e "$tmp/refused" ] && fail "$x: a refused configuration left output"
  else
    [ $rc -eq 0 ] || { fail "$x: exit $rc"; cat "$tmp/err" >&2; }
    diff -u "$n.out" "$tmp/out" || fail "$x: the configuration table differs from $n.out"
  fi
done
# ldc -o DIR: one image per task and the project naming them
if "$bin/ldc" plcopen_tasks.xml -o "$tmp/build" 2> "$tmp/err" && [ -f "$tmp/build/fast.bin" ] &&
   [ -f "$tmp/build/slow.bin" ] && [ -f "$tmp/build/plant.ldp" ]; then
  (cd "$tmp/build" && "$bin/ldc" --project plant.ldp) > "$tmp/out2" 2>&1 || fail "the written project does not check"
  diff -u plcopen_tasks.out "$tmp/out2" || fail "the written project's table differs"
else
  fail "ldc plcopen_tasks.xml -o DIR"; cat "$tmp/err" >&2
fi
# the tasks running together, sharing the relay RUN (a virtual clock: no timing in the replies)
"$bin/ldrun" plcopen_tasks.xml --io=stdio --clock=virtual < plcopen_tasks.cmds > "$tmp/replies" 2> "$tmp/err" ||
  { fail "ldrun plcopen_tasks.xml --io=stdio"; cat "$tmp/err" >&2; }
if [ "${UPDATE:-}" = 1 ]; then cp "$tmp/replies" plcopen_tasks.expected; fi
diff -u plcopen_tasks.expected "$tmp/replies" || fail "ldrun's replies differ from plcopen_tasks.expected"
# the same project in ST (st_tasks.st): the same replies, its LAMP and DONE named with their task
"$bin/ldrun" st_tasks.st --io=stdio --clock=virtual < st_tasks.cmds > "$tmp/st_replies" 2> "$tmp/err" ||
  { fail "ldrun st_tasks.st --io=stdio"; cat "$tmp/err" >&2; }
diff -u st_tasks.expected "$tmp/st_replies" || fail "ldrun's replies to st_tasks.st differ from st_tasks.expected"
for t in fast slow; do
  TASK=$t sh ../check_corpus.sh "$bin" "$here/st_tasks.st" || fail "st_tasks.st task $t on the engines"
done
# one program alone is refused without --task, and each task's program runs alike on every engine
"$bin/ldrun" plcopen_tasks.xml --scans 3 > /dev/null 2>&1 && fail "ldrun ran one program of several tasks without --task"
for t in fast slow; do
  TASK=$t sh ../check_corpus.sh "$bin" "$here/plcopen_tasks.xml" || fail "task $t on the engines"
done
"$bin/ldc" plcopen_tasks.xml --task nosuch --emit=il > /dev/null 2> "$tmp/err" && fail "--task nosuch accepted"
grep -q "no task 'nosuch' in the configuration (fast, slow)" "$tmp/err" || fail "--task nosuch: $(cat "$tmp/err")"
echo "$fails failed"
[ $fails -eq 0 ]
