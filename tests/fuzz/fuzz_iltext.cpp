// Fuzz the IL text reader: parse_il_text, then print and encode what it accepts,
// and work out its scan facts (ir/scanopt.h, what -O2 compiles from).  Then the
// reader with error recovery as the driver calls it (docs/diagnostics.md):
// accepted exactly when accepted without it, and a refused input reports
// 1..5 errors, each a located "error:" line, the fatal line only at the limit
// (tests/fuzz/fuzz_recovery.h).
#include <cstdlib>

#include "frontend/diag.h"
#include "ir/ir.h"
#include "ir/scanopt.h"
#include "tests/fuzz/fuzz_common.h"
#include "tests/fuzz/fuzz_recovery.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::string_view text = LDC_FUZZ_TEXT(data, size);
  bool refused = false;
  ldc::Program p;
  try {
    p = ldc::parse_il_text(text, "fuzz.il");
  } catch (const ldc::CompileError&) {
    refused = true;
  }
  if (!refused) try {
      (void)ldc::print_il_text(p);
      (void)ldc::encode_il(p);
      (void)ldc::scan_facts(p, p.layout(), 3);
    } catch (const ldc::CompileError&) {
    }
  ldc::Diagnostics d(ldc_fuzz::recovery_options());
  d.source("fuzz.il", text);
  try {
    (void)ldc::parse_il_text(text, "fuzz.il", [&](const ldc::CompileError& e) { d.error("fuzz.il", e); });
    if (refused != (d.errors() != 0)) std::abort();
    if (refused) ldc_fuzz::check_report(d);
  } catch (const ldc::ErrorsReported&) {  // the limit reached
    if (!refused) std::abort();
    ldc_fuzz::check_report(d);
  }
  return 0;
}
