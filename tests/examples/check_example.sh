#!/bin/sh
# check_example.sh LDRUN EXAMPLE.ld ENGINE
# Runs the example over its trace on ENGINE and compares with EXAMPLE.expected,
# whose header names the watched devices.
set -eu
ldrun=$1 src=$2 engine=$3
base=${src%.ld}
watch=$(head -n 1 "$base.expected" | cut -d, -f2-)
out=$(mktemp)
trap 'rm -f "$out"' EXIT
"$ldrun" "$src" --engine="$engine" --trace "$base.csv" --watch "$watch" > "$out"
if ! diff -u "$base.expected" "$out"; then
  echo "FAIL: $src on $engine differs from $base.expected" >&2
  exit 1
fi
