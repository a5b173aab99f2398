// backend-c40sim/gen/c40gen.cpp -- IL mnemonics -> TMS320C40 assembly templates.
#include "backend-c40sim/gen/c40gen.h"

#include <algorithm>
#include <cstring>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <span>
#include <stdexcept>

#include "ir/codegen.h"
#include "ir/scanopt.h"
#include "ir/typed.h"

namespace ldc::c40gen {

// ---------------------------------------------------------------- REAL semantics

namespace fp = c40sim::fp;

Ext real_from_ieee(uint32_t bits) { return fp::from_ieee(bits).v; }
Ext real_from_int(int32_t i) { return fp::from_int(i).v; }
uint32_t real_to_ieee(Ext x) { return fp::to_ieee(x); }
Ext real_add(Ext a, Ext b) { return fp::add(a, b).v; }
Ext real_sub(Ext a, Ext b) { return fp::sub(a, b).v; }
Ext real_mul(Ext a, Ext b) { return fp::mul(a, b).v; }
int real_compare(Ext a, Ext b) { return fp::compare(a, b); }

int32_t real_to_int32(Ext x) {
  bool ov = false;
  int32_t fl = fp::fix(x, &ov);                         // FIX   R0, R1
  Ext f = fp::from_int(fl).v;                            // FLOAT R1, R2
  int32_t plus = int32_t(uint32_t(fl) + 1u);            // ADDI3 1, R1, R3
  if (fp::compare(x, fp::kZero) >= 0) plus = fl;        // CMPF 0.0, R0; LDIGE R1, R3
  if (fp::compare(x, f) > 0) fl = plus;                 // CMPF R2, R0;  LDIGT R3, R1
  return fl;
}

namespace {
Ext kOne() { return fp::from_short(*as::c40::short_float_from_double(1.0)); }
Ext kTwo() { return fp::from_short(*as::c40::short_float_from_double(2.0)); }
}  // namespace

// x = m 2^e with the exponent field cleared (PUSHF, POP, ASH3 -24, LSH 8, LSH -8, PUSH, POPF)
static Ext split_exponent(Ext x, int32_t& e) {
  uint32_t w = fp::to_single(x);
  e = int32_t(w) >> 24;
  return fp::from_single((w << 8) >> 8);
}

Ext real_div(Ext a, Ext b) {
  Ext a0 = a;                                           // LDF R0, R6
  int32_t ea, eb;
  a = split_exponent(a, ea);                            // m_a in [1, 2) or [-2, -1)
  b = split_exponent(b, eb);                            // m_b
  int32_t k = ea - eb;                                  // SUBI R5, R4
  Ext x = fp::rcp(b).v;                                 // RCPF R1, R2
  for (int i = 0; i < 2; i++) {
    Ext t = fp::mul(x, b).v;                            // MPYF3 R2, R1, R3
    t = fp::neg(t).v;                                   // NEGF  R3, R3
    t = fp::add(t, kTwo()).v;                           // ADDF  2.0, R3
    x = fp::mul(x, t).v;                                // MPYF  R3, R2
  }
  Ext q = fp::mul(x, a).v;                              // MPYF3 R2, R0, R3
  q = fp::mul(q, kOne()).v;                             // MPYF  1.0, R3
  Ext r = fp::mul(q, b).v;                              // MPYF3 R3, R1, R5
  r = fp::sub(a, r).v;                                  // SUBF3 R5, R0, R5
  r = fp::mul(r, x).v;                                  // MPYF  R2, R5
  q = fp::add(q, r).v;                                  // ADDF  R5, R3: m_a / m_b in (1/2, 2)
  int32_t k1 = k >> 1, k2 = k - k1;                     // ASH3 -1, R4, R5; SUBI3 R5, R4, R4
  q = fp::mul(q, fp::from_single(uint32_t(k1) << 24)).v; // 2^k1 via LSH 24, PUSH, POPF; MPYF
  q = fp::mul(q, fp::from_single(uint32_t(k2) << 24)).v; // 2^k2
  if (fp::compare(a0, fp::kZero) == 0) q = fp::kZero;   // CMPF 0.0, R6; LDFEQ 0.0, R0
  return q;
}

std::string label_name(const std::string& il_label) { return "lbl_" + il_label; }

namespace {

using namespace as::c40;
using as::c40::Instruction;
using as::c40::Operand;
using M = Mnemonic;
using Item = as::Item<Instruction>;

Operand R(Reg r) { return Operand::r(r); }
Operand I(int64_t v) { return Operand::i(v); }
Operand L(std::string s) { return Operand::l(std::move(s)); }
Operand A(uint32_t addr) { return Operand::a(addr); }
Operand F(double v) {
  auto b = short_float_from_double(v);
  if (!b) throw std::logic_error("c40 backend: not a short float");
  return Operand::f(*b);
}
constexpr Reg r0 = Reg::R0, r1 = Reg::R1, r2 = Reg::R2, r3 = Reg::R3, r4 = Reg::R4, r10 = Reg::R10,
              r11 = Reg::R11;

uint32_t float_bits(float f) {
  uint32_t u;
  std::memcpy(&u, &f, 4);
  return u;
}

// ------------------------------------------------------------ bit templates
//
// Paper 003's Fig. 6 style: one row per bit mnemonic, in TI syntax, `;`
// between instructions.  %0 and %1 stand for the direct operand (@offset in
// the data page) of the IL instruction's operand 0 and 1 (a bit device or an
// edge slot; one word each, 0 or 1).  R10 is the bit stack, top in bit 0;
// R11 holds the mask ~1.
const OpTemplate kBitTemplates[] = {
    {Op::LOAD,   "LSH 1, R10; OR %0, R10"},
    {Op::LOADN,  "LSH 1, R10; OR 1, R10; XOR %0, R10"},
    {Op::AND,    "LDI %0, R0; OR R11, R0; AND R0, R10"},
    {Op::ANDN,   "ANDN %0, R10"},
    {Op::OR,     "OR %0, R10"},
    {Op::ORN,    "LDI %0, R0; XOR 1, R0; OR R0, R10"},
    {Op::LOADP,  "LDI %1, R0; LDI %0, R1; STI R1, %1; ANDN R0, R1; LSH 1, R10; OR R1, R10"},
    {Op::LOADF,  "LDI %1, R0; LDI %0, R1; STI R1, %1; ANDN R1, R0; LSH 1, R10; OR R0, R10"},
    {Op::TRUE,   "LSH 1, R10; OR 1, R10"},
    {Op::ANDBLK, "OR3 R11, R10, R0; LSH -1, R10; AND R0, R10"},
    {Op::ORBLK,  "AND3 1, R10, R0; LSH -1, R10; OR R0, R10"},
    {Op::MPS,    "AND3 1, R10, R0; LSH 1, R10; OR R0, R10"},
    {Op::MRD,    "LSH3 -1, R10, R0; XOR R10, R0; AND 1, R0; XOR R0, R10"},
    {Op::MPP,    "LSH -1, R10"},
    {Op::OUT,    "AND3 1, R10, R0; STI R0, %0"},
    {Op::OUTN,   "XOR3 1, R10, R0; AND 1, R0; STI R0, %0"},
    {Op::SET,    "AND3 1, R10, R0; OR %0, R0; STI R0, %0"},
    {Op::RST,    "LDI %0, R0; ANDN R10, R0; STI R0, %0"},
};

// The templates, parsed once; %k becomes the placeholder @k (a direct operand).
const std::vector<Instruction>* bit_template(Op op) {
  static const auto table = parse_templates<Instruction>(
      kBitTemplates, [](const std::string& s) { return parse(s); }, [](int k) { return "@" + std::to_string(k); });
  auto it = table.find(op);
  return it == table.end() ? nullptr : &it->second;
}

// ------------------------------------------------------------ application code

// Does the instruction write register r?  (Calls: every register, as far as
// the generator's bookkeeping is concerned.)
bool writes_reg(const Instruction& i, Reg r) {
  switch (i.mnemonic) {
    case M::Cmpi: case M::Cmpf: case M::Tstb: case M::Cmpi3: case M::Cmpf3: case M::Tstb3: case M::Sti: case M::Stf:
    case M::Ldpk: case M::Push: case M::Pushf: case M::Nop: case M::Br: case M::Brd: case M::Bc: case M::Bcd:
    case M::Retsc: case M::Word:
      return false;
    case M::Call: case M::Callc: return true;
    case M::Pop: case M::Popf: return i.ops[0].kind == OperandKind::Reg && i.ops[0].reg == r;
    default: break;
  }
  const Operand& d = i.ops[i.num_operands ? i.num_operands - 1 : 0];
  return d.kind == OperandKind::Reg && d.reg == r;
}

// -O2 keeps a rung's bit stack in registers, 0 or 1 each: stack position p
// (0 = the rung's first push) in kSlots[p % kNumSlots].  Nothing else uses
// them: R8 and R9 are free, R10 (the -O0 bit stack) is dead between rungs
// whose stack is their own, AR1-AR5 are neither scratch nor used by the
// routines and the math ROM.  R8-R10 set the flags when written.
const Reg kSlots[] = {Reg::R8, Reg::R9, Reg::R10, ar(1), ar(2), ar(3), ar(4), ar(5)};
constexpr int kNumSlots = 8;

// -O1 role of an IL instruction in a fused contact run (Gen::plan_runs): a
// LOAD/LOADN, the AND/ANDN/OR/ORN contacts after it and an ANDBLK/ORBLK
// ending it are computed in R0 instead of the shift register R10.
enum class Fuse : uint8_t { None, Start, Contact, Push, Combine };

// What the typed instructions share across rungs: the routines they call
// (emitted after __divf only when used, so untyped programs keep their code),
// the IL byte offsets (an index fault records its IDX's), and the bounds of
// the last IDX, which the LDX or STX right after it uses.
struct TypedState {
  bool divu = false, f2i = false, i2f = false, fadd = false, fmul = false, fdiv = false;
  std::vector<uint32_t> il_offset;  // encode_il's instr_offset, when the program has an IDX
  size_t next = 0;                  // program-order index of the instruction being built
  uint32_t span = 0;                // hi - lo of the last IDX
};

class Gen : public ClassGen<Gen> {
 public:
  // opt: the -O level; slots: this rung keeps its stack in kSlots (-O2)
  Gen(const C40Layout& w, std::vector<Item>& items, int& next_label, int opt, bool slots, TypedState& ts)
      : W_(w), items_(items), next_label_(next_label), opt_(opt), slots_(slots), ts_(ts) {}
  void instr(const ldc::Instr& in, uint8_t facts = 0);  // facts: ScanFlag bits (ir/scanopt.h)
  void ldpk_main() { items_.push_back(Item::instr(make(M::Ldpk, {I(kDataPage)}))); }
  // -O1: which instructions of the rung run in R0 (before the first instr())
  void plan_runs(const std::vector<ldc::Instr>& code);
  // -O1: before the code of `in` (and its note): ends a run of application
  // instructions that share one power test when `in` does not continue it
  void before(const ldc::Instr& in) {
    if (group_open_ && !guarded(in.op)) close_group();
  }
  void finish() { close_group(); }

 private:
  const C40Layout& W_;
  std::vector<Item>& items_;
  int& next_label_;
  const int opt_;
  const bool slots_;
  TypedState& ts_;
  uint32_t page_ = kDataPage;  // page of the direct operand of the instruction being built
  int depth_ = 0;              // stack positions in use before the current instruction (-O2)
  int z_of_ = -1;              // register whose value the Z flag reflects (-1: none)
  bool r0_top_ = false;        // R0 holds the top of the stack, 0 or 1 (-O1)
  std::optional<int32_t> r0_value_;  // R0's constant, as r0_value loaded it (within one IL instruction)
  bool group_open_ = false;    // a power test's branch to group_ is pending (-O1)
  std::string group_;
  std::vector<Fuse> fuse_;     // per IL instruction of the rung (-O1)
  std::vector<int> defer_;     // deferred_contacts of the rung (-O2, stack in registers)
  std::vector<ldc::Instr> contacts_;  // the rung's deferred contacts, by their index
  Reg pt_ = Reg::R1;           // the timer's preset (IR0 for a short constant at -O2: no flags)
  KnownStack known_;           // the stack's values known at compile time (-O2)
  bool on_ = false;            // this guarded instruction's power is on for certain: no test (-O2)
  size_t at_ = 0;              // index of the IL instruction being built

  // Application instructions: executed only when the top is 1, stack unchanged.
  static bool guarded(Op op) {
    switch (op_info(op).klass) {
      case OpClass::Move: case OpClass::Arith: case OpClass::Logic: case OpClass::Special: return true;
      case OpClass::Typed: return op_info(op).push == 0;  // the typed compares push
      default: return op == Op::RSTT || op == Op::RSTC;
    }
  }
  void close_group() {
    if (group_open_) label(group_);
    group_open_ = false;
  }

  // Emits one instruction; a direct operand outside the data page gets its
  // own LDPK before and LDPK back after it.
  void emit(Instruction i) {
    bool direct = false;
    for (unsigned k = 0; k < i.num_operands; k++) direct |= i.ops[k].kind == OperandKind::Direct;
    if (writes_reg(i, r0) || writes_reg(i, Reg::R10)) r0_top_ = false;
    if (writes_reg(i, r0)) r0_value_.reset();
    // stores leave the flags alone, and so do loads into registers outside R0-R11
    bool flags_kept = i.mnemonic == M::Sti || i.mnemonic == M::Stf ||
                      (i.mnemonic == M::Ldi && i.ops[1].kind == OperandKind::Reg && !is_extended(i.ops[1].reg));
    if (!flags_kept) z_of_ = -1;
    if (direct && page_ != kDataPage) {
      items_.push_back(Item::instr(make(M::Ldpk, {I(page_)})));
      items_.push_back(Item::instr(std::move(i)));
      ldpk_main();
    } else {
      items_.push_back(Item::instr(std::move(i)));
    }
    page_ = kDataPage;
  }
  // emit, then remember that Z reflects the destination (an integer operation
  // on R0-R11 sets Z from its result)
  void emit_z(Instruction i) {
    Reg d = i.ops[i.num_operands - 1].reg;
    emit(std::move(i));
    if (is_extended(d)) z_of_ = int(d);
  }
  void op(M m, std::initializer_list<Operand> ops) { emit(make(m, ops)); }
  void opc(M m, Cond c, std::initializer_list<Operand> ops) { emit(make_cc(m, c, ops)); }
  void label(const std::string& l) {
    items_.push_back(Item::label_def(l));
    z_of_ = -1;
    r0_top_ = false;
    r0_value_.reset();
  }
  std::string fresh() { return "L" + std::to_string(next_label_++); }
  void branch(Cond c, const std::string& l) { opc(M::Bc, c, {L(l)}); }
  void jump(const std::string& l) { op(M::Br, {L(l)}); }

