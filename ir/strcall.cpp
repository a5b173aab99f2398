// ir/strcall.cpp -- the STRING instructions as native code calls them
// (ir/mathfn.h, native_string): one checked routine, no pointer passed.
#include <cstring>
#include <vector>

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

// What a string instruction (op, t, u) takes, by a table made once from
// ops.def (op_takes and the operand letters are too slow to read on every
// call): nopd 0 if it is none; each operand's bytes as a device, and which may
// be a constant (a source of a type other than STRING).
struct Shape {
  uint8_t nopd = 0, konst_ok = 0;
  uint16_t bytes[3] = {};
};
constexpr size_t kT = size_t(kTyCount) + 1;  // the types and Ty::None
size_t ty_slot(uint32_t t) { return t == uint32_t(Ty::None) ? size_t(kTyCount) : t; }

Shape shape_of(Op op, Ty t, Ty u) {
  Shape sh;
  if (op_info(op).klass != OpClass::Typed || !op_takes(op, t, u) || !typed::is_string_instr(op, t, u)) return sh;
  Instr in;
  in.op = op, in.ty = t, in.src = u;
  const OpInfo& oi = op_info(op);
  for (int i = 0; i < oi.nopd; i++) {
    const Ty ty = operand_type(in, i);
    if (ty == Ty::None) return Shape{};
    sh.bytes[i] = uint16_t(operand_bytes(ty));
    if ((oi.operands[i] == 's' || oi.operands[i] == 'x') && ty != Ty::STRING) sh.konst_ok |= uint8_t(1u << i);
  }
  sh.nopd = uint8_t(oi.nopd);
  return sh;
}

const Shape& shape(uint32_t op, uint32_t t, uint32_t u) {
  static const std::vector<Shape> table = [] {
    std::vector<Shape> v(size_t(kOpCount) * kT * kT);
    for (int o = 0; o < kOpCount; o++)
      for (size_t i = 0; i < kT; i++)
        for (size_t j = 0; j < kT; j++)
          v[(size_t(o) * kT + i) * kT + j] =
              shape_of(Op(o), i < size_t(kTyCount) ? Ty(i) : Ty::None, j < size_t(kTyCount) ? Ty(j) : Ty::None);
    return v;
  }();
  static const Shape none;
  const size_t ti = ty_slot(t), tu = ty_slot(u);
  if (op >= uint32_t(kOpCount) || ti >= kT || tu >= kT) return none;
  return table[(size_t(op) * kT + ti) * kT + tu];
}

// The instruction `desc` packs, if it is a string instruction whose operands
// all lie in the image (devices) or may be constants: o / k as str_exec takes them.
bool decode(uint64_t desc, const uint64_t a[3], uint8_t* o[3], uint64_t k[3]) {
  if (desc >> 27 || !t_image) return false;
  const uint32_t konst = desc >> 24 & 7;
  const Shape& sh = shape(desc & 0xff, desc >> 8 & 0xff, desc >> 16 & 0xff);
  if (!sh.nopd || (konst & ~sh.konst_ok) || konst >> sh.nopd) return false;
  for (int i = 0; i < 3; i++) {
    o[i] = nullptr, k[i] = 0;
    if (i >= sh.nopd) continue;
    if (konst >> i & 1) {
      k[i] = a[i];
    } else {
      if (a[i] > t_size || t_size - a[i] < sh.bytes[i]) return false;
      o[i] = t_image + a[i];
    }
  }
  return true;
}

}  // namespace

uint64_t native_string(uint64_t, uint64_t desc, uint64_t a0, uint64_t a1, uint64_t a2) {
  const uint64_t a[3] = {a0, a1, a2};
  uint8_t* o[3];
  uint64_t k[3];
  if (!decode(desc, a, o, k)) return 0;
  const Op op = Op(desc & 0xff);
  const Ty t = Ty(desc >> 8 & 0xff), u = Ty(desc >> 16 & 0xff);
  const OpInfo& oi = op_info(op);
  if (oi.push) {  // EQ NE LT LE GT GE .STRING: two devices
    if (!o[0] || !o[1]) return 0;
    return typed::str_compare(oi.rel, typed::str_load(o[0]), typed::str_load(o[1]));
  }
  return typed::str_exec(op, t, u, o, k, t_args) ? 1 : 0;
}

ScanImageScope::ScanImageScope(uint8_t* data, size_t size) : data_(t_image), size_(t_size) {
  t_image = data, t_size = size;
}
ScanImageScope::~ScanImageScope() { t_image = data_, t_size = size_; }

}  // namespace ldc
