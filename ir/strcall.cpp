// ir/strcall.cpp -- the STRING instructions as native code calls them
// (ir/mathfn.h, native_string): one checked routine, no pointer passed.
#include <cstring>

#include "ir/ir.h"
#include "ir/mathfn.h"
#include "ir/typed.h"

namespace ldc {
namespace {

// The image this thread scans natively, and the string-argument registers
// that ARGS sets for the MID / DELETE / INSERT / REPLACE right after it.
thread_local uint8_t* t_image = nullptr;
thread_local size_t t_size = 0;
thread_local typed::StrArgs t_args;

// The bytes operand k of a string instruction spans: a STRING's 33 cells, a
// BOOL's byte, another type's cells.
uint32_t operand_bytes(Ty t) {
  if (t == Ty::STRING) return typed::kStrBytes;
  return t == Ty::BOOL ? 1u : 4u * uint32_t(ty_info(t).cells);
}

// The instruction `desc` packs, if it is a string instruction whose operands
// all lie in the image (devices) or may be constants: o / k as str_exec takes them.
bool decode(uint64_t desc, const uint64_t a[3], Instr& in, uint8_t* o[3], uint64_t k[3]) {
  if (desc >> 27 || !t_image) return false;
  const uint32_t op = desc & 0xff, t = desc >> 8 & 0xff, u = desc >> 16 & 0xff, konst = desc >> 24 & 7;
  if (op >= uint32_t(kOpCount)) return false;
  in.op = Op(op), in.ty = Ty(t), in.src = Ty(u);
  const OpInfo& oi = op_info(in.op);
  if (oi.klass != OpClass::Typed || !op_takes(in.op, in.ty, in.src) || !typed::is_string_instr(in.op, in.ty, in.src))
    return false;
  for (int i = 0; i < 3; i++) {
    o[i] = nullptr, k[i] = 0;
    const bool is_const = konst >> i & 1;
    if (i >= oi.nopd) {
      if (is_const) return false;
      continue;
    }
    const Ty ty = operand_type(in, i);
    if (is_const) {  // a source of a type other than STRING
      const char sig = oi.operands[i];
      if ((sig != 's' && sig != 'x') || ty == Ty::STRING || ty == Ty::None) return false;
      k[i] = a[i];
    } else {
      if (ty == Ty::None || a[i] > t_size || t_size - a[i] < operand_bytes(ty)) return false;
      o[i] = t_image + a[i];
    }
  }
  return true;
}

}  // namespace

uint64_t native_string(uint64_t, uint64_t desc, uint64_t a0, uint64_t a1, uint64_t a2) {
  const uint64_t a[3] = {a0, a1, a2};
  Instr in;
  uint8_t* o[3];
  uint64_t k[3];
  if (!decode(desc, a, in, o, k)) return 0;
  const OpInfo& oi = op_info(in.op);
  if (oi.push) {  // EQ NE LT LE GT GE .STRING: two devices
    if (!o[0] || !o[1]) return 0;
    return typed::str_compare(oi.rel, typed::str_load(o[0]), typed::str_load(o[1]));
  }
  return typed::str_exec(in.op, in.ty, in.src, o, k, t_args) ? 1 : 0;
}

ScanImageScope::ScanImageScope(uint8_t* data, size_t size) : data_(t_image), size_(t_size) {
  t_image = data, t_size = size;
}
ScanImageScope::~ScanImageScope() { t_image = data_, t_size = size_; }

}  // namespace ldc
