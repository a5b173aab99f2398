// backend-c/backend_c.h -- the C route (paper 001 prints rungs as C; OpenPLC and
// MatIEC users compile such C with gcc): IL -> one C function
//   void ldc_scan(unsigned char *image)
// over the same memory image as every other engine.  The bit stack becomes
// local variables s0..s31, so the C compiler can keep it in registers.
#pragma once

#include <string>
#include <vector>

#include "ir/ir.h"

namespace ldc {

// Self-contained C99 (includes <string.h>, <math.h>, <stdint.h>); compile with
// `cc -O2 -shared -fPIC -ffp-contract=off prog.c -o prog.so -lm`.
std::string generate_c(const Program& p, const Layout& layout);

inline constexpr const char* kCScanSymbol = "ldc_scan";

// Pieces of generate_c for generators that lay out their own scan function:
// the run-time helpers, the function head (declares the bit stack s0..s31), and
// the statements of rungs or of one instruction list (a condition leaves its
// value in s0).  Every line starts with `indent`.
std::string c_prelude();
std::string c_scan_head();
std::string c_rungs(const std::vector<Rung>& rungs, const std::vector<std::string>& end_labels, const Layout& layout,
                    const std::string& indent);
std::string c_code(const std::vector<Instr>& code, const Layout& layout, const std::string& indent);

// A sequential function chart as the C of paper 001 (docs/sfc.md): one
// `switch (step_status)` per scope, one case per step running its actions and
// testing its transitions; simultaneous branches as switches of their own
// inside their sequence's case, joined when all wait in their last step.
// Behaves scan by scan like lower_chart(c) on the same memory image.
std::string generate_sfc_c(const Chart& c, const Layout& layout);

}  // namespace ldc
