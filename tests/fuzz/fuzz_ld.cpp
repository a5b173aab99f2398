// Fuzz the .ld grid reader: parse_ld, print_tree, lower_to_il, print_il_text;
// then the reader with error recovery (docs/diagnostics.md) and the ladder
// warnings on what it accepts.  With recovery, an input is either accepted
// (no error reported) or ends in ErrorsReported with 1..-fmax-errors errors
// reported, each a located "error:" line; anything else aborts.
#include <cstdlib>
#include <string>

#include "frontend/diag.h"
#include "frontend/frontend.h"
#include "tests/fuzz/fuzz_common.h"
#include "tests/fuzz/fuzz_recovery.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::string_view text = LDC_FUZZ_TEXT(data, size);
  bool first_error = false;
  try {
    ldc::TreeProgram t = ldc::parse_ld(text, "fuzz.ld");
    (void)ldc::print_tree(t);
    ldc::Program p = ldc::lower_to_il(t);
    (void)ldc::print_il_text(p);
  } catch (const ldc::CompileError&) {
    first_error = true;
  }
  ldc::Diagnostics d(ldc_fuzz::recovery_options());
  try {
    ldc::Program p = ldc::parse_ld_to_il(text, "fuzz.ld", d);
    ldc::warn_ladder(p, d);
    // accepted with recovery exactly when accepted without it (bar the lowering's own
    // refusal of a rung too deeply nested, which both report)
    if (first_error || d.errors() != 0) std::abort();
  } catch (const ldc::ErrorsReported&) {
    if (!first_error) std::abort();
    ldc_fuzz::check_report(d);
  } catch (const ldc::CompileError&) {
    // lower_rung's refusal, thrown from the sink (the reader reports it as an error too)
    if (!first_error) std::abort();
  }
  return 0;
}
