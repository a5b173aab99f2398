// backend-c40sim/machine/c40interp.h -- the C40-hosted interpreter (interp.c40s): the
// classic interpreter of paper 003 written in C40 assembly, and the word form
// of the IL it runs (docs/c40.md, "The interpreter baseline").
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "backend-c40sim/machine/c40text.h"
#include "ir/ir.h"

namespace ldc::c40gen {

struct InterpProgram {
  std::vector<uint32_t> words;  // loaded at kCodeBase
  uint32_t entry = 0;           // word address of `interp`
  std::string source;           // interp.c40s
  AsmText text;                 // the assembled program (listing, labels)
};
// Assembles interp.c40s once; checks the dispatch table against ir/ops.def
// (throws std::logic_error if anything is off).
const InterpProgram& interp_program();

// The word IL: word 0 = n, then n words; an instruction is its opcode word and
// one word per operand (tag << 24 | payload), a constant followed by its value
// word, a jump target as a word offset from the first instruction.  `il` must
// be valid (validate_il).
// `starts`, if given, receives the word offset (from the first instruction)
// of every instruction, in program order.
std::vector<uint32_t> word_il(std::span<const uint8_t> il, const Layout& layout,
                              std::vector<uint32_t>* starts = nullptr);

}  // namespace ldc::c40gen
