#!/bin/sh
# layers_test.sh SRCDIR -- the pipeline's folders include one way
# (docs/architecture.md): data flows frontend -> ir -> backends -> assembler ->
# loader -> runtime, and the driver wires targets together.
#   ir        includes only ir
#   frontend  includes only ir
#   assembler includes nothing of ours but assembler, and assembler.h nothing of ours at all
#   loader    includes ir, assembler and loader: no backend, no runtime
#   runtime   includes ir, loader and runtime: no backend, and not its servers (runtime/net)
#   runtime/net  the servers (HTTP, monitor, Modbus): ir, loader, runtime and runtime/net
#   backends  include ir, assembler and loader's image-format facts, never runtime or driver
#   backend-c40sim/gen      the C40 code generator: besides those, of machine/ only the float format
#   backend-c40sim/machine  the simulated board: never gen/
#   backend-c40sim          itself holds no source (only its two parts do)
set -u
src=$1
fails=0 checks=0
# allowed FOLDER PATTERN: every #include "..." of FOLDER's files matches PATTERN
allowed() {
  dir=$1 pat=$2
  [ -d "$src/$dir" ] || { echo "FAIL: no folder $dir (the rules name it)"; return; }
  for f in "$src/$dir"/*.h "$src/$dir"/*.cpp; do
    [ -e "$f" ] || continue
    grep -o '^#include "[^"]*"' "$f" | sed 's/^#include "\(.*\)"$/\1/' | while read -r inc; do
      echo "$inc" | grep -Eq "^($pat)$" || echo "FAIL: $dir/$(basename "$f") includes \"$inc\""
    done
  done
}
out=$( {
  allowed ir 'ir/[a-z_]+\.h|(ir/)?(ops|types)\.def'
  allowed frontend 'ir/[a-z_]+\.h|frontend/[a-z_0-9]+\.h'
  allowed assembler 'assembler/[a-z_0-9]+\.h'
  allowed loader 'ir/[a-z_]+\.h|assembler/[a-z_0-9]+\.h|loader/[a-z_0-9]+\.h'
  allowed runtime 'ir/[a-z_]+\.h|loader/[a-z_0-9]+\.h|runtime/[a-z_0-9]+\.h'
  allowed runtime/net 'ir/[a-z_]+\.h|loader/[a-z_0-9]+\.h|runtime/[a-z_0-9]+\.h|runtime/net/[a-z_0-9]+\.h|runtime/monitor_page\.h'
  allowed backend-x86 'ir/[a-z_]+\.h|assembler/[a-z_0-9]+\.h|backend-x86/[a-z_0-9]+\.h'
  allowed backend-c40sim/gen 'ir/[a-z_]+\.h|assembler/[a-z_0-9]+\.h|loader/c40_map\.h|backend-c40sim/gen/[a-z_0-9]+\.h|backend-c40sim/machine/c40float\.h'
  allowed backend-c40sim/machine 'ir/[a-z_]+\.h|assembler/[a-z_0-9]+\.h|loader/c40_map\.h|backend-c40sim/machine/[a-z_0-9]+\.h'
  for f in "$src"/backend-c40sim/*.h "$src"/backend-c40sim/*.cpp; do
    [ -e "$f" ] && echo "FAIL: backend-c40sim/$(basename "$f") is outside gen/ and machine/"
  done
  allowed backend-c 'ir/[a-z_]+\.h|backend-c/[a-z_0-9]+\.h'
} )
if grep -q '^#include "' "$src/assembler/assembler.h"; then out="$out
FAIL: assembler/assembler.h includes a header of ours (the x86/C40 headers include it, not the other way)"; fi
if [ -n "$out" ]; then
  echo "$out" >&2
  n=$(echo "$out" | grep -c FAIL)
  echo "0 passed, $n failed"
  exit 1
fi
echo "12 passed, 0 failed"
