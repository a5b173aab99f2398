// backend-c/c_typed.h -- the C route's translation of the typed instructions
// (ops.def class Typed): C that computes exactly what ir/typed.h defines, in
// the C types of types.def, with no undefined behaviour (docs/il.md, "Typed
// instructions"; the limits: docs/runtime.md, "The C route").
#pragma once

#include <cstdint>
#include <string>

#include "ir/ir.h"

namespace ldc {

// The helpers the typed statements call (ld_INT, st_LREAL, the conversions'
// rounding rules, the index fault): emitted once, after c_prelude(), in a
// program that has typed instructions.
std::string c_typed_prelude();

struct CTyped {
  bool push = false;  // a compare: `text` is the pushed expression
  std::string text;   // otherwise a statement (block) run only when the top of the stack is 1
};
// One typed instruction.  `il_offset` is its byte offset in the binary IL (an
// IDX writes it into the fault record); -1 if unknown, and then an IDX is
// refused (CompileError at its source line).
CTyped c_typed(const Instr& in, const Layout& layout, int64_t il_offset);

}  // namespace ldc
