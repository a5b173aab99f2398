#!/bin/sh
# watch_names.sh BINDIR -- names in --watch and trace headers, and the
# trace cells of typed variables refused with their place (docs/format.md,
# "Traces").  Each expected value is derived in the comment above it.
set -u
bin=$1
here=$(cd "$(dirname "$0")" && pwd)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fails=0 checks=0
same() {  # same NAME EXPECTED ACTUAL
  checks=$((checks + 1))
  [ "$2" = "$3" ] || { echo "FAIL: $1: expected '$2', got '$3'" >&2; fails=$((fails + 1)); }
}
refused() {  # refused NAME PATTERN CMD...: exit 1, PATTERN on stderr
  n=$1 pat=$2
  shift 2
  checks=$((checks + 1))
  if "$@" > "$tmp/o" 2> "$tmp/e"; then echo "FAIL: $n: accepted" >&2; fails=$((fails + 1)); return; fi
  grep -qF -- "$pat" "$tmp/e" || { echo "FAIL: $n: stderr lacks '$pat':" >&2; cat "$tmp/e" >&2; fails=$((fails + 1)); }
}

# A program's name wins over a device of the same spelling: s2 is the INT
# variable at D4 (7 + 1 on scan 1 = 8), not the system bit S2 (0), whatever
# its case; t2 the TIME at D6 (1500000000 ns moved: T#1s500ms), not the timer T2.
cat > "$tmp/dev.il" <<'IL'
.alias s2 D4 INT
.alias t2 D6 TIME
.rung line 1
    LOAD    S1
    MOVE.INT 7 D4
    MOVE.TIME 1500000000 D6
.rung line 2
    TRUE
    ADD.INT D4 1 D4
.end
IL
same "name over device" "scan,s2,S2,t2
1,8,8,T#1s500ms" "$("$bin/ldrun" "$tmp/dev.il" --engine=interp --watch s2,S2,t2)"

# Refused trace cells of typed variables, at their line and column.
st=$here/st_watch.st
printf 't\nT#1x\n' > "$tmp/t1.csv"
refused "bad TIME literal" "t1.csv:2:1: error: bad TIME 'T#1x'" "$bin/ldrun" "$st" --engine=interp --trace "$tmp/t1.csv"
printf 'k,tank.level\n1,T#1s\n' > "$tmp/t2.csv"
refused "TIME into an INT" "t2.csv:2:3: error: a TIME literal where a INT is wanted: 'T#1s' for tank.level" "$bin/ldrun" "$st" --engine=interp --trace "$tmp/t2.csv"
printf 's\n'"'"'abc\n' > "$tmp/t3.csv"
refused "unterminated STRING" "t3.csv:2:1: error:" "$bin/ldrun" "$st" --engine=interp --trace "$tmp/t3.csv"
printf 'by\n256\n' > "$tmp/t4.csv"
refused "BYTE range" "t4.csv:2:1: error: value out of the BYTE range: '256' for by" "$bin/ldrun" "$st" --engine=interp --trace "$tmp/t4.csv"
printf '"a[1,2]",a[9,9]\n1,2\n' > "$tmp/t5.csv"
refused "element outside the array" "t5.csv:1:10: error: unknown device or alias 'a[9,9]'" "$bin/ldrun" "$st" --engine=interp --trace "$tmp/t5.csv"
refused "--watch of a missing member" "--watch: unknown device or alias 'tank.lvl'" "$bin/ldrun" "$st" --engine=interp --watch tank.lvl

echo "$checks checks, $fails failed"
[ $fails -eq 0 ]
