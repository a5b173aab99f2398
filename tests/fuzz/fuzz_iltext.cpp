// Fuzz the IL text reader: parse_il_text, then print and encode what it accepts.
#include "ir/ir.h"
#include "tests/fuzz/fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    ldc::Program p = ldc::parse_il_text(LDC_FUZZ_TEXT(data, size), "fuzz.il");
    (void)ldc::print_il_text(p);
    (void)ldc::encode_il(p);
  } catch (const ldc::CompileError&) {
  }
  return 0;
}
