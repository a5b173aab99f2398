// Fuzz the IEC 61131-3 IL reader: parse_iec_il, then encode and validate what
// it accepts, print it back as IEC IL (--emit=iec-il) and read that again.
#include <stdexcept>

#include "frontend/frontend.h"
#include "tests/fuzz/fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  ldc::Program p;
  try {
    p = ldc::parse_iec_il(LDC_FUZZ_TEXT(data, size), "fuzz.il");
  } catch (const ldc::CompileError&) {
    return 0;
  }
  ldc::BinaryIl bin = ldc::encode_il(p);
  if (!ldc::validate_il(bin.code, p.layout()).empty()) __builtin_trap();  // the reader wrote invalid IL
  std::string iec;
  try {
    iec = ldc::print_iec_il(p);
  } catch (const std::runtime_error&) {
    return 0;  // a program with no IEC IL form, refused by name
  }
  try {
    (void)ldc::parse_iec_il(iec, "fuzz-back.il");
  } catch (const ldc::CompileError&) {
    __builtin_trap();  // --emit=iec-il wrote something its own reader refuses
  }
  return 0;
}
