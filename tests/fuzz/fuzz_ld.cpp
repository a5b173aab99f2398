// Fuzz the .ld grid reader: parse_ld, print_tree, lower_to_il, print_il_text.
#include "frontend/frontend.h"
#include "tests/fuzz/fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    ldc::TreeProgram t = ldc::parse_ld(LDC_FUZZ_TEXT(data, size), "fuzz.ld");
    (void)ldc::print_tree(t);
    ldc::Program p = ldc::lower_to_il(t);
    (void)ldc::print_il_text(p);
  } catch (const ldc::CompileError&) {
  }
  return 0;
}
