// C40 target: opcode table, encoder, decoder.
#include <cstdio>

#include "assembler/c40_forms.h"

namespace ldc::as::c40 {
namespace detail {
namespace {

// Opcode bases: TMS320C4x User's Guide instruction descriptions; the same
// values as the opcode column of binutils' tic4x table.
constexpr Spec kSpecs[] = {
    {"ABSI", Cls::A, 0x00800000},   {"ADDI", Cls::A, 0x02000000},
    {"AND", Cls::AU, 0x02800000},   {"ANDN", Cls::AU, 0x03000000},
    {"ASH", Cls::A, 0x03800000},    {"CMPI", Cls::A, 0x04800000},
    {"LDI", Cls::A, 0x08000000},    {"LSH", Cls::A, 0x09800000},
    {"MPYI", Cls::A, 0x0a800000},   {"NEGI", Cls::A, 0x0c000000},
    {"NOT", Cls::AU, 0x0d800000},   {"OR", Cls::AU, 0x10000000},
    {"SUBI", Cls::A, 0x18000000},   {"TSTB", Cls::AU, 0x1a000000},
    {"XOR", Cls::AU, 0x1a800000},
    {"ABSF", Cls::B, 0x00000000},   {"ADDF", Cls::B, 0x01800000},
    {"CMPF", Cls::B, 0x04000000},   {"LDF", Cls::B, 0x07000000},
    {"MPYF", Cls::B, 0x0a000000},   {"NEGF", Cls::B, 0x0b800000},
    {"SUBF", Cls::B, 0x17800000},   {"FIX", Cls::AF, 0x05000000},
    {"FLOAT", Cls::BI, 0x05800000}, {"RCPF", Cls::BA, 0x1d000000},
    {"TOIEEE", Cls::B, 0x1b800000}, {"FRIEEE", Cls::B6, 0x1c000000},
    {"LDI", Cls::AB, 0x50000000},   {"LDF", Cls::BB, 0x40000000},
    {"STI", Cls::A7, 0x15000000},   {"STF", Cls::B7, 0x14000000},
    {"LDA", Cls::AY, 0x1e800000},   {"LDHI", Cls::Ldhi, 0x1fe00000},
    {"LDPK", Cls::Ldpk, 0x1f700000},
    {"ADDI3", Cls::T, 0x01000000},  {"AND3", Cls::T, 0x01800000},
    {"ANDN3", Cls::T, 0x02000000},  {"ASH3", Cls::T, 0x02800000},
    {"CMPI3", Cls::T2, 0x03800000}, {"LSH3", Cls::T, 0x04000000},
    {"MPYI3", Cls::T, 0x05000000},  {"OR3", Cls::T, 0x05800000},
    {"SUBI3", Cls::T, 0x07000000},  {"TSTB3", Cls::T2, 0x07800000},
    {"XOR3", Cls::T, 0x08000000},
    {"ADDF3", Cls::S, 0x00800000},  {"CMPF3", Cls::S2, 0x03000000},
    {"MPYF3", Cls::S, 0x04800000},  {"SUBF3", Cls::S, 0x06800000},
    {"BR", Cls::I, 0x60000000},     {"BRD", Cls::I, 0x61000000},
    {"CALL", Cls::I, 0x62000000},
    {"B", Cls::J, 0x68000000},      {"B", Cls::J, 0x68200000},  // BcondD: +D suffix
    {"CALL", Cls::JS, 0x70000000},  {"RETS", Cls::Rets, 0x78800000},
    {"DB", Cls::D, 0x6c000000},     {"DB", Cls::D, 0x6c200000},
    {"PUSH", Cls::R, 0x0f200000},   {"POP", Cls::R, 0x0e200000},
    {"PUSHF", Cls::RF, 0x0fa00000}, {"POPF", Cls::RF, 0x0ea00000},
    {"NOP", Cls::Nop, 0x0c800000},  {".word", Cls::Word, 0},
};
static_assert(std::size(kSpecs) == size_t(Mnemonic::Count_));

}  // namespace

const Spec& spec(Mnemonic m) { return kSpecs[size_t(m)]; }

ImmKind imm_kind(Cls c) {
  switch (c) {
    case Cls::A: case Cls::BI: case Cls::AB: case Cls::AY: return ImmKind::S16;
    case Cls::AU: case Cls::Ldhi: case Cls::Ldpk: return ImmKind::U16;
    case Cls::AF: case Cls::B: case Cls::BA: case Cls::BB: return ImmKind::F16;
    default: return ImmKind::None;
  }
}

bool is_float_src(Cls c) {
  return c == Cls::AF || c == Cls::B || c == Cls::BA || c == Cls::BB || c == Cls::S ||
         c == Cls::S2;
}

}  // namespace detail

using namespace detail;

bool valid_cond(unsigned c) { return c <= 20 && c != 11; }

Instruction make(Mnemonic m, std::initializer_list<Operand> ops) {
  Instruction in;
  in.mnemonic = m;
  for (const Operand& o : ops) {
    if (in.num_operands >= 3) throw AsmError("too many operands");
    in.ops[in.num_operands++] = o;
  }
  return in;
}

Instruction make_cc(Mnemonic m, Cond c, std::initializer_list<Operand> ops) {
  Instruction in = make(m, ops);
  in.cond = c;
  return in;
}

bool has_cond(Mnemonic m) {
  switch (m) {
    case Mnemonic::Ldic: case Mnemonic::Ldfc: case Mnemonic::Bc: case Mnemonic::Bcd:
    case Mnemonic::Callc: case Mnemonic::Retsc: case Mnemonic::Dbc: case Mnemonic::Dbcd:
      return true;
    default:
      return false;
  }
}

bool is_control(Mnemonic m) {
  switch (m) {
    case Mnemonic::Br: case Mnemonic::Brd: case Mnemonic::Call: case Mnemonic::Bc:
    case Mnemonic::Bcd: case Mnemonic::Callc: case Mnemonic::Retsc: case Mnemonic::Dbc:
    case Mnemonic::Dbcd:
      return true;
    default:
      return false;
  }
}

bool is_delayed(Mnemonic m) {
  return m == Mnemonic::Brd || m == Mnemonic::Bcd || m == Mnemonic::Dbcd;
}

namespace {

constexpr FixupKind kKinds[] = {
    {"disp16", 4, 0, 16, true, true, PcBase::InstructionStart, 1, 4, -1},
    {"disp16d", 4, 0, 16, true, true, PcBase::InstructionStart, 3, 4, -1},
    {"disp24", 4, 0, 24, true, true, PcBase::InstructionStart, 1, 4, -1},
    {"disp24d", 4, 0, 24, true, true, PcBase::InstructionStart, 3, 4, -1},
    {"abs32", 4, 0, 32, false, false, PcBase::InstructionStart, 0, 4, -1},
};

[[noreturn]] void bad(const Instruction& in, const std::string& why = {}) {
  std::string text;
  try {
    text = print(in);
  } catch (...) {
    text = mnemonic_name(in.mnemonic, in.cond);
  }
  throw AsmError("invalid operands for '" + text + "'" + (why.empty() ? "" : ": " + why));
}

// A request for a fixup (at most one per instruction).
struct FixReq {
  bool present = false;
  uint16_t kind = 0;
  const Operand* op = nullptr;  // Label or Address
};

bool reg_any(const Operand& o) { return o.kind == OperandKind::Reg && unsigned(o.reg) < kNumRegs; }
bool reg_ext(const Operand& o) { return o.kind == OperandKind::Reg && is_extended(o.reg); }

bool ind_valid(const Ind& i) {
  if (i.ar > 7 || i.mod > kBitRev) return false;
  if (i.mod < kIr0) return i.disp >= 1;
  return i.disp == 0;
}

// 16-bit indirect field of the general forms: mod 15-11, ARn 10-8, disp 7-0.
uint32_t long_ind(const Ind& i) { return uint32_t(i.mod) << 11 | uint32_t(i.ar) << 8 | i.disp; }
// 8-bit C3x-style 3-operand field: mod 7-3, ARn 2-0 (displacement 1 implied).
bool short_ind_ok(const Ind& i) {
  return ind_valid(i) && (i.mod >= kIr0 || i.disp == 1);
}
uint32_t short_ind(const Ind& i) { return uint32_t(i.mod) << 3 | i.ar; }
// 8-bit C4x 3-operand field: *+ARn(disp), disp 7-3 (0-31), ARn 2-0.
bool c4x_ind_ok(const Ind& i) {
  return ind_valid(i) && (i.mod == kPlain || (i.mod == kPreAdd && i.disp <= 31));
}
uint32_t c4x_ind(const Ind& i) { return uint32_t(i.mod == kPlain ? 0 : i.disp) << 3 | i.ar; }

// The general source: mode bits 22-21 and field 15-0.
bool encode_src(const Operand& o, Cls cls, uint32_t& word) {
  ImmKind ik = imm_kind(cls);
  bool ext_only = cls == Cls::AF || cls == Cls::B || cls == Cls::BB;
  switch (o.kind) {
    case OperandKind::Reg:
      if (cls == Cls::B6) return false;
      if (ext_only ? !reg_ext(o) : !reg_any(o)) return false;
      word |= 0u << 21 | uint32_t(o.reg);
      return true;
    case OperandKind::Direct:
      if (o.imm < 0 || o.imm > 0xFFFF) return false;
      word |= 1u << 21 | uint32_t(o.imm);
      return true;
    case OperandKind::Ind:
      if (!ind_valid(o.ind)) return false;
      word |= 2u << 21 | long_ind(o.ind);
      return true;
    case OperandKind::Imm:
      if (ik == ImmKind::S16 && o.imm >= -32768 && o.imm <= 32767) {
        word |= 3u << 21 | (uint32_t(o.imm) & 0xFFFF);
        return true;
      }
      if (ik == ImmKind::U16 && o.imm >= 0 && o.imm <= 0xFFFF) {
        word |= 3u << 21 | uint32_t(o.imm);
        return true;
      }
      return false;
    case OperandKind::Float:
      if (ik != ImmKind::F16 || o.imm < 0 || o.imm > 0xFFFF) return false;
      if ((o.imm >> 12) == 8 && o.imm != 0x8000) return false;  // zero is only 0x8000
      word |= 3u << 21 | uint32_t(o.imm);
      return true;
    default:
      return false;
  }
}

bool is_target(const Operand& o) {
  return o.kind == OperandKind::Label || o.kind == OperandKind::Address;
}

uint32_t encode3(const Instruction& in, const Spec& s, uint8_t nops) {
  bool flt = s.cls == Cls::S || s.cls == Cls::S2;
  bool has_dst = s.cls == Cls::T || s.cls == Cls::S;
  if (in.num_operands != nops) bad(in);
  const Operand& src2 = in.ops[0];
  const Operand& src1 = in.ops[1];
  uint32_t dst = 0;
  if (has_dst) {
    const Operand& d = in.ops[2];
    if (flt ? !reg_ext(d) : !reg_any(d)) bad(in);
    dst = uint32_t(d.reg);
  }
  auto reg_ok = [&](const Operand& o) { return flt ? reg_ext(o) : reg_any(o); };
  uint32_t opc = s.base | dst << 16;
  // Type 1 (bit 28 = 0): registers and C3x-style indirect operands.
  {
    bool ok2 = reg_ok(src2) || (src2.kind == OperandKind::Ind && short_ind_ok(src2.ind));
    bool ok1 = reg_ok(src1) || (src1.kind == OperandKind::Ind && short_ind_ok(src1.ind));
    if (ok2 && ok1) {
      uint32_t t = (src1.kind == OperandKind::Ind ? 1u : 0u) | (src2.kind == OperandKind::Ind ? 2u : 0u);
      uint32_t f2 = src2.kind == OperandKind::Ind ? short_ind(src2.ind) : uint32_t(src2.reg);
      uint32_t f1 = src1.kind == OperandKind::Ind ? short_ind(src1.ind) : uint32_t(src1.reg);
      return 0x20000000u | opc | t << 21 | f1 << 8 | f2;
    }
  }
  // Type 2 (C4x, bit 28 = 1): 8-bit immediate or *+ARn(0-31).
  {
    bool imm2 = !flt && src2.kind == OperandKind::Imm && src2.imm >= -128 && src2.imm <= 127;
    bool ind2 = src2.kind == OperandKind::Ind && c4x_ind_ok(src2.ind);
    bool reg1 = reg_ok(src1);
    bool ind1 = src1.kind == OperandKind::Ind && c4x_ind_ok(src1.ind);
    if ((imm2 || ind2) && (reg1 || ind1)) {
      uint32_t t = (ind2 ? 1u : 0u) | (ind1 ? 2u : 0u);
      if (flt && !ind2) bad(in);
      uint32_t f2 = ind2 ? c4x_ind(src2.ind) : (uint32_t(src2.imm) & 0xFF);
      uint32_t f1 = ind1 ? c4x_ind(src1.ind) : uint32_t(src1.reg);
      return 0x30000000u | opc | t << 21 | f1 << 8 | f2;
    }
  }
  bad(in);
}

uint32_t encode_word(const Instruction& in, FixReq& fix) {
  if (size_t(in.mnemonic) >= size_t(Mnemonic::Count_)) throw AsmError("invalid mnemonic");
  const Spec& s = spec(in.mnemonic);
  if (has_cond(in.mnemonic) && !valid_cond(unsigned(in.cond))) bad(in, "invalid condition");
  const Operand& a = in.ops[0];
  const Operand& b = in.ops[1];
  uint32_t cond = uint32_t(in.cond);
  auto need = [&](uint8_t n) {
    if (in.num_operands != n) bad(in);
  };
  auto target = [&](uint16_t kind, const Operand& o) {
    if (!is_target(o)) bad(in);
    fix.present = true;
    fix.kind = kind;
    fix.op = &o;
  };
  switch (s.cls) {
    case Cls::A: case Cls::AU: case Cls::AF: case Cls::BI: case Cls::B: case Cls::BA:
    case Cls::B6: case Cls::AB: case Cls::BB: case Cls::AY: {
      need(2);
      uint32_t w = s.base;
      if (s.cls == Cls::AB || s.cls == Cls::BB) w |= cond << 23;
      if (!encode_src(a, s.cls, w)) bad(in);
      bool dst_ext = s.cls == Cls::BI || s.cls == Cls::B || s.cls == Cls::BA ||
                    s.cls == Cls::B6 || s.cls == Cls::BB;
      if (s.cls == Cls::AY) {
        if (b.kind != OperandKind::Reg || unsigned(b.reg) < 8 || unsigned(b.reg) > 20) bad(in);
      } else if (dst_ext ? !reg_ext(b) : !reg_any(b)) {
        bad(in);
      }
      return w | uint32_t(b.reg) << 16;
    }
    case Cls::A7: case Cls::B7: {
      need(2);
      if (s.cls == Cls::B7 ? !reg_ext(a) : !reg_any(a)) bad(in);
      uint32_t w = s.base | uint32_t(a.reg) << 16;
      if (b.kind == OperandKind::Direct && b.imm >= 0 && b.imm <= 0xFFFF) return w | 1u << 21 | uint32_t(b.imm);
      if (b.kind == OperandKind::Ind && ind_valid(b.ind)) return w | 2u << 21 | long_ind(b.ind);
      bad(in);
    }
    case Cls::Ldhi:
      need(2);
      if (a.kind != OperandKind::Imm || a.imm < 0 || a.imm > 0xFFFF || !reg_any(b)) bad(in);
      return s.base | uint32_t(b.reg) << 16 | uint32_t(a.imm);
    case Cls::Ldpk:
      need(1);
      if (a.kind != OperandKind::Imm || a.imm < 0 || a.imm > 0xFFFF) bad(in);
      return s.base | uint32_t(a.imm);
    case Cls::T: return encode3(in, s, 3);
    case Cls::S: return encode3(in, s, 3);
    case Cls::T2: case Cls::S2: return encode3(in, s, 2);
    case Cls::I:
      need(1);
      target(in.mnemonic == Mnemonic::Brd ? Disp24D : Disp24, a);
      return s.base;
    case Cls::J: case Cls::JS: {
      need(1);
      uint32_t w = s.base | cond << 16;
      if (reg_any(a)) return w | uint32_t(a.reg);
      target(in.mnemonic == Mnemonic::Bcd ? Disp16D : Disp16, a);
      return w | 0x02000000u;
    }
    case Cls::Rets:
      need(0);
      return s.base | cond << 16;
    case Cls::D:
      need(2);
      if (a.kind != OperandKind::Reg || !is_aux(a.reg)) bad(in);
      target(in.mnemonic == Mnemonic::Dbcd ? Disp16D : Disp16, b);
      return s.base | 0x02000000u | (uint32_t(a.reg) - 8) << 22 | cond << 16;
    case Cls::R: case Cls::RF:
      need(1);
      if (s.cls == Cls::RF ? !reg_ext(a) : !reg_any(a)) bad(in);
      return s.base | uint32_t(a.reg) << 16;
    case Cls::Nop:
      if (in.num_operands == 0) return s.base;
      need(1);
      if (a.kind != OperandKind::Ind || !ind_valid(a.ind)) bad(in);
      return s.base | 2u << 21 | long_ind(a.ind);
    case Cls::Word:
      need(1);
      if (a.kind == OperandKind::Imm && a.imm >= -(int64_t(1) << 31) && a.imm <= 0xFFFFFFFFll)
        return uint32_t(a.imm);
      target(Abs32, a);
      return 0;
  }
  bad(in);
}

void encode_hook(const Instruction& in, bool long_form, Encoding& out) { out = encode(in, long_form); }

}  // namespace

const Target<Instruction>& target() {
  static const Target<Instruction> t = [] {
    Target<Instruction> x;
    x.name = "c40";
    x.fixup_kinds = kKinds;
    x.encode = &encode_hook;
    return x;
  }();
  return t;
}

Encoding encode(const Instruction& in, bool) {
  FixReq fix;
  uint32_t w = encode_word(in, fix);
  Encoding e;
  e.put32(w);
  if (fix.present) {
    Fixup f;
    f.offset = 0;
    f.kind = fix.kind;
    if (fix.op->kind == OperandKind::Label) {
      f.label = fix.op->label;
    } else {
      f.addend = fix.op->imm * 4;  // word address -> byte offset
    }
    e.add_fixup(f);
  }
  return e;
}

uint32_t encode_at(const Instruction& in, int64_t address) {
  FixReq fix;
  uint32_t w = encode_word(in, fix);
  if (!fix.present) return w;
  if (fix.op->kind == OperandKind::Label)
    throw AsmError("label '" + fix.op->label + "' needs the assembler core");
  const FixupKind& k = kKinds[fix.kind];
  int64_t v = 0;
  fixup_value(k, fix.op->imm * 4, 0, address * 4, 4, v);
  if (!fixup_fits(k, v)) throw AsmError("target " + std::to_string(fix.op->imm) + " out of range for " + std::string(k.name));
  uint8_t bytes[4] = {uint8_t(w), uint8_t(w >> 8), uint8_t(w >> 16), uint8_t(w >> 24)};
  apply_fixup(k, bytes, 0, v);
  return uint32_t(bytes[0]) | uint32_t(bytes[1]) << 8 | uint32_t(bytes[2]) << 16 |
         uint32_t(bytes[3]) << 24;
}

// ------------------------------------------------------------- decoding

namespace {

std::string hex32(uint32_t w) {
  char buf[16];
  std::snprintf(buf, sizeof buf, "0x%08x", w);
  return buf;
}

int64_t sext(uint32_t v, unsigned bits) {
  uint32_t m = 1u << (bits - 1);
  return int64_t(int32_t((v & ((m << 1) - 1)) ^ m)) - int64_t(int32_t(m));
}

Ind ind_from_long(uint32_t f) { return Ind{uint8_t(f >> 11 & 0x1F), uint8_t(f >> 8 & 7), uint8_t(f & 0xFF)}; }
Ind ind_from_short(uint32_t f) {
  uint8_t mod = uint8_t(f >> 3 & 0x1F);
  return Ind{mod, uint8_t(f & 7), uint8_t(mod < kIr0 ? 1 : 0)};
}
Ind ind_from_c4x(uint32_t f) {
  uint8_t d = uint8_t(f >> 3 & 0x1F);
  return d == 0 ? Ind{kPlain, uint8_t(f & 7), 0} : Ind{kPreAdd, uint8_t(f & 7), d};
}

Operand reg_op(uint32_t n) {
  if (n >= kNumRegs) throw AsmError("register number " + std::to_string(n));
  return Operand::r(Reg(n));
}

Operand src_op(uint32_t w, Cls cls) {
  uint32_t f = w & 0xFFFF;
  switch (w >> 21 & 3) {
    case 0: return reg_op(f);
    case 1: return Operand::d(uint16_t(f));
    case 2: return Operand::m(ind_from_long(f));
    default:
      switch (imm_kind(cls)) {
        case ImmKind::S16: return Operand::i(sext(f, 16));
        case ImmKind::U16: return Operand::i(f);
        case ImmKind::F16: return Operand::f(uint16_t(f));
        default: throw AsmError("no immediate form");
      }
  }
}

// Builds the candidate instruction for `word` under mnemonic m (whose class
// matched); throws AsmError if the fields are not valid.
Instruction candidate(Mnemonic m, uint32_t w, int64_t address) {
  const Spec& s = spec(m);
  Instruction in;
  in.mnemonic = m;
  auto set = [&](std::initializer_list<Operand> ops) {
    in.num_operands = 0;
    for (const Operand& o : ops) in.ops[in.num_operands++] = o;
  };
  uint32_t cond = w >> 16 & 0x1F;
  switch (s.cls) {
    case Cls::A: case Cls::AU: case Cls::AF: case Cls::BI: case Cls::B: case Cls::BA:
    case Cls::B6: case Cls::AY:
      set({src_op(w, s.cls), reg_op(w >> 16 & 0x1F)});
      break;
    case Cls::AB: case Cls::BB:
      in.cond = Cond(w >> 23 & 0x1F);
      set({src_op(w, s.cls), reg_op(w >> 16 & 0x1F)});
      break;
    case Cls::A7: case Cls::B7:
      if ((w >> 21 & 3) == 1) set({reg_op(w >> 16 & 0x1F), Operand::d(uint16_t(w))});
      else set({reg_op(w >> 16 & 0x1F), Operand::m(ind_from_long(w & 0xFFFF))});
      break;
    case Cls::Ldhi: set({Operand::i(w & 0xFFFF), reg_op(w >> 16 & 0x1F)}); break;
    case Cls::Ldpk: set({Operand::i(w & 0xFFFF)}); break;
    case Cls::T: case Cls::T2: case Cls::S: case Cls::S2: {
      bool type2 = (w >> 28 & 1) != 0;
      uint32_t t = w >> 21 & 3;
      uint32_t f2 = w & 0xFF, f1 = w >> 8 & 0xFF;
      Operand o2, o1;
      if (!type2) {
        o2 = (t & 2) ? Operand::m(ind_from_short(f2)) : reg_op(f2);
        o1 = (t & 1) ? Operand::m(ind_from_short(f1)) : reg_op(f1);
      } else {
        o2 = (t & 1) ? Operand::m(ind_from_c4x(f2)) : Operand::i(sext(f2, 8));
        o1 = (t & 2) ? Operand::m(ind_from_c4x(f1)) : reg_op(f1);
      }
      if (s.cls == Cls::T || s.cls == Cls::S) set({o2, o1, reg_op(w >> 16 & 0x1F)});
      else set({o2, o1});
      break;
    }
    case Cls::I: {
      int64_t bias = m == Mnemonic::Brd ? 3 : 1;
      set({Operand::a(address + bias + sext(w & 0xFFFFFF, 24))});
      break;
    }
    case Cls::J: case Cls::JS:
      in.cond = Cond(cond);
      if (w & 0x02000000) {
        int64_t bias = m == Mnemonic::Bcd ? 3 : 1;
        set({Operand::a(address + bias + sext(w & 0xFFFF, 16))});
      } else {
        set({reg_op(w & 0xFFFF)});
      }
      break;
    case Cls::Rets: in.cond = Cond(cond); set({}); break;
    case Cls::D: {
      in.cond = Cond(cond);
      if (!(w & 0x02000000)) throw AsmError("DBcond with a register target is not in the subset");
      int64_t bias = m == Mnemonic::Dbcd ? 3 : 1;
      set({Operand::r(ar(w >> 22 & 7)), Operand::a(address + bias + sext(w & 0xFFFF, 16))});
      break;
    }
    case Cls::R: case Cls::RF: set({reg_op(w >> 16 & 0x1F)}); break;
    case Cls::Nop:
      if ((w >> 21 & 3) == 2) set({Operand::m(ind_from_long(w & 0xFFFF))});
      else set({});
      break;
    case Cls::Word: throw AsmError("data");
  }
  return in;
}

// Which mnemonic a word belongs to, from its opcode bits.
std::optional<Mnemonic> classify(uint32_t w) {
  uint32_t top = w >> 24;
  if (top == 0x60) return Mnemonic::Br;
  if (top == 0x61) return Mnemonic::Brd;
  if (top == 0x62) return Mnemonic::Call;
  uint32_t op11 = w & 0xffe00000;  // opcode and the type bits of the 3-operand forms
  switch (op11 & 0xfc000000) {
    case 0x68000000:  // Bcond reg/rel, BcondD
      if ((w & 0xfde00000) == 0x68000000) return Mnemonic::Bc;
      if ((w & 0xfde00000) == 0x68200000) return Mnemonic::Bcd;
      return std::nullopt;
    case 0x6c000000:  // DBcond
      return (w & 0x00200000) ? Mnemonic::Dbcd : Mnemonic::Dbc;
    case 0x70000000:
      if ((w & 0xfde00000) == 0x70000000) return Mnemonic::Callc;
      return std::nullopt;
    case 0x78000000:
      if ((w & 0xffe00000) == 0x78800000) return Mnemonic::Retsc;
      return std::nullopt;
    default: break;
  }
  if ((w & 0xf0000000) == 0x50000000) return Mnemonic::Ldic;
  if ((w & 0xf0000000) == 0x40000000) return Mnemonic::Ldfc;
  if ((w & 0xe0000000) == 0x20000000) {  // 3-operand
    uint32_t base = w & 0x0f800000;
    for (size_t i = size_t(Mnemonic::Addi3); i <= size_t(Mnemonic::Subf3); ++i)
      if (spec(Mnemonic(i)).base == base) return Mnemonic(i);
    return std::nullopt;
  }
  if ((w & 0xe0000000) != 0) return std::nullopt;
  uint32_t base = w & 0xff800000;
  if ((w & 0xffe00000) == 0x1fe00000) return Mnemonic::Ldhi;
  if ((w & 0xffff0000) == 0x1f700000) return Mnemonic::Ldpk;
  for (size_t i = 0; i < size_t(Mnemonic::Count_); ++i) {
    Mnemonic m = Mnemonic(i);
    const Spec& s = spec(m);
    switch (s.cls) {
      case Cls::A: case Cls::AU: case Cls::AF: case Cls::BI: case Cls::B: case Cls::BA:
      case Cls::B6: case Cls::AY:
        if (s.base == base) return m;
        break;
      case Cls::A7: case Cls::B7:
        if (s.base == base) return m;
        break;
      case Cls::R: case Cls::RF:
        if ((w & 0xffe0ffff) == s.base) return m;
        break;
      case Cls::Nop:
        if (s.base == base) return m;
        break;
      default: break;
    }
  }
  return std::nullopt;
}

}  // namespace

std::optional<Instruction> decode_word(uint32_t w, int64_t address, DecodeError* error) {
  auto fail = [&](const std::string& why) -> std::optional<Instruction> {
    if (error) *error = DecodeError{address, hex32(w) + ": " + why};
    return std::nullopt;
  };
  auto m = classify(w);
  if (!m) return fail("not an instruction of the C40 subset");
  Instruction in;
  try {
    in = candidate(*m, w, address);
  } catch (const AsmError& e) {
    return fail(std::string(e.what()));
  }
  // Accept only what the encoder produces.
  uint32_t again = 0;
  try {
    again = encode_at(in, address);
  } catch (const AsmError& e) {
    return fail("not in the subset (" + std::string(e.what()) + ")");
  }
  if (again != w) return fail("alternate encoding of '" + print(in) + "' (" + hex32(again) + ")");
  return in;
}

Disassembly disassemble(std::span<const uint32_t> words, int64_t base) {
  Disassembly d;
  for (size_t i = 0; i < words.size(); ++i) {
    DecodeError e;
    int64_t addr = base + int64_t(i);
    if (auto in = decode_word(words[i], addr, &e)) d.insts.push_back({*in, addr, words[i]});
    else d.errors.push_back(e);
  }
  return d;
}

std::vector<uint32_t> words_of(std::span<const uint8_t> code) {
  std::vector<uint32_t> w(code.size() / 4);
  for (size_t i = 0; i < w.size(); ++i)
    w[i] = uint32_t(code[4 * i]) | uint32_t(code[4 * i + 1]) << 8 |
           uint32_t(code[4 * i + 2]) << 16 | uint32_t(code[4 * i + 3]) << 24;
  return w;
}

Disassembly disassemble_bytes(std::span<const uint8_t> code, int64_t base) {
  Disassembly d = disassemble(words_of(code), base);
  if (code.size() % 4)
    d.errors.push_back({base + int64_t(code.size() / 4),
                        "truncated word (" + std::to_string(code.size() % 4) + " bytes)"});
  return d;
}

}  // namespace ldc::as::c40
