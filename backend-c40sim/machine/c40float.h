// backend-c40sim/machine/c40float.h -- the TMS320C40's floating-point format:
// the 40-bit extended-precision register and the arithmetic of the
// instructions on it (docs/c40.md, "Float format and conversions").  The simulator (sim.h) executes
// with it; the code generator (gen/c40gen.h) folds constants with it.
#pragma once

#include <cstdint>

namespace ldc::c40sim {

// A 40-bit extended-precision register: an 8-bit two's complement exponent
// (bits 39-32) and a 32-bit part (bits 31-0) that holds either an integer or
// the sign bit and the 31-bit fraction of a float. Exponent -128 is zero.
struct Ext {
  uint8_t exp = 0x80;
  uint32_t man = 0;
  friend bool operator==(const Ext&, const Ext&) = default;
};

namespace fp {
// Results carry the exponent overflow (V) and underflow (UF) conditions.
struct Res {
  Ext v;
  bool overflow = false;
  bool underflow = false;
};
constexpr Ext kZero{0x80, 0};
bool is_zero(Ext x);
bool is_negative(Ext x);
double to_double(Ext x);         // exact
Res from_double(double v);       // rounds toward -infinity (the C40's truncation)
Ext from_single(uint32_t word);  // 32-bit memory float -> register (LDF)
uint32_t to_single(Ext x);       // register -> 32-bit memory float (STF, truncates)
Ext from_short(uint16_t bits);   // 16-bit short float immediate
Res from_int(int32_t i);         // FLOAT (exact)
int32_t fix(Ext x, bool* overflow);  // FIX: floor, saturating
Res add(Ext a, Ext b);
Res sub(Ext a, Ext b);  // a - b
Res mul(Ext a, Ext b);  // inputs truncated to single precision first
Res neg(Ext a);
Res abs(Ext a);
Res rcp(Ext a);  // RCPF model: 1/a truncated to 8 fraction bits
int compare(Ext a, Ext b);  // sign of a - b, exact
// TOIEEE / FRIEEE (TMS320C3x/C4x conversion tables; see docs/c40.md).
uint32_t to_ieee(Ext x);
Res from_ieee(uint32_t ieee);
}  // namespace fp

}  // namespace ldc::c40sim
