// loader/c40_check.h -- the C40 code check read_image applies to ImageTarget::C40
// images (docs/image-format.md, "The C40 code check").
#pragma once

#include <cstdint>
#include <span>
#include <string>

#include "ir/ir.h"

namespace ldc {

// At most the board's code memory (2^20 words); every word decodes with our
// disassembler (assembler/c40.h); no indirect memory operand, no branch or
// call through a register, SP never an operand; every branch, call and DB
// target is an instruction of the code outside every delay slot, except
// calls to the entry points of the math ROM; a delayed branch has three
// plain instructions after it inside the code; execution never runs past the
// last word.  A flow analysis from the entry follows per word the data page
// (DP) and the words pushed since the routine's return address: each word is
// reached with one count, POP never takes the return address, RETS only finds
// it, so every return goes where a CALL or the runtime came from; every direct
// operand reads or writes a word of the memory image with DP known from LDPK
// on every path, and routines entered by CALL leave DP alone.  Keeps about two
// bytes and a bit per word.  Returns "" if the code passes, else
// "at word 0x.. (code offset 0x..): reason".
std::string check_c40_code(std::span<const uint8_t> code, uint32_t entry, const Layout& layout);

}  // namespace ldc
