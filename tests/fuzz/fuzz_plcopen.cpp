// Fuzz the PLCopen XML importer (and its XML parser): parse_plcopen, print_tree, lower_to_il.
#include "frontend/frontend.h"
#include "tests/fuzz/fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    ldc::TreeProgram t = ldc::parse_plcopen(LDC_FUZZ_TEXT(data, size), "fuzz.xml");
    (void)ldc::print_tree(t);
    (void)ldc::lower_to_il(t);
  } catch (const ldc::CompileError&) {
  }
  return 0;
}
