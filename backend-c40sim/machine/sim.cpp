// The C40 instruction-set simulator. Semantics: TMS320C4x User's Guide
// (instruction descriptions, condition codes, data formats, pipeline); see
// docs/c40.md for what is modelled and how.
#include "backend-c40sim/machine/sim.h"

#include <bit>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

namespace ldc::c40sim {

using namespace as::c40;
using i128 = __int128;

// ============================================================ simulator

namespace {

constexpr uint32_t kC = 0x01, kV = 0x02, kZ = 0x04, kN = 0x08, kUF = 0x10, kLV = 0x20, kLUF = 0x40;

int ext_index(Reg r) {
  unsigned n = unsigned(r);
  if (n <= 7) return int(n);
  if (n >= 28 && n <= 31) return int(n - 20);
  return -1;
}

std::string hex(uint64_t v) {
  char buf[24];
  std::snprintf(buf, sizeof buf, "0x%08llx", static_cast<unsigned long long>(v));
  return buf;
}

// Register groups of the pipeline's address-register conflicts.
enum Group { kGroupAux = 0, kGroupDp = 1, kGroupSp = 2, kNoGroup = 3 };
Group group_of(Reg r) {
  unsigned n = unsigned(r);
  if ((n >= 8 && n <= 15) || r == Reg::IR0 || r == Reg::IR1 || r == Reg::BK) return kGroupAux;
  if (r == Reg::DP) return kGroupDp;
  if (r == Reg::SP) return kGroupSp;
  return kNoGroup;
}

struct SimError {
  Stop stop;
  std::string message;
};

bool cond_true(Cond c, uint32_t st) {
  bool C = st & kC, V = st & kV, Z = st & kZ, N = st & kN, UF = st & kUF, LV = st & kLV,
       LUF = st & kLUF;
  switch (c) {
    case Cond::U: return true;
    case Cond::LO: return C;
    case Cond::LS: return C || Z;
    case Cond::HI: return !C && !Z;
    case Cond::HS: return !C;
    case Cond::EQ: return Z;
    case Cond::NE: return !Z;
    case Cond::LT: return N;
    case Cond::LE: return N || Z;
    case Cond::GT: return !N && !Z;
    case Cond::GE: return !N;
    case Cond::NV: return !V;
    case Cond::V: return V;
    case Cond::NUF: return !UF;
    case Cond::UF: return UF;
    case Cond::NLV: return !LV;
    case Cond::LV: return LV;
    case Cond::NLUF: return !LUF;
    case Cond::LUF: return LUF;
    case Cond::ZUF: return Z || UF;
  }
  return false;
}

int32_t sext(uint32_t v, unsigned bits) {
  uint32_t m = 1u << (bits - 1);
  return int32_t((v & ((m << 1) - 1)) ^ m) - int32_t(m);
}

}  // namespace

std::string_view stop_name(Stop s) {
  switch (s) {
    case Stop::Returned: return "returned";
    case Stop::CycleLimit: return "cycle limit";
    case Stop::InstructionLimit: return "instruction limit";
    case Stop::MemoryFault: return "memory fault";
    case Stop::IllegalInstruction: return "illegal instruction";
    case Stop::Unsupported: return "unsupported";
  }
  return "?";
}

C40Sim::C40Sim(Config config) : cfg_(std::move(config)), cache_(cfg_.regions.size()) {
  for (const Region& r : cfg_.regions) mem_.emplace_back(r.size, 0u);
  for (Ext& e : ext_) e = Ext{0, 0};
}

size_t C40Sim::region_index(uint32_t a) const {
  for (size_t i = 0; i < cfg_.regions.size(); i++)
    if (a >= cfg_.regions[i].base && uint64_t(a) - cfg_.regions[i].base < cfg_.regions[i].size) return i;
  return SIZE_MAX;
}
Region* C40Sim::region(uint32_t a) {
  size_t i = region_index(a);
  return i == SIZE_MAX ? nullptr : &cfg_.regions[i];
}
const Region* C40Sim::region(uint32_t a) const {
  size_t i = region_index(a);
  return i == SIZE_MAX ? nullptr : &cfg_.regions[i];
}

void C40Sim::load(std::span<const uint32_t> words, uint32_t base) {
  for (size_t i = 0; i < words.size(); ++i) write(uint32_t(base + i), words[i]);
}

void C40Sim::write(uint32_t a, uint32_t v) {
  const Region* r = region(a);
  if (!r) throw std::out_of_range("no memory at " + hex(a));
  mem_[size_t(r - cfg_.regions.data())][a - r->base] = v;
}

uint32_t C40Sim::read(uint32_t a) const {
  const Region* r = region(a);
  if (!r) throw std::out_of_range("no memory at " + hex(a));
  return mem_[size_t(r - cfg_.regions.data())][a - r->base];
}

void C40Sim::set_reg(Reg r, uint32_t v) {
  int x = ext_index(r);
  if (x >= 0) ext_[x].man = v;
  else r32_[unsigned(r)] = v;
}
uint32_t C40Sim::reg(Reg r) const {
  int x = ext_index(r);
  return x >= 0 ? ext_[x].man : r32_[unsigned(r)];
}
void C40Sim::set_ext(Reg r, Ext v) {
  int x = ext_index(r);
  if (x < 0) throw std::invalid_argument("not an extended-precision register");
  ext_[x] = v;
}
Ext C40Sim::ext(Reg r) const {
  int x = ext_index(r);
  if (x < 0) throw std::invalid_argument("not an extended-precision register");
  return ext_[x];
}

uint32_t C40Sim::mem_read(uint32_t a) {
  Region* r = region(a);
  if (!r) throw SimError{Stop::MemoryFault, "read of " + hex(a) + " outside memory"};
  waits_ += r->wait_states;
  return mem_[size_t(r - cfg_.regions.data())][a - r->base];
}

void C40Sim::mem_write(uint32_t a, uint32_t v) {
  Region* r = region(a);
  if (!r) throw SimError{Stop::MemoryFault, "write of " + hex(a) + " outside memory"};
  if (!r->writable) throw SimError{Stop::MemoryFault, "write of " + hex(a) + " into the read-only region '" + r->name + "'"};
  waits_ += r->wait_states;
  mem_[size_t(r - cfg_.regions.data())][a - r->base] = v;
}

const C40Sim::Cached& C40Sim::fetch(uint32_t pc) {
  size_t ri = region_index(pc);
  if (ri == SIZE_MAX) throw SimError{Stop::MemoryFault, "fetch of " + hex(pc) + " outside memory"};
  const Region& r = cfg_.regions[ri];
  if (!r.executable)
    throw SimError{Stop::MemoryFault, "fetch of " + hex(pc) + " outside the code (region '" + r.name + "' is not executable)"};
  waits_ += r.wait_states;
  uint32_t w = mem_[ri][pc - r.base];
  std::vector<Cached>& cache = cache_[ri];
  if (cache.empty()) cache.resize(std::bit_ceil(std::min(r.size, kCacheWords)));
  Cached& c = cache[(pc - r.base) & (cache.size() - 1)];
  if (!c.valid || c.pc != pc || c.word != w) {
    auto in = decode_word(w, pc);
    c.pc = pc, c.word = w, c.valid = true, c.ok = bool(in);
    if (in) c.inst = *in;
  }
  return c;
}

namespace {

// Per-instruction operand access, flags and semantics.
class Exec {
 public:
  Exec(uint32_t* r32, Ext* ext, std::function<uint32_t(uint32_t)> rd,
       std::function<void(uint32_t, uint32_t)> wr)
      : r32_(r32), ext_(ext), rd_(std::move(rd)), wr_(std::move(wr)) {}

