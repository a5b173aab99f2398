// Fuzz the IL text reader: parse_il_text, then print and encode what it accepts,
// and work out its scan facts (ir/scanopt.h, what -O2 compiles from).
#include "ir/ir.h"
#include "ir/scanopt.h"
#include "tests/fuzz/fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    ldc::Program p = ldc::parse_il_text(LDC_FUZZ_TEXT(data, size), "fuzz.il");
    (void)ldc::print_il_text(p);
    (void)ldc::encode_il(p);
    (void)ldc::scan_facts(p, p.layout(), 3);
  } catch (const ldc::CompileError&) {
  }
  return 0;
}
