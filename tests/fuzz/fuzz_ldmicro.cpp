// Fuzz the LDmicro importer: parse_ldmicro, print_tree, lower_to_il.
#include "frontend/frontend.h"
#include "tests/fuzz/fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    ldc::TreeProgram t = ldc::parse_ldmicro(LDC_FUZZ_TEXT(data, size), "fuzz.ld");
    (void)ldc::print_tree(t);
    (void)ldc::lower_to_il(t);
  } catch (const ldc::CompileError&) {
  }
  return 0;
}