  uint32_t& st() { return r32_[unsigned(Reg::ST)]; }

  uint32_t ireg(Reg r) const {
    int x = ext_index(r);
    return x >= 0 ? ext_[x].man : r32_[unsigned(r)];
  }
  void set_ireg(Reg r, uint32_t v) {
    int x = ext_index(r);
    if (x >= 0) ext_[x].man = v;
    else r32_[unsigned(r)] = v;
  }
  Ext freg(Reg r) const {
    int x = ext_index(r);
    return x >= 0 ? ext_[x] : fp::from_single(r32_[unsigned(r)]);
  }
  void set_freg(Reg r, Ext v) {
    int x = ext_index(r);
    if (x >= 0) ext_[x] = v;
    else r32_[unsigned(r)] = fp::to_single(v);
  }

  // Effective address of an indirect operand; applies the AR update.
  uint32_t ea(const Ind& i) {
    uint32_t& a = r32_[8 + i.ar];
    if (i.mod == kPlain) return a;
    if (i.mod == kBitRev) throw SimError{Stop::Unsupported, "bit-reversed addressing is not modelled"};
    uint32_t d = i.mod >= kIr1 ? r32_[unsigned(Reg::IR1)] : i.mod >= kIr0 ? r32_[unsigned(Reg::IR0)] : i.disp;
    switch (i.mod & 7) {
      case kPreAdd: return a + d;
      case kPreSub: return a - d;
      case kPreAddMod: a += d; return a;
      case kPreSubMod: a -= d; return a;
      case kPostAdd: { uint32_t x = a; a += d; return x; }
      case kPostSub: { uint32_t x = a; a -= d; return x; }
      default: throw SimError{Stop::Unsupported, "circular addressing is not modelled"};
    }
  }
  uint32_t direct(int64_t off) { return (r32_[unsigned(Reg::DP)] & 0xFFFF) << 16 | uint32_t(off); }
  uint32_t addr_of(const Operand& o) { return o.kind == OperandKind::Direct ? direct(o.imm) : ea(o.ind); }

