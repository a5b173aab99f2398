// backend-c40sim/machine/c40text.h -- assembling C40 source text (.c40s) with our
// assembler: the math ROM and the C40-hosted interpreter are written this way.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "assembler/c40.h"

namespace ldc::c40gen {

struct AsmText {
  as::c40::C40Program program;          // one block
  as::Result result;
  std::vector<uint32_t> words;          // the code, placed at `base`
  std::map<std::string, uint32_t> labels;  // absolute word addresses
};

// Assembles `text` (TI syntax as assembler/c40.h parses it, one statement per
// line) as one block placed at word address `base`.  Besides parse_line():
//   .float V       a C40 single-precision word for the decimal V
//   %NAME_HI%      the high 16 bits of label NAME's absolute address
//   %NAME_LO%      its low 16 bits (for LDHI / OR into an address register)
//   %VAR%          vars.at("VAR") (a number the caller supplies)
// Branch operands that are numbers are absolute word addresses; they are only
// meaningful with base 0.  Throws std::runtime_error "NAME:LINE: message".
AsmText assemble_text(std::string_view text, uint32_t base, const std::string& name,
                      const std::map<std::string, int64_t>& vars = {});

}  // namespace ldc::c40gen