  // @offset of a word address (records its page for emit)
  Operand D(uint32_t addr) {
    page_ = addr >> 16;
    return Operand::d(uint16_t(addr & 0xFFFF));
  }
  uint32_t addr(const ldc::Operand& o) const {
    switch (o.kind) {
      case OpdKind::Edge: return W_.addr(Area::E, o.index);
      case OpdKind::Timer: return W_.addr(Area::TW, o.index);
      case OpdKind::Counter: return W_.addr(Area::CW, o.index);
      default: return W_.addr(o.area, o.index);
    }
  }
  Operand Dv(const ldc::Operand& o) { return D(addr(o)); }

  static int32_t const_int(const ldc::Operand& o) {
    return o.kind == OpdKind::ConstInt ? o.ival : real_to_int32(real_from_ieee(float_bits(o.fval)));
  }
  static bool is_const(const ldc::Operand& o) { return o.kind == OpdKind::ConstInt || o.kind == OpdKind::ConstReal; }

  void load_imm32(int32_t v, Reg r) {
    if (v >= -32768 && v <= 32767) return op(M::Ldi, {I(v), R(r)});
    op(M::Ldhi, {I((uint32_t(v) >> 16) & 0xFFFF), R(r)});
    if (v & 0xFFFF) op(M::Or, {I(v & 0xFFFF), R(r)});
  }
  // The source operand of an integer instruction: an immediate when it fits the
  // form (signed or unsigned 16 bits), a direct word, or `scratch` loaded first.
  Operand int_src(const ldc::Operand& b, bool unsigned_imm, Reg scratch) {
    if (is_const(b)) {
      int32_t v = const_int(b);
      if (unsigned_imm ? (v >= 0 && v <= 65535) : (v >= -32768 && v <= 32767)) return I(v);
      load_imm32(v, scratch);
      return R(scratch);
    }
    if (b.kind == OpdKind::Real) {  // only MOV reaches here with a REAL word (load_int)
      load_int(b, scratch);
      return R(scratch);
    }
    return Dv(b);
  }
  // r = INT32 value of o.  A REAL word is converted (clobbers R0-R3).
  void load_int(const ldc::Operand& o, Reg r) {
    if (is_const(o)) return load_imm32(const_int(o), r);
    if (o.kind == OpdKind::Real) {
      op(M::Frieee, {Dv(o), R(r0)});
      trunc_r0_r1();
      if (r != r1) op(M::Ldi, {R(r1), R(r)});
      return;
    }
    op(M::Ldi, {Dv(o), R(r)});
  }
  // r = the REAL value of o as a C40 float (INT32: FLOAT, exact).
  void load_real(const ldc::Operand& o, Reg r) {
    switch (o.kind) {
      case OpdKind::Real: return op(M::Frieee, {Dv(o), R(r)});
      case OpdKind::ConstInt:
        if (o.ival >= -32768 && o.ival <= 32767) return op(M::Float, {I(o.ival), R(r)});
        load_imm32(o.ival, r);
        return op(M::Float, {R(r), R(r)});
      case OpdKind::ConstReal: {
        Ext e = real_from_ieee(float_bits(o.fval));
        double v = fp::to_double(e);
        if (auto sb = short_float_from_double(v); sb && fp::from_short(*sb) == e) return op(M::Ldf, {Operand::f(*sb), R(r)});
        uint32_t w = fp::to_single(e);  // exact: FRIEEE leaves the 8 low bits 0
        load_imm32(int32_t(w), r);
        op(M::Sti, {R(r), D(kDataBase + W_.offset[int(Area::Sys)] + kSysScratchWord)});
        return op(M::Ldf, {D(kDataBase + W_.offset[int(Area::Sys)] + kSysScratchWord), R(r)});
      }
      default: return op(M::Float, {Dv(o), R(r)});
    }
  }
  // R1 = R0 (C40 float) converted to INT32: truncated toward zero, saturated
  // (FIX rounds down; add 1 for a negative non-integer).  Uses R2, R3.
  void trunc_r0_r1() {
    op(M::Fix, {R(r0), R(r1)});
    op(M::Float, {R(r1), R(r2)});
    op(M::Addi3, {I(1), R(r1), R(r3)});
    op(M::Cmpf, {F(0.0), R(r0)});
    opc(M::Ldic, Cond::GE, {R(r1), R(r3)});
    op(M::Cmpf, {R(r2), R(r0)});
    opc(M::Ldic, Cond::GT, {R(r3), R(r1)});
  }
  // Stores R0 (C40 float) into d: TOIEEE for F, else converted to INT32.
  void store_real(const ldc::Operand& d) {
    if (d.kind == OpdKind::Real) {
      op(M::Toieee, {R(r0), R(r0)});
      return op(M::Stf, {R(r0), Dv(d)});
    }
    trunc_r0_r1();
    op(M::Sti, {R(r1), Dv(d)});
  }
  // Stores R0 (INT32) into d, converted to REAL for F.
  void store_int(const ldc::Operand& d) {
    if (d.kind == OpdKind::Real) {
      op(M::Float, {R(r0), R(r0)});
      op(M::Toieee, {R(r0), R(r0)});
      return op(M::Stf, {R(r0), Dv(d)});
    }
    op(M::Sti, {R(r0), Dv(d)});
  }
  // Stores a constant word.
  void store_word(uint32_t w, const ldc::Operand& d) {
    load_imm32(int32_t(w), r0);
    op(M::Sti, {R(r0), Dv(d)});
  }
  void set_error() {
    op(M::Ldi, {I(1), R(r4)});
    op(M::Sti, {R(r4), D(W_.addr(Area::S, kBitError))});
  }
  // -O2: the register of stack position p
  static Reg slot(int p) { return kSlots[((p % kNumSlots) + kNumSlots) % kNumSlots]; }
  Reg top() const { return slot(depth_ - 1); }
  // flags: Z set when the top is 0
  void test_top() {
    if (!slots_) return op(M::Tstb, {I(1), R(r10)});
    if (z_of_ != int(top())) op(M::Tstb, {I(1), R(top())});
  }
  // r = the top, 0 or 1
  void top_to(Reg r) {
    if (slots_) return op(M::Ldi, {R(top()), R(r)});
    if (r == r0 && r0_top_) return;
    op(M::And3, {I(1), R(r10), R(r)});
    if (r == r0 && opt_ >= 1) r0_top_ = true;
  }
  // if the top of the stack is 0, skip to the returned label.  From -O1 on,
  // consecutive application instructions share one test: they change neither
  // the stack nor the slot registers.
  std::string skip_unless_power() {
    std::string skip = fresh();
    if (on_) return skip;
    if (opt_ == 0) {
      test_top();
      branch(Cond::EQ, skip);
      return skip;
    }
    if (!group_open_) {
      test_top();
      group_ = fresh();
      branch(Cond::EQ, group_);
      group_open_ = true;
    }
    return skip;  // the instruction's own end (its internal jumps)
  }
  // R0 = R0 * R1 modulo 2^32 (MPYI multiplies 24-bit operands): 16-bit halves.
  void mul32() {
    op(M::Ldi, {R(r0), R(r2)});
    op(M::And, {I(0xFFFF), R(r2)});   // al
    op(M::Ldi, {R(r1), R(r3)});
    op(M::And, {I(0xFFFF), R(r3)});   // bl
    op(M::Lsh, {I(-16), R(r0)});      // ah
    op(M::Lsh, {I(-16), R(r1)});      // bh
    op(M::Mpyi, {R(r3), R(r0)});      // ah * bl
    op(M::Mpyi, {R(r2), R(r1)});      // al * bh
    op(M::Addi, {R(r1), R(r0)});
    op(M::Lsh, {I(16), R(r0)});
    op(M::Mpyi, {R(r3), R(r2)});      // al * bl
    op(M::Addi, {R(r2), R(r0)});
  }