  uint32_t ival(const Operand& o) {
    switch (o.kind) {
      case OperandKind::Reg: return ireg(o.reg);
      case OperandKind::Imm: return uint32_t(int32_t(o.imm));
      case OperandKind::Direct: case OperandKind::Ind: return rd_(addr_of(o));
      default: throw SimError{Stop::Unsupported, "operand"};
    }
  }
  Ext fval(const Operand& o) {
    switch (o.kind) {
      case OperandKind::Reg: return freg(o.reg);
      case OperandKind::Float: return fp::from_short(uint16_t(o.imm));
      case OperandKind::Direct: case OperandKind::Ind: return fp::from_single(rd_(addr_of(o)));
      default: throw SimError{Stop::Unsupported, "operand"};
    }
  }

  // Flags are set when the destination is R0-R11 (SET COND = 0) or always
  // for compares (dst == nullptr).
  void flags(const Reg* dst, uint32_t set, uint32_t mask) {
    if (dst && ext_index(*dst) < 0) return;
    uint32_t& s = st();
    s = (s & ~mask) | (set & mask);
    if (set & kV) s |= kLV;
    if (set & kUF) s |= kLUF;
  }
  void int_flags(const Reg* dst, uint32_t res, bool n, bool v, bool c, bool set_c) {
    uint32_t f = (n ? kN : 0) | (res == 0 ? kZ : 0) | (v ? kV : 0) | (c ? kC : 0);
    flags(dst, f, kN | kZ | kV | kUF | (set_c ? kC : 0));
  }
  void logic_flags(const Reg* dst, uint32_t res) { int_flags(dst, res, res >> 31, false, false, false); }
  void float_flags(const Reg* dst, const fp::Res& r) {
    uint32_t f = (fp::is_negative(r.v) ? kN : 0) | (fp::is_zero(r.v) ? kZ : 0) |
                 (r.overflow ? kV : 0) | (r.underflow ? kUF : 0);
    flags(dst, f, kN | kZ | kV | kUF);
  }

  uint32_t rd(uint32_t a) { return rd_(a); }
  void wr(uint32_t a, uint32_t v) { wr_(a, v); }

