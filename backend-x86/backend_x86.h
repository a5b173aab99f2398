// backend-x86/backend_x86.h -- the macro compiler for x86-64 (paper 003, step 2):
// every IL mnemonic becomes a fixed assembly template.
//
// The generated function is `void scan(uint8_t* image)` (System V ABI):
//   rbx  base of the memory image (every device is [rbx + offset])
//   ebp  the bit stack (top = bit 0), as paper 003 keeps it in R10 on the C40
//   eax ecx edx xmm0-2  scratch
// REAL functions with no instruction (sin, cos, tan, exp, ln) are called through
// the read-only table below the image (image + kCallTableDisp, ir.h); no absolute
// address is baked in.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "assembler/assembler.h"
#include "assembler/x86.h"
#include "ir/ir.h"

namespace ldc {

struct X86Code {
  as::x86::X86Program program;  // block 0 prologue, one block per rung, last block epilogue
  // For rung r and its IL instruction i, the item index in block rung_block(r)
  // where the instruction's code starts (with notes, the comment item holding
  // the IL text; an index equal to the block's item count means the block's end).
  std::vector<std::vector<uint32_t>> il_items;
  // The block of rung r's code (so that no caller counts the blocks).
  static uint32_t rung_block(size_t r) { return uint32_t(r) + 1; }
};

// opt_level 0: paper 003's pure macro expansion (the bit stack shifted in ebp).
// opt_level 1: -O0 plus a peephole pass over each rung's templates.
// opt_level 2: rung by rung, the bit stack in callee-saved byte registers
// (r12b r13b r14b r15b bpl) when the rung's live stack fits, else as -O1.
// notes: comment items with each rung's line and each IL instruction's text,
// for --emit=asm and listings; an image does not need them.
X86Code generate_x86(const Program& p, const Layout& layout, int opt_level = 0, bool notes = true);

// The same blocks one at a time, for the streaming assembler (as::Assembler):
// each block is handed to `sink`, which may take its items (the generator
// reuses the block afterwards).  The global names (X86Code::program.globals)
// are x86_globals(p); the result is X86Code::il_items.  At -O2 the base
// registers' K need every block's operands first: the rungs are generated
// twice, a first time only to count them (docs/x86.md, "Compact addressing").
using X86BlockSink = std::function<void(as::Block<as::x86::Instruction>&)>;
std::vector<std::vector<uint32_t>> generate_x86_blocks(const Program& p, const Layout& layout, int opt_level, bool notes,
                                                       const X86BlockSink& sink);
// The same, il_items filled in as the blocks go: rung r's entry is there when
// its block (X86Code::rung_block(r)) reaches the sink, as the last one, and the
// sink may clear it once read (a line map made while assembling): the
// generator then takes its storage back for a rung to come.
void generate_x86_blocks(const Program& p, const Layout& layout, int opt_level, bool notes, const X86BlockSink& sink,
                         std::vector<std::vector<uint32_t>>& il_items);
std::vector<std::string> x86_globals(const Program& p);

// Names of the global labels the backend defines.
inline constexpr const char* kX86ExitLabel = "scan_exit";
std::string x86_label_name(const std::string& il_label);  // user label -> assembly label

// Where the shared timer/counter routines (as::x86::scan_routine) find T0 and C0.
as::x86::RoutineAreas x86_routine_areas(const Layout& l);

}  // namespace ldc
