// ir/mathfn.h -- the C library's double functions that native code calls for
// the typed instructions (ir/typed.h), and where their table lies.
#pragma once

#include "ir/ir.h"

namespace ldc {

// The C library's double functions of the typed instructions (ir/typed.h:
// ln log10 exp sin cos tan asin acos atan, and pow for EXPT).  Native code
// calls them through a second table of 8-byte pointers right below the REAL
// one, on the same read-only page: slot k at image + kMathTableDisp + 8k
// (docs/image-format.md, "Threat model").
enum class MathFn : uint8_t { Log, Log10, Exp, Sin, Cos, Tan, Asin, Acos, Atan, Pow, None };
constexpr int kMathSlots = int(MathFn::None);
constexpr int32_t kMathTableDisp = kCallTableDisp - 8 * kMathSlots;
constexpr int32_t math_slot_disp(MathFn f) { return kMathTableDisp + 8 * int32_t(f); }
// The function a typed instruction calls (TLN .. TATAN, TEXPT); None for the others.
constexpr MathFn math_fn(Op op) {
  switch (op) {
    case Op::TLN: return MathFn::Log;
    case Op::TLOG: return MathFn::Log10;
    case Op::TEXP: return MathFn::Exp;
    case Op::TSIN: return MathFn::Sin;
    case Op::TCOS: return MathFn::Cos;
    case Op::TTAN: return MathFn::Tan;
    case Op::TASIN: return MathFn::Asin;
    case Op::TACOS: return MathFn::Acos;
    case Op::TATAN: return MathFn::Atan;
    case Op::TEXPT: return MathFn::Pow;
    default: return MathFn::None;
  }
}
const void* math_fn_address(MathFn f);  // the table's entry: double f(double), pow double(double, double)

}  // namespace ldc