  // ClassGen's primitives
  friend class ClassGen<Gen>;
  void end_skip(const std::string& skip) { label(skip); }
  int ungated(const ldc::Instr&) { return 0; }  // no gated stores to turn off
  void load_int(const ldc::Operand& a) { load_int(a, r0); }
  void load_ints(const ldc::Operand& a, const ldc::Operand& b) { load_int(a, r0); load_int(b, r1); }
  void load_reals(const ldc::Operand& a, const ldc::Operand& b) { load_real(a, r0); load_real(b, r1); }
  void prepare_push();
  void push_cond(Rel rel);
  void compare_ints(const ldc::Operand& a, const ldc::Operand& b, Rel rel);
  void compare_reals(const ldc::Operand& a, const ldc::Operand& b, Rel rel);
  void copy_word(const ldc::Operand& a, const ldc::Operand& d);
  void move_const(const ldc::Operand& a, const ldc::Operand& d);
  void move_real_to_int(const ldc::Operand& a, const ldc::Operand& d);
  void int_arith(Op o, const ldc::Operand& a, const ldc::Operand& b);
  void real_arith(Op o);
  DivLabels div_labels(bool real);
  void branch_zero_real(const DivLabels& l);
  void divide_real() { op(M::Call, {L(kDivfLabel)}); }  // R0 = a / b
  void divisor_branch(int32_t v, const std::string& l);
  void divide_int(bool mod);
  void minus_one_result(bool mod);
  void word_not(const ldc::Operand& a) { op(M::Not, {int_src(a, true, r0), R(r0)}); }
  void shift(Op o, const ldc::Operand& a, const ldc::Operand& n);
  void bitwise(Op o, const ldc::Operand& a, const ldc::Operand& b);
  void abs_int(const ldc::Operand& a, const ldc::Operand& d);
  void real_fn(Op o, const ldc::Operand& a, const ldc::Operand& d);
  uint32_t area_addr(Area a, uint32_t n) const { return W_.addr(a, n); }
  bool gated_divmod(const ldc::Instr&) { return false; }
  bool gated_timer(const ldc::Instr&, uint32_t, uint32_t, uint32_t) { return false; }
  bool gated_counter(const ldc::Instr&, uint32_t, uint32_t) { return false; }
  void r0_value(int32_t v);
  void put_word(uint32_t a, int32_t v) { r0_value(v); op(M::Sti, {R(r0), D(a)}); }
  void put_flag(uint32_t a, int32_t v) { put_word(a, v); }
  void unless_power(const std::string& l) { test_top(); branch(Cond::EQ, l); }
  void if_power(const std::string& l) { test_top(); branch(Cond::NE, l); }
  void if_flag(uint32_t a, bool set, const std::string& l) {
    op(M::Ldi, {D(a), R(r0)});
    branch(set ? Cond::NE : Cond::EQ, l);
  }
  void restart_et(uint32_t tw) { op(M::Ldi, {I(0), R(r2)}); op(M::Sti, {R(r2), D(tw)}); }
  void et_below(const std::string& l) { op(M::Cmpi, {R(pt_), R(r2)}); branch(Cond::LT, l); }
  void q_et(uint32_t tq, Rel rel);
  void q_preset(uint32_t tq);
  void tof_on(uint32_t tw, uint32_t tq, uint32_t ti) { put_flag(tq, 1); put_flag(ti, 1); put_word(tw, 0); }
  void remember_input(uint32_t ti);
  void count(const ldc::Instr& in, uint32_t cw, uint32_t cq);
  void preset(const ldc::Operand& pt);
  void advance(uint32_t tw);
  void bit_slots(const ldc::Instr& in);
  bool bit_fused(const ldc::Instr& in, Fuse f);
  void basic(const ldc::Instr& in);
  void flow(const ldc::Instr& in);
  // typed instructions (class Typed): c40typed section below
  void typed(const ldc::Instr& in);
  void load_t(const ldc::Operand& o, Ty t, Reg r);
  void norm_t(Ty t, Reg r);
  void push_cc(Cond c);
  void real_rel(Rel rel);
  void typed_compare(const ldc::Instr& in);
  void typed_divmod(const ldc::Instr& in);
  void typed_minmax(const ldc::Instr& in);
  void typed_shift(const ldc::Instr& in);
  void typed_conv(const ldc::Instr& in);
  void real_to_int(Ty t, bool trunc);
  void typed_index(const ldc::Instr& in);
  void typed_indexed(const ldc::Instr& in);
  void checked_access(uint32_t limit, uint32_t base, Instruction access);
  template <class G>
  friend void ldc::gen_by_class(G& g, const ldc::Instr& in);
};

// The C40 condition of each relation after CMPI / CMPF a - b, in the order of
// ops.def's REL table (CMPF's flags on C40 floats have no NaN).
constexpr Cond kRelConds[] = {Cond::EQ, Cond::NE, Cond::LT, Cond::LE, Cond::GT, Cond::GE};
static_assert(sizeof kRelConds / sizeof kRelConds[0] == size_t(Rel::None));
Cond cond_of(Rel r) { return kRelConds[int(r)]; }

// push (a op b): the push is prepared in R2 (R10 << 1 | 1) and taken with LDIcond.
void Gen::prepare_push() {
  if (slots_) return op(M::Ldi, {I(0), R(slot(depth_))});  // -O2: 0, or 1 if the condition holds
  op(M::Lsh, {I(1), R(r10)});
  op(M::Or3, {I(1), R(r10), R(r2)});
}

void Gen::push_cond(Rel rel) {
  if (slots_) opc(M::Ldic, cond_of(rel), {I(1), R(slot(depth_))});
  else opc(M::Ldic, cond_of(rel), {R(r2), R(r10)});
}

void Gen::compare_ints(const ldc::Operand& a, const ldc::Operand& b, Rel rel) {
  load_int(a, r0);
  prepare_push();
  op(M::Cmpi, {int_src(b, false, r1), R(r0)});
  push_cond(rel);
}

void Gen::compare_reals(const ldc::Operand& a, const ldc::Operand& b, Rel rel) {
  load_reals(a, b);
  prepare_push();
  op(M::Cmpf, {R(r1), R(r0)});
  push_cond(rel);
}

// d = a, both REAL words: the IEEE word, exactly
void Gen::copy_word(const ldc::Operand& a, const ldc::Operand& d) {
  op(M::Ldi, {Dv(a), R(r0)});
  op(M::Sti, {R(r0), Dv(d)});
}

// d = a constant, converted at compile time (an INT32 into F: FLOAT then TOIEEE, folded)
void Gen::move_const(const ldc::Operand& a, const ldc::Operand& d) {
  bool dreal = d.kind == OpdKind::Real;
  if (a.kind == OpdKind::ConstReal && dreal) store_word(float_bits(a.fval), d);
  else if (a.kind == OpdKind::ConstInt && dreal) store_word(real_to_ieee(real_from_int(a.ival)), d);
  else store_word(uint32_t(const_int(a)), d);
}

void Gen::move_real_to_int(const ldc::Operand& a, const ldc::Operand& d) {
  load_int(a, r1);  // FRIEEE and the truncation
  op(M::Sti, {R(r1), Dv(d)});
}

// R0 = a op b (ADD SUB MUL)
void Gen::int_arith(Op o, const ldc::Operand& a, const ldc::Operand& b) {
  if (o == Op::MUL) {
    load_ints(a, b);
    return mul32();
  }
  load_int(a, r0);
  op(o == Op::ADD ? M::Addi : M::Subi, {int_src(b, false, r1), R(r0)});
}

void Gen::real_arith(Op o) { op(o == Op::ADD ? M::Addf : o == Op::SUB ? M::Subf : M::Mpyf, {R(r1), R(r0)}); }

DivLabels Gen::div_labels(bool real) {
  DivLabels l;
  l.err = fresh();
  if (!real) {
    l.minus_one = fresh();
    l.store = fresh();
  }
  return l;
}

void Gen::branch_zero_real(const DivLabels& l) {
  op(M::Cmpf, {F(0.0), R(r1)});
  branch(Cond::EQ, l.err);
}

void Gen::divisor_branch(int32_t v, const std::string& l) {
  op(M::Cmpi, {I(v), R(r1)});
  branch(Cond::EQ, l);
}

void Gen::divide_int(bool mod) {
  op(M::Call, {L(kDivLabel)});  // R0 = quotient, R1 = remainder
  if (mod) op(M::Ldi, {R(r1), R(r0)});
}

void Gen::minus_one_result(bool mod) {
  if (mod) op(M::Ldi, {I(0), R(r0)});
  else op(M::Negi, {R(r0), R(r0)});
}

void Gen::shift(Op o, const ldc::Operand& a, const ldc::Operand& n) {
  load_int(a, r0);
  if (is_const(n)) {
    int32_t c = const_int(n);
    if (c < 0 || c > 31) op(M::Ldi, {I(0), R(r0)});
    else if (c > 0) op(M::Lsh, {I(o == Op::SHL ? c : -c), R(r0)});
    return;
  }
  load_int(n, r1);
  if (o == Op::SHR) {
    op(M::Negi, {R(r1), R(r2)});
    op(M::Lsh3, {R(r2), R(r0), R(r0)});
  } else {
    op(M::Lsh3, {R(r1), R(r0), R(r0)});
  }
  op(M::Cmpi, {I(31), R(r1)});
  opc(M::Ldic, Cond::HI, {I(0), R(r0)});  // unsigned: negative counts too
}

void Gen::bitwise(Op o, const ldc::Operand& a, const ldc::Operand& b) {
  load_int(a, r0);
  M m = o == Op::WAND ? M::And : o == Op::WOR ? M::Or : M::Xor;
  op(m, {int_src(b, true, r1), R(r0)});
}

// ABS of an INT32 (INT32_MIN stays)
void Gen::abs_int(const ldc::Operand& a, const ldc::Operand& d) {
  if (a.kind == OpdKind::ConstInt) {
    int32_t v = a.ival == INT32_MIN ? INT32_MIN : (a.ival < 0 ? -a.ival : a.ival);
    if (d.kind == OpdKind::Real) store_word(real_to_ieee(real_from_int(v)), d);
    else store_word(uint32_t(v), d);
  } else {
    op(M::Absi, {Dv(a), R(r0)});
    store_int(d);
  }
}

void Gen::real_fn(Op o, const ldc::Operand& a, const ldc::Operand& d) {
  if (o == Op::ABS && d.kind == OpdKind::Real) {  // fabsf: the IEEE sign bit cleared
    if (a.kind == OpdKind::ConstReal) {
      store_word(float_bits(a.fval) & 0x7FFFFFFFu, d);
    } else {
      op(M::Ldi, {Dv(a), R(r0)});
      op(M::Lsh, {I(1), R(r0)});
      op(M::Lsh, {I(-1), R(r0)});
      op(M::Sti, {R(r0), Dv(d)});
    }
  } else if (o == Op::ABS) {  // REAL -> INT32
    if (a.kind == OpdKind::ConstReal) {
      store_word(uint32_t(real_to_int32(fp::abs(real_from_ieee(float_bits(a.fval))).v)), d);
    } else {
      load_real(a, r0);
      op(M::Absf, {R(r0), R(r0)});
      store_real(d);
    }
  } else {
    load_real(a, r0);
    op(M::Call, {A(rom_entry(rom_of(op_info(o).fn)))});
    store_real(d);
  }
}

// pt_ = timer preset, a negative one counted as 0: R1, or at -O2 IR0 for a
// constant that one LDI loads (a load into IR0 leaves the flags, so the power
// test after it can still use the Z of the rung's last contact)
void Gen::preset(const ldc::Operand& pt) {
  pt_ = r1;
  if (is_const(pt)) {
    int32_t v = std::max(const_int(pt), 0);
    if (opt_ >= 2 && v <= 32767) pt_ = Reg::IR0;
    return load_imm32(v, pt_);
  }
  load_int(pt, r1);
  opc(M::Ldic, Cond::LT, {I(0), R(r1)});
}

// R2 = advance(ET, dt, PT) (docs/il.md) with ET at tw, PT in R1; stored too.
// Uses R0.  ADDI sets V when ET + dt overflows (dt is never negative).
void Gen::advance(uint32_t tw) {
  op(M::Ldi, {D(tw), R(r0)});
  op(M::Ldi, {R(r0), R(r2)});
  op(M::Addi, {D(W_.addr(Area::Sys, kSysDtWord)), R(r2)});
  opc(M::Ldic, Cond::V, {R(pt_), R(r2)});
  op(M::Cmpi, {R(pt_), R(r2)});
  opc(M::Ldic, Cond::GT, {R(pt_), R(r2)});
  op(M::Cmpi, {R(pt_), R(r0)});
  opc(M::Ldic, Cond::GE, {R(pt_), R(r2)});
  op(M::Sti, {R(r2), D(tw)});
}

// R0 = v, unless it holds v already (put_word, put_flag and the Q settings of
// one timer or counter share it)
void Gen::r0_value(int32_t v) {
  if (r0_value_ == v) return;
  op(M::Ldi, {I(v), R(r0)});
  r0_value_ = v;
}

// tq = (R2 rel R1): Q from ET and PT
void Gen::q_et(uint32_t tq, Rel rel) {
  r0_value(0);
  op(M::Cmpi, {R(pt_), R(r2)});
  opc(M::Ldic, cond_of(rel), {I(1), R(r0)});
  op(M::Sti, {R(r0), D(tq)});
}

// tq = (R1 > 0): Q when a timing starts
void Gen::q_preset(uint32_t tq) {
  r0_value(0);
  op(M::Cmpi, {I(0), R(pt_)});
  opc(M::Ldic, Cond::GT, {I(1), R(r0)});
  op(M::Sti, {R(r0), D(tq)});
}

// ti = the top (IN, for the next scan's edge)
void Gen::remember_input(uint32_t ti) {
  if (slots_) {
    op(M::Sti, {R(top()), D(ti)});
  } else {
    top_to(r0);
    op(M::Sti, {R(r0), D(ti)});
  }
}


// CTU / CTD: the rising edge of the input, then CV (saturated) and Q
void Gen::count(const ldc::Instr& in, uint32_t cw, uint32_t cq) {
  bool up = in.op == Op::CTU;
  uint32_t e = addr(in.a[2]);
  top_to(r0);  // IN
  op(M::Ldi, {D(e), R(r1)});
  op(M::Sti, {R(r0), D(e)});
  op(M::Andn, {R(r1), R(r0)});          // rising edge: 0 or 1
  op(M::Ldi, {D(cw), R(r2)});
  op(up ? M::Addi3 : M::Subi3, {R(r0), R(r2), R(r3)});  // CV +- edge; V at the INT32 limit
  opc(M::Ldic, Cond::NV, {R(r3), R(r2)});
  op(M::Sti, {R(r2), D(cw)});
  op(M::Ldi, {I(0), R(r0)});
  if (up) {
    op(M::Cmpi, {int_src(in.a[1], false, r1), R(r2)});
    opc(M::Ldic, Cond::GE, {I(1), R(r0)});
  } else {
    op(M::Cmpi, {I(0), R(r2)});
    opc(M::Ldic, Cond::LE, {I(1), R(r0)});
  }
  op(M::Sti, {R(r0), D(cq)});
}

// -O2: a dead store, or an unread stack entry of a contact, compare or
// combine that no deferred contact pairs with, needs no code (ir/scanopt.h;
// an edge contact keeps its code, for its edge update).
void Gen::instr(const ldc::Instr& in, uint8_t facts) {
  r0_value_.reset();
  Fuse f = at_ < fuse_.size() ? fuse_[at_] : Fuse::None;
  on_ = opt_ >= 2 && guarded(in.op) && known_.on();  // -O2: a power on for certain needs no test
  int partner = at_ < defer_.size() ? defer_[at_] : -1;
  bool edge = in.op == Op::LOADP || in.op == Op::LOADF;
  if (op_info(in.op).klass == OpClass::Typed) {
    typed(in);
  } else if (partner < 0 && ((facts & kDeadStore) || ((facts & kUnread) && !edge))) {
    // nothing
  } else if (partner >= 0) {  // -O2: a deferred contact pushes nothing; its block instruction applies it
    if (size_t(partner) < at_) bit_slots(combined_contact(contacts_[size_t(partner)], in));
  } else if (slots_ && bit_template(in.op)) {
    bit_slots(in);
  } else if (f == Fuse::None || !bit_fused(in, f)) {
    gen_by_class(*this, in);
  }
  on_ = false;
  if (opt_ >= 2) known_.step(in);
  if (partner < 0) depth_ += op_info(in.op).push - op_info(in.op).pop;
  at_++;
  ts_.next++;
}

// -O1: where a LOAD or LOADN starts a run of contacts that pays to compute in
// R0 (docs/c40.md, "Optimization levels"): the run is pushed once at its end
// (`LSH 1, R10; OR R0, R10`), or an ANDBLK/ORBLK right after it combines R0
// with the top without pushing.  Per contact the -O0 templates spend AND 4
// cycles, ANDN and OR 2 (direct reads wait 1), ORN 4; in R0 they cost 2, 2, 2,
// 4, the start 1 less for LOADN and the same for LOAD, and the push 1 more
// than LOAD's shift: a run pays when it has an AND or ends in a block.
void Gen::plan_runs(const std::vector<ldc::Instr>& code) {
  defer_.clear();
  if (opt_ >= 2 && slots_) {
    defer_ = deferred_contacts(code);
    contacts_ = code;
  }
  fuse_.assign(code.size(), Fuse::None);
  if (opt_ < 1 || slots_) return;
  for (size_t i = 0; i < code.size(); i++) {
    if (code[i].op != Op::LOAD && code[i].op != Op::LOADN) continue;
    size_t j = i + 1;
    int ands = 0;
    for (; j < code.size(); j++) {
      Op o = code[j].op;
      if (o != Op::AND && o != Op::ANDN && o != Op::OR && o != Op::ORN) break;
      ands += o == Op::AND;
    }
    bool block = j < code.size() && (code[j].op == Op::ANDBLK || code[j].op == Op::ORBLK);
    if (!block && ands == 0) continue;
    fuse_[i] = Fuse::Start;
    for (size_t k = i + 1; k < j; k++) fuse_[k] = Fuse::Contact;
    if (block) fuse_[j] = Fuse::Combine;
    else fuse_[j - 1] = Fuse::Push;  // the last contact pushes
    i = j - 1;
  }
}

// The fused forms; false where the instruction has none (then the template).
bool Gen::bit_fused(const ldc::Instr& in, Fuse f) {
  auto contact = [&] {
    switch (in.op) {
      case Op::LOAD: return op(M::Ldi, {Dv(in.a[0]), R(r0)});
      case Op::LOADN: op(M::Ldi, {Dv(in.a[0]), R(r0)}); return op(M::Xor, {I(1), R(r0)});
      case Op::AND: return op(M::And, {Dv(in.a[0]), R(r0)});
      case Op::ANDN: return op(M::Andn, {Dv(in.a[0]), R(r0)});
      case Op::OR: return op(M::Or, {Dv(in.a[0]), R(r0)});
      default:  // ORN
        op(M::Ldi, {Dv(in.a[0]), R(r1)});
        op(M::Xor, {I(1), R(r1)});
        return op(M::Or, {R(r1), R(r0)});
    }
  };
  switch (f) {
    case Fuse::Start: case Fuse::Contact: contact(); return true;
    case Fuse::Push:
      contact();
      op(M::Lsh, {I(1), R(r10)});
      op(M::Or, {R(r0), R(r10)});
      r0_top_ = true;
      return true;
    case Fuse::Combine:
      if (in.op == Op::ANDBLK) op(M::Or, {R(Reg::R11), R(r0)});  // ~1 | run: AND keeps or clears the top
      op(in.op == Op::ANDBLK ? M::And : M::Or, {R(r0), R(r10)});
      return true;
    case Fuse::None: break;
  }
  return false;
}

// -O2 bit instructions on the slot registers (0 or 1 each).
void Gen::bit_slots(const ldc::Instr& in) {
  Reg d = slot(depth_), t = slot(depth_ - 1), u = slot(depth_ - 2);
  auto b = [&](int k) { return Dv(in.a[k]); };
  switch (in.op) {
    case Op::LOAD: return emit_z(make(M::Ldi, {b(0), R(d)}));
    case Op::LOADN: op(M::Ldi, {b(0), R(d)}); return emit_z(make(M::Xor, {I(1), R(d)}));
    case Op::AND: return emit_z(make(M::And, {b(0), R(t)}));
    case Op::ANDN: return emit_z(make(M::Andn, {b(0), R(t)}));
    case Op::OR: return emit_z(make(M::Or, {b(0), R(t)}));
    case Op::ORN:
      op(M::Ldi, {b(0), R(r0)});
      op(M::Xor, {I(1), R(r0)});
      return emit_z(make(M::Or, {R(r0), R(t)}));
    case Op::LOADP:  // d = b & !e; e = b
      op(M::Ldi, {b(0), R(d)});
      op(M::Ldi, {b(1), R(r0)});
      op(M::Sti, {R(d), b(1)});
      return emit_z(make(M::Andn, {R(r0), R(d)}));
    case Op::LOADF:  // d = !b & e; e = b
      op(M::Ldi, {b(1), R(d)});
      op(M::Ldi, {b(0), R(r0)});
      op(M::Sti, {R(r0), b(1)});
      return emit_z(make(M::Andn, {R(r0), R(d)}));
    case Op::TRUE: return emit_z(make(M::Ldi, {I(1), R(d)}));
    case Op::ANDBLK: return emit_z(make(M::And, {R(t), R(u)}));
    case Op::ORBLK: return emit_z(make(M::Or, {R(t), R(u)}));
    case Op::MPS: return emit_z(make(M::Ldi, {R(t), R(d)}));
    case Op::MRD: return emit_z(make(M::Ldi, {R(u), R(t)}));
    case Op::MPP: return;
    case Op::OUT: return op(M::Sti, {R(t), b(0)});
    case Op::OUTN:
      op(M::Xor3, {I(1), R(t), R(r0)});
      return op(M::Sti, {R(r0), b(0)});
    case Op::SET: case Op::RST:  // w | t, w & !t
      op(M::Ldi, {b(0), R(r0)});
      op(in.op == Op::SET ? M::Or : M::Andn, {R(t), R(r0)});
      return op(M::Sti, {R(r0), b(0)});
    default: break;
  }
  throw std::logic_error(std::string("c40 backend: no -O2 form for ") + op_info(in.op).name);
}

// The bit instructions: their template with the placeholders replaced by the
// operands' direct addresses.
void Gen::basic(const ldc::Instr& in) {
  const std::vector<Instruction>* t = bit_template(in.op);
  if (!t) throw std::logic_error(std::string("c40 backend: no template for ") + op_info(in.op).name);
  for (Instruction i : *t) {
    if (r0_top_ && i == make(M::And3, {I(1), R(r10), R(r0)})) continue;  // -O1: R0 holds the top
    for (unsigned k = 0; k < i.num_operands; k++)
      if (i.ops[k].kind == OperandKind::Direct) i.ops[k] = Dv(in.a[i.ops[k].imm]);
    emit(std::move(i));
  }
}

// ------------------------------------------------------------ typed instructions
//
// The typed instructions of issue 25 (ops.def class Typed, ir/typed.h) on the
// types that fit the C40's 32-bit word (docs/c40.md, "Typed instructions"): a
// value lives in a register as its canonical 32 bits (sign-extended for the
// signed kinds, zero-extended otherwise, BOOL 0/1, REAL its IEEE bits), so
// every result is what ir/typed.h computes, bit for bit.  REAL is handled as
// IEEE bits in integer arithmetic (moves, compares, MIN MAX NEG ABS, the
// conversions); what would need the C40's own float arithmetic, which is not
// IEEE binary32, and the 64-bit types are refused by name (c40_typed_refusal).

// R = the canonical 32 bits of operand o of type t (a device cell, made
// canonical as typed::load does; or a typed constant)
void Gen::load_t(const ldc::Operand& o, Ty t, Reg r) {
  if (o.kind == OpdKind::ConstT) return load_imm32(int32_t(uint32_t(o.bits())), r);
  if (o.kind == OpdKind::ConstInt) return load_imm32(o.ival, r);
  op(M::Ldi, {Dv(o), R(r)});
  norm_t(t, r);
}

// r wrapped to t's width and extended (typed::norm) for the 8- and 16-bit types
void Gen::norm_t(Ty t, Reg r) {
  const TyInfo& ti = ty_info(t);
  if (ti.kind == TyKind::Bool || ti.kind == TyKind::Real || ti.bits >= 32) return;
  if (typed::is_signed(t)) {
    op(M::Lsh, {I(32 - ti.bits), R(r)});
    op(M::Ash, {I(ti.bits - 32), R(r)});
  } else {
    op(M::And, {I((1 << ti.bits) - 1), R(r)});
  }
}

void Gen::push_cc(Cond c) {
  if (slots_) opc(M::Ldic, c, {I(1), R(slot(depth_))});
  else opc(M::Ldic, c, {R(r2), R(r10)});
}

// R5 = (a rel b) for the IEEE binary32 bits a in R0 and b in R1, in integer
// arithmetic: a NaN (|x| > 0x7F800000) makes every relation false but Ne;
// otherwise the order of the keys |x| (x >= 0) and -|x| (x < 0), which also
// makes -0 equal +0.  Uses R2-R6.
void Gen::real_rel(Rel rel) {
  op(M::Lsh3, {I(1), R(r0), R(r2)});
  op(M::Lsh, {I(-1), R(r2)});            // |a|
  op(M::Lsh3, {I(1), R(r1), R(Reg::R3)});
  op(M::Lsh, {I(-1), R(Reg::R3)});       // |b|
  op(M::Ldhi, {I(0x7F80), R(Reg::R6)});  // the bits of +infinity
  op(M::Ldi, {I(0), R(r4)});
  op(M::Cmpi, {R(Reg::R6), R(r2)});
  opc(M::Ldic, Cond::HI, {I(1), R(r4)});
  op(M::Cmpi, {R(Reg::R6), R(Reg::R3)});
  opc(M::Ldic, Cond::HI, {I(1), R(r4)});  // R4: a NaN
  op(M::Negi, {R(r2), R(Reg::R6)});
  op(M::Cmpi, {I(0), R(r0)});
  opc(M::Ldic, Cond::LT, {R(Reg::R6), R(r2)});
  op(M::Negi, {R(Reg::R3), R(Reg::R6)});
  op(M::Cmpi, {I(0), R(r1)});
  opc(M::Ldic, Cond::LT, {R(Reg::R6), R(Reg::R3)});
  op(M::Ldi, {I(0), R(Reg::R5)});
  op(M::Cmpi, {R(Reg::R3), R(r2)});        // CMPI's N is the exact sign: right even on overflow
  opc(M::Ldic, cond_of(rel), {I(1), R(Reg::R5)});
  op(M::Cmpi, {I(0), R(r4)});
  opc(M::Ldic, Cond::NE, {I(rel == Rel::Ne ? 1 : 0), R(Reg::R5)});
}

// The condition after CMPI b, a (a - b) for a relation of unsigned values
constexpr Cond kUnsignedConds[] = {Cond::EQ, Cond::NE, Cond::LO, Cond::LS, Cond::HI, Cond::HS};
static_assert(sizeof kUnsignedConds / sizeof kUnsignedConds[0] == size_t(Rel::None));

void Gen::typed_compare(const ldc::Instr& in) {
  const Ty t = in.ty;
  const Rel rel = op_info(in.op).rel;
  load_t(in.a[0], t, r0);
  load_t(in.a[1], t, r1);
  if (typed::is_real(t)) {
    real_rel(rel);
    prepare_push();
    op(M::Cmpi, {I(0), R(Reg::R5)});
    return push_cc(Cond::NE);
  }
  prepare_push();
  op(M::Cmpi, {R(r1), R(r0)});
  push_cc(typed::is_signed(t) ? cond_of(rel) : kUnsignedConds[int(rel)]);
}

// DIV MOD: a zero divisor gives 0 and sets S0; a signed one of -1 gives the
// negation (wrapped) or 0; else __divi (signed, and the 8- and 16-bit unsigned
// types, which it holds as positive INT32) or __divu (UDINT)
void Gen::typed_divmod(const ldc::Instr& in) {
  const Ty t = in.ty;
  const bool mod = in.op == Op::TMOD, sgn = typed::is_signed(t);
  load_t(in.a[0], t, r0);
  load_t(in.a[1], t, r1);
  std::string zero = fresh(), minus_one = fresh(), store = fresh();
  op(M::Cmpi, {I(0), R(r1)});
  branch(Cond::EQ, zero);
  if (sgn) {
    op(M::Cmpi, {I(-1), R(r1)});
    branch(Cond::EQ, minus_one);
  }
  if (t == Ty::UDINT) ts_.divu = true;
  op(M::Call, {L(t == Ty::UDINT ? kDivuLabel : kDivLabel)});  // R0 = quotient, R1 = remainder
  if (mod) op(M::Ldi, {R(r1), R(r0)});
  jump(store);
  if (sgn) {
    label(minus_one);
    if (mod) op(M::Ldi, {I(0), R(r0)});
    else op(M::Negi, {R(r0), R(r0)});
    jump(store);
  }
  label(zero);
  set_error();
  op(M::Ldi, {I(0), R(r0)});
  label(store);
  norm_t(t, r0);
  op(M::Sti, {R(r0), Dv(in.a[2])});
}

// MIN: b if b < a, else a; MAX: b if b > a (a NaN b never taken)
void Gen::typed_minmax(const ldc::Instr& in) {
  const Ty t = in.ty;
  const bool min = in.op == Op::TMIN;
  load_t(in.a[0], t, r0);
  load_t(in.a[1], t, r1);
  if (typed::is_real(t)) {
    op(M::Ldi, {R(r0), R(Reg::R7)});  // real_rel compares R0 rel R1: b rel a
    op(M::Ldi, {R(r1), R(r0)});
    op(M::Ldi, {R(Reg::R7), R(r1)});
    real_rel(min ? Rel::Lt : Rel::Gt);  // R0 = b, R1 = a
    op(M::Cmpi, {I(0), R(Reg::R5)});
    opc(M::Ldic, Cond::EQ, {R(r1), R(r0)});  // not taken: a
  } else {
    op(M::Cmpi, {R(r1), R(r0)});  // a - b
    bool sgn = typed::is_signed(t);
    opc(M::Ldic, min ? (sgn ? Cond::GT : Cond::HI) : (sgn ? Cond::LT : Cond::LO), {R(r1), R(r0)});
  }
  op(M::Sti, {R(r0), Dv(in.a[2])});
}

// SHL SHR: a count outside 0..w-1 (a negative one is huge unsigned) gives 0;
// ROL ROR: the count modulo w (w a power of two: its low bits, negative counts too)
void Gen::typed_shift(const ldc::Instr& in) {
  const Ty t = in.ty;
  const int w = ty_info(t).bits;
  load_t(in.a[0], t, r0);
  load_t(in.a[1], in.src, r1);
  if (in.op == Op::TSHL || in.op == Op::TSHR) {
    if (in.op == Op::TSHL) {
      op(M::Lsh3, {R(r1), R(r0), R(r0)});
    } else {
      op(M::Negi, {R(r1), R(r2)});
      op(M::Lsh3, {R(r2), R(r0), R(r0)});
    }
    op(M::Cmpi, {I(w - 1), R(r1)});
    opc(M::Ldic, Cond::HI, {I(0), R(r0)});
  } else {
    op(M::And, {I(w - 1), R(r1)});  // k
    if (in.op == Op::TROL) {
      op(M::Lsh3, {R(r1), R(r0), R(r2)});          // a << k
      op(M::Addi3, {I(-w), R(r1), R(Reg::R3)});
      op(M::Lsh3, {R(Reg::R3), R(r0), R(Reg::R3)});  // a >> (w - k); 0 for k = 0
    } else {
      op(M::Negi, {R(r1), R(r2)});
      op(M::Lsh3, {R(r2), R(r0), R(r2)});          // a >> k
      op(M::Ldi, {I(w), R(Reg::R3)});
      op(M::Subi, {R(r1), R(Reg::R3)});
      op(M::Lsh3, {R(Reg::R3), R(r0), R(Reg::R3)});  // a << (w - k); masked below for k = 0
    }
    op(M::Or3, {R(Reg::R3), R(r2), R(r0)});
  }
  norm_t(t, r0);
  op(M::Sti, {R(r0), Dv(in.a[2])});
}

// R0 (IEEE bits) -> the integer type t: __f2i gives the magnitude, rounded
// (ties to even) or truncated, modulo 2^32 (which is 0 where typed.h's
// result is INT64_MIN: NaN, infinities, |x| >= 2^63); R7 keeps the sign.
// CONV to an unsigned type gives 0 for a negative value.
void Gen::real_to_int(Ty t, bool trunc) {
  ts_.f2i = true;
  op(M::Ldi, {R(r0), R(Reg::R7)});
  op(M::Ldi, {I(trunc ? 1 : 0), R(r1)});
  op(M::Call, {L(kF2iLabel)});
  if (!trunc && !typed::is_signed(t)) {
    op(M::Cmpi, {I(0), R(Reg::R7)});
    opc(M::Ldic, Cond::LT, {I(0), R(r0)});
  } else {
    op(M::Negi, {R(r0), R(r1)});
    op(M::Cmpi, {I(0), R(Reg::R7)});
    opc(M::Ldic, Cond::LT, {R(r1), R(r0)});
  }
  norm_t(t, r0);
}

// CONV.T.U (typed::conv) between the 32-bit-or-narrower types
void Gen::typed_conv(const ldc::Instr& in) {
  const Ty t = in.ty, u = in.src;
  const TyKind tk = ty_info(t).kind, uk = ty_info(u).kind;
  load_t(in.a[0], u, r0);
  if (t == u) {
    // the value as it is
  } else if (tk == TyKind::Bool) {
    if (uk == TyKind::Real) op(M::Lsh, {I(1), R(r0)});  // +-0 -> 0; everything else (NaN too) is not 0
    else op(M::Cmpi, {I(0), R(r0)});
    opc(M::Ldic, Cond::NE, {I(1), R(r0)});
  } else if (tk == TyKind::Real) {  // from an integer: nearest, ties to even (as C's conversion)
    ts_.i2f = true;
    if (typed::is_signed(u)) {
      op(M::Ldi, {R(r0), R(Reg::R7)});
      op(M::Absi, {R(r0), R(r0)});  // INT32_MIN: 2^31 as unsigned
      op(M::Call, {L(kI2fLabel)});
      op(M::Ldhi, {I(0x8000), R(r1)});
      op(M::Or, {R(r0), R(r1)});
      op(M::Cmpi, {I(0), R(Reg::R7)});
      opc(M::Ldic, Cond::LT, {R(r1), R(r0)});
    } else {
      op(M::Call, {L(kI2fLabel)});
    }
  } else if (uk == TyKind::Real) {
    real_to_int(t, false);
  } else {
    norm_t(t, r0);
  }
  op(M::Sti, {R(r0), Dv(in.a[1])});
}

// IDX.T i lo hi: R7 = i - lo if lo <= i <= hi (one unsigned compare of
// i - lo with hi - lo; a UDINT of 2^31 or more is outside every INT32 range);
// else the fault record in Sys and the end of the scan (docs/il.md, "Index faults")
void Gen::typed_index(const ldc::Instr& in) {
  const Ty t = in.ty;
  const int32_t lo = in.a[1].ival, hi = in.a[2].ival;
  ts_.span = uint32_t(hi) - uint32_t(lo);
  load_t(in.a[0], t, r0);
  std::string fault = fresh(), ok = fresh();
  if (!typed::is_signed(t)) {
    op(M::Cmpi, {I(0), R(r0)});
    branch(Cond::LT, fault);
  }
  load_imm32(lo, r1);
  op(M::Subi3, {R(r1), R(r0), R(Reg::R7)});
  load_imm32(int32_t(ts_.span), r1);
  op(M::Cmpi, {R(r1), R(Reg::R7)});
  branch(Cond::LS, ok);
  label(fault);
  const uint32_t sys = kDataBase + W_.offset[int(Area::Sys)];
  op(M::Ldi, {I(kFaultIndex), R(r1)});
  op(M::Sti, {R(r1), D(sys + kSysFaultWord)});
  load_imm32(int32_t(ts_.il_offset.at(ts_.next)), r1);
  op(M::Sti, {R(r1), D(sys + kSysFaultAtWord)});
  op(M::Sti, {R(r0), D(sys + kSysFaultValueWord)});
  if (typed::is_signed(t)) op(M::Ash3, {I(-31), R(r0), R(r1)});
  else op(M::Ldi, {I(0), R(r1)});
  op(M::Sti, {R(r1), D(sys + kSysFaultValueWord + 1)});
  jump(kExitLabel);  // the scan ends here
  label(ok);
}

// The one indirect access the loader's code check accepts (loader/c40_check.cpp):
// the element offset in R0 clamped (unsigned) to `limit`, added to `base`, all
// in eight words in a row.  After IDX the clamp never changes R0; it is what
// lets the check prove that the access stays inside the memory image.
void Gen::checked_access(uint32_t limit, uint32_t base, Instruction access) {
  op(M::Ldhi, {I(limit >> 16), R(r1)});
  op(M::Or, {I(limit & 0xFFFF), R(r1)});
  op(M::Cmpi, {R(r1), R(r0)});
  opc(M::Ldic, Cond::HI, {R(r1), R(r0)});
  op(M::Ldhi, {I(base >> 16), R(ar(0))});
  op(M::Or, {I(base & 0xFFFF), R(ar(0))});
  op(M::Addi, {R(r0), R(ar(0))});
  emit(std::move(access));
}

// LDX.T base stride r / STX.T s base stride: the element base + R7 * stride
// (the register the IDX right before set), one word per element on the C40
void Gen::typed_indexed(const ldc::Instr& in) {
  const Ty t = in.ty;
  const bool store = in.op == Op::TSTX;
  const ldc::Operand& base = in.a[store ? 1 : 0];
  const int32_t stride = in.a[store ? 2 : 1].ival;
  if (store) load_t(in.a[0], t, r2);
  op(M::Ldi, {R(Reg::R7), R(r0)});
  if (stride != 1) {
    if (stride >= -32768 && stride <= 32767) {
      op(M::Mpyi, {I(stride), R(r0)});
    } else {
      load_imm32(stride, r1);
      op(M::Mpyi, {R(r1), R(r0)});
    }
  }
  uint32_t limit = uint32_t(uint64_t(ts_.span) * uint32_t(stride));
  checked_access(limit, addr(base), parse(store ? "STI R2, *AR0" : "LDI *AR0, R2"));
  if (store) return;
  norm_t(t, r2);
  op(M::Sti, {R(r2), Dv(in.a[2])});
}

void Gen::typed(const ldc::Instr& in) {
  if (std::string why = c40_typed_refusal(in); !why.empty())
    throw CompileError(in.loc.line, in.loc.col, "the C40 cannot compile " + op_spelling(in) + ": " + why);
  if (op_info(in.op).push) return typed_compare(in);
  const Ty t = in.ty;
  std::string skip = skip_unless_power();
  switch (in.op) {
    case Op::TIDX: typed_index(in); break;
    case Op::TLDX: case Op::TSTX: typed_indexed(in); break;
    case Op::TDIV: case Op::TMOD:
      if (typed::is_real(t)) goto arith;  // IEEE: no S0
      typed_divmod(in);
      break;
    case Op::TMIN: case Op::TMAX: typed_minmax(in); break;
    case Op::TSHL: case Op::TSHR: case Op::TROL: case Op::TROR: typed_shift(in); break;
    case Op::TCONV: typed_conv(in); break;
    case Op::TTRUNC:
      load_t(in.a[0], in.src, r0);
      real_to_int(t, true);
      op(M::Sti, {R(r0), Dv(in.a[1])});
      break;
    case Op::TMOVE:
      load_t(in.a[0], t, r0);
      op(M::Sti, {R(r0), Dv(in.a[1])});
      break;
    case Op::TNOT: case Op::TNEG: case Op::TABS: {
      load_t(in.a[0], t, r0);
      if (in.op == Op::TNOT) {
        if (t == Ty::BOOL) op(M::Xor, {I(1), R(r0)});
        else op(M::Not, {R(r0), R(r0)});
      } else if (typed::is_real(t)) {  // the IEEE sign bit flipped or cleared
        if (in.op == Op::TNEG) {
          op(M::Ldhi, {I(0x8000), R(r1)});
          op(M::Xor, {R(r1), R(r0)});
        } else {  // MatIEC's `x < 0 ? -x : x`: -0.0 and a negative NaN keep their sign
          std::string keep = fresh();
          load_imm32(int32_t(0xFF800000u), r1);  // -inf: above it (as INT32) lie the positives and the negative NaNs
          op(M::Cmpi, {R(r1), R(r0)});
          branch(Cond::GT, keep);
          load_imm32(std::numeric_limits<int32_t>::min(), r1);  // -0.0
          op(M::Cmpi, {R(r1), R(r0)});
          branch(Cond::EQ, keep);
          op(M::Lsh, {I(1), R(r0)});
          op(M::Lsh, {I(-1), R(r0)});
          label(keep);
        }
      } else if (in.op == Op::TNEG) {
        op(M::Negi, {R(r0), R(r0)});
      } else if (typed::is_signed(t)) {
        op(M::Absi, {R(r0), R(r0)});  // the most negative value stays
      }
      norm_t(t, r0);
      op(M::Sti, {R(r0), Dv(in.a[1])});
      break;
    }
    arith:
    default: {  // ADD SUB MUL on integers, AND OR XOR; ADD SUB MUL DIV on REAL
      load_t(in.a[0], t, r0);
      load_t(in.a[1], t, r1);
      if (typed::is_real(t)) {
        const char* routine = in.op == Op::TADD ? kFaddLabel : in.op == Op::TSUB ? kFsubLabel
                            : in.op == Op::TMUL ? kFmulLabel : kFdivLabel;
        (in.op == Op::TMUL ? ts_.fmul : in.op == Op::TDIV ? ts_.fdiv : ts_.fadd) = true;
        op(M::Call, {L(routine)});
        op(M::Sti, {R(r0), Dv(in.a[2])});
        break;
      }
      switch (in.op) {
        case Op::TADD: op(M::Addi, {R(r1), R(r0)}); break;
        case Op::TSUB: op(M::Subi, {R(r1), R(r0)}); break;
        case Op::TMUL: mul32(); break;
        case Op::TAND: op(M::And, {R(r1), R(r0)}); break;
        case Op::TOR: op(M::Or, {R(r1), R(r0)}); break;
        case Op::TXOR: op(M::Xor, {R(r1), R(r0)}); break;
        default: throw std::logic_error(std::string("c40 backend: no code for ") + op_spelling(in));
      }
      norm_t(t, r0);
      op(M::Sti, {R(r0), Dv(in.a[2])});
    }
  }
  label(skip);
}

void Gen::flow(const ldc::Instr& in) {
  if (in.op == Op::LOOP)
    throw CompileError(in.loc.line, in.loc.col,
                       "the C40 cannot compile LOOP (a loop that goes back): its code check admits forward branches "
                       "only (docs/c40.md); run the program on another engine");
  test_top();
  if (in.op == Op::END) return opc(M::Retsc, Cond::NE, {});
  std::string skip = fresh();
  branch(Cond::EQ, skip);
  jump(label_name(in.a[0].label));  // BR: 24-bit reach across the program
  label(skip);
}

// The shift-subtract division (docs/c40.md): R0 = a, R1 = b (b != 0, -1);
// returns R0 = a / b truncated toward zero, R1 = a % b (sign of a).  The bit
// lengths of |a| and |b| come from FLOAT's exponent (through the stack), so
// only the k = len|a| - len|b| + 1 quotient bits that can be 1 take a step:
// the remainder starts as |a| >> k, the dividend as |a| << (32 - k).  Steps
// of 10 cycles (a delayed DB).  Uses R2-R6, AR0 and two stack words.
const char* const kDivRoutine[] = {
    "LDI R0, R4",          // sign of the remainder: sign of a
    "XOR3 R1, R0, R5",     // sign of the quotient: bit 31 of a ^ b
    "ABSI R0, R0",         // |a| (INT32_MIN stays 0x80000000 = 2^31 unsigned)
    "ABSI R1, R1",         // |b|
    "FLOAT R0, R2",
    "PUSHF R2",
    "POP R2",
    "ASH -24, R2",         // ea = len|a| - 1 (-128 for 0)
    "LDI R0, R3",
    "LDILT 31, R2",        // |a| = 2^31
    "FLOAT R1, R3",
    "PUSHF R3",
    "POP R3",
    "ASH -24, R3",         // eb
    "CMPI 0, R1",
    "LDILT 31, R3",        // |b| = 2^31
    "SUBI3 R3, R2, R3",    // ea - eb
    "BLT div_zero",        // |a| < |b|: quotient 0
    "ADDI 1, R3",          // k steps, 1..32
    "NEGI R3, R2",
    "LSH3 R2, R0, R2",     // remainder = |a| >> k
    "ADDI3 -32, R3, R6",
    "NEGI R6, R6",
    "LSH3 R6, R0, R0",     // dividend = |a| << (32 - k)
    "SUBI 1, R3",
    "LDI R3, AR0",         // DB counts k - 1 down to -1
    "div_step: LSH3 -31, R0, R3",
    "LSH 1, R2",
    "OR R3, R2",           // remainder:dividend <<= 1
    "LSH 1, R0",
    "SUBI3 R1, R2, R3",    // remainder - |b|, C = borrow
    "LDIHS R3, R2",        // no borrow: subtract (LDI leaves C alone)
    "DBUD AR0, div_step",
    "LDI 0, R3",
    "LDIHS 1, R3",         // the quotient bit
    "OR R3, R0",
    "div_signs: NEGI R0, R3",
    "NEGI R2, R1",
    "CMPI 0, R5",
    "LDILT R3, R0",
    "CMPI 0, R4",
    "LDIGE R2, R1",
    "RETSU",
    "div_zero: LDI R0, R2",
    "LDI 0, R0",
    "BR div_signs",
};

// REAL division (docs/c40.md): R0 = a, R1 = b (b != 0); returns R0 = a / b.
// Both are split into mantissa and exponent through the stack, the mantissas
// divided (RCPF, two Newton steps, one correction: no underflow inside for any
// operands), and the quotient scaled by 2^(ea - eb) in two exact steps, so
// MPYF saturates or flushes as the range requires.  Uses R2-R6, two stack words.
const char* const kDivfRoutine[] = {
    "LDF R0, R6",
    "PUSHF R0",
    "POP R2",
    "ASH3 -24, R2, R4",    // ea
    "LSH 8, R2",
    "LSH -8, R2",
    "PUSH R2",
    "POPF R0",             // ma
    "PUSHF R1",
    "POP R2",
    "ASH3 -24, R2, R5",    // eb
    "LSH 8, R2",
    "LSH -8, R2",
    "PUSH R2",
    "POPF R1",             // mb
    "SUBI R5, R4",         // k = ea - eb
    "RCPF R1, R2",
    "MPYF3 R2, R1, R3",
    "NEGF R3, R3",
    "ADDF 2.0, R3",
    "MPYF R3, R2",
    "MPYF3 R2, R1, R3",
    "NEGF R3, R3",
    "ADDF 2.0, R3",
    "MPYF R3, R2",         // x = 1 / mb
    "MPYF3 R2, R0, R3",
    "MPYF 1.0, R3",        // q = ma x, as MPYF sees it
    "MPYF3 R3, R1, R5",
    "SUBF3 R5, R0, R5",    // r = ma - mb q
    "MPYF R2, R5",
    "ADDF R5, R3",         // q + r x
    "ASH3 -1, R4, R5",     // k1 = k >> 1
    "SUBI3 R5, R4, R4",    // k2 = k - k1
    "LSH 24, R5",
    "PUSH R5",
    "POPF R5",             // 2^k1
    "MPYF R5, R3",
    "LSH 24, R4",
    "PUSH R4",
    "POPF R4",             // 2^k2
    "MPYF3 R4, R3, R0",
    "CMPF 0.0, R6",
    "LDFEQ 0.0, R0",       // a = 0: 0
    "RETSU",
};

// -O1, after generation: a branch to the label right after it is dropped.
void drop_jumps_to_next(std::vector<Item>& items, std::vector<uint32_t>& starts) {
  std::vector<char> drop(items.size(), 0);
  for (size_t i = 0; i < items.size(); i++) {
    const Item& it = items[i];
    if (it.kind != as::ItemKind::Instruction || (it.inst.mnemonic != M::Br && it.inst.mnemonic != M::Bc)) continue;
    if (it.inst.ops[0].kind == OperandKind::Label && as::label_follows(items, i, it.inst.ops[0].label, drop)) drop[i] = 1;
  }
  as::remove_items(items, drop, starts);
}

// ------------------------------------------------------------ delay slots (-O1)
//
// A standard branch costs 4 cycles, a delayed one (BcondD, BRD) 1 and always
// runs the three instructions after it.  fill_delay_slots turns a branch into
// its delayed form when at least two slots get useful instructions (so the
// code grows by one NOP word at most), and neither path gets slower:
//  * from before the branch: an instruction that commutes with the ones it is
//    moved past (for a conditional branch, the one that sets its flags) runs
//    on both paths as before, one cycle of flush saved on both;
//  * from after a conditional branch: an instruction without a memory access
//    (no wait state) whose results are dead where the branch goes, saved on
//    the fall-through path, the same cycle on the taken one as the flush;
//  * a NOP fills the rest (1 cycle, as the flush it replaces).
// Moves stay between two IL notes, so every IL instruction keeps its code.

constexpr unsigned kFlagsBit = 32;
constexpr uint64_t kFlags = uint64_t(1) << kFlagsBit;
uint64_t bit(Reg r) { return uint64_t(1) << unsigned(r); }

// Registers an instruction reads and writes (bits 0-31 by register number,
// kFlags the status flags), its memory accesses, and whether it may not move.
struct Effect {
  uint64_t use = 0, def = 0;
  bool mem = false, store = false, fixed = false;
};
Effect effect_of(const Instruction& i) {
  Effect e;
  for (unsigned k = 0; k < i.num_operands; k++) {
    const Operand& o = i.ops[k];
    if (o.kind == OperandKind::Direct) e.mem = true, e.use |= bit(Reg::DP);
    if (o.kind == OperandKind::Ind) e.fixed = true;
  }
  auto reg_use = [&](unsigned k) {
    if (k < i.num_operands && i.ops[k].kind == OperandKind::Reg) e.use |= bit(i.ops[k].reg);
  };
  switch (i.mnemonic) {
    case M::Br: case M::Brd: case M::Bc: case M::Bcd: case M::Call: case M::Callc: case M::Retsc: case M::Dbc:
    case M::Dbcd: case M::Push: case M::Pop: case M::Pushf: case M::Popf: case M::Ldpk: case M::Lda: case M::Nop:
    case M::Word: case M::Count_:
      e.fixed = true;
      return e;
    case M::Sti: case M::Stf: reg_use(0); e.store = true; return e;
    case M::Cmpi: case M::Cmpf: case M::Tstb: case M::Cmpi3: case M::Cmpf3: case M::Tstb3:
      reg_use(0), reg_use(1), e.def |= kFlags;
      return e;
    default: break;
  }
  unsigned n = i.num_operands;
  for (unsigned k = 0; k + 1 < n; k++) reg_use(k);
  Reg d = i.ops[n - 1].reg;
  e.def |= bit(d);
  if (is_extended(d)) e.def |= kFlags;
  switch (i.mnemonic) {  // these write their destination without reading it
    case M::Ldi: case M::Ldf: case M::Ldhi: case M::Float: case M::Fix: case M::Frieee: case M::Toieee: case M::Absi:
    case M::Negi: case M::Not: case M::Absf: case M::Negf: case M::Rcpf: case M::Addi3: case M::And3: case M::Andn3:
    case M::Ash3: case M::Lsh3: case M::Mpyi3: case M::Or3: case M::Subi3: case M::Xor3: case M::Addf3: case M::Mpyf3:
    case M::Subf3:
      break;
    case M::Ldic: case M::Ldfc: e.use |= bit(d) | kFlags; break;  // keep the destination when false
    default: e.use |= bit(d); break;                               // d = d op src
  }
  return e;
}

bool is_branch(const Instruction& i) { return (i.mnemonic == M::Bc || i.mnemonic == M::Br) && i.ops[0].kind == OperandKind::Label; }

// What lives across rung blocks: the stack registers, the mask, DP, SP.
constexpr uint64_t kLiveAcross = (uint64_t(1) << unsigned(Reg::R8)) | (uint64_t(1) << unsigned(Reg::R9)) |
                                 (uint64_t(1) << unsigned(Reg::R10)) | (uint64_t(1) << unsigned(Reg::R11)) |
                                 (uint64_t(0x3E) << unsigned(Reg::AR0)) | (uint64_t(1) << unsigned(Reg::DP)) |
                                 (uint64_t(1) << unsigned(Reg::SP));

// live[i]: what is live before item i (labels and notes: before what follows).
std::vector<uint64_t> liveness(const std::vector<Item>& items) {
  std::map<std::string, size_t> at;
  for (size_t i = 0; i < items.size(); i++)
    if (items[i].kind == as::ItemKind::Label) at[items[i].label.str()] = i;
  std::vector<uint64_t> live(items.size() + 1, 0);
  live[items.size()] = kLiveAcross;
  auto target = [&](const Instruction& in) {
    auto t = in.ops[0].kind == OperandKind::Label ? at.find(in.ops[0].label) : at.end();
    return t == at.end() ? kLiveAcross : live[t->second];
  };
  for (bool changed = true; changed;) {
    changed = false;
    for (size_t i = items.size(); i-- > 0;) {
      uint64_t l = live[i + 1];
      if (items[i].kind == as::ItemKind::Instruction) {
        const Instruction& in = items[i].inst;
        switch (in.mnemonic) {
          case M::Br: l = target(in); break;
          case M::Bc: l |= target(in) | kFlags; break;
          case M::Retsc: l = (in.cond == Cond::U ? 0 : l | kFlags) | kLiveAcross; break;
          case M::Call: case M::Callc: l = ~uint64_t(0); break;  // whatever the routine may read
          default: {
            Effect e = effect_of(in);
            l = (l & ~(e.def & ~e.use)) | e.use;
            if (e.fixed) l = ~uint64_t(0);  // LDPK, NOP, a delayed branch: taken as reading everything
          }
        }
      }
      if (l != live[i]) live[i] = l, changed = true;
    }
  }
  return live;
}

// Is item k in the delay slots of a delayed branch (one of the three
// instructions after it)?  Those stay where they are.
bool in_slot(const std::vector<Item>& items, size_t k) {
  int seen = 0;
  for (size_t j = k; j-- > 0 && seen < 3;) {
    if (items[j].kind != as::ItemKind::Instruction) continue;
    if (is_delayed(items[j].inst.mnemonic)) return true;
    seen++;
  }
  return false;
}

// The instructions among v[0..end) that can move into the delay slots of a
// branch placed at `end` (its three after it), ascending: walking back over
// the instructions of this IL note, each one that commutes with those that
// stay and with the branch's flag test.
std::vector<size_t> movable_before(const std::vector<Item>& v, size_t end, bool cond, uint64_t dead_after) {
  std::vector<size_t> moved, stay;
  for (size_t k = end; k-- > 0 && moved.size() < 3;) {
    if (v[k].kind != as::ItemKind::Instruction || in_slot(v, k)) break;
    Effect x = effect_of(v[k].inst);
    if (x.fixed) break;
    bool ok = true;
    uint64_t shadow = 0;  // defined by instructions that stay, between x and here
    auto past = [&](const Effect& y) {
      if ((x.use & y.def) || (y.use & ~shadow & x.def)) ok = false;
      if ((x.store && (y.mem || y.store)) || (y.store && x.mem)) ok = false;
      shadow |= y.def;
    };
    for (auto it = stay.rbegin(); it != stay.rend(); ++it) past(effect_of(v[*it].inst));
    Effect be;
    if (cond) be.use = kFlags;
    past(be);
    if ((x.def & shadow) & ~dead_after) ok = false;  // x's result would now be the last one
    if (ok) moved.insert(moved.begin(), k);
    else stay.push_back(k);
  }
  return moved;
}

// From after a conditional branch at b: instructions without memory access
// whose results are dead at the target, while slots are left; returns the end.
size_t movable_after(const std::vector<Item>& items, size_t b, bool cond, size_t taken, uint64_t at_target) {
  size_t z_end = b + 1;
  if (cond)
    while (z_end < items.size() && taken + (z_end - b - 1) < 3 && items[z_end].kind == as::ItemKind::Instruction) {
      Effect z = effect_of(items[z_end].inst);
      if (z.fixed || z.mem || z.store || (z.def & at_target)) break;
      z_end++;
    }
  return z_end;
}

// Tries to make the branch at item b delayed; true if it did.
bool delay_branch(std::vector<Item>& items, size_t b, std::vector<uint32_t>& starts) {
  const Instruction br = items[b].inst;
  const bool cond = br.mnemonic == M::Bc;
  std::vector<uint64_t> live = liveness(items);
  uint64_t at_target = kLiveAcross;
  for (size_t i = 0; i < items.size(); i++)
    if (items[i].kind == as::ItemKind::Label && items[i].label == br.ops[0].label) at_target = live[i];
  const uint64_t dead_after = ~(at_target | (cond ? live[b + 1] : 0));
  std::vector<size_t> moved = movable_before(items, b, cond, dead_after);
  size_t z_end = movable_after(items, b, cond, moved.size(), at_target);
  size_t filled = moved.size() + (z_end - b - 1);
  if (filled < 2) return false;
  std::vector<Item> out;
  out.reserve(items.size() + 3);
  std::vector<uint32_t> index(items.size() + 1);
  for (size_t i = 0; i < items.size(); i++) {
    index[i] = uint32_t(out.size());
    if (std::find(moved.begin(), moved.end(), i) != moved.end()) continue;
    if (i == b) {
      Item d = items[i];
      d.inst.mnemonic = cond ? M::Bcd : M::Brd;
      out.push_back(std::move(d));
      for (size_t m : moved) out.push_back(items[m]);
    } else {
      out.push_back(std::move(items[i]));
    }
    if (i + 1 == z_end)
      for (size_t p = filled; p < 3; p++) out.push_back(Item::instr(make(M::Nop)));
  }
  index[items.size()] = uint32_t(out.size());
  for (auto& s : starts) s = index[s];
  items = std::move(out);
  return true;
}

// A block with a backward branch (the sign fix-up after __divi): the analysis
// again after every change.
void fill_delay_slots_slow(std::vector<Item>& items, std::vector<uint32_t>& starts) {
  for (size_t i = 0; i < items.size(); i++)
    if (items[i].kind == as::ItemKind::Instruction && is_branch(items[i].inst) && delay_branch(items, i, starts)) {
      // the branch moved up by the instructions taken from before it; go on after its slots
      while (items[i].kind != as::ItemKind::Instruction || !is_delayed(items[i].inst.mnemonic)) i--;
      i += 3;
    }
}

// fill_delay_slots makes one pass over a rung block.  The branches of rung
// code only go forward (JMP and the templates' own), so what is live after a
// branch and at its target depends only on the code after the branch, which
// the pass has not changed yet: one liveness analysis of the block serves
// every branch.  (A block with a backward branch, which only the signed
// division's fix-up makes, takes the slow path above.)  The instructions taken
// from before a branch are among the last ones already emitted.
void fill_delay_slots(std::vector<Item>& items, std::vector<uint32_t>& starts) {
  std::map<std::string, size_t> label_at;
  for (size_t i = 0; i < items.size(); i++)
    if (items[i].kind == as::ItemKind::Label) label_at[items[i].label.str()] = i;
  bool forward = true;
  for (size_t i = 0; i < items.size(); i++)
    if (items[i].kind == as::ItemKind::Instruction) {
      const Instruction& in = items[i].inst;
      for (unsigned k = 0; k < in.num_operands; k++)
        if (in.ops[k].kind == OperandKind::Label) {
          auto t = label_at.find(in.ops[k].label);
          if (t != label_at.end() && t->second <= i) forward = false;
        }
    }
  if (!forward) return fill_delay_slots_slow(items, starts);
  std::vector<uint64_t> live = liveness(items);
  std::vector<Item> out;
  out.reserve(items.size() + items.size() / 8 + 4);
  std::vector<size_t> src;  // for each item of `out`, its index in `items` (SIZE_MAX: a NOP added here)
  std::vector<uint32_t> index(items.size() + 1, 0);
  auto emit = [&](size_t i) {
    index[i] = uint32_t(out.size());
    src.push_back(i);
    out.push_back(std::move(items[i]));
  };
  for (size_t b = 0; b < items.size();) {
    if (items[b].kind != as::ItemKind::Instruction || !is_branch(items[b].inst)) {
      emit(b++);
      continue;
    }
    const Instruction br = items[b].inst;
    const bool cond = br.mnemonic == M::Bc;
    auto t = label_at.find(br.ops[0].label);
    const uint64_t at_target = t == label_at.end() ? kLiveAcross : live[t->second];
    const uint64_t dead_after = ~(at_target | (cond ? live[b + 1] : 0));
    // from before: the instructions just emitted; from after: those not yet
    std::vector<size_t> moved = movable_before(out, out.size(), cond, dead_after);
    size_t z_end = movable_after(items, b, cond, moved.size(), at_target);
    const size_t filled = moved.size() + (z_end - b - 1);
    if (filled < 2) {
      emit(b++);
      continue;
    }
    // Re-emit the tail from the first moved instruction: those that stay,
    // the delayed branch, the moved ones, the ones from after, NOPs.  An item
    // moved into the slots keeps the index of the item that now follows it in
    // its old place (as removing it and inserting it after the branch would).
    const size_t from = moved.empty() ? out.size() : moved.front();
    std::vector<Item> tail;
    std::vector<size_t> tail_src;
    for (size_t k = from; k < out.size(); k++) tail.push_back(std::move(out[k])), tail_src.push_back(src[k]);
    out.resize(from);
    src.resize(from);
    std::vector<size_t> pending;  // moved items waiting for the next kept one
    auto place = [&](Item&& it, size_t orig) {
      if (orig != SIZE_MAX) {
        index[orig] = uint32_t(out.size());
        for (size_t m : pending) index[m] = uint32_t(out.size());
        pending.clear();
      }
      src.push_back(orig);
      out.push_back(std::move(it));
    };
    std::vector<std::pair<Item, size_t>> slot;
    for (size_t k = 0; k < tail.size(); k++) {
      if (std::find(moved.begin(), moved.end(), from + k) != moved.end()) {
        pending.push_back(tail_src[k]);
        slot.emplace_back(std::move(tail[k]), tail_src[k]);
      } else {
        place(std::move(tail[k]), tail_src[k]);
      }
    }
    Item d = std::move(items[b]);
    d.inst.mnemonic = cond ? M::Bcd : M::Brd;
    place(std::move(d), b);
    for (auto& [it, orig] : slot) {  // their index is already the branch's
      src.push_back(orig);
      out.push_back(std::move(it));
    }
    for (size_t z = b + 1; z < z_end; z++) emit(z);
    for (size_t n = filled; n < 3; n++) src.push_back(SIZE_MAX), out.push_back(Item::instr(make(M::Nop)));
    b = z_end;
  }
  index[items.size()] = uint32_t(out.size());
  for (auto& s : starts) s = index[s];
  items = std::move(out);
}

// ------------------------------------------------------------ reloads (-O2)
//
// A load of what a register holds already is dropped when the flags it would
// set are dead: a rung that starts by loading what the rung before it stored
// from the same register (`STI R8, @Y0` ... `LDI @Y0, R8`), or a constant
// loaded again (`LDI 0, R0` of each RSTT in a row).  Held follows, from block
// to block, what the registers hold: an image word or a constant.  Forgotten:
// a register's value when anything else writes the register, a word when it
// is written; everything at a call, an indirect store and a label that a
// branch may reach (where DP is the main page again: -O1 restores it right
// after each far access).
struct Known {
  bool constant;
  int64_t a, b;  // constant: (value, 0); word: (DP page, offset)
  bool operator==(const Known&) const = default;
};

struct Held {
  std::map<Reg, std::vector<Known>> reg;  // a register may equal a constant and several words
  int64_t dp = kDataPage;
  bool holds(Reg r, const Known& k) const {
    auto it = reg.find(r);
    return it != reg.end() && std::find(it->second.begin(), it->second.end(), k) != it->second.end();
  }
};

// the value `LDI x, Rk` gives Rk, if x is a constant or an image word
std::optional<Known> loaded(const Instruction& in, int64_t dp) {
  if (in.mnemonic != M::Ldi || in.num_operands != 2 || in.ops[1].kind != OperandKind::Reg) return std::nullopt;
  if (in.ops[0].kind == OperandKind::Direct) return Known{false, dp, in.ops[0].imm};
  if (in.ops[0].kind == OperandKind::Imm) return Known{true, in.ops[0].imm, 0};
  return std::nullopt;
}

bool redundant_load(const Instruction& in, const Held& h) {
  std::optional<Known> k = loaded(in, h.dp);
  return k && h.holds(in.ops[1].reg, *k);
}

void track(const Instruction& in, Held& h) {
  if (in.mnemonic == M::Ldpk) { h.dp = in.ops[0].imm; return; }
  if (in.mnemonic == M::Call || in.mnemonic == M::Callc) { h.reg.clear(); return; }
  Effect e = effect_of(in);
  if (e.store) {
    if (in.ops[1].kind != OperandKind::Direct) { h.reg.clear(); return; }
    Known w{false, h.dp, in.ops[1].imm};
    for (auto& [r, ks] : h.reg) std::erase(ks, w);
    if (in.mnemonic == M::Sti && in.ops[0].kind == OperandKind::Reg) h.reg[in.ops[0].reg].push_back(w);
    return;
  }
  std::erase_if(h.reg, [&](const auto& kv) { return writes_reg(in, kv.first); });
  if (std::optional<Known> k = loaded(in, h.dp)) h.reg[in.ops[1].reg] = {*k};
}

void drop_reloads(std::vector<Item>& items, std::vector<uint32_t>& starts, Held& h) {
  std::vector<uint64_t> live = liveness(items);
  std::set<std::string> targets;  // the block's local labels that a branch names
  for (const Item& it : items)
    if (it.kind == as::ItemKind::Instruction)
      for (unsigned k = 0; k < it.inst.num_operands; k++)
        if (it.inst.ops[k].kind == OperandKind::Label) targets.insert(it.inst.ops[k].label);
  std::vector<char> drop(items.size(), 0);
  for (size_t i = 0; i < items.size(); i++) {
    if (items[i].kind == as::ItemKind::Label && (items[i].global || targets.count(items[i].label.str()))) {
      h.reg.clear();
      h.dp = kDataPage;
    }
    if (items[i].kind != as::ItemKind::Instruction) continue;
    if (redundant_load(items[i].inst, h) && !(live[i + 1] & kFlags)) drop[i] = 1;
    else track(items[i].inst, h);
  }
  as::remove_items(items, drop, starts);
}


// ---- the routines of the typed instructions (emitted only when used)

// UDINT division: R0 = a, R1 = b (unsigned, b != 0); returns R0 = a / b,
// R1 = a % b.  One restoring step per bit: the remainder:dividend pair is
// shifted left and b subtracted where it fits (unsigned: SUBI3's borrow).
// The remainder never needs a 33rd bit: before step j it is at most the j - 1
// dividend bits shifted in so far, below 2^31 before the last step.  Uses R2-R4, AR0.
const char* const kDivuRoutine[] = {
    "LDI 0, R2",
    "LDI 31, AR0",
    "divu_step: LSH3 -31, R0, R3",
    "LSH 1, R0",
    "LSH 1, R2",
    "OR R3, R2",           // remainder:dividend <<= 1
    "SUBI3 R1, R2, R3",    // remainder - b, C = borrow
    "LDIHS R3, R2",        // no borrow: subtract (LDI leaves C alone)
    "LDI 0, R4",
    "LDIHS 1, R4",
    "OR R4, R0",           // the quotient bit
    "DBU AR0, divu_step",
    "LDI R2, R1",
    "RETSU",
};

// IEEE binary32 bits in R0 -> the magnitude of the integer, modulo 2^32:
// R1 = 0 rounds to nearest (ties to even, typed::real_to_int), 1 truncates.
// Exponent E: the mantissa m (hidden bit set) shifted by E - 150; NaN, the
// infinities and everything at or above 2^55 give 0.  Uses R2-R6.
const char* const kF2iRoutine[] = {
    "LSH3 -23, R0, R2",
    "AND 0FFh, R2",        // E
    "LSH3 9, R0, R3",
    "LSH -9, R3",
    "LDHI 080h, R4",
    "OR R4, R3",           // m
    "SUBI 150, R2",        // the shift E - 150
    "BLT f2i_right",
    "LSH3 R2, R3, R0",
    "CMPI 31, R2",
    "LDIGT 0, R0",
    "RETSU",
    "f2i_right: CMPI -25, R2",
    "LDILT -25, R2",       // below 0.5: m >> 25 = 0, and m < half: no rounding up
    "LSH3 R2, R3, R0",     // q = m >> s
    "CMPI 0, R1",
    "RETSNE",              // truncated
    "NEGI R2, R5",
    "SUBI 1, R5",
    "LDI 1, R4",
    "LSH R5, R4",          // half = 1 << (s - 1)
    "LSH3 1, R4, R6",
    "SUBI 1, R6",
    "AND R3, R6",          // rem = m & (2^s - 1)
    "AND3 1, R0, R5",
    "ADDI R5, R6",         // rem + odd > half: above half, or a tie with q odd
    "ADDI3 1, R0, R5",
    "CMPI R4, R6",
    "LDIGT R5, R0",
    "RETSU",
};

// An unsigned 32-bit magnitude in R0 -> the IEEE binary32 bits of its
// nearest value (ties to even), positive.  The bit length from FLOAT's exponent
// (through the stack, as __divi); at most 24 bits are exact, more are rounded
// and the carry of a rounding up runs into the exponent field.  Uses R2-R6.
const char* const kI2fRoutine[] = {
    "CMPI 0, R0",
    "RETSEQ",
    "FLOAT R0, R2",
    "PUSHF R2",
    "POP R2",
    "ASH -24, R2",         // e = bit length - 1
    "LDI R0, R3",
    "LDILT 31, R2",        // 2^31 and above: FLOAT saw a negative number
    "LDI 23, R3",
    "SUBI R2, R3",         // 23 - e
    "BLT i2f_round",
    "LSH R3, R0",          // exact
    "BR i2f_pack",
    "i2f_round: NEGI R3, R5",
    "SUBI 1, R5",
    "LDI 1, R4",
    "LSH R5, R4",          // half = 1 << (s - 1), s = e - 23
    "LSH3 1, R4, R6",
    "SUBI 1, R6",
    "AND R0, R6",          // rem
    "LSH R3, R0",          // q = m >> s
    "AND3 1, R0, R5",
    "ADDI R5, R6",
    "ADDI3 1, R0, R5",
    "CMPI R4, R6",
    "LDIGT R5, R0",
    "i2f_pack: ADDI 126, R2",
    "LSH 23, R2",
    "ADDI R2, R0",         // (e + 126) << 23 + the mantissa with its hidden bit
    "RETSU",
};

// ---- REAL arithmetic as IEEE binary32 in integer code (ADD SUB MUL DIV .REAL):
// the C40's own floating point truncates and has no NaN, infinity or
// denormal, so these compute what x86-64's addss / subss / mulss / divss do,
// bit for bit: round to nearest, ties to even; gradual underflow; a NaN
// operand gives itself quieted (the first one if both are), an invalid
// operation the default NaN 0xFFC00000.  R0 = a, R1 = b (IEEE bits); the
// result in R0.  Use R2-R7, AR0 and two stack words.

// R0 = a, R1 = b: a NaN (|x| > 0x7F800000) returns itself quieted
#define LDC_C40_NAN_CHECK(p)                                                         \
    p "_nan: LSH3 1, R0, R3", "LDHI 0FF00h, R4", "CMPI R4, R3", "BHI fnan_a",      \
    "LSH3 1, R1, R3", "CMPI R4, R3", "BHI fnan_b"

// __fmul and __fdiv begin alike: the NaN check, then the sign of the result
// in R2, the biased exponents in R5 (a) and R6 (b), |a| and |b| shifted left
// by one in R3 and R4; a = inf goes to p_ainf, and the flags are left of
// CMPI 255, R6 (b = inf: BEQ) for the routine's own branch.
#define LDC_C40_MULDIV_PROLOGUE(p)                                                   \
    LDC_C40_NAN_CHECK(p), "XOR3 R1, R0, R2", "LDHI 08000h, R3", "AND R3, R2",      \
    "LSH3 -23, R0, R5", "AND 0FFh, R5", "LSH3 -23, R1, R6", "AND 0FFh, R6",         \
    "LSH3 1, R0, R3", "LSH3 1, R1, R4", "CMPI 255, R5", "BEQ " p "_ainf", "CMPI 255, R6"

// M in R0 (0 < M < 2^31), the exponent e' in R1, the sign in R2 (0 or
// 0x80000000): the value M * 2^(e' - 156), rounded.  M is first shifted so
// that its leading 1 is bit 29 (bits 5-0 are then below the 24-bit mantissa;
// what a right shift drops is kept as a sticky bit 0), then right again while
// the exponent is below 1 (the denormals); the carry of rounding up runs into
// the exponent field, up to the infinity.
const char* const kFpackRoutine[] = {
    "FLOAT R0, R3",
    "PUSHF R3",
    "POP R3",
    "ASH -24, R3",         // the leading 1's position
    "SUBI 29, R3",
    "ADDI R3, R1",
    "CMPI 0, R3",
    "BLE fpack_left",
    "LDI 1, R4",
    "LSH R3, R4",
    "SUBI 1, R4",
    "AND R0, R4",          // the bits shifted out
    "NEGI R3, R5",
    "LSH R5, R0",
    "CMPI 0, R4",
    "LDINE 1, R4",
    "OR R4, R0",           // sticky
    "BR fpack_sub",
    "fpack_left: NEGI R3, R3",
    "LSH R3, R0",
    "fpack_sub: CMPI 1, R1",
    "BGE fpack_round",
    "LDI 1, R3",
    "SUBI R1, R3",         // 1 - e' places to the denormal
    "LDI 1, R1",
    "CMPI 31, R3",
    "LDIGT 31, R3",
    "LDI 1, R4",
    "LSH R3, R4",
    "SUBI 1, R4",
    "AND R0, R4",
    "NEGI R3, R5",
    "LSH R5, R0",
    "CMPI 0, R4",
    "LDINE 1, R4",
    "OR R4, R0",
    "fpack_round: AND3 63, R0, R4",
    "LSH -6, R0",
    "AND3 1, R0, R5",
    "ADDI R5, R4",         // above half, or half with an odd mantissa
    "ADDI3 1, R0, R5",
    "CMPI 32, R4",
    "LDIGT R5, R0",
    "CMPI 255, R1",
    "BGE finf",
    "SUBI 1, R1",
    "LSH 23, R1",
    "ADDI R1, R0",         // the hidden bit carries into the exponent (254 and a carry: the infinity)
    "OR R2, R0",
    "RETSU",
    // the shared endings of __fadd, __fmul, __fdiv
    "finf: LDHI 07F80h, R0",
    "OR R2, R0",
    "RETSU",
    "fzero: LDI R2, R0",
    "RETSU",
    "fdefault_nan: LDHI 0FFC0h, R0",
    "RETSU",
    "fnan_a: LDHI 040h, R3",
    "OR R3, R0",
    "RETSU",
    "fnan_b: LDHI 040h, R3",
    "OR3 R3, R1, R0",
    "RETSU",
};

// R0 = a, R1 = b: the mantissas with their hidden bit (none, and exponent 1,
// for a denormal) in R0 and R1, the exponents in R5 and R6
#define LDC_C40_UNPACK                                                                              \
    "LDHI 080h, R3", "CMPI 0, R5", "LDIEQ 0, R3", "LDIEQ 1, R5", "LSH 9, R0", "LSH -9, R0", "OR R3, R0", \
    "LDHI 080h, R3", "CMPI 0, R6", "LDIEQ 0, R3", "LDIEQ 1, R6", "LSH 9, R1", "LSH -9, R1", "OR R3, R1"

// __fsub: b's sign flipped (not a NaN's: it is returned as it is), then __fadd
const char* const kFsubRoutine[] = {
    "LSH3 1, R1, R3",
    "LDHI 0FF00h, R4",
    "CMPI R4, R3",
    "BHI __fadd",
    "LDHI 08000h, R3",
    "XOR R3, R1",
};

// __fadd: the larger magnitude first (its sign is the result's), the other
// aligned to it with a sticky bit, both with 6 bits below their mantissa
// (exact for the shifts of 0 and 1 after which a subtraction cancels)
const char* const kFaddRoutine[] = {
    LDC_C40_NAN_CHECK("fadd"),
    "LSH3 -23, R0, R5",
    "AND 0FFh, R5",
    "LSH3 -23, R1, R6",
    "AND 0FFh, R6",
    "CMPI 255, R5",
    "BEQ fadd_ainf",
    "CMPI 255, R6",
    "BEQ fadd_retb",
    "LSH3 1, R0, R3",
    "BEQ fadd_azero",
    "LSH3 1, R1, R4",
    "BEQ fadd_reta",
    "CMPI R4, R3",
    "BHS fadd_ordered",
    "LDI R0, R3",          // |a| < |b|: exchange
    "LDI R1, R0",
    "LDI R3, R1",
    "LDI R5, R3",
    "LDI R6, R5",
    "LDI R3, R6",
    "fadd_ordered: LDHI 08000h, R2",
    "AND R0, R2",
    "XOR3 R1, R0, R7",     // negative: the signs differ
    LDC_C40_UNPACK,
    "LSH 6, R0",
    "LSH 6, R1",
    "SUBI3 R6, R5, R3",    // the exponent difference
    "CMPI 31, R3",
    "LDIGT 31, R3",
    "LDI 1, R4",
    "LSH R3, R4",
    "SUBI 1, R4",
    "AND R1, R4",
    "NEGI R3, R6",
    "LSH R6, R1",
    "CMPI 0, R4",
    "LDINE 1, R4",
    "OR R4, R1",
    "CMPI 0, R7",
    "BLT fadd_sub",
    "ADDI R1, R0",
    "BR fadd_pack",
    "fadd_sub: SUBI R1, R0",
    "BEQ fadd_zero",       // x - x = +0
    "fadd_pack: LDI R5, R1",
    "BR __fpack",
    "fadd_zero: LDI 0, R0",
    "RETSU",
    "fadd_ainf: CMPI 255, R6",
    "BNE fadd_reta",
    "XOR3 R1, R0, R3",
    "BGE fadd_reta",
    "BR fdefault_nan",     // inf - inf
    "fadd_azero: LSH3 1, R1, R4",
    "BNE fadd_retb",
    "AND R1, R0",          // -0 only if both are -0
    "RETSU",
    "fadd_retb: LDI R1, R0",
    "fadd_reta: RETSU",
};

// __fmul: the 48-bit product of the mantissas from 12-bit halves (MPYI
// multiplies 24 bits) in R6:R4, shifted so its leading 1 is bit 29 or below
// (sticky), the exponent ea + eb - 144 + that shift
const char* const kFmulRoutine[] = {
    LDC_C40_MULDIV_PROLOGUE("fmul"),
    "BEQ fmul_binf",
    "CMPI 0, R3",
    "BEQ fzero",
    "CMPI 0, R4",
    "BEQ fzero",
    LDC_C40_UNPACK,
    "ADDI R6, R5",         // ea + eb
    "LSH3 -12, R0, R7",    // ah
    "AND 0FFFh, R0",       // al
    "LSH3 -12, R1, R3",    // bh
    "AND 0FFFh, R1",       // bl
    "MPYI3 R1, R0, R4",    // al bl
    "MPYI3 R3, R7, R6",    // ah bh
    "MPYI R1, R7",         // ah bl
    "MPYI R0, R3",         // al bh
    "ADDI R3, R7",         // the middle, < 2^25
    "LSH3 12, R7, R3",
    "ADDI R3, R4",         // C: carry
    "LDI 0, R0",
    "LDILO 1, R0",
    "LSH3 24, R6, R3",
    "ADDI R3, R4",
    "LDI 0, R1",
    "LDILO 1, R1",
    "ADDI R1, R0",
    "LSH3 -20, R7, R3",
    "LSH -8, R6",
    "ADDI R3, R6",
    "ADDI R0, R6",         // the product: R6 high, R4 low
    "CMPI 0, R6",
    "BEQ fmul_lo",
    "FLOAT R6, R3",
    "PUSHF R3",
    "POP R3",
    "ASH -24, R3",
    "ADDI 32, R3",
    "BR fmul_k",
    "fmul_lo: FLOAT R4, R3",
    "PUSHF R3",
    "POP R3",
    "ASH -24, R3",
    "LDI R4, R0",
    "LDILT 31, R3",
    "fmul_k: SUBI 29, R3", // k: the leading 1 to bit 29
    "ADDI R3, R5",
    "CMPI 0, R3",
    "BGT fmul_right",
    "NEGI R3, R3",
    "LSH3 R3, R4, R0",
    "BR fmul_pack",
    "fmul_right: LDI 1, R0",
    "LSH R3, R0",
    "SUBI 1, R0",
    "AND R4, R0",          // the bits shifted out
    "NEGI R3, R1",
    "LSH R1, R4",
    "LDI 32, R1",
    "SUBI R3, R1",
    "LSH R1, R6",
    "OR R6, R4",
    "CMPI 0, R0",
    "LDINE 1, R0",
    "OR R4, R0",
    "fmul_pack: SUBI 144, R5",
    "LDI R5, R1",
    "BR __fpack",
    "fmul_ainf: CMPI 0, R4",
    "BEQ fdefault_nan",    // inf * 0
    "BR finf",
    "fmul_binf: CMPI 0, R3",
    "BEQ fdefault_nan",
    "BR finf",
};

// __fdiv: denormal mantissas normalized, then 31 quotient bits by restoring
// division (the quotient in [2^29, 2^31)), the remainder as the sticky bit,
// the exponent ea - eb + 126
const char* const kFdivRoutine[] = {
    LDC_C40_MULDIV_PROLOGUE("fdiv"),
    "BEQ fzero",           // finite / inf
    "CMPI 0, R4",
    "BEQ fdiv_by_zero",
    "CMPI 0, R3",
    "BEQ fzero",           // 0 / finite
    LDC_C40_UNPACK,
    "FLOAT R0, R3",
    "PUSHF R3",
    "POP R3",
    "ASH -24, R3",
    "LDI 23, R4",
    "SUBI R3, R4",
    "LSH R4, R0",
    "SUBI R4, R5",         // a normalized
    "FLOAT R1, R3",
    "PUSHF R3",
    "POP R3",
    "ASH -24, R3",
    "LDI 23, R4",
    "SUBI R3, R4",
    "LSH R4, R1",
    "SUBI R4, R6",         // b normalized
    "SUBI R6, R5",
    "ADDI 126, R5",
    "LDI 0, R3",
    "LDI 30, AR0",
    "fdiv_step: LSH 1, R3",
    "SUBI3 R1, R0, R4",
    "LDIHS R4, R0",
    "LDI 0, R4",
    "LDIHS 1, R4",
    "OR R4, R3",
    "LSH 1, R0",
    "DBU AR0, fdiv_step",
    "CMPI 0, R0",
    "LDINE 1, R0",
    "OR R3, R0",
    "LDI R5, R1",
    "BR __fpack",
    "fdiv_ainf: CMPI 255, R6",
    "BEQ fdefault_nan",    // inf / inf
    "BR finf",
    "fdiv_by_zero: CMPI 0, R3",
    "BEQ fdefault_nan",    // 0 / 0
    "BR finf",
};
#undef LDC_C40_NAN_CHECK
#undef LDC_C40_UNPACK

void add_routine(as::Block<Instruction>& b, const char* label, const char* note, std::span<const char* const> lines) {
  b.items.push_back(Item::note(note));
  b.items.push_back(Item::label_def(label, true));
  for (const char* t : lines) {
    Line l = parse_line(t);
    if (!l.label.empty()) b.items.push_back(Item::label_def(l.label));
    b.items.push_back(Item::instr(*l.inst));
  }
}

bool has_typed(const Program& p, Op only = Op(kOpCount)) {
  for (const Rung& r : p.rungs)
    for (const ldc::Instr& in : r.code)
      if (op_info(in.op).klass == OpClass::Typed && (only == Op(kOpCount) || in.op == only)) return true;
  return false;
}

}  // namespace

std::string c40_typed_refusal(const Instr& in) {
  if (typed::is_string_instr(in.op, in.ty, in.src))
    return "STRING (MatIEC's strings of up to 126 bytes) and the string functions are not in its instruction set";
  auto wide = [](Ty t) { return t != Ty::None && ty_info(t).bits > 32; };
  if (wide(in.ty) || wide(in.src))
    return "64-bit types (LINT ULINT LWORD LREAL TIME LTIME DATE TOD DT) do not fit its 32-bit word";
  if (!typed::is_real(in.ty)) return "";
  switch (in.op) {
    case Op::TEXPT: case Op::TSQRT: case Op::TLN: case Op::TLOG: case Op::TEXP: case Op::TSIN: case Op::TCOS:
    case Op::TTAN: case Op::TASIN: case Op::TACOS: case Op::TATAN:
      return "the REAL functions are C's double functions rounded to REAL, which the C40 cannot reproduce bit for bit";
    default: return "";
  }
}

namespace {
}  // namespace

C40Code generate_c40(const Program& p, const Layout& layout, int opt_level) {
  C40Layout w = C40Layout::of(layout);
  C40Code out;
  auto& prog = out.program;
  prog.globals.push_back(kExitLabel);
  prog.globals.push_back(kDivLabel);
  prog.globals.push_back(kDivfLabel);
  for (const char* l : {kDivuLabel, kF2iLabel, kI2fLabel, kFpackLabel, kFaddLabel, kFsubLabel, kFmulLabel, kFdivLabel})
    prog.globals.push_back(l);
  for (const Rung& r : p.rungs)
    for (const auto& l : r.labels) prog.globals.push_back(label_name(l));
  for (const auto& l : p.end_labels) prog.globals.push_back(label_name(l));

  as::Block<Instruction> pro;
  pro.source_line = p.rungs.empty() ? 0 : p.rungs[0].line;
  // -O2 keeps a rung's stack in the slot registers where it fits, but only
  // when no rung reads stack entries that the rungs before it pushed (IL text
  // can say that; .ld rungs never do): then nothing reads R10 across rungs.
  bool slots_ok = opt_level >= 2;
  for (const Rung& r : p.rungs) slots_ok = slots_ok && stack_fits_slots(r.code, kMaxStackDepth + 1);
  pro.items.push_back(Item::note(opt_level == 0 ? "scan: R10 = bit stack, R11 = mask ~1, DP = data page"
                                 : opt_level == 1 ? "scan: R10 = bit stack, R11 = mask ~1, DP = data page for all rungs (-O1)"
                                                  : "scan: bit stack in R8 R9 R10 AR1-AR5 or R10, R11 = mask ~1, DP = data page (-O2)"));
  if (opt_level >= 1) pro.items.push_back(Item::instr(parse("LDPK 080h")));  // once: the rungs restore it after far pages
  for (const char* t : {"LDI 0, R10", "LDHI 0FFFFh, R11", "OR 0FFFEh, R11"})
    pro.items.push_back(Item::instr(parse(t)));
  prog.blocks.push_back(std::move(pro));

  int next_label = 0;
  Held held;
  std::optional<ScanFacts> facts;  // -O2: what the scan cannot observe
  // (scan_facts does not know the typed instructions' reads and writes yet:
  // a program with one gets none of its facts)
  const bool typed_prog = has_typed(p);
  if (opt_level >= 2 && !typed_prog) facts = scan_facts(p, layout, kNumSlots);
  TypedState ts;
  if (has_typed(p, Op::TIDX)) ts.il_offset = encode_il(p).instr_offset;
  for (const Rung& r : p.rungs) {
    as::Block<Instruction> b;
    b.source_line = r.line;
    for (const auto& l : r.labels) b.items.push_back(Item::label_def(label_name(l), true));
    bool slots = slots_ok && stack_fits_slots(r.code, kNumSlots);
    b.items.push_back(Item::note("rung, line " + std::to_string(r.line) + (r.title.empty() ? "" : ": " + r.title) +
                                 (slots ? " (stack in registers)" : "")));
    Gen g(w, b.items, next_label, opt_level, slots, ts);
    g.plan_runs(r.code);
    std::vector<uint32_t> starts;
    uint8_t keep = slots ? 0xff : uint8_t(~kUnread);  // an unread entry is still shifted into R10
    size_t ri = size_t(&r - p.rungs.data());
    for (size_t k = 0; k < r.code.size(); k++) {
      // the facts' flags only: constants are folded by the reference interpreter's
      // IEEE arithmetic, and the C40 computes REALs in its own format
      const ldc::Instr& in = r.code[k];
      g.before(in);
      starts.push_back(uint32_t(b.items.size()));
      b.items.push_back(Item::note(instr_text(in)));
      // -O0: once per block, with the first instruction: the block does not depend on DP from elsewhere
      if (starts.size() == 1 && opt_level == 0) g.ldpk_main();
      g.instr(in, facts ? facts->at(ri, k) & keep : 0);
    }
    g.finish();
    if (opt_level >= 2) drop_reloads(b.items, starts, held);
    if (opt_level >= 1) {
      drop_jumps_to_next(b.items, starts);
      fill_delay_slots(b.items, starts);
    }
    out.il_items.push_back(std::move(starts));
    prog.blocks.push_back(std::move(b));
  }

  as::Block<Instruction> epi;
  epi.source_line = p.rungs.empty() ? 0 : p.rungs.back().line;
  for (const auto& l : p.end_labels) epi.items.push_back(Item::label_def(label_name(l), true));
  epi.items.push_back(Item::label_def(kExitLabel, true));
  epi.items.push_back(Item::instr(parse("RETSU")));
  epi.items.push_back(Item::note("__divi: R0 = R0 / R1, R1 = R0 % R1 (INT32, shift-subtract)"));
  epi.items.push_back(Item::label_def(kDivLabel, true));
  for (const char* t : kDivRoutine) {
    Line l = parse_line(t);
    if (!l.label.empty()) epi.items.push_back(Item::label_def(l.label));
    epi.items.push_back(Item::instr(*l.inst));
  }
  epi.items.push_back(Item::note("__divf: R0 = R0 / R1 (C40 floats)"));
  epi.items.push_back(Item::label_def(kDivfLabel, true));
  for (const char* t : kDivfRoutine) epi.items.push_back(Item::instr(parse(t)));
  if (ts.divu) add_routine(epi, kDivuLabel, "__divu: R0 = R0 / R1, R1 = R0 % R1 (UDINT)", kDivuRoutine);
  if (ts.f2i) add_routine(epi, kF2iLabel, "__f2i: R0 = |integer of the IEEE bits R0| mod 2^32 (R1 = 1: truncated)", kF2iRoutine);
  if (ts.i2f) add_routine(epi, kI2fLabel, "__i2f: R0 = IEEE bits of the unsigned R0, to nearest", kI2fRoutine);
  if (ts.fadd || ts.fmul || ts.fdiv)
    add_routine(epi, kFpackLabel, "__fpack: R0 = IEEE bits of R0 * 2^(R1 - 156), sign R2, to nearest", kFpackRoutine);
  if (ts.fadd) {
    add_routine(epi, kFsubLabel, "__fsub: R0 = R0 - R1 (IEEE binary32 bits)", kFsubRoutine);
    add_routine(epi, kFaddLabel, "__fadd: R0 = R0 + R1 (IEEE binary32 bits)", kFaddRoutine);
  }
  if (ts.fmul) add_routine(epi, kFmulLabel, "__fmul: R0 = R0 * R1 (IEEE binary32 bits)", kFmulRoutine);
  if (ts.fdiv) add_routine(epi, kFdivLabel, "__fdiv: R0 = R0 / R1 (IEEE binary32 bits)", kFdivRoutine);
  prog.blocks.push_back(std::move(epi));
  return out;
}

}  // namespace ldc::c40gen
