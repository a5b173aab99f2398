// backend-c/backend_c.h -- the C route (paper 001 prints rungs as C; OpenPLC and
// MatIEC users compile such C with gcc): IL -> one C function
//   void ldc_scan(unsigned char *image)
// over the same memory image as every other engine.  The bit stack becomes
// local variables s0..s31, so the C compiler can keep it in registers.
#pragma once

#include <string>

#include "ir/ir.h"

namespace ldc {

// Self-contained C99 (includes <string.h>, <math.h>, <stdint.h>); compile with
// `cc -O2 -shared -fPIC -ffp-contract=off prog.c -o prog.so -lm`.
std::string generate_c(const Program& p, const Layout& layout);

inline constexpr const char* kCScanSymbol = "ldc_scan";

}  // namespace ldc
