// tests/fuzz/recovery_check.h -- the error-recovery check of the importers'
// harnesses (docs/fuzzing.md, docs/diagnostics.md), as fuzz_ld.cpp does it for
// the .ld reader: each input is read twice, without recovery (the first error
// is thrown) and with it (-fmax-errors=5).  It must be accepted with recovery
// exactly when it is without, and a refused one must report 1..5 errors, each
// an "error:" line, the fatal line only at the limit; anything else aborts.
#pragma once
#include <cstdlib>
#include <string>

#include "frontend/diag.h"

namespace ldc_fuzz {

constexpr int kMaxErrors = 5;

inline ldc::DiagOptions recovery_options() {
  ldc::DiagOptions o;
  o.all = true;
  o.max_errors = kMaxErrors;
  return o;
}

// `first_error`: the reader without recovery refused the input; `refused`:
// with recovery it did (ErrorsReported, or the reader's own error type).
inline void check_recovery(bool first_error, bool refused, const ldc::Diagnostics& d) {
  if (first_error != refused) std::abort();
  if (!refused) {
    if (d.errors() != 0) std::abort();
    return;
  }
  const std::string& t = d.text();
  int lines = 0;
  for (size_t p = t.find(": error: "); p != std::string::npos; p = t.find(": error: ", p + 1)) lines++;
  // (the last line: the text of an error's source line may hold the same words)
  bool fatal = t.ends_with("fatal error: too many errors emitted, stopping now [-fmax-errors=" + std::to_string(kMaxErrors) + "]\n");
  if (d.errors() < 1 || d.errors() > kMaxErrors || lines < d.errors() || (fatal && d.errors() != kMaxErrors)) std::abort();
}

}  // namespace ldc_fuzz
