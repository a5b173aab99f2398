#!/bin/sh
# two_ways.sh BINDIR PROJECT.xml PROJECT.generated.st [TASK [NAME...]] -- one
# OpenPLC project read two ways (docs/st.md): its PLCopen XML and the ST that
# OpenPLC Editor generated from it must give the same values, scan by scan,
# for every variable both name, over 300 scans of a pseudo-random trace of the
# inputs (../random_trace.awk, as check_corpus.sh draws it), on the reference
# interpreter.  TASK: the task of a configuration of several to compare;
# NAMEs: variables the trace drives too (outputs that the program reads, as
# a simulator writes them).
set -eu
bindir=$1 xml=$2 st=$3
shift 3
task=${1:+--task $1}
[ $# -gt 0 ] && shift
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
"$bindir/ldc" "$xml" $task --emit=il > "$tmp/xml.il"
"$bindir/ldc" "$st" $task --emit=il > "$tmp/st.il" 2> "$tmp/err" || { cat "$tmp/err" >&2; exit 1; }
aliases() { sed -n 's/^\.alias \([^ ]*\) \([^ ]*\).*/\1 \2/p' "$1" | sort; }
aliases "$tmp/xml.il" > "$tmp/xml.al"
aliases "$tmp/st.il" > "$tmp/st.al"
join "$tmp/xml.al" "$tmp/st.al" > "$tmp/common"   # NAME XML-DEVICE ST-DEVICE
[ -s "$tmp/common" ] || { echo "FAIL: no variable named in both" >&2; exit 1; }
watch=$(cut -d' ' -f1 "$tmp/common" | paste -sd, -)
{ echo "-"; for n in "$@"; do echo "$n"; done; } > "$tmp/driven"  # never empty: awk's NR == FNR
awk 'NR == FNR { d[$1] = 1; next } $2 ~ /^W?X[0-9]+$/ || ($1 in d) { print $1, ($2 ~ /^W/ ? "WX" : "X") }' "$tmp/driven" "$tmp/common" |
  awk -f "$(dirname "$0")/../random_trace.awk" > "$tmp/trace.csv"
for form in xml st; do  # (a trace driving outputs is warned about: -Wtrace-output)
  eval src=\$$form
  "$bindir/ldrun" "$src" $task --engine=interp --trace "$tmp/trace.csv" --watch "$watch" > "$tmp/$form.out" 2> "$tmp/err" ||
    { cat "$tmp/err" >&2; exit 1; }
done
if ! diff -u "$tmp/xml.out" "$tmp/st.out" > "$tmp/diff"; then
  head -40 "$tmp/diff" >&2
  echo "FAIL: $st differs from $xml" >&2
  exit 1
fi
echo "$(wc -l < "$tmp/common") variables, 300 scans: the same"