 private:
  uint32_t* r32_;
  Ext* ext_;
  std::function<uint32_t(uint32_t)> rd_;
  std::function<void(uint32_t, uint32_t)> wr_;
};

uint32_t shift_l(uint32_t v, int32_t count, bool arith, bool* carry) {
  *carry = false;
  if (count > 0) {
    if (count <= 32) *carry = (uint64_t(v) << count) >> 32 & 1;
    return count >= 32 ? 0 : v << count;
  }
  if (count < 0) {
    int n = -count;
    if (arith) {
      int32_t s = int32_t(v);
      *carry = n <= 32 ? (int64_t(s) >> (n - 1)) & 1 : s < 0;
      return uint32_t(n >= 32 ? (s < 0 ? -1 : 0) : s >> n);
    }
    *carry = n <= 32 ? (uint64_t(v) >> (n - 1)) & 1 : false;
    return n >= 32 ? 0 : v >> n;
  }
  return v;
}

// One instruction's execution (C40Sim::execute): its operands, the register
// groups it uses and writes, the flag-setting operations, and one member
// function per instruction group; a group's function returns false for an
// instruction not of its group.  A control transfer is left in taken/target.
class Step {
 public:
  using M = Mnemonic;
  Step(Exec& x, uint32_t* r32, const Instruction& in, uint32_t pc, bool& taken, uint32_t& target)
      : x(x), r32_(r32), in(in), pc(pc), a(in.ops[0]), b(in.ops[1]), c(in.ops[2]), taken_(taken), target_(target) {
    for (unsigned i = 0; i < in.num_operands; ++i) {
      if (in.ops[i].kind == OperandKind::Ind) uses |= 1u << kGroupAux;
      if (in.ops[i].kind == OperandKind::Direct) uses |= 1u << kGroupDp;
    }
  }

  unsigned uses = 0, writes = 0;

  bool integer();
  bool integer3();
  bool floating();
  bool float3();
  bool conversion();
  bool load_store();
  bool stack();
  bool control();

 private:
  Exec& x;
  uint32_t* r32_;
  const Instruction& in;
  uint32_t pc;
  const Operand &a, &b, &c;
  bool& taken_;
  uint32_t& target_;

