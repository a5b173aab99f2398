#!/bin/sh
# cli_test.sh BINDIR SRCDIR -- the command line's smaller cases (issue 27):
# each check runs a tool the way a user would and compares its exit status
# and the words of its message with what docs/ says it prints.
set -u
bin=$1 src=$2
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fails=0 checks=0
fail() { echo "FAIL: $*" >&2; fails=$((fails + 1)); }
# expect STATUS 'TEXT' CMD...: CMD exits with STATUS and prints TEXT (fixed string) on stderr.
expect() {
  want=$1 text=$2
  shift 2
  checks=$((checks + 1))
  "$@" > "$tmp/out" 2> "$tmp/err" < /dev/null
  rc=$?
  if [ $rc -ne "$want" ]; then fail "$*: exit $rc, expected $want"; cat "$tmp/err" >&2; return; fi
  [ -z "$text" ] || grep -qF -- "$text" "$tmp/err" || { fail "$*: stderr lacks '$text'"; cat "$tmp/err" >&2; }
}

# --period below the runtime's 50 us minimum names the minimum and the value given
# (docs/runtime.md, "Running"); the trace runner's dt is whole milliseconds.
expect 1 "bad --period: '10us' is below the minimum of 50us" "$bin/ldrun" "$src/examples/motor.ld" --io=none --period 10us
expect 1 "bad --period: '5q' is not a duration (e.g. 500us, 10ms, 1s)" "$bin/ldrun" "$src/examples/motor.ld" --io=none --period 5q
expect 1 "bad --period: '10us' is not whole milliseconds" "$bin/ldrun" "$src/examples/motor.ld" --trace "$src/examples/motor.csv" --period 10us
cat > "$tmp/fast.ldp" <<P
resource cpu0 processor 0
  task t period 20us
    program p $src/examples/motor.ld
P
expect 1 "fast.ldp:2:17: error: bad period: '20us' is below the minimum of 50us" "$bin/ldc" --project "$tmp/fast.ldp"

# A project writes a folder: -o naming an image, or an existing file, is refused
# before anything is written (docs/runtime.md, "The project file").
expect 1 "-o $tmp/x.bin names an image, but $src/tests/runtime/projects/shared.ldp is a project of 3 tasks" \
  "$bin/ldc" --project "$src/tests/runtime/projects/shared.ldp" -o "$tmp/x.bin"
[ -e "$tmp/x.bin" ] && fail "ldc --project -o x.bin created x.bin"
expect 1 "or --task NAME -o $tmp/y.hex for one task's image" "$bin/ldc" "$src/tests/frontend/tasks/st_tasks.st" -o "$tmp/y.hex"
[ -e "$tmp/y.hex" ] && fail "ldc st_tasks.st -o y.hex created y.hex"
: > "$tmp/plainfile"
expect 1 "-o $tmp/plainfile is a file, but" "$bin/ldc" --project "$src/tests/runtime/projects/shared.ldp" -o "$tmp/plainfile"
expect 0 "" "$bin/ldc" "$src/tests/frontend/tasks/st_tasks.st" -o "$tmp/tasks"
[ -f "$tmp/tasks/plant.ldp" ] || [ -n "$(ls "$tmp/tasks"/*.ldp 2>/dev/null)" ] || fail "ldc st_tasks.st -o DIR wrote no project file"

# -o naming the project file's own folder would overwrite the project file: refused,
# the file untouched (docs/runtime.md, "The project file")
mkdir -p "$tmp/own" && cp "$src/tests/runtime/projects/shared.ldp" "$tmp/own/plant.ldp"  # configuration plant: plant.ldp is written
sed -i "s|program \([a-z]*\) \([a-z_]*\.ld\)|program \1 $src/tests/runtime/projects/\2|" "$tmp/own/plant.ldp"
cp "$tmp/own/plant.ldp" "$tmp/own.before"
expect 1 "would write $tmp/own/./plant.ldp over the project file" "$bin/ldc" --project "$tmp/own/plant.ldp" -o "$tmp/own/."
cmp -s "$tmp/own/plant.ldp" "$tmp/own.before" || fail "ldc --project p.ldp -o . changed p.ldp"

# -o - is standard output: the image byte for byte as -o FILE writes it, the --emit
# text; no file named '-'; a project (several images) refused by name.
checks=$((checks + 1))
(cd "$tmp" && "$bin/ldc" "$src/examples/motor.ld" -o motor_file.bin && "$bin/ldc" "$src/examples/motor.ld" -o - > motor_out.bin &&
  cmp -s motor_file.bin motor_out.bin && "$bin/ldc" "$src/examples/motor.ld" --emit=il -o - | grep -q '^; ldc IL' &&
  [ ! -e ./- ]) || fail "ldc -o - (the image and the IL on standard output, no file '-')"
expect 1 "-o - (standard output) takes one program, but $src/tests/frontend/tasks/st_tasks.st is a project of 2 tasks" \
  "$bin/ldc" "$src/tests/frontend/tasks/st_tasks.st" -o -
