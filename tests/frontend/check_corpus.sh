#!/bin/sh
# check_corpus.sh BINDIR SOURCE [EXPECTED_ERROR]
# Without EXPECTED_ERROR: SOURCE compiles to images that run 300 scans of a
# pseudo-random input trace on the interpreter, on native code at -O0/-O1/-O2,
# on the change-driven image (its regions walked), on the C40 simulator and
# the C40-hosted interpreter, and through the C route,
# with the same values for every alias.
# With it: ldc refuses SOURCE with exactly that message (the file named as in
# its own directory) and leaves no output behind.
set -eu
bindir=$1 src=$2
# TASK=NAME: one task's program of a PLCopen configuration of several tasks
task=${TASK:+--task $TASK}
dir=$(dirname "$src") file=$(basename "$src")
tmp=$(mktemp -d)
[ -n "${KEEP:-}" ] || trap 'rm -rf "$tmp"' EXIT
if [ $# -ge 3 ]; then
  status=0
  (cd "$dir" && "$bindir/ldc" "$file" -o "$tmp/prog.bin") 2> "$tmp/err" || status=$?
  if [ "$status" -ne 1 ]; then echo "FAIL: $src: exit status $status, expected 1" >&2; exit 1; fi
  if [ -e "$tmp/prog.bin" ]; then echo "FAIL: $src: an output file was left behind" >&2; exit 1; fi
  if ! diff -u "$3" "$tmp/err"; then echo "FAIL: $src: message differs from $3" >&2; exit 1; fi
  exit 0
fi
# A pseudo-random input trace (a fixed LCG): every input alias (X, WX) set in
# 300 scans, bits toggling, words over a small range; dt 10 ms.
# A PLCopen configuration of several tasks: it builds as a project, and each
# task's program is checked as below (TASK=NAME).
if [ -z "$task" ] && ! "$bindir/ldc" "$src" --emit=il > "$tmp/il" 2> "$tmp/ilerr"; then
  tasks=$(sed -n 's/.*the configuration has [0-9]* tasks (\([^)]*\)).*/\1/p' "$tmp/ilerr" | head -n 1 | tr -d ',')
  if [ -z "$tasks" ]; then cat "$tmp/ilerr" >&2; exit 1; fi
  "$bindir/ldc" "$src" -o "$tmp/project"
  for t in $tasks; do TASK=$t sh "$0" "$bindir" "$src"; done
  exit 0
fi
"$bindir/ldc" "$src" $task --emit=il > "$tmp/il"
watch=$(sed -n 's/^\.alias \([^ ]*\) .*/\1/p' "$tmp/il" | paste -sd, -)
inputs=$(sed -n 's/^\.alias \([^ ]*\) \(W\{0,1\}X[0-9]*\)$/\1 \2/p' "$tmp/il")
echo "$inputs" | awk -f "$(dirname "$0")/random_trace.awk" > "$tmp/trace.csv"
# The interpreter defines the meaning; native code at every level and the C40
# simulator must give the same values scan by scan.
run() {  # run NAME LDC-FLAGS ENGINE
  "$bindir/ldc" "$src" $task $2 -o "$tmp/$1.bin"
  if [ -n "$watch" ]; then
    "$bindir/ldrun" "$tmp/$1.bin" --engine=$3 --trace "$tmp/trace.csv" --watch "$watch" > "$tmp/$1"
  else
    "$bindir/ldrun" "$tmp/$1.bin" --engine=$3 --trace "$tmp/trace.csv" > "$tmp/$1"
  fi
}
run interp -O0 interp
if [ "$(wc -l < "$tmp/interp")" -ne 301 ]; then echo "FAIL: $src: expected 300 scans" >&2; exit 1; fi
# Typed instructions (issue 25: a PLCopen program's typed variables): every
# engine runs them, but the C40, a 32-bit machine, may refuse a 64-bit type or
# a REAL function; it must then say which, by name, and exit non-zero.
typed=no
if grep -q '^    [A-Z]*\.[A-Z]' "$tmp/il"; then typed=yes; fi
c40_refused() {  # c40_refused NAME: ran, or refused by name (then 0 and nothing to compare)
  [ "$typed" = yes ] || return 1
  if grep -Eq 'error: .*(LINT|ULINT|LWORD|LREAL|TIME|LTIME|DATE|TOD|DT|LOOP|[A-Z]+\.[A-Z]+)' "$tmp/$1.err"; then
    echo "note: $src: $1 refuses it by name: $(grep -m1 'error:' "$tmp/$1.err")" >&2
    return 0
  fi
  return 1
}
# native-cd: the change-driven image (ldc --change-driven), its regions walked
# every scan (LDC_REGIONS=walk, docs/change-driven.md)
export LDC_REGIONS=walk
for v in "native-O0 -O0 native" "native-O1 -O1 native" "native-O2 -O2 native" "fast -O0 fast" \
         "native-cd --change-driven=1 native" "c40sim --target=c40 c40sim" "c40interp -O0 c40interp"; do
  set -- $v
  if ! (run $1 $2 $3) 2> "$tmp/$1.err"; then
    case $1 in c40*) c40_refused $1 && continue ;; esac
    cat "$tmp/$1.err" >&2; echo "FAIL: $src: $1 failed" >&2; exit 1
  fi
  if ! diff -u "$tmp/interp" "$tmp/$1"; then echo "FAIL: $src: $1 differs from the interpreter" >&2; exit 1; fi
done
# the C route (ldc --emit=c and the system cc) from the source
if [ -n "$watch" ]; then
  "$bindir/ldrun" "$src" $task --engine=c --trace "$tmp/trace.csv" --watch "$watch" > "$tmp/c"
else
  "$bindir/ldrun" "$src" $task --engine=c --trace "$tmp/trace.csv" > "$tmp/c"
fi
if ! diff -u "$tmp/interp" "$tmp/c"; then echo "FAIL: $src: the C route differs from the interpreter" >&2; exit 1; fi
