// Fuzz the .sfc reader (docs/sfc.md): parse_sfc, lower_chart, print_il_text, the
// switch-form C, and a few scans of the reference interpreter over the IL;
// then the reader with error recovery (tests/fuzz/fuzz_recovery.h).
#include "backend-c/backend_c.h"
#include "frontend/diag.h"
#include "frontend/frontend.h"
#include "tests/fuzz/fuzz_common.h"
#include "tests/fuzz/fuzz_recovery.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::string_view text = LDC_FUZZ_TEXT(data, size);
  bool first_error = false;
  try {
    ldc::Chart c = ldc::parse_sfc(text, "fuzz.sfc");
    ldc::Program p = ldc::lower_chart(c);
    (void)ldc::print_il_text(p);
    (void)ldc::generate_sfc_c(c, p.layout());
    ldc::BinaryIl bin = ldc::encode_il(p);
    if (!ldc::validate_il(bin.code, p.layout()).empty()) __builtin_trap();  // the compiler made bad IL
    ldc::Interpreter interp(bin.code, p.layout());
    ldc::Memory m(p.layout());
    for (int scan = 0; scan < 4; scan++) {
      m.set_bit(ldc::Area::S, ldc::kBitFirstScan, scan == 0);
      m.set_int(ldc::Area::Sys, 0, 10);
      interp.scan(m.data());
    }
  } catch (const ldc::CompileError&) {
    first_error = true;
  }
  ldc::Diagnostics d(ldc_fuzz::recovery_options());
  bool refused = false;
  try {
    ldc::Chart c = ldc::parse_sfc(text, "fuzz.sfc", d);
    try {
      (void)ldc::lower_chart(c);
    } catch (const ldc::CompileError&) {  // what lowering refuses: refused without recovery too
      if (!first_error || d.errors() != 0) std::abort();
      return 0;
    }
  } catch (const ldc::ErrorsReported&) {
    refused = true;
  }
  ldc_fuzz::check_recovery(first_error, refused, d);
  return 0;
}
