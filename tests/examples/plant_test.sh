#!/bin/sh
# plant_test.sh BINDIR SRCDIR -- the example project examples/plant (README.md,
# "An example project"): it checks (ldc --project), and runs as the README runs
# it, with Modbus and the monitor, the commands of plant.cmds on the line
# protocol answering plant.expected; the banner names both servers.
set -u
bin=$1 src=$2
here=$(cd "$(dirname "$0")" && pwd)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fails=0
fail() { echo "FAIL: $*" >&2; fails=$((fails + 1)); }
"$bin/ldc" --project "$src/examples/plant/plant.ldp" > "$tmp/table" 2>&1 || { fail "ldc --project"; cat "$tmp/table" >&2; }
"$bin/ldrun" --project "$src/examples/plant/plant.ldp" --io=stdio --modbus 127.0.0.1:0 --monitor 127.0.0.1:0 \
  --monitor-write < "$here/plant.cmds" > "$tmp/out" 2> "$tmp/err" || fail "ldrun exit $?"
diff -u "$here/plant.expected" "$tmp/out" || fail "replies differ from plant.expected"
grep -q "^ldrun: Modbus TCP on 127.0.0.1:[0-9]*$" "$tmp/err" || fail "no Modbus line in the banner"
grep -q "^ldrun: monitor on http://127.0.0.1:[0-9]*/ (writes allowed)$" "$tmp/err" || fail "no monitor line in the banner"
[ $fails -eq 0 ] || cat "$tmp/err" >&2
echo "$fails failed"
[ $fails -eq 0 ]
