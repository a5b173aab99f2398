#!/bin/sh
# check_diag.sh BINDIR CASE.ld|ldp|xml|sfc|rtsp|il -- one diagnostics case (docs/diagnostics.md);
# a project (.ldp) is compiled with `ldc --project`, its -o a directory.
# The case's `# ARGS: ...` line (`// ARGS: ...` in RTSP, `; ARGS: ...` in ldc IL text) gives ldc's options; stderr must be CASE.err
# exactly (LDC_UPDATE=1 rewrites it, to be reviewed as a diff).  The exit
# status is 1 when CASE.err reports an error and 0 otherwise, and the image
# (-o) exists exactly when the status is 0 and ARGS has no -fsyntax-only.
# A `# NO: ...` line runs the case again with those options (a -Wno-name, or
# none for a warning that is off by default): no diagnostics, status 0.
set -u
bin=$1 case=$2
dir=$(dirname "$case") file=$(basename "$case")
name=${file%.*}
input=$file
out=out.bin noout=no.bin
case $file in *.ldp) input="--project $file" out=out noout=no ;; esac  # a project writes a folder
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fails=0
bad() { fails=$((fails + 1)); echo "FAIL: $name: $*" >&2; }
args=$(sed -n 's@^\(#\|//\|;\) ARGS: *@@p' "$case" | head -n 1)
cd "$dir" || exit 1
# shellcheck disable=SC2086  # ARGS is a list of options
"$bin/ldc" $input $args -o "$tmp/$out" > "$tmp/stdout" 2> "$tmp/stderr"
rc=$?
if [ "${LDC_UPDATE:-}" = 1 ]; then cp "$tmp/stderr" "$name.err"; fi
if ! cmp -s "$tmp/stderr" "$name.err"; then bad "stderr differs from $name.err"; diff -u "$name.err" "$tmp/stderr" >&2; fi
want=0
grep -q -e '^[^ ]*: error: ' -e '^fatal error: ' "$name.err" && want=1
[ "$rc" -eq "$want" ] || bad "exit status $rc, expected $want"
[ -s "$tmp/stdout" ] && bad "something on stdout"
if [ "$rc" -eq 0 ] && ! echo " $args " | grep -q ' -fsyntax-only '; then
  [ -e "$tmp/$out" ] || bad "no image written"
else
  [ -e "$tmp/$out" ] && bad "an image was written (exit $rc, ARGS '$args')"
fi
[ -z "$(ls "$tmp" | grep -v -e "^$out\$" -e '^stdout$' -e '^stderr$')" ] || bad "a temporary file was left: $(ls "$tmp")"
if grep -q '^# NO:' "$file"; then
  no=$(sed -n 's/^# NO: *//p' "$file" | head -n 1)
  # shellcheck disable=SC2086
  "$bin/ldc" $input $no -o "$tmp/$noout" > "$tmp/stdout" 2> "$tmp/stderr"
  rc=$?
  [ "$rc" -eq 0 ] && [ ! -s "$tmp/stderr" ] && [ -e "$tmp/$noout" ] || { bad "with '$no': exit $rc, or diagnostics, or no image:"; cat "$tmp/stderr" >&2; }
fi
[ "$fails" -eq 0 ] && echo "$name: passed" || exit 1
