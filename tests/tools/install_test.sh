#!/bin/sh
# install_test.sh BUILDDIR SRCDIR -- the tools as users of other compilers
# expect them: --help (every option, exit 0) and --version, manual pages made
# from docs/man that name every option of --help, and `cmake --install` putting
# tools and pages under a prefix from which they run.
set -u
build=$1 src=$2
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fails=0 checks=0
ok() { checks=$((checks + 1)); }
bad() { checks=$((checks + 1)); fails=$((fails + 1)); echo "FAIL: $*" >&2; }

version=$(sed -n 's/^project(ldc VERSION \([0-9.]*\).*/\1/p' "$src/CMakeLists.txt")
for t in driver/ldc driver/ldrun driver/ldobjdump bench/ldbench bench/ldgen; do
  name=${t#*/}
  "$build/$t" --help > "$tmp/help" 2> "$tmp/err" && ok || bad "$name --help: exit status not 0"
  grep -q "^usage: $name" "$tmp/help" && ok || bad "$name --help: no usage on stdout"
  [ -s "$tmp/err" ] && bad "$name --help wrote to stderr" || ok
  [ "$("$build/$t" --version)" = "$name (ldc) $version" ] && ok || bad "$name --version: '$("$build/$t" --version)'"
  # every option the usage names is in the manual page
  for opt in $(grep -o -- '--[a-z][a-z0-9-]*\|-O[012]\| -o ' "$tmp/help" | sed 's/ //g' | sort -u); do
    grep -q -F -- "\`$opt" "$src/docs/man/$name.1.md" && ok || bad "docs/man/$name.1.md does not describe $opt"
  done
done

# the pages and the tools under a prefix
cmake --install "$build" --prefix "$tmp/prefix" > "$tmp/install.log" 2>&1 && ok || { bad "cmake --install"; cat "$tmp/install.log" >&2; }
for name in ldc ldrun ldobjdump ldbench ldgen; do
  [ "$(PATH="$tmp/prefix/bin:/usr/bin:/bin" $name --version)" = "$name (ldc) $version" ] && ok || bad "$name from the prefix's bin"
  page="$tmp/prefix/share/man/man1/$name.1"
  head -1 "$page" 2>/dev/null | grep -q "^\.TH $(echo $name | tr a-z A-Z) 1 " && ok || bad "$page: no .TH line"
  if command -v groff > /dev/null; then
    groff -man -Tutf8 -ww -z "$page" 2> "$tmp/groff" && [ ! -s "$tmp/groff" ] && ok || { bad "groff warns on $page"; cat "$tmp/groff" >&2; }
  fi
done
PATH="$tmp/prefix/bin:$PATH" ldc "$src/examples/motor.ld" -o "$tmp/motor.bin" && ok || bad "ldc from the PATH"
# shm_client, which docs/runtime.md and ldrun(1) show, is installed and runs
PATH="$tmp/prefix/bin:/usr/bin:/bin" shm_client --help | grep -q "^usage: shm_client" && ok || bad "shm_client from the prefix's bin"
# every document a page cites is installed where its FILES section says, and no page
# points into the source tree's docs/
for name in ldc ldrun ldobjdump ldbench ldgen; do
  grep -q 'docs/[A-Za-z0-9_-]*\.md' "$src/docs/man/$name.1.md" && bad "$name.1.md cites docs/*.md of the source tree"
  for doc in $(grep -o '[A-Za-z0-9_-]*\.md' "$src/docs/man/$name.1.md" | grep -v '^FILE\.md$' | sort -u); do
    [ -f "$tmp/prefix/share/doc/ldc/$doc" ] && ok || bad "$name.1 cites $doc, not installed in share/doc/ldc"
  done
done

# md2man refuses what it does not understand, located, and writes nothing
printf '# bad(1) -- a page\n### three hashes\n' > "$tmp/bad.1.md"
"$build/tools/md2man" "$tmp/bad.1.md" "$tmp/bad.1" 2> "$tmp/err"
[ $? -eq 1 ] && grep -q "bad.1.md:2: error:" "$tmp/err" && [ ! -e "$tmp/bad.1" ] && [ ! -e "$tmp/bad.1.tmp" ] && ok || bad "md2man on a bad page"
printf 'no title\n' > "$tmp/bad.1.md"
"$build/tools/md2man" "$tmp/bad.1.md" "$tmp/bad.1" 2> "$tmp/err"
[ $? -eq 1 ] && grep -q "bad.1.md:1: error:" "$tmp/err" && ok || bad "md2man without a title"

echo "$((checks - fails)) passed, $fails failed"
[ $fails -eq 0 ]
