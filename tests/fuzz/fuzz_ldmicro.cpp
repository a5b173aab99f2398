// Fuzz the LDmicro importer: parse_ldmicro, print_tree, lower_to_il; then the
// importer with error recovery (tests/fuzz/fuzz_recovery.h) and the ladder
// warnings on what it accepts.
#include "frontend/frontend.h"
#include "tests/fuzz/fuzz_common.h"
#include "tests/fuzz/fuzz_recovery.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::string_view text = LDC_FUZZ_TEXT(data, size);
  bool first_error = false;
  try {
    ldc::TreeProgram t = ldc::parse_ldmicro(text, "fuzz.ld");
    (void)ldc::print_tree(t);
    (void)ldc::lower_to_il(t);
  } catch (const ldc::CompileError&) {
    first_error = true;
  }
  ldc::Diagnostics d(ldc_fuzz::recovery_options());
  bool refused = false, lowering_refused = false;
  try {
    ldc::TreeProgram t = ldc::parse_ldmicro(text, "fuzz.ld", d);
    try {
      ldc::warn_ladder(ldc::lower_to_il(t), d, true);
    } catch (const ldc::CompileError&) {  // a rung too deep for the bit stack: refused without recovery too
      lowering_refused = true;
    }
  } catch (const ldc::ErrorsReported&) {
    refused = true;
  }
  if (lowering_refused) {
    if (!first_error || d.errors() != 0) std::abort();
    return 0;
  }
  ldc_fuzz::check_recovery(first_error, refused, d);
  return 0;
}
