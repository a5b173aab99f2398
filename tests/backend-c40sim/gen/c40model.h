// tests/backend-c40sim/gen/c40model.h -- what C40 code computes, as a C++ IL interpreter.
//
// The C40 has no IEEE arithmetic: REAL operands are converted to its own float
// format (FRIEEE, FLOAT), computed in 40-bit registers that truncate, and
// stored back with TOIEEE.  This model runs the IL over the byte image of
// docs/il.md with exactly that arithmetic (c40gen.h's real_* functions, the
// math ROM's host results), so the simulated native code and the C40-hosted
// interpreter must match it bit for bit after every scan (tests/backend-c40sim/gen).
//
// In Mode::Check it instead keeps the state of the reference interpreter
// (IEEE binary32, docs/il.md) and, for every REAL operation it executes,
// computes the C40 result from the same inputs and checks it against the IEEE
// one: REAL results within a few units in the last place (CheckReport::kUlps),
// REAL -> INT32 results the truncation of such a value, compares and the
// division-by-zero test identical.  Operations whose inputs or result lie
// outside the C40 format (NaN, infinities, denormals, |x| > FLT_MAX) or that
// convert an INT32 that binary32 cannot hold exactly are counted, not checked
// (docs/c40.md, "Precision").  So: model(C40) == simulator, model(Check) ==
// reference interpreter, and every step between the two is within the bound.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "ir/ir.h"

namespace ldc::c40gen {

struct CheckReport {
  // the bound, in binary32 units in the last place, per mnemonic kind
  // The C40 truncates (toward -infinity) where IEEE rounds to nearest: one
  // unit at most for ADD SUB MUL DIV ABS and the INT32 -> REAL conversions
  // (__divf: 1 ulp over 20 million random normal quotients, tests/backend-c40sim/gen).
  static constexpr uint32_t kUlpsArith = 1;
  static constexpr uint32_t kUlpsRom = 0;      // the math ROM returns the host's binary32 result
  static uint32_t ulps_for(Op op);

  uint64_t checked[kOpCount] = {};     // REAL operations compared, by mnemonic
  uint64_t outside[kOpCount] = {};     // not compared: operand or result outside the C40 format
  uint64_t rounding[kOpCount] = {};    // not compared: an INT32 operand binary32 rounds
  uint32_t max_ulps[kOpCount] = {};    // largest distance seen
  uint64_t violations = 0;
  std::vector<std::string> first_violations;  // up to 10, with the scan and IL offset
  uint64_t total_checked() const;
  uint64_t total_outside() const;
  uint64_t total_rounding() const;
};

class C40Model {
 public:
  enum class Mode : uint8_t { C40, Check };
  C40Model(std::span<const uint8_t> il, const Layout& layout, Mode mode);  // il must be valid
  void scan(uint8_t* mem);
  const CheckReport& report() const { return report_; }

 private:
  std::vector<uint8_t> il_;
  Layout layout_;
  Mode mode_;
  CheckReport report_;
  uint64_t scans_ = 0;
};

// binary32 distance in units in the last place (0 for equal values, +0 == -0).
uint32_t ulp_distance(float a, float b);

}  // namespace ldc::c40gen
