#!/bin/sh
# tools/fuzz.sh NAME SECONDS -- fuzz one reader with libFuzzer (docs/fuzzing.md).
#   NAME: ld ldmicro plcopen iltext ilbin trace image hex project iecil rtsp sfc modbus http
# Builds build-fuzz/ with clang (-fsanitize=fuzzer,address,undefined) if needed,
# seeds fuzz-corpus/NAME/ (git-ignored) from the reader's seed directories,
# runs for SECONDS and prints the executions.  Crashes land in fuzz-corpus/NAME-crashes/.
# LDC_FUZZ_ARGS adds libFuzzer flags (e.g. "-fork=1 -ignore_crashes=1" to go on past a known crash,
# "-max_len=4096" to keep the slow readers' mutants small).
# LDC_FUZZ_CORPUS puts the corpora elsewhere than fuzz-corpus/ (e.g. outside the worktree);
# LDC_FUZZ_BUILD names another fuzz build directory.
set -eu
name=${1:?usage: tools/fuzz.sh NAME SECONDS}
secs=${2:-60}
root=$(cd "$(dirname "$0")/.." && pwd)
build=${LDC_FUZZ_BUILD:-$root/build-fuzz}
if [ ! -f "$build/CMakeCache.txt" ]; then
  CXX=clang++ cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DLDC_FUZZ=ON -DLDC_SANITIZE=ON >/dev/null
fi
# one build of $build at a time: two at once (a run restarted while the last
# one still built) can leave an object older than its source yet newer in time
if command -v flock >/dev/null; then
  flock "$build/.build-lock" cmake --build "$build" --target "fuzz_$name" -j"${LDC_FUZZ_JOBS:-2}" >/dev/null
else
  cmake --build "$build" --target "fuzz_$name" -j"${LDC_FUZZ_JOBS:-2}" >/dev/null
fi
corpora=${LDC_FUZZ_CORPUS:-$root/fuzz-corpus}
corpus=$corpora/$name
crashes=$corpora/$name-crashes
mkdir -p "$corpus" "$crashes"
# seeds: the directories tests/fuzz/CMakeLists.txt lists for this reader
seeds=$(sed -n "s/^set(_fuzz_seeds_$name \(.*\))$/\1/p" "$root/tests/fuzz/CMakeLists.txt")
if grep -q "^set(_fuzz_seeds_$name " "$root/tests/fuzz/CMakeLists.txt" && [ -z "$seeds" ]; then
  echo "tools/fuzz.sh: the seed list of $name in tests/fuzz/CMakeLists.txt is not on one line" >&2
  exit 2
fi
for d in $seeds "tests/fuzz/regressions/$name"; do
  [ -d "$root/$d" ] || continue
  find "$root/$d" -type f ! -name '*.md' | while read -r f; do
    cp "$f" "$corpus/seed_$(echo "$f" | cksum | cut -d' ' -f1)"
  done
done
# the project harness writes every input to $TMPDIR: keep that in memory
# (/tmp on disk ran it at ~220 exec/s on a busy machine, /dev/shm at ~7,000)
if [ -z "${TMPDIR:-}" ] && [ -d /dev/shm ] && [ -w /dev/shm ]; then export TMPDIR=/dev/shm; fi
log=$corpora/$name-$(date +%Y%m%d-%H%M%S).log
set +e
"$build/tests/fuzz/fuzz_$name" -max_total_time="$secs" -timeout=10 -rss_limit_mb=2048 \
  -artifact_prefix="$crashes/" -print_final_stats=1 ${LDC_FUZZ_ARGS:-} "$corpus" >"$log" 2>&1
rc=$?
set -e
grep -E '^stat::number_of_executed_units|^stat::peak_rss_mb|ERROR|SUMMARY' "$log" || true
echo "corpus: $(ls "$corpus" | wc -l) files; crashes: $(ls "$crashes" | wc -l); exit $rc; log $log"
exit $rc
