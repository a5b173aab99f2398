#!/bin/sh
# two_ways.sh BINDIR PROJECT.xml PROJECT.generated.st -- one OpenPLC project read
# two ways (docs/st.md): its PLCopen XML and the ST that OpenPLC Editor
# generated from it must give the same values, scan by scan, for every
# variable both name, over 300 scans of a pseudo-random trace of the inputs
# (../random_trace.awk, as check_corpus.sh draws it), on the reference interpreter.
set -eu
bindir=$1 xml=$2 st=$3
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
"$bindir/ldc" "$xml" --emit=il > "$tmp/xml.il"
"$bindir/ldc" "$st" --emit=il > "$tmp/st.il"
aliases() { sed -n 's/^\.alias \([^ ]*\) \([^ ]*\).*/\1 \2/p' "$1" | sort; }
aliases "$tmp/xml.il" > "$tmp/xml.al"
aliases "$tmp/st.il" > "$tmp/st.al"
join "$tmp/xml.al" "$tmp/st.al" > "$tmp/common"   # NAME XML-DEVICE ST-DEVICE
[ -s "$tmp/common" ] || { echo "FAIL: no variable named in both" >&2; exit 1; }
watch=$(cut -d' ' -f1 "$tmp/common" | paste -sd, -)
awk '$2 ~ /^W?X[0-9]+$/ { print $1, $2 }' "$tmp/common" | awk -f "$(dirname "$0")/../random_trace.awk" > "$tmp/trace.csv"
"$bindir/ldrun" "$xml" --engine=interp --trace "$tmp/trace.csv" --watch "$watch" > "$tmp/xml.out"
"$bindir/ldrun" "$st" --engine=interp --trace "$tmp/trace.csv" --watch "$watch" > "$tmp/st.out"
if ! diff -u "$tmp/xml.out" "$tmp/st.out" > "$tmp/diff"; then
  head -40 "$tmp/diff" >&2
  echo "FAIL: $st differs from $xml" >&2
  exit 1
fi
echo "$(wc -l < "$tmp/common") variables, 300 scans: the same"
