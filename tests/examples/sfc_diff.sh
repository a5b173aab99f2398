#!/bin/sh
# sfc_diff.sh BINDIR CHART.sfc SEED -- a chart's IL against its switch-form C
# (docs/sfc.md) on a random trace: inputs X0..X7 and dt change at random for
# 300 scans; the reference interpreter, the C route (ldc --emit=c compiled by
# cc), native x86-64 at -O2 and the C40 simulator (-O0, -O2) must print the same step
# flags, outputs, words and timers scan by scan.
set -eu
bindir=$1 src=$2 seed=$3
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
awk -v seed="$seed" 'BEGIN {
  srand(seed); print "dt,X0,X1,X2,X3,X4,X5,X6,X7";
  for (i = 0; i < 300; i++) {
    line = (rand() < 0.5 ? 100 : int(rand() * 1500));
    for (b = 0; b < 8; b++) line = line "," (rand() < 0.35 ? 1 : 0);
    print line
  }
}' > "$tmp/trace.csv"
steps=$("$bindir/ldc" "$src" --emit=il | awk '$1 == ".alias" && $3 ~ /^M/ { printf ",%s", $2 }')
watch="Y0,Y1,Y2,Y3,Y4,Y5,Y6,D0,T0,T1,T2,T5,M1$steps"
"$bindir/ldrun" "$src" --engine=interp --trace "$tmp/trace.csv" --watch "$watch" > "$tmp/ref"
"$bindir/ldrun" "$src" --engine=c --trace "$tmp/trace.csv" --watch "$watch" > "$tmp/c"
"$bindir/ldc" "$src" -O2 -o "$tmp/x86.bin"
"$bindir/ldrun" "$tmp/x86.bin" --engine=native --trace "$tmp/trace.csv" --watch "$watch" > "$tmp/native"
"$bindir/ldc" "$src" --target=c40 -o "$tmp/c40.bin"
"$bindir/ldrun" "$tmp/c40.bin" --engine=c40sim --trace "$tmp/trace.csv" --watch "$watch" > "$tmp/c40"
"$bindir/ldc" "$src" --target=c40 -O2 -o "$tmp/c40o2.bin"
"$bindir/ldrun" "$tmp/c40o2.bin" --engine=c40sim --trace "$tmp/trace.csv" --watch "$watch" > "$tmp/c40o2"
# the trace must move the chart: at least three different step-flag rows
moves=$(cut -d, -f15- "$tmp/ref" | sort -u | wc -l)
[ "$moves" -ge 4 ] || { echo "FAIL: the random trace leaves $src almost still ($moves states)" >&2; exit 1; }
for e in c native c40 c40o2; do
  if ! diff -u "$tmp/ref" "$tmp/$e" > "$tmp/diff"; then
    head -n 40 "$tmp/diff" >&2
    echo "FAIL: $src (seed $seed): $e differs from the interpreter" >&2
    exit 1
  fi
done