expect 1 "ldc: error: cannot write the image to standard output" sh -c "\"$bin/ldc\" \"$src/examples/motor.ld\" -o - > /dev/full"
expect 1 "ldc: error: cannot write the --emit=il text to standard output" sh -c "\"$bin/ldc\" \"$src/examples/motor.ld\" --emit=il > /dev/full"

# ldobjdump takes a source as ldrun does: compiled in memory, the listing that of
# the image ldc writes (but the header line, which says where the code came from).
checks=$((checks + 1))
"$bin/ldc" "$src/examples/motor.ld" -O1 -o "$tmp/motor.bin" && "$bin/ldobjdump" "$tmp/motor.bin" > "$tmp/dump.bin" &&
  "$bin/ldobjdump" "$src/examples/motor.ld" -O1 > "$tmp/dump.src" 2> "$tmp/err" ||
  { fail "ldobjdump motor.ld"; cat "$tmp/err" >&2; }
grep -qF "file format ldc-x86-64 (compiled in memory from $src/examples/motor.ld at -O1)" "$tmp/dump.src" ||
  fail "ldobjdump motor.ld: header"
sed 1,2d "$tmp/dump.bin" > "$tmp/a" && sed 1,2d "$tmp/dump.src" > "$tmp/b" && cmp -s "$tmp/a" "$tmp/b" ||
  fail "ldobjdump motor.ld differs from ldobjdump of ldc's image"
expect 0 "" "$bin/ldobjdump" "$src/examples/motor.ld" --target=c40 -O2
grep -qF "file format ldc-c40" "$tmp/out" || fail "ldobjdump --target=c40: header"
expect 1 "is an image, already compiled: --target, -O and --task are for a source" "$bin/ldobjdump" "$tmp/motor.bin" -O2
expect 1 "nothere.ld: error: cannot open" "$bin/ldobjdump" "$tmp/nothere.ld"

# ldc --project -o DIR keeps the project's retentive file: the written project names
# the same file from DIR, so running it continues with the memory the source project
# saved (docs/runtime.md, "The project file").
mkdir -p "$tmp/src/sub" "$tmp/built"
printf '|--[X0]--(Y0)\n' > "$tmp/src/sub/p.ld"
cat > "$tmp/src/plant.ldp" <<P
retain plant.ret every 1s
resource cpu0 processor 0
  task main period 1ms
    program p sub/p.ld
P
checks=$((checks + 1))
printf 'set K3 1\nsave\nquit\n' | "$bin/ldrun" --project "$tmp/src/plant.ldp" --io=stdio > "$tmp/out" 2> "$tmp/err" &&
  [ -f "$tmp/src/plant.ret" ] || { fail "the source project saved no retentive file"; cat "$tmp/out" "$tmp/err" >&2; }
"$bin/ldc" --project "$tmp/src/plant.ldp" -o "$tmp/built/plant" 2> "$tmp/err" || { fail "ldc --project -o"; cat "$tmp/err" >&2; }
grep -qx "retain ../../src/plant.ret every 1s" "$tmp/built/plant/plant.ldp" || { fail "built retain line"; cat "$tmp/built/plant/plant.ldp" >&2; }
printf 'get K3\nquit\n' | "$bin/ldrun" --project "$tmp/built/plant/plant.ldp" --io=stdio > "$tmp/out" 2> "$tmp/err"
grep -qx "K3 = 1" "$tmp/out" || { fail "the built project did not start from the saved retentive memory"; cat "$tmp/out" "$tmp/err" >&2; }
[ -e "$tmp/built/plant/plant.ret" ] && fail "the built project made a retentive file of its own"
(cd "$tmp/src" && "$bin/ldc" --project plant.ldp -o out 2> "$tmp/err") || fail "ldc --project -o out"
grep -qx "retain ../plant.ret every 1s" "$tmp/src/out/plant.ldp" || fail "ldc --project -o out: retain line"

# The line protocol writes what Modbus and the monitor write: a task's alias of an
# output by TASK.NAME, D0 of the first task unnamed (docs/runtime.md, "The line protocol").
mkdir -p "$tmp/lp"
printf '|--[X0]--(Y0)\n' > "$tmp/lp/fast.ld"
printf 'alias fault = Y5\n|--[fault]--(Y6)\n' > "$tmp/lp/slow.ld"
cat > "$tmp/lp/p.ldp" <<P
resource cpu0 processor 0
  task fast period 1ms
    program f fast.ld
  task slow period 2ms
    program s slow.ld
P
checks=$((checks + 1))
printf 'set slow.fault 1\nwait 3\nget Y6\nset D0 5\nget fast.D0\nquit\n' |
  "$bin/ldrun" --project "$tmp/lp/p.ldp" --io=stdio > "$tmp/out" 2> "$tmp/err"
printf 'ok\nok\nY6 = 1\nok\nfast.D0 = 5\nok bye\n' | diff - "$tmp/out" > /dev/null ||
  { fail "set slow.fault / set D0 in a project"; cat "$tmp/out" "$tmp/err" >&2; }

