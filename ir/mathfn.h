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

// ---- STRING instructions in native code (docs/x86.md, "Strings")
//
// Native code runs a string instruction (ir/typed.h, "strings") by calling
// native_string through one more slot right below the math table, on the
// same page (the slots above keep their places: images written before it
// call what they called).  It passes no pointer: `desc` packs the
// instruction (native_string_desc) and a0..a2 are its operands, each a byte
// offset into the image (a device) or a constant's canonical bits.  The image
// is the one this thread is scanning, which the runtime names around every
// native scan (ScanImageScope), so code, however crafted, can only make the
// routine work inside that image: it checks the op, the types and that every
// operand lies inside the image, and does nothing otherwise.  The first
// argument (rdi) is not read: rdi is a base register of -O2 code, which only
// a `lea` may set (loader/x86_check.cpp), so the call leaves it as it is and
// passes desc in rsi, a0..a2 in rdx, rcx, r8.  Returns a
// compare's result (0 / 1), or for the others 1 where S0 is to be set
// (MatIEC's ENO FALSE) and 0 otherwise.
constexpr int32_t kStrSlotDisp = kMathTableDisp - 8;
constexpr uint32_t native_string_desc(Op op, Ty t, Ty u, unsigned konst_mask) {
  return uint32_t(op) | uint32_t(t) << 8 | uint32_t(u) << 16 | uint32_t(konst_mask & 7) << 24;
}
uint64_t native_string(uint64_t unused, uint64_t desc, uint64_t a0, uint64_t a1, uint64_t a2);
// While one lives, native_string on this thread works in [data, data + size).
class ScanImageScope {
 public:
  ScanImageScope(uint8_t* data, size_t size);
  ~ScanImageScope();
  ScanImageScope(const ScanImageScope&) = delete;
  ScanImageScope& operator=(const ScanImageScope&) = delete;

 private:
  uint8_t* data_;
  size_t size_;
};

}  // namespace ldc
