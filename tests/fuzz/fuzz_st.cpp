// Fuzz the Structured Text reader (frontend/st, docs/st.md): parse_st, then
// encode and validate what it accepts.
#include "frontend/frontend.h"
#include "tests/fuzz/fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  ldc::Program p;
  try {
    p = ldc::parse_st(LDC_FUZZ_TEXT(data, size), "fuzz.st");
  } catch (const ldc::CompileError&) {
    return 0;
  }
  ldc::BinaryIl bin = ldc::encode_il(p);
  if (!ldc::validate_il(bin.code, p.layout()).empty()) __builtin_trap();  // the reader wrote invalid IL
  return 0;
}
