#!/bin/sh
# cli_test.sh BINDIR SRCDIR -- end-to-end checks of ldc, ldrun and ldobjdump.
set -u
bin=$1 src=$2
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fails=0 checks=0
ok() { checks=$((checks + 1)); }
bad() { checks=$((checks + 1)); fails=$((fails + 1)); echo "FAIL: $*" >&2; }
expect_fail() {  # expect_fail NAME PATTERN CMD... : exit 1 and PATTERN on stderr
  name=$1 pat=$2; shift 2
  "$@" > "$tmp/out" 2> "$tmp/err"; rc=$?
  if [ $rc -ne 1 ]; then bad "$name: exit $rc, expected 1"; return; fi
  if ! grep -q -- "$pat" "$tmp/err"; then bad "$name: stderr lacks '$pat':"; cat "$tmp/err" >&2; return; fi
  ok
}

# a compile error leaves no output file, not even a temporary one
printf '|--[X0]--(Y0)--(Y1)\n' > "$tmp/bad.ld"
expect_fail "series outputs" "bad.ld:1:16: error: outputs cannot be in series" "$bin/ldc" "$tmp/bad.ld" -o "$tmp/bad.bin"
if ls "$tmp" | grep -q 'bad.bin'; then bad "output file left behind after an error"; else ok; fi
grep -q '^|--\[X0\]--(Y0)--(Y1)$' "$tmp/err" && grep -q '^               \^$' "$tmp/err" && ok || bad "source line and caret missing"

# an image round trip on every engine, from .bin and from Intel HEX
"$bin/ldc" "$src/examples/traffic.ld" -o "$tmp/t.bin" && ok || bad "ldc -o"
"$bin/ldc" "$src/examples/traffic.ld" --emit=hex -o "$tmp/t.hex" && ok || bad "ldc --emit=hex"
for f in t.bin t.hex; do
  for e in native interp fast; do
    "$bin/ldrun" "$tmp/$f" --engine=$e --trace "$src/examples/traffic.csv" --watch Y0,Y1,Y2,T0 > "$tmp/$f.$e" || bad "ldrun $f $e"
    cmp -s "$tmp/$f.$e" "$tmp/t.bin.native" && ok || bad "$f on $e differs from t.bin on native"
  done
done

# a source compiled in memory at each -O level, and on the fast interpreter, runs as the image does
for o in -O0 -O1 -O2; do
  "$bin/ldrun" "$src/examples/traffic.ld" $o --trace "$src/examples/traffic.csv" --watch Y0,Y1,Y2,T0 > "$tmp/src$o" || bad "ldrun source $o"
  cmp -s "$tmp/src$o" "$tmp/t.bin.native" && ok || bad "ldrun source $o differs from the image on native"
done
"$bin/ldrun" "$src/examples/traffic.ld" --engine=fast --trace "$src/examples/traffic.csv" --watch Y0,Y1,Y2,T0 > "$tmp/srcfast" || bad "ldrun source fast"
cmp -s "$tmp/srcfast" "$tmp/t.bin.native" && ok || bad "ldrun source on fast differs from the image on native"
expect_fail "-O on an image" "is for a source compiled to native code (.*); an image is already compiled" "$bin/ldrun" "$tmp/t.bin" -O2
expect_fail "-O on an interpreter" "is for a source compiled to native code (.*); the fast engine interprets the IL" \
  "$bin/ldrun" "$src/examples/traffic.ld" --engine=fast -O2

