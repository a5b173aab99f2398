// Fuzz the Structured Text reader (frontend/st, docs/st.md) as the driver
// calls it: import_st (one program, or a CONFIGURATION of several tasks, one
// program each), then encode and validate every program it accepts.  Then
// import_st with error recovery (docs/diagnostics.md): accepted exactly when
// accepted without recovery, and a refused input reports 1..5 errors, each a
// located "error:" line, the fatal line only at the limit
// (tests/fuzz/fuzz_recovery.h).
#include <cstdlib>

#include "frontend/diag.h"
#include "frontend/frontend.h"
#include "tests/fuzz/fuzz_common.h"
#include "tests/fuzz/fuzz_recovery.h"

namespace {
void check(const ldc::TreeProgram& t) {
  ldc::Program p = ldc::lower_to_il(t);
  ldc::BinaryIl bin = ldc::encode_il(p);
  if (!ldc::validate_il(bin.code, p.layout()).empty()) __builtin_trap();  // the reader wrote invalid IL
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::string_view text = LDC_FUZZ_TEXT(data, size);
  ldc::PlcopenImport im;
  bool refused = false;
  try {
    im = ldc::import_st(text, "fuzz.st");
  } catch (const ldc::CompileError&) {
    refused = true;
  }
  if (!refused) {
    if (im.tasks.empty()) check(im.single);
    for (const ldc::PlcopenTask& t : im.tasks) check(t.tree);
  }
  ldc_fuzz::check_reading(refused, [&](ldc::Diagnostics& d) { (void)ldc::import_st(text, "fuzz.st", d); });
  return 0;
}
