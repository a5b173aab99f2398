#!/bin/sh
# trace_driver_test.sh BINDIR SRCDIR -- every example through the runtime's
# trace driver (--io=trace --clock=virtual --free-run), on both engines,
# must print exactly its .expected: the scan task, the block refresh of the
# global image and the driver add nothing to what ldrun --trace prints.
set -u
bin=$1 src=$2
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fails=0 checks=0
for f in "$src"/examples/*.ld; do
  base=${f%.ld}
  [ -f "$base.expected" ] || continue
  watch=$(head -n 1 "$base.expected" | cut -d, -f2-)
  for engine in native interp; do
    checks=$((checks + 1))
    if ! "$bin/ldrun" "$f" --engine=$engine --io=trace --clock=virtual --free-run --trace "$base.csv" --watch "$watch" \
         > "$tmp/out" 2> "$tmp/err"; then
      echo "FAIL: $f on $engine: exit status" >&2; cat "$tmp/err" >&2; fails=$((fails + 1)); continue
    fi
    if ! diff -u "$base.expected" "$tmp/out" > "$tmp/diff"; then
      echo "FAIL: $f on $engine differs from $base.expected" >&2; head -20 "$tmp/diff" >&2; fails=$((fails + 1))
    fi
  done
done
echo "$((checks - fails)) passed, $fails failed"
[ $fails -eq 0 ] && [ $checks -gt 0 ]