# ldobjdump lists every rung with its IL
"$bin/ldobjdump" "$tmp/t.bin" > "$tmp/dump" && ok || bad "ldobjdump"
grep -q '; rung 1, line' "$tmp/dump" && grep -q ';   TON T' "$tmp/dump" && ok || bad "ldobjdump lacks rung/IL lines"
grep -Eq '^; [0-9]+ bytes, [0-9]+ instructions, [0-9]+ IL; branch sites: [0-9]+ jcc, [0-9]+ jmp, [0-9]+ call$' "$tmp/dump" && ok || bad "ldobjdump lacks the branch-site count"
# ... and, where it can read the source, the source line of the code that follows (objdump -S)
"$bin/ldc" "$src/tests/frontend/st/st_loops.st" -o "$tmp/st.bin" && "$bin/ldobjdump" "$tmp/st.bin" > "$tmp/stdump" && ok || bad "ldobjdump of ST"
grep -q '^; 22:     a\[i\] := i \* i;$' "$tmp/stdump" && grep -q '^;   LOOP @' "$tmp/stdump" && ok || bad "ldobjdump lacks the ST source lines or the LOOP"
# SEL is a select: at -O2 no branch on its condition (the only jcc left is
# the first scan's initial values), and a program with loops is -O2 code with
# no base registers (docs/x86.md, "Select" and "Loops")
cat > "$tmp/sel.st" <<'EOS'
PROGRAM p
VAR crc : WORD := 16#FFFF; x : DINT; g : BOOL; END_VAR
crc := SEL((crc AND 16#0001) <> 0, SHR(crc, 1), SHR(crc, 1) XOR 16#A001);
x := SEL(g, x - 1, x + 1);
g := NOT g;
END_PROGRAM
EOS
"$bin/ldc" "$tmp/sel.st" -O2 -o "$tmp/sel.bin" && "$bin/ldobjdump" "$tmp/sel.bin" > "$tmp/seldump" && ok || bad "ldc of SEL"
grep -q 'branch sites: 1 jcc, 0 jmp' "$tmp/seldump" && grep -q 'cmove' "$tmp/seldump" && ok || bad "SEL is not branch-free at -O2"
"$bin/ldc" "$src/tests/frontend/st/st_loops.st" -O2 -o "$tmp/st2.bin" && "$bin/ldobjdump" "$tmp/st2.bin" > "$tmp/st2dump" && ok || bad "ldc -O2 of loops"
grep -q 'lea rbp, \[rdi+0x40\]' "$tmp/st2dump" && ! grep -q 'lea rdi, \[rbp' "$tmp/st2dump" && ok || bad "-O2 of a program with loops: not the -O2 frame, or base registers set"

# bad images are refused before anything runs
printf 'garbage' > "$tmp/g.bin"
expect_fail "garbage image" "g.bin: error: truncated header" "$bin/ldrun" "$tmp/g.bin"
head -c 200 "$tmp/t.bin" > "$tmp/trunc.bin"
expect_fail "truncated image" "trunc.bin: error: truncated file" "$bin/ldrun" "$tmp/trunc.bin"
cp "$tmp/t.bin" "$tmp/flip.bin"
printf '\377' | dd of="$tmp/flip.bin" bs=1 seek=300 conv=notrunc 2>/dev/null
expect_fail "flipped byte" "flip.bin: error:" "$bin/ldrun" "$tmp/flip.bin"
expect_fail "flipped byte in ldobjdump" "flip.bin: error:" "$bin/ldobjdump" "$tmp/flip.bin"
sed '2s/^:10/:11/' "$tmp/t.hex" > "$tmp/bad.hex"
expect_fail "bad hex" "bad.hex:2:" "$bin/ldrun" "$tmp/bad.hex"

# usage errors
expect_fail "no input" "no input file" "$bin/ldc"
expect_fail "unknown engine" "unknown engine" "$bin/ldrun" "$tmp/t.bin" --engine=foo
expect_fail "bad watch" "unknown device or alias 'Q9'" "$bin/ldrun" "$tmp/t.bin" --watch Q9
printf 'X0,dt\n1,abc\n' > "$tmp/bad.csv"
expect_fail "bad trace" "bad.csv:2:3: error: bad value 'abc'" "$bin/ldrun" "$tmp/t.bin" --trace "$tmp/bad.csv"
expect_fail "missing file" "cannot open" "$bin/ldc" "$tmp/nope.ld"

# -o a device or a pipe writes into it and never replaces it with a file (as root a rename
# would replace /dev/null): a FIFO with a reader gets the image, and stays a FIFO (a FIFO
# in the test's own folder, so that a regression cannot break the machine's /dev/null)
mkfifo "$tmp/pipe"
cat "$tmp/pipe" > "$tmp/piped.bin" &
reader=$!
"$bin/ldc" "$src/examples/traffic.ld" -o "$tmp/pipe" && ok || bad "ldc -o FIFO"
if [ -p "$tmp/pipe" ]; then wait $reader; ok; else kill $reader 2>/dev/null; bad "ldc -o replaced the FIFO with a file"; fi
cmp -s "$tmp/piped.bin" "$tmp/t.bin" && ok || bad "the image written into a FIFO differs from ldc -o FILE"

# IL whose rung reads what the rung before it left: the C route refuses it at its place, with
# no output file left, while native code runs it
printf '.rung line 1\n    LOAD X1\n    LOAD X2\n    OUT Y0\n.rung line 2\n    ORBLK\n    OUT Y1\n.end\n' > "$tmp/shared.il"
expect_fail "C route, shared stack" "shared.il:6:5: error: the C route cannot compile ORBLK" "$bin/ldc" "$tmp/shared.il" --emit=c -o "$tmp/shared.c"
if [ -e "$tmp/shared.c" ]; then bad "C output left behind after an error"; else ok; fi
expect_fail "ldrun C route, shared stack" "shared.il:6:5: error: the C route cannot compile ORBLK" "$bin/ldrun" "$tmp/shared.il" --engine=c
"$bin/ldrun" "$tmp/shared.il" -O2 --scans 1 > /dev/null && ok || bad "native -O2 on a shared stack"

# diagnostics options (docs/diagnostics.md; the cases themselves are tests/frontend/diagnostics)
expect_fail "unknown -W name" "ldc: error: unknown warning option '-Wdouble-coils'; did you mean '-Wdouble-coil'?" \
  "$bin/ldc" "$src/examples/motor.ld" -Wdouble-coils
expect_fail "bad -fmax-errors" "bad -fmax-errors value 'many'" "$bin/ldc" "$src/examples/motor.ld" -fmax-errors=many
# `ldc FILE` with neither -o nor --emit: compiled and checked, nothing written, nothing said
mkdir "$tmp/quiet"
(cd "$tmp/quiet" && "$bin/ldc" "$src/examples/motor.ld" > "$tmp/quiet.out" 2>&1) && [ ! -s "$tmp/quiet.out" ] && [ -z "$(ls "$tmp/quiet")" ] \
  && ok || bad "ldc FILE without -o is not a silent check"
(cd "$tmp/quiet" && "$bin/ldc" "$tmp/bad.ld" > "$tmp/quiet.out" 2>&1); [ $? -eq 1 ] && grep -q "bad.ld:1:16: error:" "$tmp/quiet.out" \
  && ok || bad "ldc FILE without -o does not report the error"
# -fsyntax-only with a project writes no directory
"$bin/ldc" -fsyntax-only --project "$src/tests/runtime/projects/shared.ldp" -o "$tmp/proj" > "$tmp/proj.out" 2>&1 && [ ! -e "$tmp/proj" ] \
  && ok || bad "ldc -fsyntax-only --project wrote something or failed"

echo "$checks checks, $fails failed"
echo "$((checks - fails)) passed, $fails failed"
[ $fails -eq 0 ]
