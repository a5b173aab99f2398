#!/bin/sh
# protocol_test.sh BINDIR PROJECTS -- the line protocol through pipes: a
# project built by ldc --project runs with --io=stdio, the commands of
# protocol.cmds go in on stdin, and the replies (timings masked) must be
# protocol.expected.  LDC_UPDATE=1 rewrites the expected file.
set -u
bin=$1 dir=$2
here=$(cd "$(dirname "$0")" && pwd)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
cd "$dir" || exit 1
"$bin/ldc" --project shared.ldp -o "$tmp/build" || exit 1
"$bin/ldrun" --project "$tmp/build/plant.ldp" --io=stdio < "$here/protocol.cmds" > "$tmp/out" 2> "$tmp/err"
rc=$?
sed -e 's/switched at scan [0-9]*: latency [0-9.]* [mu]s (switch [0-9.]* [mu]s)/switched at scan N: latency T (switch T)/' \
    "$tmp/out" > "$tmp/replies"
if [ "${LDC_UPDATE:-}" = 1 ]; then cp "$tmp/replies" "$here/protocol.expected"; fi
fails=0
[ $rc -eq 0 ] || { echo "FAIL: ldrun exit $rc" >&2; cat "$tmp/err" >&2; fails=$((fails + 1)); }
diff -u "$here/protocol.expected" "$tmp/replies" || { echo "FAIL: replies differ" >&2; fails=$((fails + 1)); }
# End of input quits as well, and status is one line.
printf 'status\n' | "$bin/ldrun" --project "$tmp/build/plant.ldp" --io=stdio > "$tmp/st" 2>&1
grep -q '^state RUN; task fast: [0-9]* scans, [0-9]* overruns, scan .*; task belt: .*; task slow: ' "$tmp/st" ||
  { echo "FAIL: status line" >&2; cat "$tmp/st" >&2; fails=$((fails + 1)); }
echo "$fails failed"
[ $fails -eq 0 ]
