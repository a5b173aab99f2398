#!/bin/sh
# c40_cli_test.sh BINDIR SRCDIR -- the C40 route of the command-line tools:
# ldc --target=c40 (image, --emit=hex|asm|listing), ldrun --engine=c40sim |
# c40interp | interp on the same image (and on the .ld), --cycles, ldobjdump,
# -O1/-O2, and the messages of what is refused.  Every example's expected
# output must come out of both C40 engines, native code at every level.
set -eu
bin=$1 src=$2
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }
expect_fail() {  # WHAT PATTERN CMD...
  what=$1 pat=$2; shift 2
  if "$@" > "$tmp/out" 2> "$tmp/err"; then fail "$what: exit 0"; fi
  grep -q -- "$pat" "$tmp/err" || { cat "$tmp/err" >&2; fail "$what: no '$pat' in the message"; }
}
for f in "$src"/examples/*.ld "$src"/examples/*.sfc; do
  n=$(basename "$f"); n=${n%.*}
  base=${f%.*}
  watch=$(head -n 1 "$base.expected" | cut -d, -f2-)
  "$bin/ldc" "$f" --target=c40 -o "$tmp/$n.bin" || fail "ldc $n"
  "$bin/ldc" "$f" --target=c40 --emit=hex > "$tmp/$n.hex" || fail "ldc --emit=hex $n"
  for e in c40sim c40interp interp; do
    "$bin/ldrun" "$tmp/$n.bin" --engine=$e --trace "$base.csv" --watch "$watch" > "$tmp/out" || fail "ldrun $n $e"
    diff -u "$base.expected" "$tmp/out" || fail "$n on $e (image) differs from $n.expected"
  done
  "$bin/ldrun" "$tmp/$n.hex" --engine=c40sim --trace "$base.csv" --watch "$watch" > "$tmp/out" || fail "ldrun $n.hex"
  diff -u "$base.expected" "$tmp/out" || fail "$n (HEX) differs"
  "$bin/ldrun" "$f" --engine=c40sim --trace "$base.csv" --watch "$watch" > "$tmp/out" || fail "ldrun $n source c40sim"
  diff -u "$base.expected" "$tmp/out" || fail "$n from source on c40sim differs"
  "$bin/ldobjdump" "$tmp/$n.bin" > "$tmp/dump" || fail "ldobjdump $n"
  grep -q "file format ldc-c40" "$tmp/dump" || fail "ldobjdump $n: format line"
  grep -q "; rung 1, line" "$tmp/dump" || fail "ldobjdump $n: rung notes"
  for O in 1 2; do
    "$bin/ldc" "$f" --target=c40 -O$O -o "$tmp/$n.O$O.bin" || fail "ldc -O$O $n"
    "$bin/ldrun" "$tmp/$n.O$O.bin" --engine=c40sim --trace "$base.csv" --watch "$watch" > "$tmp/out" || fail "ldrun $n -O$O"
    diff -u "$base.expected" "$tmp/out" || fail "$n at -O$O on c40sim differs from $n.expected"
  done
  # fewer cycles per level over the whole trace
  for O in 0 1 2; do
    [ $O = 0 ] && img="$tmp/$n.bin" || img="$tmp/$n.O$O.bin"
    "$bin/ldrun" "$img" --engine=c40sim --trace "$base.csv" --watch "$watch" --cycles |
      awk -F, 'NR > 1 { s += $(NF - 1) } END { print s }' > "$tmp/cyc$O"
  done
  [ "$(cat "$tmp/cyc1")" -lt "$(cat "$tmp/cyc0")" ] && [ "$(cat "$tmp/cyc2")" -lt "$(cat "$tmp/cyc1")" ] ||
    fail "$n: cycles -O0 $(cat "$tmp/cyc0"), -O1 $(cat "$tmp/cyc1"), -O2 $(cat "$tmp/cyc2")"
done
# --cycles: two more columns, 50 ns per cycle
"$bin/ldrun" "$tmp/motor.bin" --engine=c40sim --trace "$src/examples/motor.csv" --watch Y0 --cycles > "$tmp/cyc"
head -n 1 "$tmp/cyc" | grep -qx "scan,Y0,cycles,us" || fail "--cycles header: $(head -n 1 "$tmp/cyc")"
awk -F, 'NR > 1 { if ($3 + 0 <= 0 || $4 + 0 != $3 * 0.05) exit 1 }' "$tmp/cyc" || fail "--cycles values"
"$bin/ldrun" "$tmp/motor.bin" --engine=c40interp --trace "$src/examples/motor.csv" --watch Y0 --cycles > "$tmp/cyci"
awk -F, 'NR == FNR { if (FNR > 1) n[FNR] = $3; next } FNR > 1 && $3 + 0 <= n[FNR] * 5 { exit 1 }' "$tmp/cyc" "$tmp/cyci" ||
  fail "the C40-hosted interpreter should take several times the cycles of native code"
# --emit=asm and --emit=listing
"$bin/ldc" "$src/examples/motor.ld" --target=c40 --emit=asm > "$tmp/m.s"
grep -q "TMS320C40, GNU as syntax" "$tmp/m.s" || fail "--emit=asm header"
grep -q "LDPK 0x80" "$tmp/m.s" || fail "--emit=asm LDPK"
"$bin/ldc" "$src/examples/motor.ld" --target=c40 --emit=listing > "$tmp/m.lst"
grep -q "^000000  087e0000" "$tmp/m.lst" || fail "--emit=listing first word"
# the optimized code keeps its rung and IL notes; -O2 says which rungs keep the stack in registers
"$bin/ldc" "$src/examples/motor.ld" --target=c40 -O2 --emit=asm > "$tmp/m2.s"
grep -q "TMS320C40, GNU as syntax (tic4x, as -mcpu=40), -O2" "$tmp/m2.s" || fail "-O2 --emit=asm header"
grep -q "; rung, line 38: start/stop with seal-in (stack in registers)" "$tmp/m2.s" || fail "-O2 --emit=asm rung note"
grep -q "; LOAD X3" "$tmp/m2.s" || fail "-O2 --emit=asm IL note"
[ "$(grep -c "LDPK" "$tmp/m2.s")" = 1 ] || fail "-O2: one LDPK per scan"
"$bin/ldc" "$src/examples/motor.ld" --target=c40 -O1 --emit=listing > "$tmp/m1.lst"
grep -q "^000000  1f700080.*LDPK 0x80" "$tmp/m1.lst" || fail "-O1 --emit=listing first word: $(grep -m1 "^000000" "$tmp/m1.lst")"
grep -q "; ANDN X2" "$tmp/m1.lst" || fail "-O1 --emit=listing IL note"
# refused, with a message
"$bin/ldc" "$src/examples/motor.ld" -o "$tmp/x86.bin"
expect_fail "c40sim on an x86-64 image" "is not a C40 image" "$bin/ldrun" "$tmp/x86.bin" --engine=c40sim
expect_fail "native on a C40 image" "is a C40 image; use --engine=c40sim" "$bin/ldrun" "$tmp/motor.bin"
expect_fail "--cycles on x86" "--cycles needs" "$bin/ldrun" "$tmp/x86.bin" --cycles
expect_fail "-O3" "unknown option '-O3'" "$bin/ldc" "$src/examples/motor.ld" --target=c40 -O3 -o "$tmp/o.bin"
# without -o the image is built and checked, and nothing is written or said (docs/diagnostics.md)
mkdir "$tmp/empty"
(cd "$tmp/empty" && "$bin/ldc" "$src/examples/motor.ld" --target=c40 > "$tmp/noout.out" 2>&1) || fail "ldc --target=c40 without -o"
[ ! -s "$tmp/noout.out" ] && [ -z "$(ls "$tmp/empty")" ] || fail "ldc --target=c40 without -o said or wrote something"
expect_fail "--emit=c40 tree is fine, --emit=bogus is not" "not available" "$bin/ldc" "$src/examples/motor.ld" --target=c40 --emit=bogus
# a damaged C40 image is refused before anything runs (here by its checksum;
# c40image_test.cpp refuses code the checksum does not catch)
cp "$tmp/motor.bin" "$tmp/bad.bin"
code=$(od -An -tu4 -j 172 -N 4 "$tmp/motor.bin" | tr -d ' ')  # the 'code' section's file offset (table entry 0)
printf '\377\377\377\377' | dd of="$tmp/bad.bin" bs=1 seek=$((code + 20)) conv=notrunc 2> /dev/null
expect_fail "damaged image" "checksum" "$bin/ldrun" "$tmp/bad.bin" --engine=c40sim
# the IL interpreter runs the x86 image's IL on the C40 too
"$bin/ldrun" "$tmp/x86.bin" --engine=c40interp --trace "$src/examples/motor.csv" --watch "$(head -n 1 "$src/examples/motor.expected" | cut -d, -f2-)" > "$tmp/out"
diff -u "$src/examples/motor.expected" "$tmp/out" || fail "c40interp on an x86 image"
# typed instructions (docs/c40.md, "Typed instructions"): INT wraps at 16 bits on the C40 as in
# the reference interpreter; a 64-bit type is refused at its line, the C40-hosted interpreter
# refuses typed instructions by name
printf '.rung line 1\nTRUE\nMOVE.INT 32767 D0\nADD.INT D0 1 D1\nDIV.REAL 1.0 3.0 D2\n.end\n' > "$tmp/t.il"
"$bin/ldc" "$tmp/t.il" --target=c40 -o "$tmp/t.bin" || fail "ldc typed"
"$bin/ldrun" "$tmp/t.bin" --engine=c40sim --scans 2 --watch D0,D1,D2 > "$tmp/out" || fail "ldrun typed"
"$bin/ldrun" "$tmp/t.il" --engine=interp --scans 2 --watch D0,D1,D2 > "$tmp/ref" || fail "ldrun typed interp"
diff -u "$tmp/ref" "$tmp/out" || fail "typed on c40sim differs from interp"
grep -q "^1,32767,-32768,1051372203$" "$tmp/out" || fail "INT 32767 + 1 wraps to -32768, 1.0/3.0 is 0x3eaaaaab: $(cat "$tmp/out")"
printf '.rung line 1\nTRUE\nADD.LINT D0 D2 D4\n.end\n' > "$tmp/l.il"
expect_fail "64-bit type" "l.il:3:1: error: the C40 cannot compile ADD.LINT: 64-bit types" "$bin/ldc" "$tmp/l.il" --target=c40 -o "$tmp/l.bin"
expect_fail "typed on c40interp" "cannot run MOVE.INT" "$bin/ldrun" "$tmp/t.il" --engine=c40interp --scans 1
echo "c40 cli: ok"
