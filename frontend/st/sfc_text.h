// frontend/st/sfc_text.h -- a sequential function chart written as text in a
// POU body (IEC 61131-3 SFC elements: INITIAL_STEP, STEP, TRANSITION, ACTION,
// as OpenPLC and Beremiz write an SFC POU into generated_plc.st), rewritten
// as the ST statements that run it the way MatIEC's generated C does
// (docs/st.md, "Sequential function charts").  The statements are then read
// like any other body, so a chart in a FUNCTION_BLOCK keeps its steps in each
// instance.
#pragma once

#include <set>
#include <string>
#include <vector>

#include "frontend/iecil/iecil.h"

namespace ldc::st {

// Is `k` (followed by `next`) the first word of a chart's element?
bool sfc_element_start(const iecil::Tok& k, const iecil::Tok& next);

struct SfcText {
  // name, initial value ("TRUE"/"FALSE") and where: the chart's state, BOOL variables
  struct Var {
    std::string name, init;
    iecil::Tok at;
  };
  std::vector<Var> vars;
  std::vector<iecil::Tok> body;  // ST statements, then the END_ word and End
};

// Reads the chart from t[pos] up to the word `end` (END_PROGRAM ...; pos is
// left on it).  `variables`: the upper-case names the POU can use as variables
// (an action association naming one sets it; any other names an ACTION).
// Throws CompileError at the element it cannot take.
SfcText sfc_to_st(const std::vector<iecil::Tok>& t, size_t& pos, const std::string& end, const std::set<std::string>& variables);

}  // namespace ldc::st
