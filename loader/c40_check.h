// loader/c40_check.h -- the C40 code check read_image applies to ImageTarget::C40
// images (docs/image-format.md, "The C40 code check").
#pragma once

#include <cstdint>
#include <span>
#include <string>

#include "ir/ir.h"

namespace ldc {

// Every word decodes with our disassembler (assembler/c40.h); no indirect
// memory operand and no branch or call through a register; every branch,
// call and DB target is an instruction of the code, except calls to the entry
// points of the math ROM; a delayed branch has three plain instructions after
// it inside the code; every direct operand reads or writes a word of the
// memory image, with the data page (DP) known from LDPK on every path that
// reaches it (a flow analysis over the code; calls keep DP).
// Returns "" if the code passes, else "at word 0x..: reason".
std::string check_c40_code(std::span<const uint8_t> code, uint32_t entry, const Layout& layout);

}  // namespace ldc
