// Fuzz the IEC 61131-3 IL reader: parse_iec_il, then encode and validate what
// it accepts, print it back as IEC IL (--emit=iec-il) and read that again.
// Then parse_iec_il with error recovery (docs/diagnostics.md): accepted
// exactly when accepted without recovery, and a refused input reports 1..5
// errors, each a located "error:" line, the fatal line only at the limit
// (tests/fuzz/fuzz_recovery.h).
#include <cstdlib>
#include <stdexcept>

#include "frontend/diag.h"
#include "frontend/frontend.h"
#include "tests/fuzz/fuzz_common.h"
#include "tests/fuzz/fuzz_recovery.h"

namespace {
void check(const ldc::Program& p) {
  ldc::BinaryIl bin = ldc::encode_il(p);
  if (!ldc::validate_il(bin.code, p.layout()).empty()) __builtin_trap();  // the reader wrote invalid IL
  std::string iec;
  try {
    iec = ldc::print_iec_il(p);
  } catch (const std::runtime_error&) {
    return;  // a program with no IEC IL form, refused by name
  }
  try {
    (void)ldc::parse_iec_il(iec, "fuzz-back.il");
  } catch (const ldc::CompileError&) {
    __builtin_trap();  // --emit=iec-il wrote something its own reader refuses
  }
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::string_view text = LDC_FUZZ_TEXT(data, size);
  bool refused = false;
  try {
    check(ldc::parse_iec_il(text, "fuzz.il"));
  } catch (const ldc::CompileError&) {
    refused = true;
  }
  ldc_fuzz::check_reading(refused, [&](ldc::Diagnostics& d) { (void)ldc::parse_iec_il(text, "fuzz.il", d); });
  return 0;
}
