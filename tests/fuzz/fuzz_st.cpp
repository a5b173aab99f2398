// Fuzz the Structured Text reader (frontend/st, docs/st.md) as the driver
// calls it: import_st (one program, or a CONFIGURATION of several tasks, one
// program each), then encode and validate every program it accepts.
#include "frontend/frontend.h"
#include "tests/fuzz/fuzz_common.h"

namespace {
void check(const ldc::TreeProgram& t) {
  ldc::Program p = ldc::lower_to_il(t);
  ldc::BinaryIl bin = ldc::encode_il(p);
  if (!ldc::validate_il(bin.code, p.layout()).empty()) __builtin_trap();  // the reader wrote invalid IL
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  ldc::PlcopenImport im;
  try {
    im = ldc::import_st(LDC_FUZZ_TEXT(data, size), "fuzz.st");
  } catch (const ldc::CompileError&) {
    return 0;
  }
  if (im.tasks.empty()) check(im.single);
  for (const ldc::PlcopenTask& t : im.tasks) check(t.tree);
  return 0;
}
