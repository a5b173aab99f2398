#!/bin/sh
# names_protocol.sh BINDIR -- the line protocol by variable name on
# names.st (docs/runtime.md, "The line protocol"): names.cmds on stdin of
# ldrun --io=none --control=stdin, the replies must be names.expected
# (derived by hand in names.st).  Every value waits for scans (wait 2), so
# the replies do not depend on timing.
set -u
bin=$1
here=$(cd "$(dirname "$0")" && pwd)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
"$bin/ldrun" "$here/names.st" --io=none --control=stdin --period 1ms < "$here/names.cmds" > "$tmp/out" 2> "$tmp/err"
rc=$?
fails=0
[ $rc -eq 0 ] || { echo "FAIL: ldrun exit $rc" >&2; cat "$tmp/err" >&2; fails=$((fails + 1)); }
diff -u "$here/names.expected" "$tmp/out" || { echo "FAIL: replies differ" >&2; fails=$((fails + 1)); }
echo "$fails failed"
[ $fails -eq 0 ]
