// Fuzz the RTSP reader (paper 000's language, docs/rtsp.md): preprocess and
// parse, then print, lower and encode the trees of what it accepts; then the
// reader with error recovery (tests/fuzz/fuzz_recovery.h).
#include "frontend/diag.h"
#include "frontend/frontend.h"
#include "tests/fuzz/fuzz_common.h"
#include "tests/fuzz/fuzz_recovery.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::string_view text = LDC_FUZZ_TEXT(data, size);
  bool first_error = false;
  try {
    ldc::TreeProgram t = ldc::parse_rtsp(text, "fuzz.rtsp");
    (void)ldc::print_tree(t);
    ldc::Program p = ldc::lower_to_il(t);
    ldc::BinaryIl bin = ldc::encode_il(p);
    if (!ldc::validate_il(bin.code, p.layout()).empty()) __builtin_trap();  // the reader made invalid IL
  } catch (const ldc::CompileError&) {
    first_error = true;
  }
  ldc::Diagnostics d(ldc_fuzz::recovery_options());
  bool refused = false;
  try {
    ldc::TreeProgram t = ldc::parse_rtsp(text, "fuzz.rtsp", d);
    try {
      (void)ldc::lower_to_il(t);
    } catch (const ldc::CompileError&) {  // a rung too deep for the bit stack: refused without recovery too
      if (!first_error || d.errors() != 0) std::abort();
      return 0;
    }
  } catch (const ldc::ErrorsReported&) {
    refused = true;
  }
  ldc_fuzz::check_recovery(first_error, refused, d);
  return 0;
}