  void wrote(Reg r) {
    Group g = group_of(r);
    if (g != kNoGroup) writes |= 1u << g;
  }
  void set_i(Reg r, uint32_t v) {
    x.set_ireg(r, v);
    wrote(r);
  }
  void set_f(Reg r, Ext v) {
    x.set_freg(r, v);
    wrote(r);
  }
  void branch(uint32_t t) {
    taken_ = true;
    target_ = t;
  }
  uint32_t target_of(const Operand& o) { return o.kind == OperandKind::Reg ? x.ireg(o.reg) : uint32_t(o.imm); }
  void push(uint32_t v) {
    uint32_t& sp = r32_[unsigned(Reg::SP)];
    sp += 1;
    x.wr(sp, v);
  }
  uint32_t pop() {
    uint32_t& sp = r32_[unsigned(Reg::SP)];
    uint32_t v = x.rd(sp);
    sp -= 1;
    return v;
  }
  // Integer arithmetic on int64 for the flags (N from the exact result).
  void arith(const Reg* dst, int64_t exact, uint32_t out, bool carry, bool set_c) {
    bool v = exact < INT32_MIN || exact > INT32_MAX;
    x.int_flags(dst, out, exact < 0, v, carry, set_c);
  }
  uint32_t add_op(const Reg* dst, uint32_t p, uint32_t q) {
    uint32_t out = p + q;
    arith(dst, int64_t(int32_t(p)) + int32_t(q), out, (uint64_t(p) + q) >> 32, true);
    return out;
  }
  uint32_t sub_op(const Reg* dst, uint32_t p, uint32_t q) {  // p - q
    uint32_t out = p - q;
    arith(dst, int64_t(int32_t(p)) - int32_t(q), out, p < q, true);
    return out;
  }
  uint32_t mpy_op(const Reg* dst, uint32_t p, uint32_t q) {  // 24 x 24 bits
    int64_t prod = int64_t(sext(p, 24)) * sext(q, 24);
    uint32_t out = uint32_t(uint64_t(prod));
    arith(dst, prod, out, false, false);
    return out;
  }
  uint32_t shift_op(const Reg* dst, uint32_t v, uint32_t count, bool ar) {
    bool carry = false;
    uint32_t out = shift_l(v, sext(count & 0x7F, 7), ar, &carry);
    x.int_flags(dst, out, out >> 31, false, carry, true);
    return out;
  }
  uint32_t logic(const Reg* dst, uint32_t out) {
    x.logic_flags(dst, out);
    return out;
  }
  Ext fres(const Reg* dst, const fp::Res& r) {
    x.float_flags(dst, r);
    return r.v;
  }
  void fcmp(Ext p, Ext q) {  // flags of p - q
    fp::Res r = fp::sub(p, q);
    int s = fp::compare(p, q);
    uint32_t f = (s < 0 ? kN : 0) | (s == 0 ? kZ : 0) | (r.overflow ? kV : 0) | (r.underflow ? kUF : 0);
    x.flags(nullptr, f, kN | kZ | kV | kUF);
  }
  // LDIc/LDFc whose condition is false: only the address update happens.
  bool skipped_load(M conditional) {
    if (in.mnemonic != conditional || cond_true(in.cond, x.st())) return false;
    if (a.kind == OperandKind::Ind) x.ea(a.ind);
    return true;
  }
  void load_i(Reg r, uint32_t v) {
    set_i(r, v);
    x.int_flags(&r, v, v >> 31, false, false, false);
  }
};

// LDI, ABSI, NEGI and the two-operand integer and logic instructions.
bool Step::integer() {
  switch (in.mnemonic) {
    case M::Ldi: case M::Ldic:
      if (!skipped_load(M::Ldic)) load_i(b.reg, x.ival(a));
      return true;
    case M::Absi: {
      int32_t s = int32_t(x.ival(a));
      uint32_t out = s < 0 ? uint32_t(0) - uint32_t(s) : uint32_t(s);
      set_i(b.reg, out);
      arith(&b.reg, s < 0 ? -int64_t(s) : s, out, false, false);
      return true;
    }
    case M::Negi: { uint32_t s = x.ival(a); set_i(b.reg, sub_op(&b.reg, 0, s)); return true; }
    case M::Addi: { uint32_t s = x.ival(a); set_i(b.reg, add_op(&b.reg, x.ireg(b.reg), s)); return true; }
    case M::Subi: { uint32_t s = x.ival(a); set_i(b.reg, sub_op(&b.reg, x.ireg(b.reg), s)); return true; }
    case M::Cmpi: { uint32_t s = x.ival(a); sub_op(nullptr, x.ireg(b.reg), s); return true; }
    case M::Mpyi: { uint32_t s = x.ival(a); set_i(b.reg, mpy_op(&b.reg, x.ireg(b.reg), s)); return true; }
    case M::And: { uint32_t s = x.ival(a); set_i(b.reg, logic(&b.reg, x.ireg(b.reg) & s)); return true; }
    case M::Andn: { uint32_t s = x.ival(a); set_i(b.reg, logic(&b.reg, x.ireg(b.reg) & ~s)); return true; }
    case M::Or: { uint32_t s = x.ival(a); set_i(b.reg, logic(&b.reg, x.ireg(b.reg) | s)); return true; }
    case M::Xor: { uint32_t s = x.ival(a); set_i(b.reg, logic(&b.reg, x.ireg(b.reg) ^ s)); return true; }
    case M::Not: { uint32_t s = x.ival(a); set_i(b.reg, logic(&b.reg, ~s)); return true; }
    case M::Tstb: { uint32_t s = x.ival(a); logic(nullptr, x.ireg(b.reg) & s); return true; }
    case M::Lsh: { uint32_t s = x.ival(a); set_i(b.reg, shift_op(&b.reg, x.ireg(b.reg), s, false)); return true; }
    case M::Ash: { uint32_t s = x.ival(a); set_i(b.reg, shift_op(&b.reg, x.ireg(b.reg), s, true)); return true; }
    default: return false;
  }
}

// The three-operand integer instructions: c = b OP a (CMPI3, TSTB3: flags only).
bool Step::integer3() {
  switch (in.mnemonic) {
    case M::Addi3: case M::Subi3: case M::Mpyi3: case M::And3: case M::Andn3: case M::Or3:
    case M::Xor3: case M::Lsh3: case M::Ash3: case M::Cmpi3: case M::Tstb3: break;
    default: return false;
  }
  uint32_t s2 = x.ival(a), s1 = x.ival(b);
  const Reg* d = (in.mnemonic == M::Cmpi3 || in.mnemonic == M::Tstb3) ? nullptr : &c.reg;
  uint32_t out = 0;
  switch (in.mnemonic) {
    case M::Addi3: out = add_op(d, s1, s2); break;
    case M::Subi3: case M::Cmpi3: out = sub_op(d, s1, s2); break;
    case M::Mpyi3: out = mpy_op(d, s1, s2); break;
    case M::And3: case M::Tstb3: out = logic(d, s1 & s2); break;
    case M::Andn3: out = logic(d, s1 & ~s2); break;
    case M::Or3: out = logic(d, s1 | s2); break;
    case M::Xor3: out = logic(d, s1 ^ s2); break;
    case M::Lsh3: out = shift_op(d, s1, s2, false); break;
    default: out = shift_op(d, s1, s2, true); break;
  }
  if (d) set_i(*d, out);
  return true;
}

// LDF and the two-operand floating-point instructions.
bool Step::floating() {
  switch (in.mnemonic) {
    case M::Ldf: case M::Ldfc:
      if (!skipped_load(M::Ldfc)) set_f(b.reg, fres(&b.reg, fp::Res{x.fval(a), false, false}));
      return true;
    case M::Absf: { Ext s = x.fval(a); set_f(b.reg, fres(&b.reg, fp::abs(s))); return true; }
    case M::Negf: { Ext s = x.fval(a); set_f(b.reg, fres(&b.reg, fp::neg(s))); return true; }
    case M::Addf: { Ext s = x.fval(a); set_f(b.reg, fres(&b.reg, fp::add(x.freg(b.reg), s))); return true; }
    case M::Subf: { Ext s = x.fval(a); set_f(b.reg, fres(&b.reg, fp::sub(x.freg(b.reg), s))); return true; }
    case M::Mpyf: { Ext s = x.fval(a); set_f(b.reg, fres(&b.reg, fp::mul(x.freg(b.reg), s))); return true; }
    case M::Cmpf: { Ext s = x.fval(a); fcmp(x.freg(b.reg), s); return true; }
    case M::Rcpf: {
      Ext s = a.kind == OperandKind::Reg ? x.freg(a.reg) : x.fval(a);
      set_f(b.reg, fres(&b.reg, fp::rcp(s)));
      return true;
    }
    default: return false;
  }
}

// The three-operand floating-point instructions: c = b OP a (CMPF3: flags only).
bool Step::float3() {
  if (in.mnemonic != M::Addf3 && in.mnemonic != M::Subf3 && in.mnemonic != M::Mpyf3 && in.mnemonic != M::Cmpf3)
    return false;
  Ext s2 = x.fval(a), s1 = x.fval(b);
  if (in.mnemonic == M::Cmpf3) {
    fcmp(s1, s2);
    return true;
  }
  fp::Res r = in.mnemonic == M::Addf3 ? fp::add(s1, s2) : in.mnemonic == M::Subf3 ? fp::sub(s1, s2) : fp::mul(s1, s2);
  set_f(c.reg, fres(&c.reg, r));
  return true;
}

// FIX, FLOAT and the IEEE conversions.
bool Step::conversion() {
  switch (in.mnemonic) {
    case M::Fix: {
      Ext s = x.fval(a);
      bool ov = false;
      uint32_t out = uint32_t(fp::fix(s, &ov));
      set_i(b.reg, out);
      x.int_flags(&b.reg, out, out >> 31, ov, false, false);
      return true;
    }
    case M::Float: { uint32_t s = x.ival(a); set_f(b.reg, fres(&b.reg, fp::from_int(int32_t(s)))); return true; }
    case M::Toieee: {
      uint32_t w = fp::to_ieee(x.fval(a));
      set_f(b.reg, fp::from_single(w));
      x.flags(&b.reg, (w >> 31 ? kN : 0) | ((w & 0x7FFFFFFF) == 0 ? kZ : 0), kN | kZ | kV | kUF);
      return true;
    }
    case M::Frieee: { fp::Res r = fp::from_ieee(x.rd(x.addr_of(a))); set_f(b.reg, fres(&b.reg, r)); return true; }
    default: return false;
  }
}

// Stores, LDA, LDHI, LDPK and NOP (whose operand may update an AR).
bool Step::load_store() {
  switch (in.mnemonic) {
    case M::Sti: x.wr(x.addr_of(b), x.ireg(a.reg)); return true;
    case M::Stf: x.wr(x.addr_of(b), fp::to_single(x.freg(a.reg))); return true;
    case M::Lda: set_i(b.reg, x.ival(a)); return true;
    case M::Ldhi: load_i(b.reg, uint32_t(a.imm) << 16); return true;
    case M::Ldpk: {
      uint32_t& dp = r32_[unsigned(Reg::DP)];
      dp = (dp & 0xFFFF0000u) | uint32_t(a.imm);
      writes |= 1u << kGroupDp;
      return true;
    }
    case M::Nop:
      if (in.num_operands == 1) x.ea(a.ind);
      return true;
    default: return false;
  }
}

// PUSH, PUSHF, POP, POPF.
bool Step::stack() {
  switch (in.mnemonic) {
    case M::Push: uses |= 1u << kGroupSp; push(x.ireg(a.reg)); return true;
    case M::Pushf: uses |= 1u << kGroupSp; push(fp::to_single(x.freg(a.reg))); return true;
    case M::Pop: uses |= 1u << kGroupSp; load_i(a.reg, pop()); return true;
    case M::Popf: {
      uses |= 1u << kGroupSp;
      fp::Res r{fp::from_single(pop()), false, false};
      set_f(a.reg, fres(&a.reg, r));
      return true;
    }
    default: return false;
  }
}

// Branches, calls, returns and DBc.
bool Step::control() {
  switch (in.mnemonic) {
    case M::Br: case M::Brd: branch(uint32_t(a.imm)); return true;
    case M::Bc: case M::Bcd:
      if (cond_true(in.cond, x.st())) branch(target_of(a));
      return true;
    case M::Call:
      uses |= 1u << kGroupSp;
      push(pc + 1);
      branch(uint32_t(a.imm));
      return true;
    case M::Callc:
      uses |= 1u << kGroupSp;
      if (cond_true(in.cond, x.st())) {
        push(pc + 1);
        branch(target_of(a));
      }
      return true;
    case M::Retsc:
      uses |= 1u << kGroupSp;
      if (cond_true(in.cond, x.st())) branch(pop());
      return true;
    case M::Dbc: case M::Dbcd: {
      uses |= 1u << kGroupAux;
      uint32_t& r = r32_[unsigned(a.reg)];
      r -= 1;
      if (cond_true(in.cond, x.st()) && int32_t(r) >= 0) branch(uint32_t(b.imm));
      return true;
    }
    default: return false;
  }
}

}  // namespace

// Executes one instruction (not its control transfer: that is left in
// taken_/target_). Returns the decode-phase register groups it used as a
// bit set in the high bits and the groups it writes in the low bits.
unsigned C40Sim::execute(const Instruction& in, uint32_t pc) {
  Exec x(r32_, ext_, [this](uint32_t a) { return mem_read(a); },
         [this](uint32_t a, uint32_t v) { mem_write(a, v); });
  Step s(x, r32_, in, pc, taken_, target_);
  if (!(s.integer() || s.integer3() || s.floating() || s.float3() || s.conversion() || s.load_store() || s.stack() ||
        s.control()))
    throw SimError{Stop::IllegalInstruction, "not an instruction"};  // .word and the like
  return s.uses << 8 | s.writes;
}

RunResult C40Sim::call(uint32_t entry, uint64_t max_cycles) {
  RunResult res;
  uint64_t cycles = 0, count = 0;
  // The cycle (end of execute) of the last write to each register group.
  int64_t last_write[3] = {INT64_MIN / 2, INT64_MIN / 2, INT64_MIN / 2};
  uint32_t pc = entry, prev = entry;  // prev: the instruction before pc, for fault messages
  int delay = 0;  // instructions left in the delay slots of a taken delayed branch
  uint32_t delayed_target = 0;
  auto finish = [&](Stop s, std::string err) {
    res.stop = s;
    res.cycles = cycles;
    res.instructions = count;
    res.pc = pc;
    res.error = std::move(err);
    res.ns = double(cycles) * cfg_.ns_per_cycle;
    return res;
  };
  try {
    uint32_t& sp = r32_[unsigned(Reg::SP)];
    sp += 1;
    mem_write(sp, cfg_.return_address);
  } catch (const SimError& e) {
    return finish(e.stop, "call: " + e.message + " (SP " + hex(r32_[unsigned(Reg::SP)]) + ")");
  }
  for (;;) {
    if (pc == cfg_.return_address && delay == 0) return finish(Stop::Returned, "");
    if (cycles >= max_cycles)
      return finish(Stop::CycleLimit, "cycle limit " + std::to_string(max_cycles) + " reached at PC " + hex(pc));
    if (count >= cfg_.max_instructions)
      return finish(Stop::InstructionLimit,
                    "instruction limit " + std::to_string(cfg_.max_instructions) + " reached at PC " + hex(pc));
    waits_ = 0;
    taken_ = false;
    unsigned cost = 1;
    const Instruction* inst = nullptr;
    try {
      const Cached& c = fetch(pc);
      if (!c.ok) {
        DecodeError e;
        decode_word(c.word, pc, &e);
        return finish(Stop::IllegalInstruction, "illegal instruction at " + hex(pc) + ": " + e.message);
      }
      inst = &c.inst;
      if (delay > 0 && is_control(inst->mnemonic))
        return finish(Stop::Unsupported, "branch in a delay slot at " + hex(pc));
      unsigned ug = execute(*inst, pc);
      unsigned uses = ug >> 8, writes = ug & 0xFF;
      // Register conflicts: a register of a group that an instruction wrote
      // in its execute phase can be used for addressing (decode phase) two
      // cycles later.
      int64_t stall = 0;
      for (int g = 0; g < 3; ++g)
        if (uses >> g & 1) stall = std::max<int64_t>(stall, last_write[g] + 2 - int64_t(cycles));
      cost += unsigned(stall) + waits_;
      if (is_control(inst->mnemonic) && !is_delayed(inst->mnemonic)) cost += 3;  // pipeline flush
      cycles += cost;
      for (int g = 0; g < 3; ++g)
        if (writes >> g & 1) last_write[g] = int64_t(cycles);
    } catch (const SimError& e) {
      return finish(e.stop, e.message + ", at PC " + hex(pc) + (count ? " (after the instruction at " + hex(prev) + ")" : ""));
    }
    ++count;
    if (trace_) trace_(TraceEntry{pc, inst, cycles - cost, cost});
    uint32_t next = pc + 1;
    if (taken_) {
      if (is_delayed(inst->mnemonic)) {
        delay = 3;
        delayed_target = target_;
      } else {
        next = target_;
      }
    } else if (delay > 0 && --delay == 0) {
      next = delayed_target;
    }
    prev = pc;
    pc = next;
  }
}

}  // namespace ldc::c40sim
