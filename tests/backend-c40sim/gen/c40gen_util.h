// tests/backend-c40sim/gen/c40gen_util.h -- engines and checks shared by the C40 tests.
#pragma once

#include <memory>
#include <string>

#include "tests/backend-c40sim/gen/c40model.h"
#include "ir/ir.h"
#include "driver/c40_target.h"
#include "runtime/runtime.h"
#include "tests/diff/harness.h"

namespace ldc::c40gen::test {

// Engines for a compiled program (harness.h EngineFactory shape).
std::unique_ptr<Engine> make_native(const Program& p, int opt_level = 0);  // generate_c40 + assemble + c40sim
diff::EngineFactory native_at(int opt_level);                             // make_native at that level
std::unique_ptr<Engine> make_interp(const Program& p);  // make_c40interp_engine over the binary IL
std::unique_ptr<Engine> make_model(const Program& p);   // C40Model, Mode::C40
// C40Model in Mode::Check; its report is written to *report after every scan.
diff::EngineFactory make_check(CheckReport* report);

// The comparisons of docs/c40.md, "How the C40 engines are tested", each
// after every scan of the trace:
//   native   == model (C40)     byte for byte, the code at -O0, -O1 and -O2
//   interp   == model (C40)     byte for byte
//   model (Check) == reference  byte for byte, and no step outside the bound
struct Verdict {
  diff::Outcome native, interp, check;  // native: -O0 (or the engine given)
  diff::Outcome native_o1, native_o2;   // Same when an engine was given
  CheckReport report;
  int scans = 0;
  bool ok() const;
  std::string text() const;  // what failed, for messages
  // The first failure as one Outcome (a precision violation is a Differ at
  // scan 0 with the message), for the minimizer.
  diff::Outcome first_failure() const;
};
// `native` replaces the native engines of all levels (to test the test).
Verdict check_c40(const std::string& ld, const std::string& csv, const diff::EngineFactory& native = {});

}  // namespace ldc::c40gen::test