# A runtime that runs until stopped says on stderr what runs and how to stop it
# (docs/runtime.md, "Running"); stdout stays the line protocol's.
checks=$((checks + 1))
"$bin/ldrun" --project "$tmp/lp/p.ldp" --io=none --modbus 0 > "$tmp/bout" 2> "$tmp/berr" &
pid=$!
i=0
while [ $i -lt 100 ] && ! grep -q "Ctrl-C to stop" "$tmp/berr"; do sleep 0.1; i=$((i + 1)); done
kill -INT $pid
wait $pid || fail "ldrun ended with status $? after SIGINT"
for line in "ldrun: running $tmp/lp/p.ldp: 2 tasks, native code, I/O none" \
            "ldrun:   task fast: program f ($tmp/lp/fast.ld), period 1ms, priority 0, processor 0" \
            "ldrun:   task slow: program s ($tmp/lp/slow.ld), period 2ms, priority 0, processor 0" \
            "ldrun: Ctrl-C to stop"; do
  grep -qxF "$line" "$tmp/berr" || { fail "banner lacks '$line'"; cat "$tmp/berr" >&2; }
done
port=$(sed -n 's/^ldrun: modbus: listening on 127.0.0.1:\([0-9]*\) .*/\1/p' "$tmp/berr")
grep -qxF "ldrun: Modbus TCP on 127.0.0.1:$port" "$tmp/berr" || { fail "banner lacks the Modbus port"; cat "$tmp/berr" >&2; }
[ -s "$tmp/bout" ] && fail "ldrun wrote on stdout: $(cat "$tmp/bout")"
# a run of so many scans, and the trace driver's, end by themselves: no banner
expect 0 "" "$bin/ldrun" "$src/examples/motor.ld" --io=none --scans 3
grep -q "Ctrl-C" "$tmp/err" && fail "banner with --scans"
expect 0 "" "$bin/ldrun" "$src/examples/motor.ld" --io=trace --trace "$src/examples/motor.csv" --watch Y0 --clock=virtual --free-run
grep -q "Ctrl-C" "$tmp/err" && fail "banner in trace mode"

# --change-driven (docs/change-driven.md) makes an image: other outputs, a bad N and
# the C40 are refused by name, and nothing is written.
expect 1 "ldc: error: --change-driven makes an image: it goes with -o FILE.bin or --emit=hex, not with --emit=il" \
  "$bin/ldc" "$src/examples/motor.ld" --change-driven --emit=il
expect 1 "--change-driven=N takes a number of rungs from 1 to 65536, not '0'" "$bin/ldc" "$src/examples/motor.ld" --change-driven=0 -o "$tmp/cd.bin"
expect 1 "--change-driven is for the x86-64 target, not c40" "$bin/ldc" "$src/examples/motor.ld" --change-driven --target=c40 -o "$tmp/cd.bin"
[ -e "$tmp/cd.bin" ] && fail "a refused --change-driven left cd.bin"
expect 0 "" "$bin/ldc" "$src/examples/motor.ld" --change-driven=3 -O2 -o "$tmp/cd.bin"
checks=$((checks + 1))
"$bin/ldobjdump" "$tmp/cd.bin" | grep -q "change-driven scan (docs/change-driven.md): [0-9]* regions of up to 3 rungs" ||
  fail "ldobjdump does not list the region table"

# ldrun's warnings (docs/diagnostics.md): a trace column writing an output, --period 0 in
# trace mode; -Wno-NAME and -w silence them, -Werror makes them errors (exit 1).
printf 'X1,Y0,dt\n1,0,10\n' > "$tmp/yout.csv"
expect 0 "yout.csv:1:4: warning: column 'Y0' writes the output Y0 before every scan" \
  "$bin/ldrun" "$src/examples/eq1.ld" --trace "$tmp/yout.csv"
checks=$((checks + 1))
grep -q '^X1,Y0,dt$' "$tmp/err" && grep -q '^   \^$' "$tmp/err" || fail "-Wtrace-output: no quoted line and caret"
expect 0 "" "$bin/ldrun" "$src/examples/eq1.ld" --trace "$tmp/yout.csv" -Wno-trace-output
checks=$((checks + 1))
[ -s "$tmp/err" ] && fail "-Wno-trace-output still warns"
expect 1 "error: column 'Y0' writes the output Y0 before every scan" "$bin/ldrun" "$src/examples/eq1.ld" --trace "$tmp/yout.csv" -Werror
checks=$((checks + 1))
[ -s "$tmp/out" ] && fail "-Werror ran the trace anyway"
expect 0 "ldrun: warning: --period 0: dt is 0 in every scan, so no timer advances [-Wperiod]" \
  "$bin/ldrun" "$src/examples/eq1.ld" --period 0 --scans 1
expect 0 "" "$bin/ldrun" "$src/examples/eq1.ld" --period 0 --scans 1 -w
checks=$((checks + 1))
[ -s "$tmp/err" ] && fail "-w still warns"
expect 1 "ldrun: error: unknown warning option '-Wperod'" "$bin/ldrun" "$src/examples/eq1.ld" -Wperod

echo "$((checks - fails)) passed, $fails failed"
[ $fails -eq 0 ]
