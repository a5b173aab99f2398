// Fuzz the .sfc reader (docs/sfc.md): parse_sfc, lower_chart, print_il_text, the
// switch-form C, and a few scans of the reference interpreter over the IL.
#include "backend-c/backend_c.h"
#include "frontend/frontend.h"
#include "tests/fuzz/fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    ldc::Chart c = ldc::parse_sfc(LDC_FUZZ_TEXT(data, size), "fuzz.sfc");
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
  }
  return 0;
}
