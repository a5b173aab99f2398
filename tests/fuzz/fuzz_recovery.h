// tests/fuzz/fuzz_recovery.h -- the check every reader's harness makes of its
// error recovery (docs/diagnostics.md, docs/fuzzing.md): with a Diagnostics,
// an input is accepted exactly when the reader without recovery accepts it,
// and a refused one reports 1..kMaxErrors errors, each a located "error:"
// line, with the fatal line only at the limit.  Anything else aborts.
#pragma once
#include <cstdlib>
#include <string>

#include "frontend/diag.h"

namespace ldc_fuzz {

constexpr int kMaxErrors = 5;

// The diagnostics a harness reads with: every warning, at most kMaxErrors errors.
inline ldc::DiagOptions recovery_options() {
  ldc::DiagOptions o;
  o.all = true;
  o.max_errors = kMaxErrors;
  return o;
}

// A refused input's report: every "error:" line is one counted error, and the
// cascade stays within the limit (at most kMaxErrors, then the fatal line: the
// report's last line -- an error's quoted source line may hold the same words).
inline void check_report(const ldc::Diagnostics& d) {
  const std::string& t = d.text();
  int lines = 0;
  for (size_t p = t.find(": error: "); p != std::string::npos; p = t.find(": error: ", p + 1)) lines++;
  bool fatal = t.ends_with("fatal error: too many errors emitted, stopping now [-fmax-errors=" + std::to_string(kMaxErrors) + "]\n");
  if (d.errors() < 1 || d.errors() > kMaxErrors || lines < d.errors() || (fatal && d.errors() != kMaxErrors)) std::abort();
}

// `first_error`: the reader without recovery refused the input; `refused`:
// with recovery it did (ErrorsReported, or the reader's own error type).
inline void check_recovery(bool first_error, bool refused, const ldc::Diagnostics& d) {
  if (first_error != refused) std::abort();
  if (!refused) {
    if (d.errors() != 0) std::abort();
    return;
  }
  check_report(d);
}

// Reads the input again with recovery (`read(d)`) and checks the result
// against `refused`, the verdict without it: accepted, or refused with a
// report as above, or refused by an error the reader cannot go on from
// (thrown as without recovery: the lexer, the file's structure).
template <class F>
void check_reading(bool refused, F&& read) {
  ldc::Diagnostics d(recovery_options());
  try {
    read(d);
  } catch (const ldc::ErrorsReported&) {
    if (!refused) std::abort();
    check_report(d);
    return;
  } catch (const ldc::CompileError&) {
    if (!refused) std::abort();
    return;
  }
  if (refused || d.errors() != 0) std::abort();
}

}  // namespace ldc_fuzz
