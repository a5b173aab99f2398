// Fuzz the PLCopen XML importer (and its XML parser): parse_plcopen,
// print_tree, lower_to_il; then import_plcopen with error recovery as the
// driver calls it (docs/diagnostics.md): accepted exactly when accepted
// without recovery, and a refused input reports 1..5 errors, each a located
// "error:" line, the fatal line only at the limit (tests/fuzz/fuzz_recovery.h).
#include <cstdlib>

#include "frontend/diag.h"
#include "frontend/frontend.h"
#include "tests/fuzz/fuzz_common.h"
#include "tests/fuzz/fuzz_recovery.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::string_view text = LDC_FUZZ_TEXT(data, size);
  bool refused = false;
  try {
    ldc::TreeProgram t = ldc::parse_plcopen(text, "fuzz.xml");
    (void)ldc::print_tree(t);
    (void)ldc::lower_to_il(t);
  } catch (const ldc::CompileError&) {
    refused = true;
  }
  // import_plcopen takes configurations of several tasks too, which
  // parse_plcopen refuses: its own verdict without recovery is the reference
  bool refused_import = false;
  try {
    (void)ldc::import_plcopen(text, "fuzz.xml");
  } catch (const ldc::CompileError&) {
    refused_import = true;
  }
  if (refused_import && !refused) std::abort();  // parse_plcopen accepts only what import_plcopen does
  ldc_fuzz::check_reading(refused_import, [&](ldc::Diagnostics& d) { (void)ldc::import_plcopen(text, "fuzz.xml", d); });
  return 0;
}
