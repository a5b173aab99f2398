// backend-x86/x86gen.cpp -- IL mnemonics -> x86-64 assembly templates.
#include <algorithm>
#include <array>
#include <optional>
#include <bitset>
#include <climits>
#include <cstring>
#include <map>
#include <set>
#include <stdexcept>

#include "backend-x86/backend_x86.h"
#include "backend-x86/base_savings.h"
#include "ir/codegen.h"
#include "ir/scanopt.h"
#include "ir/mathfn.h"
#include "ir/typed.h"

namespace ldc {
namespace {

using namespace as::x86;
using as::x86::Operand;
using as::x86::Instruction;
using M = Mnemonic;
using Item = as::Item<Instruction>;

// ------------------------------------------------------------ bit templates
//
// The bit instructions are pure templates, one row per mnemonic, written in
// the assembler's own syntax (GNU as, Intel, noprefix).  Instructions are
// separated by ';'.  `%0` and `%1` stand for the memory operand
// `[rbx + address]` of the IL instruction's operand 0 and 1: a bit device or
// an edge slot, one byte each.  The bit stack is ebp, top in bit 0:
// a push is `lea ebp, [rax+rbp*2]` with the new bit in eax.
const OpTemplate kBitTemplates[] = {
    {Op::LOAD,   "movzx eax, byte ptr %0; lea ebp, [rax+rbp*2]"},
    {Op::LOADN,  "movzx eax, byte ptr %0; xor eax, 1; lea ebp, [rax+rbp*2]"},
    {Op::AND,    "movzx eax, byte ptr %0; or eax, -2; and ebp, eax"},
    {Op::ANDN,   "movzx eax, byte ptr %0; not eax; and ebp, eax"},
    {Op::OR,     "movzx eax, byte ptr %0; or ebp, eax"},
    {Op::ORN,    "movzx eax, byte ptr %0; xor eax, 1; or ebp, eax"},
    {Op::LOADP,  "movzx eax, byte ptr %0; movzx ecx, byte ptr %1; mov byte ptr %1, al; not ecx; and eax, ecx; lea ebp, [rax+rbp*2]"},
    {Op::LOADF,  "movzx eax, byte ptr %0; movzx ecx, byte ptr %1; mov byte ptr %1, al; not eax; and eax, ecx; lea ebp, [rax+rbp*2]"},
    {Op::TRUE,   "lea ebp, [rbp+rbp*1+1]"},
    {Op::ANDBLK, "mov eax, ebp; shr ebp, 1; or eax, -2; and ebp, eax"},
    {Op::ORBLK,  "mov eax, ebp; shr ebp, 1; and eax, 1; or ebp, eax"},
    {Op::MPS,    "mov eax, ebp; and eax, 1; lea ebp, [rax+rbp*2]"},
    {Op::MRD,    "mov eax, ebp; shr eax, 1; and eax, 1; and ebp, -2; or ebp, eax"},
    {Op::MPP,    "shr ebp, 1"},
    {Op::OUT,    "mov eax, ebp; and eax, 1; mov byte ptr %0, al"},
    {Op::OUTN,   "mov eax, ebp; not eax; and eax, 1; mov byte ptr %0, al"},
    {Op::SET,    "mov eax, ebp; and eax, 1; or byte ptr %0, al"},
    {Op::RST,    "mov eax, ebp; not eax; and byte ptr %0, al"},
};

constexpr int32_t kMark[2] = {0x10000000, 0x20000000};
constexpr const char* kLabelPrefix = "lbl_";  // x86_label_name
// the global label of the k-th out-of-line IDX fault record (x86_globals declares one per IDX)
std::string idx_fault_label(int k) { return "idx_fault_" + std::to_string(k); }

// The templates, parsed once; %k becomes the placeholder [rbx+kMark[k]].
const std::vector<Instruction>* bit_template(Op op) {
  static const auto table = parse_templates<Instruction>(
      kBitTemplates, [](const std::string& s) { return parse(s); },
      [](int k) { return "[rbx+" + std::to_string(kMark[k]) + "]"; });
  auto it = table.find(op);
  return it == table.end() ? nullptr : &it->second;
}

// ------------------------------------------------------------ application code

Operand R(Reg r) { return Operand::r(r); }
Operand I(int64_t v) { return Operand::i(v); }
Operand L(as::Name s) { return Operand::l(s); }
Mem mem_at(Size size, uint32_t addr) {
  Mem m;
  m.size = size;
  m.base = r64(BX);
  m.disp = int32_t(addr);
  return m;
}
Operand B(uint32_t addr) { return Operand::m(mem_at(Size::Byte, addr)); }
Operand Dw(uint32_t addr) { return Operand::m(mem_at(Size::Dword, addr)); }
// a branch in its rel32 form (`{disp32}`): its target lies in another block
// (a global label, scan_exit, a fault record out of line)
Instruction far(Instruction j) {
  j.long_branch = true;
  return j;
}
const Reg eax = r32(AX), ecx = r32(CX), edx = r32(DX), ebp = r32(BP), esi = r32(SI), edi = r32(DI), al = r8(AX), cl = r8(CX);
const Reg r8d = r32(R8), r9d = r32(R9), r10d = r32(R10), r11d = r32(R11);
const Reg xmm0 = xmm(0), xmm1 = xmm(1), xmm2 = xmm(2);

uint32_t float_bits(float f) {
  uint32_t u;
  std::memcpy(&u, &f, 4);
  return u;
}

// -O2 keeps the bit stack in callee-saved byte registers: the entry at
// stack position p lives in kSlots[p % kNumSlots] (0 or 1 in the low byte).
// They survive the calls to the REAL functions.  r15 and r14 are base
// registers (as::x86::kBaseRegs, compact addressing), so three slots.
// Rungs are generated in the -O0 frame's registers (rbx the image, ebp the
// bit stack) and then moved to the -O2 frame's (to_o2_frame: rbx and rbp
// swap), so the first slot, bpl here, is bl there: no REX prefix.
const Reg kSlots[] = {r8(BP), r8(R12), r8(R13)};
constexpr int kNumSlots = 3;
const as::x86::Reg kO2Image = r64(as::x86::image_reg(true));  // rbp
using as::x86::kImageBias;  // rbp = image + kImageBias: to_o2_frame biases the displacements made from image offsets

// Turns gate_ off for one instruction's code (restored at the end of scope).
struct Ungated {
  bool& flag;
  bool saved;
  explicit Ungated(bool& f, bool when = true) : flag(f), saved(f) {
    if (when) f = false;
  }
  ~Ungated() { flag = saved; }
};

bool writes_reg(const Instruction& i, uint8_t num);
// Does `in`, which writes register n, leave its upper half zero?  Every write of
// its 32-bit form does (and cwde, of eax); 8- and 16-bit writes keep it, 64-bit
// ones and calls may set it: unknown.
bool zero_extends(const Instruction& in, uint8_t n) {
  if (in.mnemonic == M::Cwde) return n == AX;
  return in.mnemonic != M::Call && in.num_operands > 0 && in.ops[0].kind == OperandKind::Reg && in.ops[0].reg == r32(n);
}

// The bytes a memory operand covers.
uint32_t mem_width(const Mem& m) {
  return m.size == Size::Dword ? 4 : m.size == Size::Qword ? 8 : m.size == Size::Word ? 2 : 1;
}

// -O2: the REAL and LREAL constants of the typed instructions that the
// program uses more than once (the eight most used; 0 is `xorps`), each kept
// in a register of its own, xmm8..xmm15, for the whole scan.  The prologue
// loads them, and so does every call into the C library (the math functions,
// STRING), which may write every xmm register, right after it; nothing else
// writes xmm8..xmm15 (the shared timer routines use no xmm register), so at
// every label, whatever jumps there, each holds its constant.  A typed
// instruction reads the register where it would have loaded the constant
// (`mulsd xmm0, xmm8` for `mov rdx, imm64; movq xmm1, rdx; mulsd xmm0, xmm1`).
class RealConsts {
 public:
  static constexpr int kRegs = 8, kFirst = 8;
  static RealConsts of(const Program& p);
  // the register that holds the constant of these bits (a REAL's in the low 32
  // and `single`), if one does
  std::optional<Reg> reg(uint64_t bits, bool single) const {
    auto k = std::find(keys_.begin(), keys_.end(), Key{bits, single});
    if (k == keys_.end()) return std::nullopt;
    return as::x86::xmm(unsigned(kFirst + (k - keys_.begin())));
  }
  // the instructions that load every register (rdx written)
  std::vector<Instruction> loads() const {
    std::vector<Instruction> v;
    for (size_t k = 0; k < keys_.size(); k++) {
      const Key& c = keys_[k];
      const Reg x = as::x86::xmm(unsigned(kFirst + k));
      if (c.single || c.bits <= UINT32_MAX) v.push_back(make(M::Mov, {Operand::r(r32(DX)), Operand::i(int64_t(uint32_t(c.bits)))}));
      else v.push_back(make(M::Mov, {Operand::r(r64(DX)), Operand::i(int64_t(c.bits))}));
      v.push_back(make(c.single ? M::Movd : M::Movq, {Operand::r(x), Operand::r(c.single ? r32(DX) : r64(DX))}));
    }
    return v;
  }
  bool empty() const { return keys_.empty(); }

 private:
  struct Key {
    uint64_t bits;
    bool single;
    bool operator==(const Key&) const = default;
  };
  std::vector<Key> keys_;  // keys_[k] in xmm(kFirst + k)
  static void count(std::vector<std::pair<Key, int>>& n, Key c);
  static bool rounds_to_int(Ty to);
};

class Gen : public ClassGen<Gen> {
 public:
  // known: the rung's (empty), storage the caller keeps from rung to rung
  // o1: -O1 (its typed runs skip the power test where the power is on for certain)
  Gen(const Layout& l, std::vector<Item>& items, bool slots, bool gate, std::bitset<8>* used, KnownStack& known, bool o1 = false,
      bool base_regs = true)
      : L_(l), items_(items), slots_(slots), gate_(gate), bases_(gate), reload_bases_(gate && base_regs), known_(known), o1_(o1),
        used_(used) {}

  // facts: ScanFlag bits (ir/scanopt.h); reuse: the earlier division it takes,
  // quotient_to: where a MOD also stores its quotient (ScanFacts), if any
  void instr(const ldc::Instr& in, uint8_t facts = 0, const ldc::DivReuse* reuse = nullptr,
             const ldc::Operand* quotient_to = nullptr);
  // `LOAD g; MOVE.T a d; MPP` (SEL's lowering, and the typed reader's update
  // of a timer instance's ET; LOADN g: where g is 0): d := g ? a : d without
  // a branch; false: not that shape
  static bool is_select(const ldc::Instr& load, const ldc::Instr& move, const ldc::Instr& mpp);
  void select(const ldc::Instr& load, const ldc::Instr& move, const ldc::Instr& mpp);
  static bool is_compare_jump(const ldc::Instr& cmp, const ldc::Instr& jmp, const ldc::Instr& mpp);
  void compare_jump(const ldc::Instr& cmp, const ldc::Instr& jmp, const ldc::Instr& mpp);
  void follow(const ldc::Instr& in);
  void use_consts(const RealConsts* c) { consts_ = c && !c->empty() ? c : nullptr; }

 private:
  const Layout& L_;
  std::vector<Item>& items_;
  int next_label_ = 0;
  bool slots_;     // -O2: the stack in kSlots; else the -O0 shift register in ebp
  bool gate_;      // -O2: branch-free power gating (cmov) instead of `je skip`
  bool bases_;     // -O2 (its frame, its facts)
  bool reload_bases_;  // -O2 with the base registers set: rdi is reloaded after a REAL call (none in a program with loops)
  const RealConsts* consts_ = nullptr;  // -O2: the constants in xmm8..xmm15
  KnownStack& known_;  // -O2: the stack's values known at compile time
  // -O1: the same for its typed runs alone (-O2's known_ also folds timers, gates ...)
  KnownStack power_;
  bool o1_ = false;
  // a typed run needs no power test: the power is on for certain
  bool power_known_on() const { return (bases_ && known_.on()) || (o1_ && power_.on()); }
  bool on_ = false;   // -O2: this instruction's power is on for certain (no gate, no test)
  const ldc::DivReuse* reuse_ = nullptr;  // -O2: this division's earlier result (ScanFacts::reused)
  const ldc::Operand* quotient_to_ = nullptr;  // -O2: this MOD's quotient goes there too (ScanFacts::early_quotient)
  std::bitset<8>* used_;  // the shared routines called (as::x86::Routine)
  int depth_ = 0;  // stack positions in use before the current instruction

  // pos >= -2 (bit_slots names the two entries below the top of a stack that
  // never goes below the rung's first push): one unsigned remainder, of pos
  // moved up by a multiple of kNumSlots
  Reg slot(int pos) const { return kSlots[unsigned(pos + kNumSlots * kMaxStackDepth) % kNumSlots]; }
  Reg top8() const { return slot(depth_ - 1); }
  static Reg wide(Reg r8) { return r32(r8.num); }
  void test_top() {
    if (slots_) emit(M::Test, {R(top8()), R(top8())});
    else emit(M::Test, {R(ebp), I(1)});
  }
  // A 32-bit register holding the top, 0 or 1: the top slot (its upper bits
  // are zero, every push writes the full register) or esi from ebp.
  Reg power() {
    if (slots_) return wide(top8());
    emit(M::Mov, {R(esi), R(ebp)});
    emit(M::And, {R(esi), I(1)});
    return esi;
  }
  // esi = the top, 0 or 1: the power a shared routine takes
  void power_to_esi() {
    if (Reg p = power(); p != esi) emit(M::Mov, {R(esi), R(p)});
  }
  // eax = the top, 0 or 1
  void top_to_eax() {
    if (slots_) emit(M::Movzx, {R(eax), R(top8())});
    else { emit(M::Mov, {R(eax), R(ebp)}); emit(M::And, {R(eax), I(1)}); }
  }
  void bit_slots(const ldc::Instr& in);
  template <class G>
  friend void ldc::gen_by_class(G& g, const ldc::Instr& in);

  // a new instruction item at the end, a copy of an empty one (a few wide
  // moves; one built in place is zeroed by `rep stos`, slow to start)
  Instruction& next_instr() { return items_.emplace_back(kEmptyInstr).inst; }
  static inline const Item kEmptyInstr = Item::instr({});
  void emit(const Instruction& i) {
    next_instr() = i;
    if (any_held_) forget_written(i);
  }
  void emit(M m, std::initializer_list<Operand> ops) {
    if (ops.size() > 3) throw std::logic_error("x86 backend: more than 3 operands");
    Instruction& in = next_instr();
    in.mnemonic = m;
    in.num_operands = uint8_t(ops.size());  // set once: a count bumped in memory is reloaded after each operand stored
    for (size_t k = 0; k < ops.size(); k++) in.ops[k] = ops.begin()[k];
    if (any_held_) forget_written(in);
  }
  void jcc(Cond c, const std::string& label) { emit(make_cc(M::Jcc, c, {L(label)})); }
  void jump(const std::string& label) { emit(M::Jmp, {L(label)}); }
  void label(const std::string& l) {
    items_.push_back(Item::label_def(l));
    forget_all();  // a jump may arrive with anything in the registers
  }

  // ---- -O2: the cells the registers hold (docs/x86.md, "Values held in registers")
  //
  // After a typed store `mov [d], reg` or a typed load of d into reg, reg holds
  // d's value (as load32 / load64 of d's type makes it) until an instruction
  // writes reg or d's bytes, a call, or a label.  A later load of d then reads
  // the register: store-to-load forwarding through memory costs 4 to 7 cycles a
  // hop on the chains of temporaries an ST expression makes (`sequence.st`).
  struct Held {
    uint32_t addr = 0;
    Ty ty = Ty::BOOL;
    bool exact = false;  // the register's low bytes are the cell's bytes (BOOL: 1, two cells: 8, else 4)
    bool upper_zero = false;  // bits 63..32 are 0: a load32 may take the register as it is
    bool valid = false;
  };
  std::array<Held, 16> held_{};
  bool any_held_ = false;
  // r11 holds the last IDX's index (minus its lo) of the cell `addr`, checked against lo..hi
  struct HeldIndex {
    uint32_t addr = 0;
    Ty ty = Ty::BOOL;
    int64_t lo = 0, hi = 0;
    bool valid = false;
  } idx_held_;
  static uint32_t held_width(Ty t) { return t == Ty::BOOL ? 1 : ty_info(t).cells == 2 ? 8 : 4; }
  // r10 holds r11 * scaled_ (an LDX / STX's element offset), where not 0
  int64_t scaled_ = 0;
  void forget_all() {
    if (any_held_) held_.fill({}), idx_held_.valid = false, scaled_ = 0, any_held_ = false;
  }
  void forget_written(const Instruction& i);
  bool upper_zero_now(uint8_t n) const;
  // upper_zero: bits 63..32 of the register are 0 (its last writer wrote 32 bits)
  void hold(unsigned n, Ty t, uint32_t addr, bool exact, bool upper_zero = false) {
    if (!slots_ || n == SP || n == BX) return;  // only the -O2 frame's rungs (no later peephole); never the image base
    held_[n] = {addr, t, exact, upper_zero, true};
    any_held_ = true;
  }
  // the register holding cell `addr` as type t would load it, or -1
  int holder(Ty t, uint32_t addr) const;
  // the register whose low `width` bytes are the cell's, or -1
  int raw_holder(uint32_t addr, uint32_t width) const;
  // bit byte `addr` as the bit instructions read it: the low byte of a register
  // that holds it as it is in memory (a BOOL stored), else the byte
  Operand held_byte(uint32_t addr) const {
    const int h = holder(Ty::BOOL, addr);
    return h >= 0 && held_[size_t(h)].exact ? R(r8(uint8_t(h))) : B(addr);
  }
  std::string fresh() { return "L" + std::to_string(next_label_++); }

  uint32_t addr(const ldc::Operand& o) const {
    switch (o.kind) {
      case OpdKind::Edge: return L_.addr(Area::E, o.index);
      case OpdKind::Timer: return L_.addr(Area::TW, o.index);
      case OpdKind::Counter: return L_.addr(Area::CW, o.index);
      default: return L_.addr(o.area, o.index);
    }
  }
  static bool is_const(const ldc::Operand& o) { return o.kind == OpdKind::ConstInt || o.kind == OpdKind::ConstReal; }

  // eax = INT32 value of o (REAL converted: truncate, saturate, NaN -> 0)
  void load_int(const ldc::Operand& o, Reg r) {
    if (o.kind == OpdKind::ConstInt) emit(M::Mov, {R(r), I(o.ival)});
    else if (o.kind == OpdKind::ConstReal) emit(M::Mov, {R(r), I(real_to_int(o.fval))});
    else if (o.kind == OpdKind::Real) { load_real(o, xmm0); real_to_int_eax(); if (r != eax) emit(M::Mov, {R(r), R(eax)}); }
    else emit(M::Mov, {R(r), Dw(addr(o))});
  }
  // x = REAL value of o
  void load_real(const ldc::Operand& o, Reg x) {
    if (o.kind == OpdKind::ConstReal || o.kind == OpdKind::ConstInt) {
      float f = o.kind == OpdKind::ConstReal ? o.fval : int_to_real(o.ival);
      uint32_t bits = float_bits(f);
      if (bits == 0) emit(M::Xorps, {R(x), R(x)});
      else { emit(M::Mov, {R(edx), I(int32_t(bits))}); emit(M::Movd, {R(x), R(edx)}); }
    } else if (o.kind == OpdKind::Real) emit(M::Movss, {R(x), Dw(addr(o))});
    else emit(M::Cvtsi2ss, {R(x), Dw(addr(o))});
  }
  // xmm0 -> eax with the IL's REAL -> INT32 rule
  void real_to_int_eax() {
    std::string done = fresh(), nan = fresh();
    emit(M::Cvttss2si, {R(eax), R(xmm0)});
    emit(M::Cmp, {R(eax), I(INT32_MIN)});
    jcc(Cond::NE, done);
    emit(M::Ucomiss, {R(xmm0), R(xmm0)});
    jcc(Cond::P, nan);
    emit(M::Xorps, {R(xmm2), R(xmm2)});
    emit(M::Ucomiss, {R(xmm0), R(xmm2)});
    jcc(Cond::BE, done);  // negative: INT32_MIN is right
    emit(M::Mov, {R(eax), I(INT32_MAX)});
    jump(done);
    label(nan);
    emit(M::Xor, {R(eax), R(eax)});
    label(done);
  }
  // -O2: d = power ? eax : d, without a branch
  void gated_store(const ldc::Operand& d) {
    test_top();
    emit(make_cc(M::Cmovcc, Cond::E, {R(eax), Dw(addr(d))}));
    emit(M::Mov, {Dw(addr(d)), R(eax)});
  }
  // d = the 32 bits `bits` (an INT32 or a REAL's pattern), with power
  void store_imm(const ldc::Operand& d, int32_t bits) {
    if (!gate_) return emit(M::Mov, {Dw(addr(d)), I(bits)});
    emit(M::Mov, {R(eax), I(bits)});
    gated_store(d);
  }
  // store eax (INT32) into d, converting to REAL for F
  void store_int(const ldc::Operand& d) {
    if (gate_) {
      if (d.kind == OpdKind::Real) { emit(M::Cvtsi2ss, {R(xmm0), R(eax)}); emit(M::Movd, {R(eax), R(xmm0)}); }
      return gated_store(d);
    }
    if (d.kind == OpdKind::Real) {
      emit(M::Cvtsi2ss, {R(xmm0), R(eax)});
      emit(M::Movss, {Dw(addr(d)), R(xmm0)});
    } else emit(M::Mov, {Dw(addr(d)), R(eax)});
  }
  // store xmm0 (REAL) into d, converting to INT32 for words
  void store_real(const ldc::Operand& d) {
    if (gate_) {
      if (d.kind == OpdKind::Real) emit(M::Movd, {R(eax), R(xmm0)});
      else real_to_int_eax();
      return gated_store(d);
    }
    if (d.kind == OpdKind::Real) emit(M::Movss, {Dw(addr(d)), R(xmm0)});
    else { real_to_int_eax(); emit(M::Mov, {Dw(addr(d)), R(eax)}); }
  }
  // the source operand form for `op eax, <b>`: an immediate or a dword in the image
  Operand int_src(const ldc::Operand& b) {
    if (b.kind == OpdKind::ConstInt) return I(b.ival);
    return Dw(addr(b));
  }
  void set_error() { emit(M::Mov, {B(L_.addr(Area::S, kBitError)), I(1)}); }
  void push_al() {
    if (slots_) return emit(M::Movzx, {R(wide(slot(depth_))), R(al)});
    emit(M::Movzx, {R(eax), R(al)});
    emit(M::Lea, {R(ebp), Operand::m(Mem{Size::None, r64(AX), r64(BP), 2, 0})});
  }
  // if the top of the stack is 0, skip to the returned label; with gate_,
  // nothing ("" : the stores are gated instead)
  std::string skip_unless_power() {
    if (gate_ || on_) return "";
    std::string skip = fresh();
    test_top();
    jcc(Cond::E, skip);
    return skip;
  }

  void basic(const ldc::Instr& in);
  void flow(const ldc::Instr& in);
  void loop(const ldc::Instr& in);

  // ClassGen's primitives
  friend class ClassGen<Gen>;
  void load_int(const ldc::Operand& a) { load_int(a, eax); }
  void load_ints(const ldc::Operand& a, const ldc::Operand& b) { load_int(a, eax); load_int(b, ecx); }
  void load_reals(const ldc::Operand& a, const ldc::Operand& b) { load_real(a, xmm0); load_real(b, xmm1); }
  void compare_ints(const ldc::Operand& a, const ldc::Operand& b, Rel rel);
  void compare_reals(const ldc::Operand& a, const ldc::Operand& b, Rel rel);
  void copy_word(const ldc::Operand& a, const ldc::Operand& d);
  void move_const(const ldc::Operand& a, const ldc::Operand& d);
  void move_real_to_int(const ldc::Operand& a, const ldc::Operand& d);
  void int_arith(Op op, const ldc::Operand& a, const ldc::Operand& b);
  void real_arith(Op op);
  Ungated ungated(const ldc::Instr& in);
  DivLabels div_labels(bool real);
  void branch_zero_real(const DivLabels& l);
  void divide_real() { emit(M::Divss, {R(xmm0), R(xmm1)}); }
  void divisor_branch(int32_t v, const std::string& l);
  void divide_int(bool mod);
  void minus_one_result(bool mod);
  void word_not(const ldc::Operand& a);
  void shift(Op op, const ldc::Operand& a, const ldc::Operand& n);
  void bitwise(Op op, const ldc::Operand& a, const ldc::Operand& b);
  void abs_int(const ldc::Operand& a, const ldc::Operand& d);
  void real_fn(Op op, const ldc::Operand& a, const ldc::Operand& d);
  uint32_t area_addr(Area a, uint32_t n) const { return L_.addr(a, n); }
  bool gated_divmod(const ldc::Instr& in);
  void reused_division(const ldc::Instr& in, const ldc::DivReuse& r);
  bool divide_by_constant(const ldc::Instr& in);
  bool gated_timer(const ldc::Instr& in, uint32_t tw, uint32_t tq, uint32_t ti);
  void ton_on(const ldc::Instr& in, uint32_t tw, uint32_t tq, uint32_t ti);
  void mton_slots(const ldc::Instr& in, uint32_t tw, uint32_t tq, uint32_t ti);
  bool gated_counter(const ldc::Instr& in, uint32_t cw, uint32_t cq);
  void put_word(uint32_t a, int32_t v) { emit(M::Mov, {Dw(a), I(v)}); }
  void put_flag(uint32_t a, int32_t v) { emit(M::Mov, {B(a), I(v)}); }
  // the timers' power tests; none (or a jump) where the power is on for certain
  void unless_power(const std::string& l) {
    if (!known_.on()) test_top(), jcc(Cond::E, l);
  }
  void if_power(const std::string& l) {
    if (known_.on()) return jump(l);
    test_top();
    jcc(Cond::NE, l);
  }
  void if_flag(uint32_t a, bool set, const std::string& l) {
    emit(M::Cmp, {B(a), I(0)});
    jcc(set ? Cond::NE : Cond::E, l);
  }
  void restart_et(uint32_t tw) { emit(M::Mov, {Dw(tw), I(0)}); emit(M::Xor, {R(eax), R(eax)}); }
  void et_below(const std::string& l) { emit(M::Cmp, {R(eax), R(ecx)}); jcc(Cond::L, l); }
  void q_et(uint32_t tq, Rel rel);
  void q_preset(uint32_t tq);
  void tof_on(uint32_t tw, uint32_t tq, uint32_t ti) { put_flag(tq, 1); put_word(tw, 0); put_flag(ti, 1); }
  void remember_input(uint32_t ti);
  void count(const ldc::Instr& in, uint32_t cw, uint32_t cq);
  void preset(const ldc::Operand& pt);
  void advance(uint32_t tw);
  void advance_edx(uint32_t tw);
  void timer_gated(const ldc::Instr& in);
  void call_routine(as::x86::Routine r) {
    used_->set(size_t(r));
    emit(M::Call, {L(as::x86::routine_name(r))});
  }
  void counter_gated(const ldc::Instr& in);
  void reset_masked(std::initializer_list<Operand> dwords, std::initializer_list<Operand> bytes);
  void end_skip(const std::string& skip) {
    if (!skip.empty()) label(skip);
  }

  // ---- the typed instructions (docs/x86.md, "Typed instructions"; ir/typed.h)
 public:
  void set_il_offset(uint32_t off) { il_offset_ = off; }

 private:
  uint32_t il_offset_ = 0;  // the IL byte offset of the instruction being compiled (an IDX's fault record)
  std::string typed_skip_;  // the open power test of a run of typed instructions (Gen::typed), "" if none
 public:
  // ends a run of typed instructions: the label its power test skips to
  void close_typed_run() {
    flush_idx_check();
    if (!typed_skip_.empty()) label(typed_skip_), typed_skip_.clear();
  }
  // -O2: an IDX right before the LDX / STX `next` (to be compiled next) leaves
  // its check to that access's own (`cmp r11, n; ja` to the IDX's fault
  // record, which goes to `cold`, named from `*count`)
  void set_next(const ldc::Instr* next) { next_ = next; }
  void use_cold(std::vector<Item>* cold, int* count) { cold_ = cold, cold_count_ = count; }

 private:
  int64_t idx_span_ = -1;   // the last IDX's hi - lo: the bound of the LDX / STX right after it
  const ldc::Instr* next_ = nullptr;
  std::vector<Item>* cold_ = nullptr;
  int* cold_count_ = nullptr;
  std::string idx_fault_;  // an IDX's fault record (in cold_) that the access right after it checks against, or ""
  bool hold_idx_after_check_ = false;  // idx_held_ becomes valid when the deferred check is made
  bool defers_check() const;
  int64_t element_bytes(const ldc::Instr& access) const;
  static bool scales(int64_t bytes);
  std::string cold_fault(int64_t lo);
  std::array<Instruction, 4> fault_record(uint32_t kind, const Operand& value) const;
  void flush_idx_check();
  void idx_checked();
  void typed(const ldc::Instr& in);
  void typed_compare(const ldc::Instr& in);
  Cond int_compare(const ldc::Instr& in);
  void typed_move(const ldc::Instr& in);
  void typed_arith(const ldc::Instr& in);
  void typed_divmod(const ldc::Instr& in);
  void typed_minmax(const ldc::Instr& in);
  void typed_logic(const ldc::Instr& in);
  void typed_shift(const ldc::Instr& in);
  void typed_neg_abs(const ldc::Instr& in);
  void typed_math(const ldc::Instr& in);
  void typed_string(const ldc::Instr& in);
  void typed_conv(const ldc::Instr& in);
  void typed_idx(const ldc::Instr& in);
  void typed_indexed(const ldc::Instr& in);
  uint32_t taddr(const ldc::Operand& o) const { return L_.addr(o.area, o.index); }
  void mov_imm(Reg r64, uint64_t v);
  void load32(Ty t, const ldc::Operand& o, Reg r);
  void load_raw32(const ldc::Operand& o, Reg r);
  Operand src32(const ldc::Operand& o) const;
  void load_pair(Ty t, const ldc::Operand& a, const ldc::Operand& b);
  void load64(Ty t, const ldc::Operand& o, Reg r);
  void normalize(Ty t, Reg r);
  void store_int_reg(Ty t, RegNum n, const ldc::Operand& d, bool canonical = false);
  void load_x(Ty t, const ldc::Operand& o, Reg x);
  void load_xd(Ty t, const ldc::Operand& o, Reg x);
  Operand real_src(Ty t, const ldc::Operand& o, Reg x);
  bool from_held(Ty t, const ldc::Operand& o, Reg x);
  Reg real_reg(Ty t, const ldc::Operand& o, Reg x);
  std::optional<Reg> const_reg(uint64_t bits, bool single) const {
    return consts_ ? consts_->reg(bits, single) : std::nullopt;
  }
  void reload_consts() {
    if (consts_)
      for (const Instruction& i : consts_->loads()) emit(Instruction(i));
  }
  void store_x(Ty t, Reg x, const ldc::Operand& d);
  void store_xd(Ty t, Reg x, const ldc::Operand& d);
  void double_const(Reg x, double d);
  void real_round_to_int(bool is_signed);
  void unsigned_to_real(Ty to);
  void guarded_div64(bool is_signed);
  void call_table(int32_t disp);
};

// The x86 forms of each relation, in the order of ops.def's REL table.
// After `cmp` a signed condition; after `ucomiss` an unsigned one, where an
// unordered (NaN) result sets ZF, PF and CF: only A and AE are false then, so
// Lt and Le test their swap_operands relation (Gt, Ge) on the operands
// exchanged, and Eq / Ne fold in the parity flag (false / true on NaN).
struct X86Rel {
  Rel rel;
  Cond int_cc;     // setcc after `cmp a, b`
  Cond real_cc;    // setcc after `ucomiss a, b`, or `ucomiss b, a` if swap
  bool swap;
  bool parity;     // then: setcc parity_cc into cl, parity_op al, cl
  Cond parity_cc;
  M parity_op;
};
constexpr X86Rel kX86Rels[] = {
    {Rel::Eq, Cond::E,  Cond::E,  false, true,  Cond::NP, M::And},
    {Rel::Ne, Cond::NE, Cond::NE, false, true,  Cond::P,  M::Or},
    {Rel::Lt, Cond::L,  Cond::A,  true,  false, {},       {}},
    {Rel::Le, Cond::LE, Cond::AE, true,  false, {},       {}},
    {Rel::Gt, Cond::G,  Cond::A,  false, false, {},       {}},
    {Rel::Ge, Cond::GE, Cond::AE, false, false, {},       {}},
};
static_assert([] {
  for (int r = 0; r < int(Rel::None); r++) {
    const X86Rel& x = kX86Rels[r];
    if (x.rel != Rel(r)) return false;
    if (x.swap && kX86Rels[int(swap_operands(x.rel))].real_cc != x.real_cc) return false;
  }
  return true;
}(), "kX86Rels follows ops.def's REL table");
constexpr const X86Rel& x86_rel(Rel r) { return kX86Rels[int(r)]; }

// push (a REL b), INT32
void Gen::compare_ints(const ldc::Operand& a, const ldc::Operand& b, Rel rel) {
  const X86Rel& x = x86_rel(rel);
  if (slots_) emit(M::Xor, {R(wide(slot(depth_))), R(wide(slot(depth_)))});  // no partial-register chain
  bool word = !is_const(a) && a.kind != OpdKind::Real;
  if (bases_ && word && b.kind == OpdKind::ConstInt) {
    emit(M::Cmp, {Dw(addr(a)), I(b.ival)});  // -O2: the word against the constant, no load
  } else {
    load_int(a, eax);
    emit(M::Cmp, {R(eax), int_src(b)});
  }
  if (slots_) return emit(make_cc(M::Setcc, x.int_cc, {R(slot(depth_))}));
  emit(make_cc(M::Setcc, x.int_cc, {R(al)}));
  push_al();
}

// push (a REL b), REAL
void Gen::compare_reals(const ldc::Operand& a, const ldc::Operand& b, Rel rel) {
  const X86Rel& x = x86_rel(rel);
  load_reals(a, b);
  if (x.swap) emit(M::Ucomiss, {R(xmm1), R(xmm0)});
  else emit(M::Ucomiss, {R(xmm0), R(xmm1)});
  emit(make_cc(M::Setcc, x.real_cc, {R(al)}));
  if (x.parity) {
    emit(make_cc(M::Setcc, x.parity_cc, {R(cl)}));
    emit(x.parity_op, {R(al), R(cl)});
  }
  push_al();
}

// d = a, both REAL words
void Gen::copy_word(const ldc::Operand& a, const ldc::Operand& d) {
  emit(M::Mov, {R(eax), Dw(addr(a))});
  if (gate_) gated_store(d);
  else emit(M::Mov, {Dw(addr(d)), R(eax)});
}

// d = a constant: its 32 bits, but a REAL one into a word is converted at run time
void Gen::move_const(const ldc::Operand& a, const ldc::Operand& d) {
  if (a.kind == OpdKind::ConstReal && d.kind != OpdKind::Real) return move_real_to_int(a, d);
  if (a.kind == OpdKind::ConstReal) return store_imm(d, int32_t(float_bits(a.fval)));
  store_imm(d, d.kind == OpdKind::Real ? int32_t(float_bits(int_to_real(a.ival))) : a.ival);
}

void Gen::move_real_to_int(const ldc::Operand& a, const ldc::Operand& d) {
  load_real(a, xmm0);
  store_real(d);
}

// eax = a op b (ADD SUB MUL)
void Gen::int_arith(Op op, const ldc::Operand& a, const ldc::Operand& b) {
  load_int(a, eax);
  if (op == Op::MUL) {
    if (b.kind == OpdKind::ConstInt) emit(M::Imul, {R(eax), R(eax), I(b.ival)});
    else emit(M::Imul, {R(eax), Dw(addr(b))});
  } else {
    emit(op == Op::ADD ? M::Add : M::Sub, {R(eax), int_src(b)});
  }
}

void Gen::real_arith(Op op) {
  emit(op == Op::ADD ? M::Addss : op == Op::SUB ? M::Subss : M::Mulss, {R(xmm0), R(xmm1)});
}

// DIV and MOD keep the `je skip` of -O0 at every level: a zero divisor sets
// S0; so do the calls to the REAL function table: no call without power.
Ungated Gen::ungated(const ldc::Instr& in) {
  const OpInfo& i = op_info(in.op);
  return Ungated(gate_, i.klass == OpClass::Arith || (i.klass == OpClass::Special && real_fn_info(i.fn).called));
}

DivLabels Gen::div_labels(bool real) {
  DivLabels l;
  if (real) {
    l.divide = fresh();
    l.err = fresh();
  } else {
    l.err = fresh();
    l.minus_one = fresh();
  }
  return l;
}

// The signed magic number of a constant divisor d, 2 <= |d| < 2^31: for every
// INT32 n, n / d (truncated) is hi32(m * n) (+ n where d > 0 > m, - n where
// d < 0 < m) shifted right arithmetically by s, plus 1 where that is negative
// (Warren, Hacker's Delight, 10-1).
struct Magic {
  int32_t m;
  int s;
};
Magic magic_of(int32_t d) {
  const uint32_t two31 = 0x80000000u, ad = d < 0 ? 0u - uint32_t(d) : uint32_t(d);
  const uint32_t t = two31 + (uint32_t(d) >> 31), anc = t - 1 - t % ad;
  int p = 31;
  uint32_t q1 = two31 / anc, r1 = two31 - q1 * anc, q2 = two31 / ad, r2 = two31 - q2 * ad, delta;
  do {
    p++;
    q1 *= 2, r1 *= 2;
    if (r1 >= anc) q1++, r1 -= anc;
    q2 *= 2, r2 *= 2;
    if (r2 >= ad) q2++, r2 -= ad;
    delta = ad - r2;
  } while (q1 < delta || (q1 == delta && r1 == 0));
  uint32_t m = q2 + 1;
  return {int32_t(d < 0 ? 0u - m : m), p - 32};
}

// -O2: INT32 DIV / MOD by a constant other than 0, 1, -1 and INT32_MIN: no
// idiv, no S0, a multiply by the magic number; eax = the result, n kept in ecx.
bool Gen::divide_by_constant(const ldc::Instr& in) {
  const ldc::Operand &a = in.a[0], &b = in.a[1], &d = in.a[2];
  if (!bases_ || a.is_real() || b.kind != OpdKind::ConstInt || b.ival == INT32_MIN || (b.ival >= -1 && b.ival <= 1))
    return false;
  Magic mg = magic_of(b.ival);
  load_int(a, ecx);
  emit(M::Mov, {R(eax), I(mg.m)});
  emit(M::Imul, {R(ecx)});  // edx = hi32(m * n)
  if (b.ival > 0 && mg.m < 0) emit(M::Add, {R(edx), R(ecx)});
  if (b.ival < 0 && mg.m > 0) emit(M::Sub, {R(edx), R(ecx)});
  if (mg.s > 0) emit(M::Sar, {R(edx), I(mg.s)});
  emit(M::Mov, {R(eax), R(edx)});
  emit(M::Shr, {R(eax), I(31)});
  emit(M::Add, {R(eax), R(edx)});  // the quotient, truncated
  if (in.op == Op::MOD) {
    emit(M::Imul, {R(eax), R(eax), I(b.ival)});
    emit(M::Sub, {R(ecx), R(eax)});
    emit(M::Mov, {R(eax), R(ecx)});  // n - q * d: the sign of n
  }
  store_int(d);
  return true;
}

// -O2: DIV and MOD without a branch (docs/x86.md, "Branch-free division").
// r8b = the divisor is zero; an INT32 divisor of 0 or -1 becomes 1 before the
// division (as::x86::safe_divisor), and x / -1 is then negated; the result is
// stored where r8b < power (power and a divisor other than zero: one compare
// of two 0/1 bytes), and S0 |= power and a zero divisor.  A constant divisor
// takes divide_by_constant instead.  Power on for certain takes the branching
// form: this one's `or` into S0 chains every division of the scan through
// memory (the one-class arithmetic program 880 ns -> 1.31 us a scan with it).
bool Gen::gated_divmod(const ldc::Instr& in) {
  if (reuse_ && on_) {
    if (!reuse_->stored_early) reused_division(in, *reuse_);  // else the MOD before stored the quotient
    return true;
  }
  if (divide_by_constant(in)) return true;
  if (!bases_ || on_) return false;
  const ldc::Operand &a = in.a[0], &b = in.a[1], &d = in.a[2];
  const Reg r8d = r32(R8), r8b = r8(R8);
  bool mod = in.op == Op::MOD;
  if (!mod && (a.is_real() || b.is_real())) {
    load_reals(a, b);
    emit(M::Xorps, {R(xmm2), R(xmm2)});
    emit(M::Ucomiss, {R(xmm1), R(xmm2)});
    emit(make_cc(M::Setcc, Cond::E, {R(r8b)}));
    emit(make_cc(M::Setcc, Cond::NP, {R(cl)}));  // a NaN divisor is not zero
    emit(M::And, {R(r8b), R(cl)});
    emit(M::Divss, {R(xmm0), R(xmm1)});
    if (d.kind == OpdKind::Real) emit(M::Movd, {R(eax), R(xmm0)});
    else real_to_int_eax();
  } else {
    load_ints(a, b);
    emit(M::Mov, {R(r8d), R(ecx)});
    for (const Instruction& i : as::x86::safe_divisor()) emit(i);
    emit(M::Cdq, {});
    emit(M::Idiv, {R(ecx)});
    if (mod) emit(M::Mov, {R(eax), R(edx)});  // 0 for a divisor of 0 or -1
    else {
      emit(M::Mov, {R(edx), R(eax)});
      emit(M::Neg, {R(edx)});
      emit(M::Cmp, {R(r8d), I(-1)});
      emit(make_cc(M::Cmovcc, Cond::E, {R(eax), R(edx)}));  // x / -1 = -x, wrapping
    }
    emit(M::Test, {R(r8d), R(r8d)});
    emit(make_cc(M::Setcc, Cond::E, {R(r8b)}));
    if (d.kind == OpdKind::Real) { emit(M::Cvtsi2ss, {R(xmm0), R(eax)}); emit(M::Movd, {R(eax), R(xmm0)}); }
  }
  const Reg p = power();
  emit(M::Cmp, {R(r8b), R(r8(p.num))});
  emit(make_cc(M::Cmovcc, Cond::AE, {R(eax), Dw(addr(d))}));  // not r8b < power: d keeps its value
  emit(M::Mov, {Dw(addr(d)), R(eax)});
  emit(M::And, {R(r8d), R(p)});
  emit(M::Or, {B(L_.addr(Area::S, kBitError)), R(r8b)});
  return true;
}

// -O2, power on for certain: an INT32 division whose operands were divided
// before in the scan (ScanFacts::reused) takes that result, or a - q*b for a
// MOD after a DIV, where the divisor is not 0; where it is, d keeps its value
// and S0 is still set from the earlier division.  No idiv, no branch.
void Gen::reused_division(const ldc::Instr& in, const ldc::DivReuse& r) {
  const ldc::Operand &a = in.a[0], &b = in.a[1], &d = in.a[2];
  if (r.remainder_from_quotient) {
    emit(M::Mov, {R(ecx), Dw(addr(r.from))});
    emit(M::Imul, {R(ecx), Dw(addr(b))});
    load_int(a, eax);
    emit(M::Sub, {R(eax), R(ecx)});  // a - (a / b) * b, wrapping: 0 for b = -1
  } else {
    load_int(r.from, eax);
  }
  emit(M::Cmp, {Dw(addr(b)), I(0)});
  emit(make_cc(M::Cmovcc, Cond::E, {R(eax), Dw(addr(d))}));
  emit(M::Mov, {Dw(addr(d)), R(eax)});
}

void Gen::branch_zero_real(const DivLabels& l) {
  emit(M::Xorps, {R(xmm2), R(xmm2)});
  emit(M::Ucomiss, {R(xmm1), R(xmm2)});
  jcc(Cond::P, l.divide);  // NaN divisor: not zero
  jcc(Cond::E, l.err);
  label(l.divide);
}

void Gen::divisor_branch(int32_t v, const std::string& l) {
  if (v == 0) emit(M::Test, {R(ecx), R(ecx)});
  else emit(M::Cmp, {R(ecx), I(v)});
  jcc(Cond::E, l);
}

void Gen::divide_int(bool mod) {
  emit(M::Cdq, {});
  emit(M::Idiv, {R(ecx)});
  if (mod && quotient_to_) emit(M::Mov, {Dw(addr(*quotient_to_)), R(eax)});  // for a DIV after it
  if (mod) emit(M::Mov, {R(eax), R(edx)});
}

// every branch of DIV / MOD goes forward
void Gen::minus_one_result(bool mod) {
  if (mod && quotient_to_) {  // x / -1 = -x, wrapping, for a DIV after it
    emit(M::Mov, {R(edx), R(eax)});
    emit(M::Neg, {R(edx)});
    emit(M::Mov, {Dw(addr(*quotient_to_)), R(edx)});
  }
  if (mod) emit(M::Xor, {R(eax), R(eax)});
  else emit(M::Neg, {R(eax)});
}

void Gen::word_not(const ldc::Operand& a) {
  load_int(a, eax);
  emit(M::Not, {R(eax)});
}

// eax = a << n or a >> n (logical); counts outside 0..31 give 0
void Gen::shift(Op op, const ldc::Operand& a, const ldc::Operand& n) {
  load_int(a, eax);
  M m = op == Op::SHL ? M::Shl : M::Shr;
  if (n.kind == OpdKind::ConstInt) {
    if (n.ival < 0 || n.ival > 31) emit(M::Xor, {R(eax), R(eax)});
    else if (n.ival > 0) emit(m, {R(eax), I(n.ival)});
  } else if (bases_) {  // -O2, branch-free; unsigned above 31: negative counts too
    load_int(n, ecx);
    emit(m, {R(eax), R(cl)});
    emit(M::Xor, {R(edx), R(edx)});
    emit(M::Cmp, {R(ecx), I(31)});
    emit(make_cc(M::Cmovcc, Cond::A, {R(eax), R(edx)}));
  } else {
    std::string zero = fresh(), store = fresh();
    load_int(n, ecx);
    emit(M::Cmp, {R(ecx), I(31)});
    jcc(Cond::A, zero);  // unsigned: negative counts too
    emit(m, {R(eax), R(cl)});
    jump(store);
    label(zero);
    emit(M::Xor, {R(eax), R(eax)});
    label(store);
  }
}

void Gen::bitwise(Op op, const ldc::Operand& a, const ldc::Operand& b) {
  load_int(a, eax);
  emit(op == Op::WAND ? M::And : op == Op::WOR ? M::Or : M::Xor, {R(eax), int_src(b)});
}

// ABS of an INT32
void Gen::abs_int(const ldc::Operand& a, const ldc::Operand& d) {
  load_int(a, eax);
  emit(M::Mov, {R(ecx), R(eax)});
  emit(M::Sar, {R(ecx), I(31)});
  emit(M::Xor, {R(eax), R(ecx)});
  emit(M::Sub, {R(eax), R(ecx)});
  store_int(d);
}

void Gen::real_fn(Op op, const ldc::Operand& a, const ldc::Operand& d) {
  const RealFn fn = op_info(op).fn;
  load_real(a, xmm0);
  if (real_fn_info(fn).called) {
    emit(M::Call, {Operand::m(mem_at(Size::Qword, uint32_t(call_slot_disp(fn))))});
    // the call may clobber the caller-saved base registers (rdi): point them
    // back (their K is filled in with the region's, BasePlan::rewrite), from
    // rbx, which to_o2_frame makes the -O2 frame's image register
    if (reload_bases_)
      for (RegNum r : as::x86::kBaseRegs)
        if (as::x86::caller_saved(r)) emit(M::Lea, {R(r64(r)), Operand::m(mem_at(Size::None, 0))});
    reload_consts();
  } else if (fn == RealFn::Sqrt) {
    emit(M::Sqrtss, {R(xmm0), R(xmm0)});
  } else {  // Abs: the sign bit cleared
    emit(M::Movd, {R(eax), R(xmm0)});
    emit(M::And, {R(eax), I(0x7fffffff)});
    emit(M::Movd, {R(xmm0), R(eax)});
  }
  store_real(d);
}

// ecx = timer preset, negative counted as 0
void Gen::preset(const ldc::Operand& pt) {
  if (pt.kind == OpdKind::ConstInt) {
    emit(M::Mov, {R(ecx), I(pt.ival < 0 ? 0 : pt.ival)});
    return;
  }
  load_int(pt, ecx);
  emit(M::Xor, {R(edx), R(edx)});
  emit(M::Test, {R(ecx), R(ecx)});
  emit(make_cc(M::Cmovcc, Cond::S, {R(ecx), R(edx)}));
}

// eax = advance(ET, dt, PT) (docs/il.md); ET at tw, PT in ecx; stores it too
void Gen::advance(uint32_t tw) {
  advance_edx(tw);
  emit(M::Mov, {R(eax), R(edx)});
  emit(M::Mov, {Dw(tw), R(eax)});
}

// edx = advance(ET, dt, PT) without a branch; eax = ET (read from tw), PT in
// ecx (>= 0), r10d the wrapped sum.  The IL's rule: ET >= PT ? PT : min(ET +
// dt, PT) with the sum exact.  edx starts at PT; after the add, L says the
// exact sum is negative (below PT: the IL keeps the wrapped sum, exact unless
// it overflowed downwards); else the sum at most PT unsigned is the sum itself,
// and above PT unsigned it is above PT exactly (an upward overflow too: its
// wrapped value is 2^32 less, over 2^31 unsigned).
void Gen::advance_edx(uint32_t tw) {
  emit(M::Mov, {R(eax), Dw(tw)});
  emit(M::Mov, {R(r10d), R(eax)});
  emit(M::Add, {R(r10d), Dw(kSysDt)});
  emit(M::Mov, {R(edx), R(ecx)});
  emit(make_cc(M::Cmovcc, Cond::L, {R(edx), R(r10d)}));
  emit(M::Cmp, {R(r10d), R(ecx)});
  emit(make_cc(M::Cmovcc, Cond::BE, {R(edx), R(r10d)}));
  emit(M::Cmp, {R(eax), R(ecx)});
  emit(make_cc(M::Cmovcc, Cond::GE, {R(edx), R(ecx)}));
}

// RSTT / RSTC with power: each operand &= (top - 1), 0 with power, all ones without
void Gen::reset_masked(std::initializer_list<Operand> dwords, std::initializer_list<Operand> bytes) {
  if (known_.on()) {  // power on for certain: plain zero stores
    for (const Operand& o : dwords) emit(M::Mov, {o, I(0)});
    for (const Operand& o : bytes) emit(M::Mov, {o, I(0)});
    return;
  }
  if (slots_) emit(M::Movzx, {R(ecx), R(top8())});
  else { emit(M::Mov, {R(ecx), R(ebp)}); emit(M::And, {R(ecx), I(1)}); }
  emit(M::Sub, {R(ecx), I(1)});
  for (const Operand& o : dwords) emit(M::And, {o, R(ecx)});
  for (const Operand& o : bytes) emit(M::And, {o, R(cl)});
}

// -O2 timers: a call to the shared routine of the kind (as::x86::scan_routine:
// branch-free, conditional moves over every outcome) with the timer number in
// edx, the preset in ecx and the input in esi.
void Gen::timer_gated(const ldc::Instr& in) {
  power_to_esi();
  preset(in.a[1]);  // clamped here, not in the routine: most presets are constants
  emit(M::Mov, {R(r8(DX)), I(int32_t(in.a[0].index & 0xff))});  // the routine takes dl only (movzx edx, dl)
  call_routine(in.op == Op::TON ? as::x86::Routine::Ton : in.op == Op::TOF ? as::x86::Routine::Tof : as::x86::Routine::Tp);
}

// -O2, TON with power on for certain: ET = TI ? advance(ET) : 0 (the input's
// first scan), Q = ET >= PT, TI = 1, without a branch or a call.
void Gen::ton_on(const ldc::Instr& in, uint32_t tw, uint32_t tq, uint32_t ti) {
  preset(in.a[1]);
  advance_edx(tw);
  emit(M::Xor, {R(eax), R(eax)});
  emit(M::Cmp, {B(ti), I(0)});
  emit(make_cc(M::Cmovcc, Cond::E, {R(edx), R(eax)}));
  emit(M::Mov, {Dw(tw), R(edx)});
  emit(M::Cmp, {R(edx), R(ecx)});
  emit(make_cc(M::Setcc, Cond::GE, {R(al)}));
  emit(M::Mov, {B(tq), R(al)});
  emit(M::Mov, {B(ti), I(1)});
}

// -O2 with the stack in the slots, MTON (MatIEC's TON, docs/il.md) without a
// branch: running = IN and TI (not the rising scan, not off); done before
// (Q): ET and Q held, else ET advanced and Q = ET >= PT; not running: ET = 0,
// Q = 0; then TI = IN.  (ST's timers are MTON: a branch on each of IN, TI and
// Q is mispredicted wherever they change.)
void Gen::mton_slots(const ldc::Instr& in, uint32_t tw, uint32_t tq, uint32_t ti) {
  power_to_esi();
  preset(in.a[1]);
  advance_edx(tw);  // eax = ET, edx = advanced
  emit(M::Movzx, {R(r10d), B(tq)});
  emit(M::Test, {R(r10d), R(r10d)});
  emit(make_cc(M::Cmovcc, Cond::NE, {R(edx), R(eax)}));  // done: ET held
  emit(M::Cmp, {R(edx), R(ecx)});
  emit(make_cc(M::Setcc, Cond::GE, {R(al)}));
  emit(M::Movzx, {R(eax), R(al)});
  emit(M::Or, {R(eax), R(r10d)});  // done, or done now
  emit(M::Xor, {R(r10d), R(r10d)});
  emit(M::Movzx, {R(r11d), B(ti)});
  emit(M::And, {R(r11d), R(esi)});  // running (its flags: the cmove's)
  emit(make_cc(M::Cmovcc, Cond::E, {R(edx), R(r10d)}));  // not running: ET = 0
  emit(M::And, {R(eax), R(r11d)});
  emit(M::Mov, {Dw(tw), R(edx)});
  emit(M::Mov, {B(tq), R(al)});
  remember_input(ti);
}

// -O2: RSTT gated by a mask, TON TOF TP by the shared routines (they have
// ldc's own rules; MTON inline without a branch, MTOF and MTP inline)
bool Gen::gated_timer(const ldc::Instr& in, uint32_t tw, uint32_t tq, uint32_t ti) {
  if (!gate_) return false;
  // power on for certain: TON straight-line (ton_on); TOF and TP inline without
  // their power tests (TOF is three stores, TP branches on flags that change rarely)
  if (in.op == Op::TON && known_.on()) return ton_on(in, tw, tq, ti), true;
  if (in.op == Op::MTON && slots_) return mton_slots(in, tw, tq, ti), true;
  if (in.op != Op::RSTT && known_.on()) return false;
  if (in.op == Op::RSTT) reset_masked({Dw(tw)}, {B(tq), B(ti)});
  else if (in.op == Op::TON || in.op == Op::TOF || in.op == Op::TP) timer_gated(in);
  else return false;
  return true;
}

// tq = (eax rel ecx): Q from ET and PT
void Gen::q_et(uint32_t tq, Rel rel) {
  emit(M::Cmp, {R(eax), R(ecx)});
  emit(make_cc(M::Setcc, x86_rel(rel).int_cc, {R(al)}));
  emit(M::Mov, {B(tq), R(al)});
}

// tq = (ecx > 0): Q when a timing starts
void Gen::q_preset(uint32_t tq) {
  emit(M::Test, {R(ecx), R(ecx)});
  emit(make_cc(M::Setcc, Cond::G, {R(al)}));
  emit(M::Mov, {B(tq), R(al)});
}

// ti = the top (IN, for the next scan's edge)
void Gen::remember_input(uint32_t ti) {
  if (slots_) emit(M::Mov, {B(ti), R(top8())});
  else { top_to_eax(); emit(M::Mov, {B(ti), R(al)}); }
}


// -O2 counters: the shared routine with the counter number in edx, the preset
// in ecx, the power in esi and the edge slot's number in r8d (the routine
// keeps the input there and counts its rising edge).
void Gen::counter_gated(const ldc::Instr& in) {
  power_to_esi();
  emit(M::Mov, {R(r32(R8)), I(int32_t(in.a[2].index))});
  emit(M::Mov, {R(r8(DX)), I(int32_t(in.a[0].index & 0xff))});  // the routine takes dl only (movzx edx, dl)
  bool up = in.op == Op::CTU;
  if (up) load_int(in.a[1], ecx);
  call_routine(up ? as::x86::Routine::Ctu : as::x86::Routine::Ctd);
}

// -O2: RSTC gated by a mask, CTU CTD by the shared routines
bool Gen::gated_counter(const ldc::Instr& in, uint32_t cw, uint32_t cq) {
  if (!gate_) return false;
  // power on for certain: the edge comes only on the first scan, so count()'s
  // branch on it is always predicted and beats the routine's straight line
  if (in.op != Op::RSTC && known_.on()) return false;
  if (in.op == Op::RSTC) reset_masked({Dw(cw)}, {B(cq)});
  else counter_gated(in);
  return true;
}


// CTU / CTD without -O2: the rising edge of the input, then CV and Q
void Gen::count(const ldc::Instr& in, uint32_t cw, uint32_t cq) {
  bool up = in.op == Op::CTU;
  uint32_t e = addr(in.a[2]);
  std::string q = fresh();
  top_to_eax();
  emit(M::Movzx, {R(ecx), B(e)});
  emit(M::Mov, {B(e), R(al)});
  emit(M::Not, {R(ecx)});
  emit(M::And, {R(eax), R(ecx)});  // rising edge of the input
  emit(M::Mov, {R(edx), Dw(cw)});
  jcc(Cond::E, q);
  emit(M::Cmp, {R(edx), I(up ? INT32_MAX : INT32_MIN)});
  jcc(Cond::E, q);
  emit(up ? M::Add : M::Sub, {R(edx), I(1)});
  emit(M::Mov, {Dw(cw), R(edx)});
  label(q);
  if (up) {
    load_int(in.a[1], eax);
    emit(M::Cmp, {R(edx), R(eax)});
    emit(make_cc(M::Setcc, Cond::GE, {R(al)}));
  } else {
    emit(M::Test, {R(edx), R(edx)});
    emit(make_cc(M::Setcc, Cond::LE, {R(al)}));
  }
  emit(M::Mov, {B(cq), R(al)});
}

// At -O2 an instruction of the move, arith, logic or special class whose power
// is on for certain (KnownStack: a rung from the rail, `TRUE`) is emitted with
// neither gate nor test; timers and counters then take their inline code
// without the power tests (gated_timer, gated_counter).
//
// A dead store needs no code, nor does a typed instruction whose destination
// already holds its result, an unread stack entry none but an edge
// contact's edge update (ir/scanopt.h); the stack is followed all the same.
void Gen::instr(const ldc::Instr& in, uint8_t facts, const ldc::DivReuse* reuse, const ldc::Operand* quotient_to) {
  if (!idx_fault_.empty() && ((in.op != Op::TLDX && in.op != Op::TSTX) || (facts & (kDeadStore | kUnread | kHeld))))
    flush_idx_check();  // (Blocks sets next_ only where the access comes and is compiled: a safety net)
  OpClass k = op_info(in.op).klass;
  if (k != OpClass::Typed || op_info(in.op).push) close_typed_run();
  reuse_ = reuse;
  quotient_to_ = quotient_to;
  on_ = bases_ && known_.on() &&
        (k == OpClass::Move || k == OpClass::Arith || k == OpClass::Logic || k == OpClass::Special);
  if ((facts & kUnread) && (in.op == Op::LOADP || in.op == Op::LOADF)) {
    emit(M::Movzx, {R(eax), B(addr(in.a[0]))});
    emit(M::Mov, {B(addr(in.a[1])), R(al)});
  } else if (!(facts & (kDeadStore | kUnread | kHeld))) {
    Ungated plain(gate_, on_);
    gen_by_class(*this, in);
  }
  on_ = false;
  reuse_ = nullptr;
  quotient_to_ = nullptr;
  follow(in);
}

// What `in` does to the stack, followed at compile time (its code made or not)
void Gen::follow(const ldc::Instr& in) {
  if (bases_) known_.step(in);
  if (o1_) power_.step(in);
  depth_ += op_info(in.op).push - op_info(in.op).pop;
}

// -O2 bit instructions: one or two operations on the slot registers.  A push
// writes the whole 32-bit register (movzx, mov r32), so a slot never depends
// on what it held in an earlier rung (no partial-register chain), and its
// upper bits are zero: 32-bit copies and masks are exact.
void Gen::bit_slots(const ldc::Instr& in) {
  Reg d = slot(depth_), t = slot(depth_ - 1), u = slot(depth_ - 2);
  Reg dw = wide(d), tw = wide(t), uw = wide(u);
  Operand b0 = in.nopd() > 0 ? B(addr(in.a[0])) : Operand{}, b1 = in.nopd() > 1 ? B(addr(in.a[1])) : Operand{};
  const Operand r0 = in.nopd() > 0 && in.a[0].kind == OpdKind::Bit ? held_byte(addr(in.a[0])) : b0;
  switch (in.op) {
    case Op::LOAD: return emit(M::Movzx, {R(dw), r0});
    case Op::LOADN: emit(M::Movzx, {R(dw), r0}); return emit(M::Xor, {R(dw), I(1)});
    case Op::AND: return emit(M::And, {R(t), r0});
    case Op::OR: return emit(M::Or, {R(t), r0});
    case Op::ANDN:  // top & !b of two 0/1 bytes is top > b
      emit(M::Cmp, {R(t), r0});
      return emit(make_cc(M::Setcc, Cond::A, {R(t)}));
    case Op::ORN:  // top | !b is top >= b
      emit(M::Cmp, {R(t), r0});
      return emit(make_cc(M::Setcc, Cond::AE, {R(t)}));
    case Op::LOADP:  // d = b & !e (of 0/1 bytes: b > e); e = b (mov keeps the flags)
    case Op::LOADF:  // d = !b & e (b < e); e = b
      emit(M::Movzx, {R(dw), b0});
      emit(M::Cmp, {R(d), b1});
      emit(M::Mov, {b1, R(d)});
      return emit(make_cc(M::Setcc, in.op == Op::LOADP ? Cond::A : Cond::B, {R(d)}));
    case Op::TRUE: return emit(M::Mov, {R(dw), I(1)});
    case Op::ANDBLK: return emit(M::And, {R(uw), R(tw)});
    case Op::ORBLK: return emit(M::Or, {R(uw), R(tw)});
    case Op::MPS: return emit(M::Mov, {R(dw), R(tw)});
    case Op::MRD: return emit(M::Mov, {R(tw), R(uw)});
    case Op::MPP: return;
    case Op::OUT:
      emit(M::Mov, {b0, R(t)});
      return in.a[0].kind == OpdKind::Bit ? hold(t.num, Ty::BOOL, addr(in.a[0]), true) : void();
    case Op::SET: return emit(M::Or, {b0, R(t)});
    case Op::OUTN: case Op::RST:
      emit(M::Mov, {R(eax), R(tw)});
      emit(M::Xor, {R(eax), I(1)});
      return emit(in.op == Op::OUTN ? M::Mov : M::And, {b0, R(al)});
    default: break;
  }
  throw std::logic_error(std::string("x86 backend: no -O2 form for ") + op_info(in.op).name);
}

// The bit instructions: -O2 on the slot registers, else their template with
// the placeholders replaced by the operands' addresses.
void Gen::basic(const ldc::Instr& in) {
  if (slots_) return bit_slots(in);
  const std::vector<Instruction>* t = bit_template(in.op);
  if (!t) throw std::logic_error(std::string("x86 backend: no template for ") + op_info(in.op).name);
  for (Instruction i : *t) {
    for (int k = 0; k < i.num_operands; k++) {
      Mem& m = i.ops[k].mem;
      if (i.ops[k].kind != OperandKind::Mem) continue;
      if (m.disp == kMark[0]) m.disp = int32_t(addr(in.a[0]));
      else if (m.disp == kMark[1]) m.disp = int32_t(addr(in.a[1]));
    }
    emit(std::move(i));
  }
}

void Gen::flow(const ldc::Instr& in) {
  if (in.op == Op::LOOP) return loop(in);
  const std::string to = in.op == Op::JMP ? x86_label_name(in.a[0].label) : kX86ExitLabel;
  if (bases_ && known_.on()) return emit(far(make(M::Jmp, {L(to)})));  // -O2, `TRUE; JMP l` (an ST ELSIF arm's end): taken for certain
  test_top();
  emit(far(make_cc(M::Jcc, Cond::NE, {L(to)})));
}

// LOOP (docs/il.md "Loops"): with power, the back edge counted in Sys
// kSysLoops and taken below the budget, else the loop fault; the shape the
// loader's code check admits as the one backward branch (docs/image-format.md):
//   add dword [rbx+kSysLoops], 1; cmp dword [rbx+kSysLoops], kLoopBudget; jae fault; jmp head
void Gen::loop(const ldc::Instr& in) {
  std::string skip = fresh(), fault = fresh();
  test_top();
  jcc(Cond::E, skip);
  emit(M::Add, {Dw(kSysLoops), I(1)});
  emit(M::Cmp, {Dw(kSysLoops), I(kLoopBudget)});
  emit(far(make_cc(M::Jcc, Cond::AE, {L(fault)})));
  emit(far(make(M::Jmp, {L(x86_label_name(in.a[0].label))})));
  label(fault);
  for (const Instruction& i : fault_record(kFaultLoop, I(kLoopBudget))) emit(i);
  label(skip);
}

// ------------------------------------------------------------ typed instructions
//
// docs/x86.md, "Typed instructions": the IEC types at their widths, exactly as
// ir/typed.h computes them.  A type of up to 32 bits works in a 32-bit
// register, extended to 32 bits as its cell holds it (movsx / movzx loads); a
// 64-bit type in a 64-bit register; REAL and LREAL in xmm0 / xmm1.  Add, sub,
// mul, the logic and neg depend only on the low bits of their operands: they
// take the raw cells and the store cuts the result to the width.  Every typed
// instruction but the compares is skipped by a branch without power (the
// -O2 gating by cmov is for the INT32 words); none where the power is on for
// certain.
namespace {
const Reg rax = r64(AX), rcx = r64(CX), rdx = r64(DX), r10 = r64(R10), r11 = r64(R11);
Operand Q(uint32_t addr) { return Operand::m(mem_at(Size::Qword, addr)); }
Operand W16(uint32_t addr) { return Operand::m(mem_at(Size::Word, addr)); }
int ty_bits(Ty t) { return ty_info(t).bits; }
bool two_cells(Ty t) { return ty_info(t).cells == 2; }
bool is_tconst(const ldc::Operand& o) { return o.kind == OpdKind::ConstT || o.kind == OpdKind::ConstInt; }
uint64_t tconst(const ldc::Operand& o) { return o.kind == OpdKind::ConstT ? o.bits() : uint64_t(int64_t(o.ival)); }
constexpr uint64_t kSignBit64 = uint64_t(1) << 63;
}  // namespace

void RealConsts::count(std::vector<std::pair<Key, int>>& n, Key c) {
  auto it = std::find_if(n.begin(), n.end(), [&](const auto& e) { return e.first == c; });
  if (it == n.end()) n.push_back({c, 1});
  else it->second++;
}

// A CONV from REAL / LREAL to an integer or bit string type (real_round_to_int)?
bool RealConsts::rounds_to_int(Ty to) {
  const TyKind k = ty_info(to).kind;
  return k != TyKind::Bool && k != TyKind::Real && k != TyKind::Time && k != TyKind::Date && k != TyKind::String;
}

// The operands counted are those load_x / real_src would load: both sources
// of a REAL / LREAL ADD SUB MUL DIV MIN MAX or compare; and 0.5 and the sign
// bit for each CONV that real_round_to_int makes.
RealConsts RealConsts::of(const Program& p) {
  std::vector<std::pair<Key, int>> n;
  for (const Rung& r : p.rungs)
    for (const ldc::Instr& in : r.code) {
      const OpInfo& oi = op_info(in.op);
      if (in.op == Op::TCONV && typed::is_real(in.src) && rounds_to_int(in.ty)) {  // real_round_to_int's s
        count(n, {typed::bits_of(0.5), false});
        if (typed::is_signed(in.ty)) count(n, {kSignBit64, false});
      }
      if (oi.klass != OpClass::Typed || !typed::is_real(in.ty)) continue;
      const bool binary = in.op == Op::TADD || in.op == Op::TSUB || in.op == Op::TMUL || in.op == Op::TDIV ||
                          in.op == Op::TMIN || in.op == Op::TMAX;
      if (!binary && !oi.push) continue;
      const bool single = ty_bits(in.ty) == 32;
      for (int k = 0; k < 2; k++) {
        if (!is_tconst(in.a[k])) continue;
        const Key c{single ? tconst(in.a[k]) & UINT32_MAX : tconst(in.a[k]), single};
        if (c.bits != 0) count(n, c);  // (0 is xorps)
      }
    }
  std::stable_sort(n.begin(), n.end(), [](const auto& a, const auto& b) { return a.second > b.second; });
  RealConsts rc;
  for (const auto& [c, uses] : n)
    if (uses >= 2 && int(rc.keys_.size()) < kRegs) rc.keys_.push_back(c);
  return rc;
}

bool Gen::is_select(const ldc::Instr& load, const ldc::Instr& move, const ldc::Instr& mpp) {
  if ((load.op != Op::LOAD && load.op != Op::LOADN) || move.op != Op::TMOVE || mpp.op != Op::MPP) return false;
  const Ty t = move.ty;
  if (t == Ty::BOOL || typed::is_string_instr(move.op, t, move.src)) return false;
  return ty_bits(t) == 32 || ty_bits(t) == 64 || ty_bits(t) == 16 || ty_bits(t) == 8;
}
// `mov eax, a` (a's value extended as MOVE.T stores it); `cmp byte g, 0;
// cmove eax, d; mov d, eax`: d's cell rewritten as it was where g is 0 (rax
// for two cells).
// LOAD pushes g as the top and MPP pops it: the stack is as before.
void Gen::select(const ldc::Instr& load, const ldc::Instr& move, const ldc::Instr& mpp) {
  close_typed_run();
  const Ty t = move.ty;
  const ldc::Operand &a = move.a[0], &d = move.a[1];
  const bool wide = two_cells(t);
  const Reg r = wide ? rax : eax;
  if (wide) load64(t, a, rax);
  else load32(t, a, eax);  // canonical, as MOVE.T stores it (a D word an untyped instruction wrote may not be)
  emit(M::Cmp, {B(addr(load.a[0])), I(0)});
  emit(make_cc(M::Cmovcc, load.op == Op::LOAD ? Cond::E : Cond::NE, {R(r), wide ? Q(taddr(d)) : Dw(taddr(d))}));
  emit(M::Mov, {wide ? Q(taddr(d)) : Dw(taddr(d)), R(r)});
  for (const ldc::Instr* in : {&load, &move, &mpp}) follow(*in);
}

// r (64-bit) = v, in the shortest form
void Gen::mov_imm(Reg r, uint64_t v) {
  if (v <= UINT32_MAX) emit(M::Mov, {R(r32(r.num)), I(int64_t(v))});
  else emit(M::Mov, {R(r), I(int64_t(v))});  // imm32 sign-extended, or movabs
}

// What an instruction ends: the registers it writes, the cells whose bytes
// it may write (all of them for a call or an indexed or unknown operand).
void Gen::forget_written(const Instruction& i) {
  if (i.mnemonic == M::Call) return forget_all();
  if (i.num_operands && i.ops[0].kind == OperandKind::Mem && i.mnemonic != M::Cmp && i.mnemonic != M::Test) {
    const Mem& m = i.ops[0].mem;
    if (m.index.valid() || !(m.base == r64(BX)) || m.size == Size::None) return forget_all();
    const uint32_t first = uint32_t(m.disp), end = first + mem_width(m);
    for (Held& h : held_)
      if (h.valid && h.addr < end && first < h.addr + held_width(h.ty)) h.valid = false;
    if (idx_held_.valid && idx_held_.addr < end && first < idx_held_.addr + held_width(idx_held_.ty)) idx_held_.valid = false;
  }
  for (uint8_t n = 0; n < held_.size(); n++)
    if (held_[n].valid && writes_reg(i, n)) held_[n].valid = false;
  if (idx_held_.valid && writes_reg(i, R11)) idx_held_.valid = false;
  if (scaled_ && (writes_reg(i, R10) || writes_reg(i, R11))) scaled_ = 0;
}

// Are bits 63..32 of register n zero: did its last writer in this straight
// line write its 32-bit form (a `setcc` of its low byte keeps them)?
bool Gen::upper_zero_now(uint8_t n) const {
  for (size_t k = items_.size(), seen = 0; k-- > 0 && seen < 16;) {
    const Item& it = items_[k];
    if (it.kind == as::ItemKind::Label) return false;
    if (it.kind != as::ItemKind::Instruction) continue;
    seen++;
    const Instruction& i = it.inst;
    if (!writes_reg(i, n) || i.mnemonic == M::Setcc) continue;  // a setcc keeps bits 63..8: the writer before it decides
    return zero_extends(i, n);
  }
  return false;
}

// A value: the same type, or integer types whose loads extend alike (a
// 32-bit cell is its value whatever its type).
int Gen::holder(Ty t, uint32_t addr) const {
  if (!any_held_) return -1;
  for (int n = 0; n < int(held_.size()); n++) {
    const Held& h = held_[size_t(n)];
    if (!h.valid || h.addr != addr) continue;
    if (h.ty == t) return n;
    if (t == Ty::BOOL || h.ty == Ty::BOOL || two_cells(t) || two_cells(h.ty) || typed::is_real(t) || typed::is_real(h.ty)) continue;
    if (ty_bits(t) == 32 && ty_bits(h.ty) == 32) return n;
    if (ty_bits(t) == ty_bits(h.ty) && typed::is_signed(t) == typed::is_signed(h.ty)) return n;
  }
  return -1;
}

// The cell's first `width` bytes (4 or 8) as they are in memory.
int Gen::raw_holder(uint32_t addr, uint32_t width) const {
  if (!any_held_) return -1;
  for (int n = 0; n < int(held_.size()); n++) {
    const Held& h = held_[size_t(n)];
    if (h.valid && h.exact && h.addr == addr && h.ty != Ty::BOOL && held_width(h.ty) >= width) return n;
  }
  return -1;
}

// r (32-bit) = o's value of type t (up to 32 bits), extended to 32 bits as its cell holds it
void Gen::load32(Ty t, const ldc::Operand& o, Reg r) {
  if (is_tconst(o)) return emit(M::Mov, {R(r), I(int64_t(uint32_t(tconst(o))))});
  const uint32_t a = taddr(o);
  const bool sgn = typed::is_signed(t);
  if (int n = holder(t, a); n >= 0) {
    const Held h = held_[size_t(n)];
    // its low byte is 0 or 1 / a 32-bit move clears bits 63..32, which a 64-bit value cut at its store left set
    if (t == Ty::BOOL) emit(M::Movzx, {R(r), R(r8(uint8_t(n)))});
    else if (n != r.num || !h.upper_zero) emit(M::Mov, {R(r), R(r32(uint8_t(n)))});
    return hold(r.num, h.ty, a, h.exact, true);
  }
  if (t == Ty::BOOL) {  // any byte but 0 is 1 (typed::load)
    emit(M::Xor, {R(r), R(r)});
    emit(M::Cmp, {B(a), I(0)});
    emit(make_cc(M::Setcc, Cond::NE, {R(r8(r.num))}));
  } else {
    switch (ty_bits(t)) {
      case 8: emit(sgn ? M::Movsx : M::Movzx, {R(r), B(a)}); break;
      case 16: emit(sgn ? M::Movsx : M::Movzx, {R(r), W16(a)}); break;
      default: emit(M::Mov, {R(r), Dw(a)}); break;
    }
  }
  hold(r.num, t, a, t != Ty::BOOL && ty_bits(t) == 32, true);
}

// eax = a, ecx = b (load32): b first where eax holds it
void Gen::load_pair(Ty t, const ldc::Operand& a, const ldc::Operand& b) {
  if (!is_tconst(b) && holder(t, taddr(b)) == AX) return load32(t, b, ecx), load32(t, a, eax);
  load32(t, a, eax), load32(t, b, ecx);
}

// r (32-bit) = o's cell as it is (the low bits of a wrapping operation)
void Gen::load_raw32(const ldc::Operand& o, Reg r) {
  if (is_tconst(o)) return emit(M::Mov, {R(r), I(int64_t(uint32_t(tconst(o))))});
  if (const int n = raw_holder(taddr(o), 4); n == r.num && held_[size_t(n)].upper_zero) return;  // there, as a load leaves it
  emit(M::Mov, {R(r), src32(o)});
  hold(r.num, Ty::DWORD, taddr(o), true, true);
}

// the second operand of `op r32, <o>`: the register holding o's 32-bit cell exactly, or the cell
Operand Gen::src32(const ldc::Operand& o) const {
  if (int n = raw_holder(taddr(o), 4); n >= 0) return R(r32(uint8_t(n)));
  return Dw(taddr(o));
}

// r (64-bit) = o's canonical value of type t (typed.h: sign- or zero-extended)
void Gen::load64(Ty t, const ldc::Operand& o, Reg r) {
  if (is_tconst(o)) return mov_imm(r, tconst(o));
  if (two_cells(t)) {
    const uint32_t a = taddr(o);
    if (int n = raw_holder(a, 8); n >= 0) {
      if (n != r.num) emit(M::Mov, {R(r), R(r64(uint8_t(n)))});
    } else {
      emit(M::Mov, {R(r), Q(a)});
    }
    return hold(r.num, t, a, true);
  }
  if (typed::is_signed(t) && r.num != AX) {  // SINT INT DINT sign-extended at once (an IDX's index into r11)
    const uint32_t a = taddr(o);
    if (int n = holder(t, a); n >= 0) emit(M::Movsxd, {R(r), R(r32(uint8_t(n)))});  // (as load32 would have it)
    else if (ty_bits(t) == 8) emit(M::Movsx, {R(r), B(a)});
    else if (ty_bits(t) == 16) emit(M::Movsx, {R(r), W16(a)});
    else emit(M::Movsxd, {R(r), Dw(a)});
    return hold(r.num, t, a, ty_bits(t) == 32, false);
  }
  load32(t, o, r32(r.num));  // a 32-bit write clears bits 63..32: zero-extended
  if (typed::is_signed(t)) emit(M::Cdqe, {});  // (rax)
}

// r (32-bit) cut to t's width and extended as t's cell holds it
void Gen::normalize(Ty t, Reg r) {
  if (t == Ty::BOOL || ty_bits(t) >= 32) return;
  const bool sgn = typed::is_signed(t);
  if (ty_bits(t) == 8) return emit(sgn ? M::Movsx : M::Movzx, {R(r), R(r8(r.num))});
  if (!sgn) return emit(M::And, {R(r), I(0xffff)});
  if (r.num == AX) return emit(M::Cwde, {});
  emit(M::Shl, {R(r), I(16)});
  emit(M::Sar, {R(r), I(16)});
}

// d = register n's value of type t (BOOL: its low byte, 0 or 1); canonical:
// the register holds t's canonical value already (no cut at the store)
void Gen::store_int_reg(Ty t, RegNum n, const ldc::Operand& d, bool canonical) {
  if (t == Ty::BOOL) emit(M::Mov, {B(taddr(d)), R(r8(n))});
  else if (two_cells(t)) emit(M::Mov, {Q(taddr(d)), R(r64(n))});
  else {
    if (!canonical) normalize(t, r32(n));
    emit(M::Mov, {Dw(taddr(d)), R(r32(n))});
  }
  hold(n, t, taddr(d), true, t != Ty::BOOL && !two_cells(t) && upper_zero_now(n));
}

// x = o (REAL or LREAL), its bits as they are
void Gen::load_x(Ty t, const ldc::Operand& o, Reg x) {
  const bool single = ty_bits(t) == 32;
  if (is_tconst(o)) {
    uint64_t v = tconst(o);
    if (v == 0) return emit(M::Xorps, {R(x), R(x)});
    if (auto k = const_reg(single ? v & UINT32_MAX : v, single)) return emit(single ? M::Movss : M::Movsd, {R(x), R(*k)});
    if (single) return emit(M::Mov, {R(edx), I(int64_t(uint32_t(v)))}), emit(M::Movd, {R(x), R(edx)});
    mov_imm(rdx, v);
    return emit(M::Movq, {R(x), R(rdx)});
  }
  if (from_held(t, o, x)) return;
  if (single) return emit(M::Movss, {R(x), Dw(taddr(o))});
  emit(M::Movsd, {R(x), Q(taddr(o))});
}

// -O2: x = the bits of cell o from the general register that holds them
// exactly (an LDX's element in eax, say), if one does
bool Gen::from_held(Ty t, const ldc::Operand& o, Reg x) {
  const int n = holder(t, taddr(o));
  if (n < 0 || !held_[size_t(n)].exact) return false;
  const bool single = ty_bits(t) == 32;
  emit(single ? M::Movd : M::Movq, {R(x), R(single ? r32(uint8_t(n)) : r64(uint8_t(n)))});
  return true;
}

// x = o's value as a double (a REAL widened: exact)
void Gen::load_xd(Ty t, const ldc::Operand& o, Reg x) {
  if (ty_bits(t) == 64) return load_x(t, o, x);
  if (is_tconst(o)) return double_const(x, double(typed::f32(tconst(o))));
  emit(M::Cvtss2sd, {R(x), Dw(taddr(o))});
}

void Gen::double_const(Reg x, double d) {
  uint64_t v = typed::bits_of(d);
  if (v == 0) return emit(M::Xorps, {R(x), R(x)});
  if (auto k = const_reg(v, false)) return emit(M::Movsd, {R(x), R(*k)});
  mov_imm(rdx, v);
  emit(M::Movq, {R(x), R(rdx)});
}

// the second operand of an SSE operation on type t: o's memory, or x loaded
// with the constant, or with the cell's bits from the general register that
// holds them (-O2: an LDX's element in eax; no reload of the store just made)
Operand Gen::real_src(Ty t, const ldc::Operand& o, Reg x) {
  if (is_tconst(o)) return R(real_reg(t, o, x));
  if (from_held(t, o, x)) return R(x);
  return ty_bits(t) == 32 ? Dw(taddr(o)) : Q(taddr(o));
}

// the register that holds o (REAL or LREAL): its constant's register, else x loaded with it
Reg Gen::real_reg(Ty t, const ldc::Operand& o, Reg x) {
  const bool single = ty_bits(t) == 32;
  if (is_tconst(o))
    if (auto k = const_reg(single ? tconst(o) & UINT32_MAX : tconst(o), single)) return *k;
  load_x(t, o, x);
  return x;
}

void Gen::store_x(Ty t, Reg x, const ldc::Operand& d) {
  if (ty_bits(t) == 32) emit(M::Movss, {Dw(taddr(d)), R(x)});
  else emit(M::Movsd, {Q(taddr(d)), R(x)});
}

// d = x, a double, as t (REAL rounds to binary32)
void Gen::store_xd(Ty t, Reg x, const ldc::Operand& d) {
  if (ty_bits(t) == 32) emit(M::Cvtsd2ss, {R(x), R(x)});
  store_x(t, x, d);
}

// A run of typed instructions that do not push shares one power test: none
// of them changes the stack, so one `test; je` skips the whole run (the label
// is placed when an instruction of another kind comes, or the rung ends:
// close_typed_run).
void Gen::typed(const ldc::Instr& in) {
  if (typed::is_string_instr(in.op, in.ty, in.src)) return typed_string(in);
  if (op_info(in.op).push) return typed_compare(in);
  if (typed_skip_.empty() && !power_known_on()) {
    typed_skip_ = fresh();
    test_top();
    jcc(Cond::E, typed_skip_);
  }
  switch (in.op) {
    case Op::TMOVE: typed_move(in); break;
    case Op::TADD: case Op::TSUB: case Op::TMUL: typed_arith(in); break;
    case Op::TDIV: case Op::TMOD: typed_divmod(in); break;
    case Op::TMIN: case Op::TMAX: typed_minmax(in); break;
    case Op::TAND: case Op::TOR: case Op::TXOR: case Op::TNOT: typed_logic(in); break;
    case Op::TSHL: case Op::TSHR: case Op::TROL: case Op::TROR: typed_shift(in); break;
    case Op::TNEG: case Op::TABS: typed_neg_abs(in); break;
    case Op::TSQRT: case Op::TLN: case Op::TLOG: case Op::TEXP: case Op::TSIN: case Op::TCOS: case Op::TTAN:
    case Op::TASIN: case Op::TACOS: case Op::TATAN: case Op::TEXPT: typed_math(in); break;
    case Op::TCONV: case Op::TTRUNC: typed_conv(in); break;
    case Op::TIDX: typed_idx(in); break;
    case Op::TLDX: case Op::TSTX: typed_indexed(in); break;
    default: throw std::logic_error(std::string("x86 backend: no code for the typed instruction ") + op_info(in.op).name);
  }
}

// push (a REL b) of type t: signed, unsigned or IEEE (kX86Rels) by the kind
void Gen::typed_compare(const ldc::Instr& in) {
  const Ty t = in.ty;
  const X86Rel& x = x86_rel(op_info(in.op).rel);
  if (typed::is_real(t)) {
    const bool single = ty_bits(t) == 32;
    const Reg a = real_reg(t, in.a[0], xmm0), b = real_reg(t, in.a[1], xmm1);
    const M ucom = single ? M::Ucomiss : M::Ucomisd;
    if (x.swap) emit(ucom, {R(b), R(a)});
    else emit(ucom, {R(a), R(b)});
    emit(make_cc(M::Setcc, x.real_cc, {R(al)}));
    if (x.parity) {
      emit(make_cc(M::Setcc, x.parity_cc, {R(cl)}));
      emit(x.parity_op, {R(al), R(cl)});
    }
    return push_al();
  }
  // -O2: the result straight into its slot, zeroed before the compare; eax
  // keeps the operand it was loaded with (a CASE compares one value again and again)
  const Reg slot8 = slots_ ? slot(depth_) : al;
  if (slots_) emit(M::Xor, {R(wide(slot8)), R(wide(slot8))});
  emit(make_cc(M::Setcc, int_compare(in), {R(slot8)}));
  if (!slots_) push_al();
}

// The flags of an integer compare (a REL b), and the condition that is its result:
// signed: the INT32 conditions; unsigned (bits, BOOL): below / above
Cond Gen::int_compare(const ldc::Instr& in) {
  const Ty t = in.ty;
  static constexpr Cond kUnsigned[] = {Cond::E, Cond::NE, Cond::B, Cond::BE, Cond::A, Cond::AE};
  const Cond cc = typed::is_signed(t) ? x86_rel(op_info(in.op).rel).int_cc : kUnsigned[int(op_info(in.op).rel)];
  if (two_cells(t)) {
    load64(t, in.a[0], rax);
    const ldc::Operand& b = in.a[1];
    if (is_tconst(b) && int64_t(tconst(b)) == int64_t(int32_t(tconst(b)))) emit(M::Cmp, {R(rax), I(int64_t(tconst(b)))});
    else if (is_tconst(b)) mov_imm(rcx, tconst(b)), emit(M::Cmp, {R(rax), R(rcx)});
    else emit(M::Cmp, {R(rax), Q(taddr(b))});
  } else {
    const ldc::Operand &a = in.a[0], &b = in.a[1];
    if (is_tconst(b) || (ty_bits(t) == 32 && t != Ty::BOOL)) {
      // a held in a register (its 32 bits as load32 makes them): compared there
      const int n = t == Ty::BOOL || is_tconst(a) ? -1 : holder(t, taddr(a));
      Reg ra = eax;
      if (n >= 0) ra = r32(uint8_t(n));
      else load32(t, a, eax);
      emit(M::Cmp, {R(ra), is_tconst(b) ? I(int64_t(uint32_t(tconst(b)))) : src32(b)});
    } else {
      load_pair(t, a, b), emit(M::Cmp, {R(eax), R(ecx)});
    }
  }
  return cc;
}

// `CMP.T a b; JMP l; MPP` (an ST IF or CASE arm, a loop's test, after the typed
// reader's fuse_compare): -O2 jumps on the compare's flags, the result never
// made a bit (the push and the pop cancel, as the JMP leaves the stack alone).
bool Gen::is_compare_jump(const ldc::Instr& cmp, const ldc::Instr& jmp, const ldc::Instr& mpp) {
  if ((cmp.op == Op::LOAD || cmp.op == Op::LOADN) && cmp.a[0].kind == OpdKind::Bit)  // `LOAD x; JMP l; MPP`
    return jmp.op == Op::JMP && mpp.op == Op::MPP;
  const OpInfo& oi = op_info(cmp.op);
  return oi.klass == OpClass::Typed && oi.push == 1 && !typed::is_real(cmp.ty) && cmp.ty != Ty::STRING &&
         !typed::is_string_instr(cmp.op, cmp.ty, cmp.src) && jmp.op == Op::JMP && mpp.op == Op::MPP;
}
void Gen::compare_jump(const ldc::Instr& cmp, const ldc::Instr& jmp, const ldc::Instr& mpp) {
  close_typed_run();
  Cond cc;
  if (cmp.op == Op::LOAD || cmp.op == Op::LOADN) {
    // the bit's byte as the slot would have it: LOAD jumps on byte != 0, LOADN on (byte ^ 1) != 0
    emit(M::Cmp, {held_byte(addr(cmp.a[0])), I(cmp.op == Op::LOAD ? 0 : 1)});
    cc = Cond::NE;
  } else {
    cc = int_compare(cmp);
  }
  emit(far(make_cc(M::Jcc, cc, {L(x86_label_name(jmp.a[0].label))})));
  for (const ldc::Instr* in : {&cmp, &jmp, &mpp}) follow(*in);
}

// d = a: the value loaded in its type (narrow cells made canonical), stored whole
void Gen::typed_move(const ldc::Instr& in) {
  const Ty t = in.ty;
  const ldc::Operand &a = in.a[0], &d = in.a[1];
  if (is_tconst(a) && t != Ty::BOOL) {
    const uint64_t v = tconst(a);
    if (!two_cells(t)) return emit(M::Mov, {Dw(taddr(d)), I(int64_t(uint32_t(v)))});
    // one 64-bit store: a later 64-bit load of two 32-bit stores is not forwarded (it waits for both to retire)
    if (int64_t(v) == int64_t(int32_t(v))) return emit(M::Mov, {Q(taddr(d)), I(int64_t(v))});
    mov_imm(rax, v);
    return emit(M::Mov, {Q(taddr(d)), R(rax)});
  }
  if (is_tconst(a)) return emit(M::Mov, {B(taddr(d)), I(int64_t(tconst(a) & 1))});
  // -O2: from the register that holds a (as load32 / load64 would leave it), eax untouched
  if (const int n = two_cells(t) ? raw_holder(taddr(a), 8) : typed::is_real(t) ? -1 : holder(t, taddr(a)); n >= 0) {
    const Held h = held_[size_t(n)];
    const uint8_t r = uint8_t(n);
    emit(M::Mov, {t == Ty::BOOL ? B(taddr(d)) : two_cells(t) ? Q(taddr(d)) : Dw(taddr(d)), R(t == Ty::BOOL ? r8(r) : two_cells(t) ? r64(r) : r32(r))});
    return hold(r, t, taddr(d), true, h.upper_zero);
  }
  if (two_cells(t)) {
    emit(M::Mov, {R(rax), Q(taddr(a))});
    return emit(M::Mov, {Q(taddr(d)), R(rax)});
  }
  load32(t, a, eax);
  store_int_reg(t, AX, d);
}

// ADD SUB MUL: the raw cells (the low bits decide), cut at the store; REAL / LREAL by SSE
void Gen::typed_arith(const ldc::Instr& in) {
  const Ty t = in.ty;
  const ldc::Operand &a = in.a[0], &b = in.a[1], &d = in.a[2];
  if (typed::is_real(t)) {
    const bool single = ty_bits(t) == 32;
    load_x(t, a, xmm0);
    Operand src = real_src(t, b, xmm1);
    M m = in.op == Op::TADD ? (single ? M::Addss : M::Addsd) : in.op == Op::TSUB ? (single ? M::Subss : M::Subsd)
                                                                                  : (single ? M::Mulss : M::Mulsd);
    emit(m, {R(xmm0), src});
    return store_x(t, xmm0, d);
  }
  const M m = in.op == Op::TADD ? M::Add : in.op == Op::TSUB ? M::Sub : M::Imul;
  if (two_cells(t)) {
    load64(t, a, rax);
    if (is_tconst(b) && int64_t(tconst(b)) == int64_t(int32_t(tconst(b)))) {
      if (m == M::Imul) emit(M::Imul, {R(rax), R(rax), I(int64_t(tconst(b)))});
      else emit(m, {R(rax), I(int64_t(tconst(b)))});
    } else if (is_tconst(b)) {
      mov_imm(rcx, tconst(b));
      emit(m, {R(rax), R(rcx)});
    } else {
      emit(m, {R(rax), Q(taddr(b))});
    }
    return store_int_reg(t, AX, d);
  }
  load_raw32(a, eax);
  if (is_tconst(b)) {
    const int64_t v = int64_t(int32_t(uint32_t(tconst(b))));
    if (m == M::Imul) emit(M::Imul, {R(eax), R(eax), I(v)});
    else emit(m, {R(eax), I(v)});
  } else {
    emit(m, {R(eax), src32(b)});
  }
  store_int_reg(t, AX, d);
}

// DIV MOD (typed::arith): an integer divisor of 0 gives 0 and sets S0; a
// signed divisor of -1 gives -a (wrapping) and 0; else C's truncating
// division of the canonical values (by a constant of a signed type up to 32
// bits a multiply by its magic number, no division).  The division is one of the guarded forms
// the loader accepts (docs/image-format.md): idiv after its tests of 0 and
// -1, div after its test of 0.
void Gen::typed_divmod(const ldc::Instr& in) {
  const Ty t = in.ty;
  const ldc::Operand &a = in.a[0], &b = in.a[1], &d = in.a[2];
  if (typed::is_real(t)) {  // DIV only (ops.def): IEEE, no error
    load_x(t, a, xmm0);
    emit(ty_bits(t) == 32 ? M::Divss : M::Divsd, {R(xmm0), real_src(t, b, xmm1)});
    return store_x(t, xmm0, d);
  }
  const bool mod = in.op == Op::TMOD, sgn = typed::is_signed(t), w64 = two_cells(t);
  if (sgn && !w64 && is_tconst(b)) {  // SINT INT DINT by a constant: the magic multiply of divide_by_constant
    const int32_t c = int32_t(uint32_t(tconst(b)));
    if (c != 0 && c != 1 && c != -1 && c != INT32_MIN) {
      const Magic mg = magic_of(c);
      load32(t, a, ecx);
      emit(M::Mov, {R(eax), I(mg.m)});
      emit(M::Imul, {R(ecx)});  // edx = hi32(m * n)
      if (c > 0 && mg.m < 0) emit(M::Add, {R(edx), R(ecx)});
      if (c < 0 && mg.m > 0) emit(M::Sub, {R(edx), R(ecx)});
      if (mg.s > 0) emit(M::Sar, {R(edx), I(mg.s)});
      emit(M::Mov, {R(eax), R(edx)});
      emit(M::Shr, {R(eax), I(31)});
      emit(M::Add, {R(eax), R(edx)});  // the quotient, truncated
      if (mod) {
        emit(M::Imul, {R(eax), R(eax), I(c)});
        emit(M::Sub, {R(ecx), R(eax)});
        emit(M::Mov, {R(eax), R(ecx)});  // n - q * c: the sign of n
      }
      return store_int_reg(t, AX, d);
    }
  }
  const Reg A = w64 ? rax : eax, C = w64 ? rcx : ecx, Dx = w64 ? rdx : edx;
  std::string zero = fresh(), minus_one = fresh(), store = fresh();
  if (w64) load64(t, a, rax), load64(t, b, rcx);
  else load32(t, a, eax), load32(t, b, ecx);
  emit(M::Test, {R(C), R(C)});
  jcc(Cond::E, zero);
  if (sgn) {
    emit(M::Cmp, {R(C), I(-1)});
    jcc(Cond::E, minus_one);
    emit(w64 ? M::Cqo : M::Cdq, {});
    emit(M::Idiv, {R(C)});
  } else {
    emit(M::Xor, {R(edx), R(edx)});
    emit(M::Div, {R(C)});
  }
  if (mod) emit(M::Mov, {R(A), R(Dx)});
  jump(store);
  if (sgn) {
    label(minus_one);
    if (mod) emit(M::Xor, {R(eax), R(eax)});
    else emit(M::Neg, {R(A)});
    jump(store);
  }
  label(zero);
  emit(M::Xor, {R(eax), R(eax)});
  set_error();
  label(store);
  store_int_reg(t, AX, d);
}

// MIN MAX (typed::arith): b < a ? b : a, b > a ? b : a; minss / maxss
// (dest b, source a) are exactly that, NaN and signed zeros included
void Gen::typed_minmax(const ldc::Instr& in) {
  const Ty t = in.ty;
  const ldc::Operand &a = in.a[0], &b = in.a[1], &d = in.a[2];
  const bool mx = in.op == Op::TMAX;
  if (typed::is_real(t)) {
    const bool single = ty_bits(t) == 32;
    load_x(t, b, xmm0);
    emit(single ? (mx ? M::Maxss : M::Minss) : (mx ? M::Maxsd : M::Minsd), {R(xmm0), real_src(t, a, xmm1)});
    return store_x(t, xmm0, d);
  }
  const bool sgn = typed::is_signed(t);
  const Cond cc = mx ? (sgn ? Cond::G : Cond::A) : (sgn ? Cond::L : Cond::B);
  if (two_cells(t)) {
    load64(t, a, rax), load64(t, b, rcx);
    emit(M::Cmp, {R(rcx), R(rax)});
    emit(make_cc(M::Cmovcc, cc, {R(rax), R(rcx)}));
  } else {
    load32(t, a, eax), load32(t, b, ecx);
    emit(M::Cmp, {R(ecx), R(eax)});
    emit(make_cc(M::Cmovcc, cc, {R(eax), R(ecx)}));
  }
  store_int_reg(t, AX, d);
}

// AND OR XOR NOT: BOOL on 0 / 1; bit strings on the raw cells, cut at the store
void Gen::typed_logic(const ldc::Instr& in) {
  const Ty t = in.ty;
  const ldc::Operand& a = in.a[0];
  if (in.op == Op::TNOT) {
    const ldc::Operand& d = in.a[1];
    if (t == Ty::BOOL) load32(t, a, eax), emit(M::Xor, {R(eax), I(1)});
    else if (two_cells(t)) load64(t, a, rax), emit(M::Not, {R(rax)});
    else load_raw32(a, eax), emit(M::Not, {R(eax)});
    return store_int_reg(t, AX, d);
  }
  const ldc::Operand &b = in.a[1], &d = in.a[2];
  const M m = in.op == Op::TAND ? M::And : in.op == Op::TOR ? M::Or : M::Xor;
  if (t == Ty::BOOL) {
    load_pair(t, a, b);
    emit(m, {R(eax), R(ecx)});
  } else if (two_cells(t)) {
    load64(t, a, rax), load64(t, b, rcx);
    emit(m, {R(rax), R(rcx)});
  } else {
    load_raw32(a, eax);
    if (is_tconst(b)) emit(m, {R(eax), I(int64_t(int32_t(uint32_t(tconst(b)))))});
    else emit(m, {R(eax), src32(b)});
    // AND with a constant of t (a bit string: from 0 to t's largest value) leaves one too
    return store_int_reg(t, AX, d, in.op == Op::TAND && is_tconst(b) && !typed::is_signed(t));
  }
  store_int_reg(t, AX, d);
}

// SHL SHR (typed::shift): a count outside 0..width-1 (a negative one too)
// gives 0; ROL ROR take the count modulo the width, which is what the
// rotation instructions do at 32 and 64 bits (count & 31, & 63); a BYTE or
// WORD is replicated over 32 bits first (imul by 0x01010101 / 0x00010001),
// so rotating those 32 bits by any count rotates each copy by count mod 8 / 16.
void Gen::typed_shift(const ldc::Instr& in) {
  const Ty t = in.ty, u = in.src;
  const ldc::Operand &a = in.a[0], &n = in.a[1], &d = in.a[2];
  const int w = ty_bits(t);
  const bool w64 = w == 64;
  const Reg A = w64 ? rax : eax;
  if (w64) load64(t, a, rax);
  else load32(t, a, eax);
  const bool rotate = in.op == Op::TROL || in.op == Op::TROR;
  if (is_tconst(n) && !rotate) {
    const uint64_t c = tconst(n);
    const bool zero = (typed::is_signed(u) && int64_t(c) < 0) || c >= uint64_t(w);
    if (zero) emit(M::Xor, {R(eax), R(eax)});
    else if (c > 0) emit(in.op == Op::TSHL ? M::Shl : M::Shr, {R(A), I(int64_t(c))});
    // 0, or a zero-extended value shifted right: still t's canonical value
    return store_int_reg(t, AX, d, zero || (in.op == Op::TSHR && !typed::is_signed(t)));
  }
  // the count in rcx: canonical, so a negative signed count is a huge unsigned one
  if (two_cells(u)) load64(u, n, rcx);
  else load32(u, n, ecx);
  if (rotate) {
    const M m = in.op == Op::TROL ? M::Rol : M::Ror;
    if (w == 8) emit(M::Imul, {R(eax), R(eax), I(0x01010101)});
    if (w == 16) emit(M::Imul, {R(eax), R(eax), I(0x00010001)});
    emit(m, {R(A), R(cl)});
    return store_int_reg(t, AX, d);
  }
  emit(in.op == Op::TSHL ? M::Shl : M::Shr, {R(A), R(cl)});
  emit(M::Xor, {R(edx), R(edx)});
  emit(M::Cmp, {R(two_cells(u) ? rcx : ecx), I(w - 1)});
  emit(make_cc(M::Cmovcc, Cond::A, {R(A), R(w64 ? rdx : edx)}));
  store_int_reg(t, AX, d);
}

// NEG ABS: integers wrap at the width (ABS of the most negative is itself);
// REAL / LREAL: C's -x, and MatIEC's __abs_signed x < 0 ? -x : x
void Gen::typed_neg_abs(const ldc::Instr& in) {
  const Ty t = in.ty;
  const ldc::Operand &a = in.a[0], &d = in.a[1];
  const bool neg = in.op == Op::TNEG;
  if (typed::is_real(t)) {  // NEG flips the sign bit (C's -x); ABS is x < 0 ? -x : x (-0.0 and NaN kept)
    const bool single = ty_bits(t) == 32;
    const Reg A = single ? eax : rax, C = single ? ecx : rcx;
    if (single) load_raw32(a, eax);
    else load64(t, a, rax);
    if (single) emit(M::Mov, {R(ecx), I(int64_t(0x80000000u))});
    else mov_imm(rcx, kSignBit64);
    emit(M::Xor, {R(C), R(A)});  // -x
    if (neg) {
      emit(M::Mov, {R(A), R(C)});
    } else {
      emit(single ? M::Movd : M::Movq, {R(xmm0), R(A)});
      emit(M::Xorps, {R(xmm1), R(xmm1)});
      emit(single ? M::Ucomiss : M::Ucomisd, {R(xmm1), R(xmm0)});  // above: 0 > x, ordered
      emit(make_cc(M::Cmovcc, Cond::A, {R(A), R(C)}));
    }
    return emit(M::Mov, {single ? Dw(taddr(d)) : Q(taddr(d)), R(A)});
  }
  const bool w64 = two_cells(t);
  const Reg A = w64 ? rax : eax, C = w64 ? rcx : ecx;
  if (neg) {
    if (w64) load64(t, a, rax);
    else load_raw32(a, eax);
    emit(M::Neg, {R(A)});
  } else if (typed::is_signed(t)) {  // a < 0 ? -a : a
    if (w64) load64(t, a, rax);
    else load32(t, a, eax);
    emit(M::Mov, {R(C), R(A)});
    emit(M::Neg, {R(A)});
    emit(make_cc(M::Cmovcc, Cond::S, {R(A), R(C)}));  // -a negative: a was positive (or the most negative)
  } else {
    if (w64) load64(t, a, rax);
    else load32(t, a, eax);
  }
  store_int_reg(t, AX, d);
}

// xmm0 = f(xmm0) (and xmm1 for pow) through the math table below the image
// (or, given kStrSlotDisp, the STRING routine)
void Gen::call_table(int32_t disp) {
  emit(M::Call, {Operand::m(mem_at(Size::Qword, uint32_t(disp)))});
  // the callee may clobber the caller-saved base registers (rdi): point them
  // back, as real_fn does
  if (reload_bases_)
    for (RegNum r : as::x86::kBaseRegs)
      if (as::x86::caller_saved(r)) emit(M::Lea, {R(r64(r)), Operand::m(mem_at(Size::None, 0))});
  reload_consts();
}

// A STRING instruction: a call of native_string through its slot below the
// math table (ir/mathfn.h, kStrSlotDisp) with the instruction packed in esi and its operands
// in rdx, rcx, r8 (an image offset, or a constant's canonical bits; rdi, a
// base register at -O2, is left alone and not read); eax
// comes back as a compare's result, pushed, or else 1 where S0 is to be set.
// The other typed instructions of a run share its power test (Gen::typed).
void Gen::typed_string(const ldc::Instr& in) {
  const OpInfo& oi = op_info(in.op);
  if (!oi.push && typed_skip_.empty() && !power_known_on()) {
    typed_skip_ = fresh();
    test_top();
    jcc(Cond::E, typed_skip_);
  }
  static constexpr RegNum kArg[] = {DX, CX, R8};
  unsigned konst = 0;
  for (int k = 0; k < oi.nopd; k++) {
    if (is_tconst(in.a[k])) konst |= 1u << k, mov_imm(r64(kArg[k]), tconst(in.a[k]));
    else emit(M::Mov, {R(r32(kArg[k])), I(int64_t(taddr(in.a[k])))});
  }
  emit(M::Mov, {R(esi), I(int64_t(native_string_desc(in.op, in.ty, in.src, konst)))});
  call_table(kStrSlotDisp);
  if (oi.push) return push_al();
  emit(M::Or, {B(L_.addr(Area::S, kBitError)), R(al)});
}

// SQRT inline (sqrtsd: exact); the others call the C library's double function
// (ir.h, MathFn); a REAL goes in widened and comes out rounded, as typed::unary does
void Gen::typed_math(const ldc::Instr& in) {
  const Ty t = in.ty;
  const ldc::Operand& a = in.a[0];
  const ldc::Operand& d = in.a[op_info(in.op).nopd - 1];
  load_xd(t, a, xmm0);
  if (in.op == Op::TSQRT) {
    emit(M::Sqrtsd, {R(xmm0), R(xmm0)});
  } else {
    if (in.op == Op::TEXPT) load_xd(t, in.a[1], xmm1);
    call_table(math_slot_disp(math_fn(in.op)));
  }
  store_xd(t, xmm0, d);
}

// rax = xmm0 (a double) to an integer as typed::real_to_int, MatIEC's
// __real_to_sint / __real_to_uint: y = x + s, s = 0.5 with x's sign (to an
// unsigned type +0.5, and 0 below 0 or NaN), rounded in double, then
// __real_round(y): (LINT) y, made even toward zero where y is an integer.
// That is y - s, rounded to the nearest integer with ties to even
// (cvtsd2si, the default MXCSR), which the code computes:
// * y not an integer, n < |y| < n + 1: |y - s| lies in (n - 1/2, n + 1/2)
//   (the subtraction is exact: y, s and y - s are multiples of y's ulp), so
//   n, the (LINT) y;
// * y an integer m below 2^53: y - s is m -+ 1/2 exactly, a tie, which goes
//   to the even one of m and its neighbour toward zero: MatIEC's;
// * |y| from 2^52 on (an integer, even where x + s rounded, by ties to even):
//   y - s rounds back to y, even: (LINT) y as MatIEC;
// * NaN, or |y| from 2^63 on: INT64_MIN, as typed::to_i64.
// x = -0.0 gives 0 with either sign of s.  s is built from xmm8.. where
// RealConsts keeps the sign bit and 0.5.  Clobbers rcx, rdx, xmm0..xmm2.
void Gen::real_round_to_int(bool is_signed) {
  const std::optional<Reg> half = const_reg(typed::bits_of(0.5), false), sign = const_reg(kSignBit64, false);
  Reg s = xmm1;
  if (!is_signed) {
    emit(M::Movsd, {R(xmm2), R(xmm0)});  // x
    if (half) s = *half;
    else mov_imm(rcx, typed::bits_of(0.5)), emit(M::Movq, {R(xmm1), R(rcx)});
  } else if (half && sign) {
    emit(M::Movsd, {R(xmm1), R(xmm0)});
    emit(M::Andps, {R(xmm1), R(*sign)});
    emit(M::Xorps, {R(xmm1), R(*half)});  // copysign(0.5, x): disjoint bits
  } else {
    mov_imm(rcx, typed::bits_of(0.5));
    emit(M::Movq, {R(rdx), R(xmm0)});
    mov_imm(rax, kSignBit64);
    emit(M::And, {R(rdx), R(rax)});
    emit(M::Or, {R(rcx), R(rdx)});
    emit(M::Movq, {R(xmm1), R(rcx)});
  }
  emit(M::Addsd, {R(xmm0), R(s)});  // y
  emit(M::Subsd, {R(xmm0), R(s)});
  emit(M::Cvtsd2si, {R(rax), R(xmm0)});
  if (is_signed) return;
  emit(M::Xor, {R(ecx), R(ecx)});
  emit(M::Xorps, {R(xmm1), R(xmm1)});
  emit(M::Ucomisd, {R(xmm2), R(xmm1)});
  emit(make_cc(M::Cmovcc, Cond::B, {R(rax), R(rcx)}));  // x < 0 or NaN: 0
}

// xmm0 = rax, an unsigned 64-bit value, as `to` (REAL or LREAL) with one
// rounding: at 2^63 and above, half of it with the lost bit kept sticky, doubled
// (what a C compiler does for (double) uint64_t)
void Gen::unsigned_to_real(Ty to) {
  const bool single = ty_bits(to) == 32;
  const M cvt = single ? M::Cvtsi2ss : M::Cvtsi2sd;
  std::string big = fresh(), done = fresh();
  emit(M::Test, {R(rax), R(rax)});
  jcc(Cond::S, big);
  emit(cvt, {R(xmm0), R(rax)});
  jump(done);
  label(big);
  emit(M::Mov, {R(rcx), R(rax)});
  emit(M::Shr, {R(rcx), I(1)});
  emit(M::And, {R(eax), I(1)});
  emit(M::Or, {R(rcx), R(rax)});
  emit(cvt, {R(xmm0), R(rcx)});
  emit(single ? M::Addss : M::Addsd, {R(xmm0), R(xmm0)});
  label(done);
}

// rax, rdx = rax / rcx, rax % rcx (signed or not), in the guarded form the
// loader accepts; rcx is a constant other than 0 and -1 here, so the guard's
// branches are never taken
void Gen::guarded_div64(bool is_signed) {
  std::string never = fresh();
  emit(M::Test, {R(rcx), R(rcx)});
  jcc(Cond::E, never);
  if (is_signed) {
    emit(M::Cmp, {R(rcx), I(-1)});
    jcc(Cond::E, never);
    emit(M::Cqo, {});
    emit(M::Idiv, {R(rcx)});
  } else {
    emit(M::Xor, {R(edx), R(edx)});
    emit(M::Div, {R(rcx)});
  }
  label(never);
}

// CONV (typed::conv) and TRUNC (typed::trunc)
void Gen::typed_conv(const ldc::Instr& in) {
  const Ty to = in.ty, from = in.src;
  const ldc::Operand &a = in.a[0], &d = in.a[1];
  const TyKind tk = ty_info(to).kind, fk = ty_info(from).kind;
  auto time_like = [](TyKind k) { return k == TyKind::Time || k == TyKind::Date; };
  if (in.op == Op::TTRUNC) {  // toward zero; NaN and out of range INT64_MIN, then cut
    load_xd(from, a, xmm0);
    emit(M::Cvttsd2si, {R(rax), R(xmm0)});
    return store_int_reg(to, AX, d);
  }
  if (to == from) {
    ldc::Instr mv = in;
    mv.op = Op::TMOVE;
    return typed_move(mv);
  }
  if (tk == TyKind::Bool) {  // != 0 (a NaN too)
    if (fk == TyKind::Real) {
      load_xd(from, a, xmm0);
      emit(M::Xorps, {R(xmm1), R(xmm1)});
      emit(M::Ucomisd, {R(xmm0), R(xmm1)});
      emit(make_cc(M::Setcc, Cond::NE, {R(al)}));
      emit(make_cc(M::Setcc, Cond::P, {R(cl)}));
      emit(M::Or, {R(al), R(cl)});
    } else {
      load64(from, a, rax);
      emit(M::Test, {R(rax), R(rax)});
      emit(make_cc(M::Setcc, Cond::NE, {R(al)}));
    }
    return emit(M::Mov, {B(taddr(d)), R(al)});
  }
  if (fk == TyKind::Real) {
    load_xd(from, a, xmm0);
    if (tk == TyKind::Real) return store_xd(to, xmm0, d);
    if (time_like(tk)) {  // __real_to_time: seconds (LINT) x, then (x - seconds) * 1e9 ns, each toward zero
      emit(M::Cvttsd2si, {R(rax), R(xmm0)});
      emit(M::Cvtsi2sd, {R(xmm1), R(rax)});
      emit(M::Subsd, {R(xmm0), R(xmm1)});
      double_const(xmm1, 1e9);
      emit(M::Mulsd, {R(xmm0), R(xmm1)});
      emit(M::Cvttsd2si, {R(rcx), R(xmm0)});
      emit(M::Imul, {R(rax), R(rax), I(typed::kNsPerS)});  // wrapping
      emit(M::Add, {R(rax), R(rcx)});
      return store_int_reg(to, AX, d);
    }
    real_round_to_int(typed::is_signed(to));
    return store_int_reg(to, AX, d);
  }
  if (tk == TyKind::Real && typed::is_signed(from) && !two_cells(from)) {  // a signed value of up to 32 bits
    load32(from, a, eax);
    emit(ty_bits(to) == 32 ? M::Cvtsi2ss : M::Cvtsi2sd, {R(xmm0), R(eax)});
    return store_x(to, xmm0, d);
  }
  load64(from, a, rax);
  if (time_like(fk)) {  // MatIEC's timespec: seconds and nanoseconds, both toward zero
    if (tk == TyKind::Time) return store_int_reg(to, AX, d);
    const bool dt_split = from == Ty::DT && (to == Ty::DATE || to == Ty::TOD);
    if (tk == TyKind::Date && !dt_split) return store_int_reg(to, AX, d);
    mov_imm(rcx, uint64_t(typed::kNsPerS));
    guarded_div64(true);  // rax = seconds, rdx = nanoseconds
    if (tk == TyKind::Real) {  // __time_to_real: seconds + nanoseconds / 1e9
      emit(M::Cvtsi2sd, {R(xmm0), R(rax)});
      emit(M::Cvtsi2sd, {R(xmm1), R(rdx)});
      double_const(xmm2, 1e9);
      emit(M::Divsd, {R(xmm1), R(xmm2)});
      emit(M::Addsd, {R(xmm0), R(xmm1)});
      return store_xd(to, xmm0, d);
    }
    if (dt_split) {  // __date_and_time_to_date / _time_of_day: C's % on the seconds, a day added below 1970
      const Reg r8q = r64(R8), r9q = r64(R9);
      constexpr int64_t kDay = typed::kNsPerDay / typed::kNsPerS;
      emit(M::Mov, {R(r8q), R(rdx)});  // nanoseconds
      emit(M::Mov, {R(r9q), R(rax)});  // seconds
      mov_imm(rcx, uint64_t(kDay));
      guarded_div64(true);  // rdx = seconds % day
      emit(M::Mov, {R(r10), R(r9q)});
      emit(M::Sar, {R(r10), I(63)});
      emit(M::And, {R(r10), I(kDay)});  // seconds < 0 ? day : 0
      if (to == Ty::DATE) {
        emit(M::Mov, {R(rax), R(r9q)});
        emit(M::Sub, {R(rax), R(rdx)});
        emit(M::Sub, {R(rax), R(r10)});
        emit(M::Imul, {R(rax), R(rax), I(typed::kNsPerS)});
      } else {
        emit(M::Mov, {R(rax), R(rdx)});
        emit(M::Add, {R(rax), R(r10)});
        emit(M::Imul, {R(rax), R(rax), I(typed::kNsPerS)});
        emit(M::Add, {R(rax), R(r8q)});
      }
    }
    return store_int_reg(to, AX, d);  // __time_to_int: the seconds, cut
  }
  // from BOOL, an integer or a bit string: rax canonical
  if (tk == TyKind::Real) {
    if (!typed::is_signed(from) && two_cells(from)) unsigned_to_real(to);
    else emit(ty_bits(to) == 32 ? M::Cvtsi2ss : M::Cvtsi2sd, {R(xmm0), R(rax)});
    return store_x(to, xmm0, d);
  }
  if (time_like(tk)) emit(M::Imul, {R(rax), R(rax), I(typed::kNsPerS)});  // __int_to_time: seconds, wrapping
  store_int_reg(to, AX, d);
}

// IDX (typed::index_ok): r11 = index - lo where lo <= index <= hi (as the
// loader's check of each LDX / STX expects it: 0 .. hi - lo), else the fault
// record (Sys+8 kind, Sys+12 this IDX's IL offset, Sys+16 the index) and the
// scan ends
void Gen::typed_idx(const ldc::Instr& in) {
  const Ty t = in.ty;
  const int64_t lo = int32_t(tconst(in.a[1])), hi = int32_t(tconst(in.a[2])), span = hi - lo;
  const bool cell = !is_tconst(in.a[0]);
  const HeldIndex& h = idx_held_;
  if (cell && h.valid && h.addr == taddr(in.a[0]) && h.ty == t && h.lo == lo && h.hi == hi) {
    idx_span_ = span;  // -O2: r11 holds this index, checked already (nothing wrote it or its cell since)
    return;
  }
  if (cold_) {  // -O2: the fault record out of line, no label in the rung
    const bool sign_test = !typed::is_signed(t) && two_cells(t) && lo < 0;
    if (sign_test) load64(t, in.a[0], rax), emit(M::Mov, {R(r11), R(rax)});
    else load64(t, in.a[0], r11);  // (the fault record takes the index back from r11)
    if (lo != 0) emit(M::Sub, {R(r11), I(lo)});
    idx_fault_ = cold_fault(lo);
    if (sign_test) {  // above INT64_MAX: outside, whatever lo is
      emit(M::Test, {R(rax), R(rax)});
      emit(far(make_cc(M::Jcc, Cond::S, {L(idx_fault_)})));
    }
    idx_span_ = span;
    idx_held_ = {taddr(in.a[0]), t, lo, hi, false};
    hold_idx_after_check_ = slots_ && cell;  // (typed_indexed, flush_idx_check)
    if (!defers_check()) flush_idx_check();  // the check here: the access after it multiplies r11
    return;
  }
  std::string ok = fresh(), fault = fresh();
  load64(t, in.a[0], rax);
  if (!typed::is_signed(t) && two_cells(t) && lo < 0) {  // above INT64_MAX: outside, whatever lo is
    emit(M::Test, {R(rax), R(rax)});
    jcc(Cond::S, fault);
  }
  emit(M::Mov, {R(r11), R(rax)});
  if (lo != 0) emit(M::Sub, {R(r11), I(lo)});
  if (span <= INT32_MAX) emit(M::Cmp, {R(r11), I(span)});
  else mov_imm(rcx, uint64_t(span)), emit(M::Cmp, {R(r11), R(rcx)});
  jcc(Cond::BE, ok);
  const std::array<Held, 16> at_jump = held_;  // `ok` is reached from the jbe alone: what was held there still is
  label(fault);
  for (const Instruction& i : fault_record(kFaultIndex, R(rax))) emit(i);
  label(ok);
  idx_span_ = span;
  if (!slots_ || !cell) return;
  held_ = at_jump, any_held_ = true;
  idx_held_ = {taddr(in.a[0]), t, lo, hi, true};
}

// Does the IDX leave its check to the LDX / STX right after it (-O2, set_next)?
// Only where that access scales r11 itself (a stride of 1, 2, 4 or 8 bytes):
// r10 = r11 * stride of an unchecked index could wrap into range.
bool Gen::defers_check() const {
  return cold_ && next_ && (next_->op == Op::TLDX || next_->op == Op::TSTX) && scales(element_bytes(*next_));
}

// An LDX's / STX's stride in bytes; an x86 index scales by 1, 2, 4 or 8 alone
int64_t Gen::element_bytes(const ldc::Instr& access) const {
  const bool ldx = access.op == Op::TLDX;
  return int64_t(int32_t(tconst(access.a[ldx ? 1 : 2]))) * int64_t(L_.elem_size(access.a[ldx ? 0 : 1].area));
}
bool Gen::scales(int64_t bytes) { return bytes == 1 || bytes == 2 || bytes == 4 || bytes == 8; }

// An IDX's fault record out of line (in cold_, after the last rung): the
// index back in rax (r11 + lo: the access may have loaded its value into
// rax), kind, this IDX's IL offset, the index; then the scan ends.  Its label.
std::string Gen::cold_fault(int64_t lo) {
  const std::string name = idx_fault_label((*cold_count_)++);
  std::vector<Item>& c = *cold_;
  c.push_back(Item::label_def(name, true));
  c.push_back(Item::instr(make(M::Mov, {R(rax), R(r11)})));
  if (lo != 0) c.push_back(Item::instr(make(M::Add, {R(rax), I(lo)})));
  for (const Instruction& i : fault_record(kFaultIndex, R(rax))) c.push_back(Item::instr(i));
  return name;
}

// The fault record of this IDX or LOOP (Sys+8 kind, Sys+12 its IL offset,
// Sys+16 the value: the index, the budget), then the scan's end.
std::array<Instruction, 4> Gen::fault_record(uint32_t kind, const Operand& value) const {
  return {make(M::Mov, {Dw(kSysFault), I(kind)}), make(M::Mov, {Dw(kSysFaultAt), I(int64_t(il_offset_))}),
          make(M::Mov, {Q(kSysFaultValue), value}), far(make(M::Jmp, {L(kX86ExitLabel)}))};
}

// The check an IDX left to an access that did not come: `cmp r11, span; ja fault`.
void Gen::flush_idx_check() {
  if (idx_fault_.empty()) return;
  if (idx_span_ <= INT32_MAX) emit(M::Cmp, {R(r11), I(idx_span_)});
  else mov_imm(rcx, uint64_t(idx_span_)), emit(M::Cmp, {R(r11), R(rcx)});
  emit(far(make_cc(M::Jcc, Cond::A, {L(idx_fault_)})));
  idx_checked();
}
void Gen::idx_checked() {
  idx_fault_.clear();
  if (hold_idx_after_check_) idx_held_.valid = true, any_held_ = true;
  hold_idx_after_check_ = false;
}

// LDX / STX: element base + r11 * stride.  The access is right after its own
// bounds check, `cmp <index>, <last byte offset>; ja scan_exit`, on the very
// register it indexes with: the loader's code check verifies that pair and
// the extent (docs/image-format.md), whatever the IDX before did.  A stride
// whose bytes are 1, 2, 4 or 8 scales r11; another is multiplied into r10.
void Gen::typed_indexed(const ldc::Instr& in) {
  const Ty t = in.ty;
  const bool ldx = in.op == Op::TLDX;
  const ldc::Operand& base = in.a[ldx ? 0 : 1];
  // the IL validator puts an LDX / STX right after an IDX; native code keeps the
  // index in r11 from one to the other, so both must be in one rung (with the
  // same power): a rung that starts with the LDX is refused by name
  if (idx_span_ < 0)
    throw CompileError(in.loc.line, in.loc.col,
                       "x86-64: " + op_spelling(in) + " must follow its IDX in the same rung (native code keeps the index in a register)");
  const int64_t span = idx_span_;
  const int64_t bytes = element_bytes(in);
  if (!ldx) {  // the value first
    if (t == Ty::BOOL) load32(t, in.a[0], eax);
    else if (two_cells(t)) load64(t, in.a[0], rax);
    else load32(t, in.a[0], eax);
  }
  // the element's bytes as accessed: a BOOL's byte, a 64-bit type's two cells, a
  // load of a narrow type its low 8 or 16 bits, else the whole cell
  Size size = t == Ty::BOOL ? Size::Byte : two_cells(t) ? Size::Qword : Size::Dword;
  if (ldx && ty_bits(t) == 8) size = Size::Byte;
  if (ldx && ty_bits(t) == 16) size = Size::Word;
  Mem m = mem_at(size, taddr(base));
  if (bytes != 0) {
    Reg idx = r11;
    int64_t bound = span;
    if (scales(bytes)) {
      m.scale = uint8_t(bytes);
    } else {
      if (scaled_ != bytes) emit(M::Imul, {R(r10), R(r11), I(bytes)});  // -O2: else r10 holds it already
      if (slots_) scaled_ = bytes, any_held_ = true;
      idx = r10;
      bound = span * bytes;
    }
    m.index = idx;
    emit(M::Cmp, {R(idx), I(bound)});
    emit(far(make_cc(M::Jcc, Cond::A, {L(idx_fault_.empty() ? kX86ExitLabel : idx_fault_)})));
    if (!idx_fault_.empty()) idx_checked();  // the IDX's own check, done: r11 is in 0 .. span
  }
  if (!ldx) {
    if (t == Ty::BOOL) return emit(M::Mov, {Operand::m(m), R(al)});
    return emit(M::Mov, {Operand::m(m), R(two_cells(t) ? rax : eax)});
  }
  const ldc::Operand& d = in.a[2];
  if (t == Ty::BOOL) {  // (the indexed operand right after its bounds check: no xor between)
    emit(M::Cmp, {Operand::m(m), I(0)});
    emit(make_cc(M::Setcc, Cond::NE, {R(al)}));
    emit(M::Mov, {B(taddr(d)), R(al)});
  } else if (two_cells(t)) {
    emit(M::Mov, {R(rax), Operand::m(m)});
    emit(M::Mov, {Q(taddr(d)), R(rax)});
  } else {
    const bool sgn = typed::is_signed(t);
    if (ty_bits(t) < 32) emit(sgn ? M::Movsx : M::Movzx, {R(eax), Operand::m(m)});
    else emit(M::Mov, {R(eax), Operand::m(m)});
    emit(M::Mov, {Dw(taddr(d)), R(eax)});
  }
  hold(AX, t, taddr(d), true, t != Ty::BOOL);  // the element as load32 / load64 makes it, stored whole (a BOOL: al)
}

// ------------------------------------------------------------ -O1 peephole
//
// Over the -O0 templates of one rung:
//  * `mov eax, ebp; and eax, 1` when eax already holds the top (after a push,
//    or after the same pair) is dropped; `test ebp, 1` becomes `test eax, eax`;
//  * `movzx eax, byte ptr [m]` when eax already holds that byte is dropped;
//  * a push (`lea ebp, ...`) whose stack is never read again is dropped: the
//    stack is dead at the end of a rung and at jumps out of it, unless a rung
//    of the program reads what an earlier one left (`shared`, shares_stack);
//  * a jump to the label right after it is dropped.
// Notes (the IL text items) stay, so IL instructions keep their places.
bool is_reg(const Operand& o, uint8_t num) { return o.kind == OperandKind::Reg && o.reg.cls != RegClass::Xmm && o.reg.num == num; }
bool mem_uses(const Operand& o, uint8_t num) {
  return o.kind == OperandKind::Mem && ((o.mem.base.valid() && o.mem.base.cls == RegClass::Gp64 && o.mem.base.num == num) ||
                                        (o.mem.index.valid() && o.mem.index.num == num));
}
bool writes_reg(const Instruction& i, uint8_t num) {
  switch (i.mnemonic) {  // (one jump by a table: WordInEax asks this of every instruction)
    // a call keeps the callee-saved registers (the shared routines and libm alike): ebp's stack survives it
    case M::Call: return !(num == BX || num == BP || num >= R12);
    case M::Idiv: case M::Div: if (num == AX || num == DX) return true; break;
    case M::Cdq: case M::Cqo: if (num == DX) return true; break;
    case M::Cwde: case M::Cdqe: return num == AX;
    case M::Imul: if (i.num_operands == 1) return num == AX || num == DX; break;  // edx:eax = eax * r/m32
    case M::Cmp: case M::Test: case M::Push: case M::Jmp: case M::Jcc: case M::Ucomiss: return false;
    default: break;
  }
  return i.num_operands != 0 && is_reg(i.ops[0], num);
}
bool reads_reg(const Instruction& i, uint8_t num) {
  for (unsigned k = 0; k < i.num_operands; k++) {
    if (mem_uses(i.ops[k], num)) return true;
    if (is_reg(i.ops[k], num)) {
      bool pure_write = k == 0 && (i.mnemonic == M::Mov || i.mnemonic == M::Movzx || i.mnemonic == M::Lea ||
                                   i.mnemonic == M::Setcc || i.mnemonic == M::Movd || i.mnemonic == M::Cvttss2si || i.mnemonic == M::Pop);
      if (!pure_write) return true;
    }
  }
  return (i.mnemonic == M::Idiv || i.mnemonic == M::Div) && num == DX;
}
bool same_text(const Instruction& i, const char* text) {
  static std::map<const char*, Instruction> cache;  // by the literal's address: no string made per call
  auto it = cache.find(text);
  if (it == cache.end()) it = cache.emplace(text, parse(text)).first;
  return i == it->second;
}

// Marks in `drop` each branch that `is_branch` picks, not dropped yet, whose
// target is the label right after it (the -O1 peephole, drop_unreachable).
template <class IsBranch>
void drop_jumps_to_next(const std::vector<Item>& items, std::vector<char>& drop, IsBranch is_branch) {
  for (size_t i = 0; i < items.size(); i++) {
    const Item& it = items[i];
    if (drop[i] || !is_branch(it)) continue;
    if (it.inst.ops[0].kind == OperandKind::Label && as::label_follows(items, i, it.inst.ops[0].label, drop)) drop[i] = 1;
  }
}

// -O2: code that no branch reaches goes (after an unconditional jmp, up to a
// label some branch names; the power tests that KnownStack drops leave such
// code behind), and then a jmp to the label right after it.
void drop_unreachable(std::vector<Item>& items, std::vector<uint32_t>& starts) {
  auto is_jmp = [](const Item& it) { return it.kind == as::ItemKind::Instruction && it.inst.mnemonic == M::Jmp; };
  if (std::none_of(items.begin(), items.end(), is_jmp)) return;  // most rungs: nothing to look for
  std::vector<char> drop(items.size(), 0);
  for (bool changed = true; changed;) {  // dropped branches may leave their labels unnamed
    std::set<uint32_t> named;            // labels a kept branch of the block names (ids)
    for (size_t i = 0; i < items.size(); i++)
      if (!drop[i] && items[i].kind == as::ItemKind::Instruction)
        for (unsigned k = 0; k < items[i].inst.num_operands; k++)
          if (items[i].inst.ops[k].kind == OperandKind::Label) named.insert(items[i].inst.ops[k].label.id());
    changed = false;
    bool dead = false;
    for (size_t i = 0; i < items.size(); i++) {
      const Item& it = items[i];
      if (it.kind == as::ItemKind::Label && (it.global || named.count(it.label.id()))) dead = false;
      else if (it.kind != as::ItemKind::Comment && dead && !drop[i]) drop[i] = 1, changed = true;
      if (!drop[i] && is_jmp(it)) dead = true;
    }
  }
  drop_jumps_to_next(items, drop, is_jmp);
  as::remove_items(items, drop, starts);
}

void peephole(std::vector<Item>& items, std::vector<uint32_t>& starts, bool shared) {
  std::vector<char> drop(items.size(), 0);
  auto next_instr = [&](size_t i) {
    for (size_t j = i + 1; j < items.size(); j++)
      if (items[j].kind != as::ItemKind::Comment && !drop[j]) return j;
    return items.size();
  };
  // forward: what eax holds
  bool eax_top = false;
  int64_t eax_byte = -1;
  for (size_t i = 0; i < items.size(); i++) {
    Item& it = items[i];
    if (it.kind == as::ItemKind::Label) { eax_top = false; eax_byte = -1; continue; }
    if (it.kind != as::ItemKind::Instruction) continue;
    Instruction& in = it.inst;
    size_t j = next_instr(i);
    if (same_text(in, "mov eax, ebp") && j < items.size() && items[j].kind == as::ItemKind::Instruction &&
        same_text(items[j].inst, "and eax, 1")) {
      if (eax_top) drop[i] = drop[j] = 1;
      eax_top = true;
      eax_byte = -1;
      i = j;
      continue;
    }
    if (same_text(in, "test ebp, 1") && eax_top) { in = parse("test eax, eax"); continue; }
    if (in.mnemonic == M::Movzx && is_reg(in.ops[0], AX) && in.ops[1].kind == OperandKind::Mem && mem_uses(in.ops[1], BX) &&
        in.ops[1].mem.size == Size::Byte && !in.ops[1].mem.index.valid()) {
      if (eax_byte == in.ops[1].mem.disp) { drop[i] = 1; continue; }
      eax_top = false;
      eax_byte = in.ops[1].mem.disp;
      continue;
    }
    if (in.mnemonic == M::Lea && is_reg(in.ops[0], BP) && mem_uses(in.ops[1], AX)) { eax_top = true; continue; }  // a push of eax
    if (writes_reg(in, AX)) { eax_top = false; eax_byte = -1; }
    if (writes_reg(in, BP)) eax_top = false;
    if (in.num_operands && in.ops[0].kind == OperandKind::Mem) eax_byte = -1;  // a store may change that byte
    if (in.mnemonic == M::Jmp || in.mnemonic == M::Jcc) { eax_top = false; eax_byte = -1; }
  }
  // backward: is the stack (ebp) read again?
  std::map<uint32_t, bool> live_at;  // by label name id
  bool live = shared;
  for (size_t k = items.size(); k-- > 0;) {
    Item& it = items[k];
    if (drop[k]) continue;
    if (it.kind == as::ItemKind::Label) { live_at[it.label.id()] = live; continue; }
    if (it.kind != as::ItemKind::Instruction) continue;
    const Instruction& in = it.inst;
    if (in.mnemonic == M::Jmp || in.mnemonic == M::Jcc) {
      bool target = shared;  // global targets (other rungs, scan_exit): the stack is dead there, if not shared
      if (in.ops[0].kind == OperandKind::Label) {
        auto t = live_at.find(in.ops[0].label.id());
        if (t != live_at.end()) target = t->second;
      }
      live = in.mnemonic == M::Jmp ? target : (live || target);
      continue;
    }
    if (in.mnemonic == M::Lea && is_reg(in.ops[0], BP) && !live) { drop[k] = 1; continue; }
    if (writes_reg(in, BP) && !reads_reg(in, BP)) live = false;
    if (reads_reg(in, BP)) live = true;
  }
  drop_jumps_to_next(items, drop, [](const Item& it) {
    return it.kind == as::ItemKind::Instruction && (it.inst.mnemonic == M::Jmp || it.inst.mnemonic == M::Jcc);
  });
  as::remove_items(items, drop, starts);
}

// ------------------------------------------------------------ -O2: the frame's registers
//
// A rung is generated with rbx the image and ebp the bit stack (the -O0
// templates and the slot code alike); the -O2 frame (as::x86::image_reg) has
// them the other way round, so every register and memory operand of the rung
// swaps rbx and rbp, at every width.  A permutation of two callee-saved
// registers, so the code computes exactly the same.
// A register's number in the other frame, by table (a memory operand's base
// and index need no test of their class: rip and none are number 0).
constexpr std::array<uint8_t, 16> kSwapped = [] {
  std::array<uint8_t, 16> t{};
  for (uint8_t n = 0; n < 16; n++) t[n] = n == BX ? uint8_t(BP) : n == BP ? uint8_t(BX) : n;
  return t;
}();
void to_o2_frame(std::vector<Item>& items) {
  for (Item& it : items) {
    if (it.kind != as::ItemKind::Instruction) continue;
    for (unsigned k = 0; k < it.inst.num_operands; k++) {
      Operand& o = it.inst.ops[k];
      if (o.kind == OperandKind::Reg && o.reg.cls != RegClass::Xmm) o.reg.num = kSwapped[o.reg.num];
      else if (o.kind == OperandKind::Mem) {
        o.mem.base.num = kSwapped[o.mem.base.num], o.mem.index.num = kSwapped[o.mem.index.num];
        if (o.mem.base == kO2Image) o.mem.disp -= kImageBias;  // rbp points kImageBias bytes into the image
      }
    }
  }
}

// An operand of the -O2 frame that names image bytes by a plain displacement
// from the image register (no index): the operands the passes below follow
// byte by byte; any other memory operand may be anywhere.
bool image_at(const Operand& o) { return o.kind == OperandKind::Mem && o.mem.base == kO2Image && !o.mem.index.valid(); }

// ------------------------------------------------------------ -O2: a word kept in eax
//
// After `mov dword ptr [w], eax` (every gated store ends so) or `mov eax,
// dword ptr [w]`, eax holds the word w until something writes eax or w, a
// call, or a label (a jump may arrive with anything in eax).  Meanwhile a
// `mov eax, [w]` is dropped, a read of w as the second operand of mov, cmp,
// add, sub, and, or, xor, imul, cmov or cvtsi2ss reads eax instead, and
// `cmp dword ptr [w], imm` becomes `cmp eax, imm`: no load, and shorter.
// What eax holds carries over from one rung to the next (a rung that jumps
// land on starts with its labels, which forget it).
//
// The same for xmm0 and the REAL / LREAL of the typed instructions: after
// `movss dword ptr [w], xmm0` / `movsd qword ptr [w], xmm0` (or the load),
// xmm0 holds w until something writes xmm0 or w, a call, or a label, and a
// `movss` / `movsd xmm0, [w]` of the same size is dropped (a chain of LREAL
// instructions, each reading what the one before stored), and a `mov eax, [w]`
// of the REAL it holds becomes `movd eax, xmm0`.
class WordInEax {
 public:
  void forget() { word_ = -1, xword_ = -1; }
  void run(std::vector<Item>& items, std::vector<uint32_t>& starts) {
    drop_.assign(items.size(), 0);
    bool any = false;
    for (size_t i = 0, n = items.size(); i < n; i++) {  // (n read once: for all the compiler knows, the stores change it)
      if (const size_t j = second_in_xmm0(items, i)) {  // b to xmm1 first: `movsd xmm1, xmm0; movsd xmm0, [a]; addsd xmm0, xmm1`
        const bool single = xsize_ == Size::Dword;
        items[j].inst.ops[1] = Operand::r(xmm(1));
        items.insert(items.begin() + ptrdiff_t(i), Item::instr(as::x86::make(single ? M::Movss : M::Movsd, {Operand::r(xmm(1)), Operand::r(xmm(0))})));
        drop_.insert(drop_.begin() + ptrdiff_t(i), 0);
        for (uint32_t& s : starts)
          if (s > i) s++;
        n++, i++;
      }
      Item& it = items[i];
      if (it.kind == as::ItemKind::Label) forget();
      if (it.kind != as::ItemKind::Instruction) continue;
      if (loads(it.inst) && held(it.inst.ops[1])) {
        // eax holds w, but after a store of eax the upper half of rax may not
        // be zero as the load's would leave it (a 64-bit result stored cut to
        // its low word): then `mov eax, eax` stands for the load
        if (upper_zero_) drop_[i] = 1, any = true;
        else it.inst = as::x86::make(M::Mov, {Operand::r(r32(AX)), Operand::r(r32(AX))}), upper_zero_ = true;
        continue;
      }
      if (xloads(it.inst) && xheld(it.inst.ops[1])) { drop_[i] = 1, any = true; continue; }
      if (loads(it.inst) && xsize_ == Size::Dword && xheld(it.inst.ops[1])) {  // a REAL xmm0 holds: its bits
        const int64_t w = it.inst.ops[1].mem.disp;
        it.inst = as::x86::make(M::Movd, {Operand::r(r32(AX)), Operand::r(xmm(0))});
        word_ = w, upper_zero_ = true;
        continue;
      }
      if (word_ >= 0) use_eax(it.inst);
      xafter(it.inst);
      after(it.inst);
    }
    if (any) as::remove_items(items, drop_, starts);
  }

 private:
  static bool eax32(const Operand& o) { return o.kind == OperandKind::Reg && o.reg == r32(AX); }
  static bool image_dword(const Operand& o) {
    return image_at(o) && o.mem.size == Size::Dword;
  }
  bool held(const Operand& o) const { return word_ >= 0 && image_dword(o) && o.mem.disp == word_; }
  static bool loads(const Instruction& in) { return in.mnemonic == M::Mov && eax32(in.ops[0]) && image_dword(in.ops[1]); }
  static bool reads_second(M m) {
    switch (m) {
      case M::Mov: case M::Cmp: case M::Add: case M::Sub: case M::And: case M::Or: case M::Xor: case M::Imul:
      case M::Cmovcc: case M::Cvtsi2ss:
        return true;
      default: return false;
    }
  }
  void use_eax(Instruction& in) const {
    if (in.num_operands == 2 && reads_second(in.mnemonic) && held(in.ops[1])) in.ops[1] = Operand::r(r32(AX));
    else if (in.mnemonic == M::Cmp && in.num_operands == 2 && held(in.ops[0]) && in.ops[1].kind == OperandKind::Imm)
      in.ops[0] = Operand::r(r32(AX));
  }
  // may `in` write the bytes of the word held?
  bool hits(const Instruction& in) const {
    if (in.num_operands == 0 || in.ops[0].kind != OperandKind::Mem || in.mnemonic == M::Cmp || in.mnemonic == M::Test)
      return false;
    if (!image_at(in.ops[0])) return true;
    const Mem& m = in.ops[0].mem;
    return m.disp < word_ + 4 && word_ < m.disp + 8;
  }
  void after(const Instruction& in) {
    if (in.mnemonic == M::Mov && image_dword(in.ops[0]) && eax32(in.ops[1])) { word_ = in.ops[0].mem.disp; return; }
    if (loads(in)) { word_ = in.ops[1].mem.disp, upper_zero_ = true; return; }
    if (writes_reg(in, AX) || in.mnemonic == M::Call) upper_zero_ = zero_extends(in, AX);
    if (word_ >= 0 && (writes_reg(in, AX) || in.mnemonic == M::Call || hits(in))) word_ = -1;  // (xmm0's word stays: xafter)
  }

  // Item i loads xmm0 with a, and the next instruction, item j (returned; else
  // 0), is `op xmm0, [b]` (add, sub, mul, div, min, max) of the b xmm0 holds
  // now: b can be read from xmm1 instead (the operands' order, which decides a
  // NaN's sign or min/max of a NaN, stays).  A store of b and a reload of it
  // then never wait on each other.
  size_t second_in_xmm0(const std::vector<Item>& items, size_t i) const {
    if (xword_ < 0 || items[i].kind != as::ItemKind::Instruction || !xloads(items[i].inst) || xheld(items[i].inst.ops[1]))
      return 0;
    size_t j = i + 1;
    while (j < items.size() && items[j].kind == as::ItemKind::Comment) j++;
    if (j == items.size() || items[j].kind != as::ItemKind::Instruction) return 0;
    const Instruction& op = items[j].inst;
    switch (op.mnemonic) {
      case M::Addss: case M::Subss: case M::Mulss: case M::Divss: case M::Minss: case M::Maxss:
      case M::Addsd: case M::Subsd: case M::Mulsd: case M::Divsd: case M::Minsd: case M::Maxsd: break;
      default: return 0;
    }
    return op.num_operands == 2 && xmm0(op.ops[0]) && xheld(op.ops[1]) ? j : 0;
  }
  // xmm0: movss / movsd between xmm0 and an image operand of their size
  static bool xmm0(const Operand& o) { return o.kind == OperandKind::Reg && o.reg == xmm(0); }
  static bool image_plain(const Operand& o) {
    return image_at(o) &&
           (o.mem.size == Size::Dword || o.mem.size == Size::Qword);
  }
  static bool xmove(M m) { return m == M::Movss || m == M::Movsd; }
  static bool xloads(const Instruction& in) {
    return xmove(in.mnemonic) && in.num_operands == 2 && xmm0(in.ops[0]) && image_plain(in.ops[1]);
  }
  bool xheld(const Operand& o) const { return xword_ >= 0 && image_plain(o) && o.mem.disp == xword_ && o.mem.size == xsize_; }
  // may `in` write xmm0's bytes (an xmm destination), or the word it holds?
  bool xhits(const Instruction& in) const {
    if (in.num_operands == 0) return in.mnemonic == M::Cdq || in.mnemonic == M::Cdqe || in.mnemonic == M::Cqo ||
                                     in.mnemonic == M::Cwde ? false : true;
    if (in.mnemonic == M::Ucomiss || in.mnemonic == M::Ucomisd || in.mnemonic == M::Cmp || in.mnemonic == M::Test) return false;
    const Operand& o = in.ops[0];
    if (o.kind == OperandKind::Reg) return o.reg.cls == RegClass::Xmm && o.reg.num == 0;
    if (o.kind != OperandKind::Mem) return in.mnemonic == M::Call || in.mnemonic == M::Jmp || in.mnemonic == M::Jcc;
    if (!image_at(o)) return true;
    return o.mem.disp < xword_ + 8 && xword_ < o.mem.disp + 8;
  }
  void xafter(const Instruction& in) {
    if (xmove(in.mnemonic) && in.num_operands == 2 && image_plain(in.ops[0]) && xmm0(in.ops[1])) {
      xword_ = in.ops[0].mem.disp, xsize_ = in.ops[0].mem.size;  // a store of xmm0
      return;
    }
    if (xloads(in)) { xword_ = in.ops[1].mem.disp, xsize_ = in.ops[1].mem.size; return; }
    if (xword_ >= 0 && (in.mnemonic == M::Call || xhits(in))) xword_ = -1;
  }

  int64_t word_ = -1;  // the image offset of the word eax holds, or -1
  bool upper_zero_ = false;  // the upper half of rax is zero (its last writer wrote eax, or loaded it)
  int64_t xword_ = -1;  // the image offset of the REAL / LREAL xmm0 holds, or -1
  Size xsize_ = Size::None;
  std::vector<char> drop_;  // run's, kept from rung to rung
};

// ------------------------------------------------------------ -O2: bytes read back from registers
//
// A byte stored from a register, `mov byte ptr [b], r8`, and read again further
// down the straight line (the BOOL temporaries of an ST expression: each
// operator stores its result, the next reads it back) is read from a register
// instead: store-to-load forwarding of a byte costs about 2 ns a hop on the AMD
// EPYC (docs/BENCHMARKS.md, "Where sequence.st's time goes"), a register
// nothing.  The register is the store's own source while nothing writes it;
// after that, a spare scratch register (kSpares) that nothing touches from the
// store to the last read and whose value nothing reads afterwards in the rung,
// given the byte by `mov spare32, source32` right after the store.  A read is a
// byte operand [b] of cmp, test, movzx, movsx, mov, and, or, xor, add, sub
// (every such form takes a register there).  The store stays: memory is
// exact for everything else.  Forwarding ends at a label (a jump may arrive
// from anywhere), an unconditional jump, a call, any write that may reach b,
// or after kReach instructions (a read of b of another shape stays a load).
//
// Sound because the generator's code never reads a scratch register after a
// label that it did not write since (every label forgets what registers
// hold), except what an IDX's own label keeps; the check of "nothing reads it
// afterwards" runs to the end of the rung, across labels, so it sees those.
// eax is never a spare: WordInEax carries it from rung to rung.
class BytesFromRegisters {
 public:
  static void run(std::vector<Item>& items, std::vector<uint32_t>& starts) {
    for (size_t i = 0; i < items.size(); i++)
      if (stored_byte(items[i])) forward(items, starts, i);
  }

 private:
  static constexpr uint8_t kSpares[] = {R9, R8, R10, R11, SI, DX, CX};
  static constexpr size_t kReach = 400;
  static bool image_byte(const Operand& o) {
    return image_at(o) && o.mem.size == Size::Byte;
  }
  static bool stored_byte(const Item& it) {
    return it.kind == as::ItemKind::Instruction && it.inst.mnemonic == M::Mov && it.inst.num_operands == 2 &&
           image_byte(it.inst.ops[0]) && it.inst.ops[1].kind == OperandKind::Reg && it.inst.ops[1].reg.cls == RegClass::Gp8;
  }
  // the operand of `in` that reads byte b and may be a register instead, or -1
  static int byte_read(const Instruction& in, int32_t b) {
    auto at = [&](unsigned k) { return in.num_operands > k && image_byte(in.ops[k]) && in.ops[k].mem.disp == b; };
    switch (in.mnemonic) {
      case M::Cmp: case M::Test:
        if (at(0) && in.ops[1].kind != OperandKind::Mem) return 0;
        [[fallthrough]];
      case M::Movzx: case M::Movsx: case M::Mov: case M::And: case M::Or: case M::Xor: case M::Add: case M::Sub:
        return at(1) && in.ops[0].kind == OperandKind::Reg ? 1 : -1;
      default: return -1;
    }
  }
  // may `in` write byte b?
  static bool writes_byte(const Instruction& in, int32_t b, const as::x86::Effects& e) {
    for (unsigned k = 0; k < in.num_operands; k++) {
      const Operand& o = in.ops[k];
      if (o.kind != OperandKind::Mem || !as::x86::writes_operand(e.ops[k])) continue;
      if (!image_at(o)) return true;  // anywhere
      if (o.mem.disp <= b && b < o.mem.disp + int32_t(mem_width(o.mem))) return true;
    }
    return false;
  }
  // register n: does `in` read it (a write of its low byte keeps the rest: a read), write all of it?
  static bool reads(const Instruction& in, const as::x86::Effects& e, uint8_t n) {
    if (e.stack == as::x86::StackUse::Call || (e.reads >> n & 1)) return true;
    for (unsigned k = 0; k < in.num_operands; k++) {
      const Operand& o = in.ops[k];
      if (o.kind == OperandKind::Mem && ((o.mem.base.cls == RegClass::Gp64 && o.mem.base.num == n) ||
                                         (o.mem.index.valid() && o.mem.index.num == n)))
        return true;
      if (o.kind == OperandKind::Reg && o.reg.cls != RegClass::Xmm && o.reg.num == n &&
          (as::x86::reads_operand(e.ops[k]) || o.reg.cls == RegClass::Gp8))
        return true;
    }
    return false;
  }
  static bool writes(const Instruction& in, const as::x86::Effects& e, uint8_t n) {
    if (e.stack == as::x86::StackUse::Call || (e.writes >> n & 1)) return true;
    for (unsigned k = 0; k < in.num_operands; k++)
      if (in.ops[k].kind == OperandKind::Reg && in.ops[k].reg.cls != RegClass::Xmm && in.ops[k].reg.num == n &&
          as::x86::writes_operand(e.ops[k]))
        return true;
    return false;
  }
  // nothing in the rung after item `from` reads register n before writing it
  // (within kReach * 4 instructions: else taken as read)
  static bool dead_after(const std::vector<Item>& items, size_t from, uint8_t n) {
    for (size_t j = from + 1, seen = 0; j < items.size(); j++) {
      if (++seen > kReach * 4) return false;
      if (items[j].kind != as::ItemKind::Instruction) continue;
      const as::x86::Effects e = as::x86::effects(items[j].inst);
      if (reads(items[j].inst, e, n)) return false;
      if (writes(items[j].inst, e, n)) return true;
    }
    return true;
  }
  static void forward(std::vector<Item>& items, std::vector<uint32_t>& starts, size_t i) {
    const int32_t b = items[i].inst.ops[0].mem.disp;
    const uint8_t src = items[i].inst.ops[1].reg.num;
    std::vector<std::pair<size_t, int>> direct, late;  // (item, operand): reads while src holds b / after
    size_t last = i;
    bool src_kept = true;
    for (size_t j = i + 1, seen = 0; j < items.size() && seen < kReach; j++) {
      const Item& it = items[j];
      if (it.kind == as::ItemKind::Label) break;
      if (it.kind != as::ItemKind::Instruction) continue;
      seen++;
      const Instruction& in = it.inst;
      const as::x86::Effects e = as::x86::effects(in);
      if (e.stack == as::x86::StackUse::Call) break;
      if (const int k = byte_read(in, b); k >= 0) {
        (src_kept ? direct : late).push_back({j, k});
        last = j;
      }
      if (writes_byte(in, b, e)) break;
      if (writes(in, e, src)) src_kept = false;
      if (in.mnemonic == M::Jmp) break;
    }
    for (auto [j, k] : direct) items[j].inst.ops[size_t(k)] = Operand::r(r8(src));
    if (late.empty()) return;
    for (uint8_t t : kSpares) {
      if (t == src || !untouched_until(items, i, last, t) || !dead_after(items, last, t)) continue;
      for (auto [j, k] : late) items[j].inst.ops[size_t(k)] = Operand::r(r8(t));
      items.insert(items.begin() + ptrdiff_t(i) + 1, Item::instr(as::x86::make(M::Mov, {Operand::r(r32(t)), Operand::r(r32(src))})));
      for (uint32_t& s : starts)
        if (s > i) s++;
      return;
    }
  }
  static bool untouched_until(const std::vector<Item>& items, size_t i, size_t last, uint8_t n) {
    for (size_t j = i + 1; j <= last; j++) {
      if (items[j].kind != as::ItemKind::Instruction) continue;
      const as::x86::Effects e = as::x86::effects(items[j].inst);
      if (reads(items[j].inst, e, n) || writes(items[j].inst, e, n)) return false;
    }
    return true;
  }
};

// ------------------------------------------------------------ -O2: stores nothing reads
//
// A store to a cell of the image (`mov`, `movss`, `movsd`, `movd`, `movq` or
// `setcc` with a plain image operand as destination) that a later store of the
// same straight line writes over whole, with nothing in between that may read
// any of its bytes, is dropped: a chain of typed instructions each storing its
// result where the next overwrites it (`MUL.LREAL d 0.25 d` after `SUB.LREAL
// a b d`: the first result is read from xmm0, never from d).  The line ends at
// a jump or branch (the code at its target may read the cell), a call, any use
// of the stack, or after kReach instructions: the store then stays.  A label
// does not end it: the paths from the store all run on to the second store,
// whatever else arrives at the label.  A read that may reach the bytes is an
// operand read through any base but the image's, an indexed one, or an image
// operand overlapping them.
// Memory after the line is what it would have been: every byte dropped is
// written again before anything can read it.  It runs after the passes that
// turn loads into register reads (WordInEax, BytesFromRegisters), so a store
// whose every reader now reads a register may go.
class DeadStores {
 public:
  static void run(std::vector<Item>& items, std::vector<uint32_t>& starts) {
    std::vector<char> drop(items.size(), 0);
    bool any = false;
    for (size_t i = 0; i < items.size(); i++)
      if (plain_store(items[i]) && overwritten(items, i)) drop[i] = 1, any = true;
    if (any) as::remove_items(items, drop, starts);
  }

 private:
  static constexpr size_t kReach = 64;
  static bool plain_store(const Item& it) {
    if (it.kind != as::ItemKind::Instruction || it.inst.num_operands == 0 || !image_at(it.inst.ops[0])) return false;
    switch (it.inst.mnemonic) {
      case M::Mov: case M::Movss: case M::Movsd: case M::Movd: case M::Movq: case M::Setcc:
        return as::x86::effects(it.inst).ops[0] == as::x86::Use::W;
      default: return false;
    }
  }
  // is the store at item i written over whole before anything may read it?
  static bool overwritten(const std::vector<Item>& items, size_t i) {
    const Mem& c = items[i].inst.ops[0].mem;
    const int64_t lo = c.disp, hi = lo + int64_t(mem_width(c));
    for (size_t j = i + 1, seen = 0; j < items.size() && seen < kReach; j++) {
      const Item& it = items[j];
      if (it.kind != as::ItemKind::Instruction) continue;
      seen++;
      const Instruction& in = it.inst;
      const as::x86::Effects e = as::x86::effects(in);
      if (in.mnemonic == M::Jcc || in.mnemonic == M::Jmp || e.stack != as::x86::StackUse::None) return false;  // (call, ret)
      bool covers = false;
      for (unsigned k = 0; k < in.num_operands; k++) {
        const Operand& o = in.ops[k];
        if (o.kind != OperandKind::Mem) continue;
        const bool plain = image_at(o);
        const int64_t olo = o.mem.disp, ohi = olo + int64_t(mem_width(o.mem));
        if (as::x86::reads_operand(e.ops[k]) && (!plain || (olo < hi && lo < ohi))) return false;
        if (e.ops[k] == as::x86::Use::W && plain && olo <= lo && hi <= ohi) covers = true;
      }
      if (covers) return true;
    }
    return false;
  }
};

}  // namespace

std::string x86_label_name(const std::string& il_label) { return std::string(kLabelPrefix) + il_label; }

as::x86::RoutineAreas x86_routine_areas(const Layout& l) {
  as::x86::RoutineAreas a;
  a.tw = int32_t(l.addr(Area::TW, 0));
  a.tq = int32_t(l.addr(Area::TQ, 0));
  a.ti = int32_t(l.addr(Area::TI, 0));
  a.cw = int32_t(l.addr(Area::CW, 0));
  a.cq = int32_t(l.addr(Area::CQ, 0));
  a.dt = int32_t(kSysDt);
  a.e = int32_t(l.addr(Area::E, 0));
  a.e_count = int32_t(l.count[int(Area::E)]);
  return a;
}

// -O2 compact addressing (docs/x86.md, "Compact addressing"): the rungs are
// taken in regions of consecutive blocks; at the start of each region the
// base registers (as::x86::kBaseRegs) are pointed where that region's
// [rbp+disp32] operands are (a `lea reg, [rbp+K]` where one pays), and the
// operands inside a register's disp8 window [K-128, K+127] become [reg+d8].
// (Displacements from rbp, which points kImageBias bytes into the image: the
// frame swap biases them, to_o2_frame, and K is counted from rbp too.)
bool rewritable(const Instruction& in, const as::x86::Operand& o) {
  return image_at(o) && in.mnemonic != M::Call && in.mnemonic != M::Lea && (o.mem.disp < -128 || o.mem.disp > 127);
}
namespace {

struct Op {
  int64_t first, last;  // the bytes a rewritable operand accesses
  bool rex;             // its instruction has a REX prefix anyway (r15/r14 then cost no byte more than rdi)
};
using Ops = std::vector<Op>;
// the loader's range for K (as::x86::kBaseKMin, kBaseKTop: image offsets),
// here counted from rbp
constexpr int64_t kBaseKMin = as::x86::kBaseKMin - kImageBias;
constexpr int64_t kBaseKTop = as::x86::kBaseKTop + kImageBias;
constexpr int64_t kLeaBytes = 7;    // lea reg, [rbp+disp32]
// A region ends after the block that brings it kRegionOps operands (or before
// a jump target).  Picked by measuring code bytes of ldbench's plant and
// synthetic programs (docs/x86.md): 16 to 64 operands and one region of
// lookahead or none come within 0.5% of each other.
constexpr size_t kRegionOps = 32;
constexpr int kNewWindows = 3;  // windows a region may point registers to (the fullest ones)
static_assert(size_t(kNumBases + kNewWindows) <= x86gen::BaseSavings::kMaxWindows);

bool has_rex(const Instruction& in) {
  for (unsigned k = 0; k < in.num_operands; k++) {
    const Operand& o = in.ops[k];
    if (o.kind == OperandKind::Reg && (o.reg.num >= 8 || o.reg.cls == RegClass::Gp64 || (o.reg.cls == RegClass::Gp8 && o.reg.num >= 4)))
      return true;
  }
  return false;
}

// Is `in` a reload of a base register after a REAL call (`lea reg, [rbp+K]`)?
bool reloads_base(const Instruction& in) {
  if (in.mnemonic != M::Lea || in.ops[1].mem.base != kO2Image) return false;
  for (RegNum r : kBaseRegs)
    if (in.ops[0].reg == r64(r)) return true;
  return false;
}

// Is `in` a jump to a rung's global label?
bool jumps_to_rung(const Instruction& in) {
  return (in.mnemonic == M::Jmp || in.mnemonic == M::Jcc) && in.ops[0].kind == OperandKind::Label &&
         in.ops[0].label.view().starts_with(kLabelPrefix);
}

// What a region's plan and rewrite look at, gathered as each of its blocks
// comes (one look at the items, not one a pass): the rewritable operands (their
// bytes for the plan, where they are for the rewrite), the reloads of the base
// registers and the jumps to the rungs' global labels.  The pointers stay valid
// while the blocks wait in the region: a moved vector keeps its storage.
struct RegionRefs {
  Ops ops;
  std::vector<Mem*> mems;              // ops' operands, in order
  std::vector<Instruction*> reloads;   // reloads_base
  std::vector<uint32_t> jumps;         // jumps_to_rung: their labels' ids

  void add(as::Block<Instruction>& b) {
    for (Item& it : b.items) {
      if (it.kind != as::ItemKind::Instruction) continue;
      Instruction& in = it.inst;
      if (reloads_base(in)) reloads.push_back(&in);
      else if (jumps_to_rung(in)) jumps.push_back(in.ops[0].label.id());
      for (unsigned k = 0; k < in.num_operands; k++)
        if (rewritable(in, in.ops[k])) {
          Mem& m = in.ops[k].mem;
          ops.push_back({m.disp, int64_t(m.disp) + mem_width(m) - 1, has_rex(in)});
          mems.push_back(&m);
        }
    }
  }
  void clear() { ops.clear(), mems.clear(), reloads.clear(), jumps.clear(); }
};

bool covers(int64_t k, int64_t first, int64_t last) { return first >= k - 128 && last <= k + 127; }

// The fullest window [lo, lo+255] over ops (sorted), as the K in the middle of
// the slack its operands leave (0 if none).  O(n): an operand is at most 8
// bytes, so only those starting in the window's last 7 bytes may end past it.
int64_t best_window(const Ops& ops) {
  size_t best = 0, end = 0, best_i = 0, best_end = 0;
  for (size_t i = 0; i < ops.size(); i++) {
    if (i > 0 && ops[i].first == ops[i - 1].first) continue;
    int64_t lo = ops[i].first;
    while (end < ops.size() && ops[end].first <= lo + 255) end++;
    size_t n = end - i;
    for (size_t j = end; j-- > i && ops[j].first > lo + 248;)
      if (ops[j].last > lo + 255) n--;
    if (n > best) best = n, best_i = i, best_end = end;
  }
  if (!best) return 0;
  int64_t lo = ops[best_i].first, last = lo;
  for (size_t j = best_i; j < best_end; j++)
    if (ops[j].last <= lo + 255) last = std::max(last, ops[j].last);
  return (lo + 128 + last - 127) / 2;
}

// The window each register takes for a region (BasePlan::plan): r itself
// (keep, or nothing if not known) or new window j (kNumBases + j), no new one
// twice; the most bytes saved, the first found of equal ones, trying register
// 0's choice fastest, then 1's, then 2's (keep first, then the new ones in order).
std::array<size_t, kNumBases> best_windows(size_t news, bool free, const x86gen::BaseSavings& sv) {
  static_assert(kNumBases == 3);
  auto window = [](size_t r, size_t o) { return o == 0 ? r : kNumBases + o - 1; };  // o: 0 keep, j > 0 new j-1
  std::array<size_t, kNumBases> best_choice{0, 1, 2};
  int64_t best = INT64_MIN;
  for (size_t o2 = 0; o2 <= news; o2++)
    for (size_t o1 = 0; o1 <= news; o1++) {
      if (o1 && o1 == o2) continue;
      const uint32_t other_w = 1u << window(1, o1) | 1u << window(2, o2);
      const int64_t leas = (o1 != 0) + (o2 != 0);
      for (size_t o0 = 0; o0 <= news; o0++) {
        if (o0 && (o0 == o1 || o0 == o2)) continue;
        const int64_t saved = (free ? 0 : -kLeaBytes * (leas + (o0 != 0))) + sv.saved(1u << window(0, o0), other_w);
        if (saved > best) best = saved, best_choice = {window(0, o0), window(1, o1), window(2, o2)};
      }
    }
  return best_choice;
}

// The base registers' K as the regions go (unknown after a jump target, which
// a path from elsewhere may reach with other values).
class BasePlan {
 public:
  explicit BasePlan(uint32_t image_size) : kmax_(int64_t(image_size) - kBaseKTop) {
    if (kmax_ < kBaseKMin) throw std::logic_error("x86 backend: memory image too small for base registers");
  }
  bool known(int r) const { return known_[size_t(r)]; }
  int64_t k(int r) const { return k_[size_t(r)]; }
  void forget(int r) { known_[size_t(r)] = false; }
  void set(int r, int64_t k) { k_[size_t(r)] = k, known_[size_t(r)] = true; }

  // Points the registers for a region with these operands; returns those that
  // need a lea at its start.  Each register keeps its K or takes one of the
  // kNewWindows fullest windows (found greedily: the fullest, then the fullest
  // of the operands it leaves ...); every such choice is counted in bytes
  // saved (3 an operand through rdi, 2 or 3 through r15/r14, which need a REX)
  // less 7 a lea (none when `free`: the prologue's), and the best one taken.
  // Operands are counted by the set of windows that cover them (BaseSavings), so
  // a choice costs O(1), not O(operands).  Every register is set when `free`.
  std::array<bool, kNumBases> plan(Ops& ops, bool free) {
    if (ops.empty() && !free) return {};
    // by first byte, as best_window walks them (the order of ties changes nothing below)
    std::sort(ops.begin(), ops.end(), [](const Op& a, const Op& b) { return a.first < b.first; });
    std::vector<int64_t>& news = news_;  // the new windows' K
    Ops& rest = rest_;
    news.clear();
    for (rest.assign(ops.begin(), ops.end()); news.size() < size_t(kNewWindows) && !rest.empty();) {
      int64_t kw = std::clamp(best_window(rest), kBaseKMin, kmax_);
      size_t before = rest.size();
      std::erase_if(rest, [&](const Op& o) { return covers(kw, o.first, o.last); });
      if (rest.size() == before) break;
      news.push_back(kw);
    }
    // windows: 0..2 the registers' present K (if known), 3.. the new ones
    const size_t nw = kNumBases + news.size();
    auto window_k = [&](size_t w) { return w < kNumBases ? k(int(w)) : news[w - kNumBases]; };
    x86gen::BaseSavings& sv = savings_;
    sv.clear(nw);
    std::array<int64_t, x86gen::BaseSavings::kMaxWindows> wk{};  // the windows in use: their K
    size_t nk = 0;
    std::array<uint32_t, x86gen::BaseSavings::kMaxWindows> wbit{};
    for (size_t w = 0; w < nw; w++)
      if (w >= kNumBases || known(int(w))) wk[nk] = window_k(w), wbit[nk++] = 1u << w;
    for (const Op& o : ops) {
      uint32_t mask = 0;
      for (size_t j = 0; j < nk; j++)
        if (covers(wk[j], o.first, o.last)) mask |= wbit[j];
      if (mask) sv.add(mask, o.rex);
    }
    sv.sum_subsets();
    const std::array<size_t, kNumBases> best_choice = best_windows(news.size(), free, sv);
    std::array<bool, kNumBases> lea{};
    for (int r = 0; r < kNumBases; r++)
      if (best_choice[size_t(r)] != size_t(r)) set(r, window_k(best_choice[size_t(r)])), lea[size_t(r)] = true;
    if (free)
      for (int r = 0; r < kNumBases; r++)
        if (!lea[size_t(r)]) set(r, known(r) ? k(r) : kBaseKMin), lea[size_t(r)] = true;
    return lea;
  }

  // Rewrites a region's operands through the known registers, and fills in
  // the K of the leas after REAL calls (the reloads): the region's, or the
  // lowest K for a register the region does not use (known from then on:
  // `reloaded`).
  void rewrite(const RegionRefs& refs, std::array<bool, kNumBases>& reloaded) const {
    for (Instruction* in : refs.reloads)
      for (int r = 0; r < kNumBases; r++)
        if (in->ops[0].reg == r64(kBaseRegs[r]))
          in->ops[1].mem.disp = int32_t(known(r) ? k(r) : kBaseKMin), reloaded[size_t(r)] = true;
    for (Mem* m : refs.mems) {
      const int64_t first = m->disp, last = first + mem_width(*m) - 1;
      for (int r = 0; r < kNumBases; r++)
        if (known(r) && covers(k(r), first, last)) {
          m->base = r64(kBaseRegs[r]);
          m->disp = int32_t(first - k(r));
          break;
        }
    }
  }

 private:
  int64_t kmax_;
  std::array<int64_t, kNumBases> k_{};
  std::array<bool, kNumBases> known_{};
  x86gen::BaseSavings savings_;  // plan's
  std::vector<int64_t> news_;    // plan's, kept from region to region
  Ops rest_;                     // plan's, kept from region to region
};

// -O2: the blocks gathered into regions, each given its base registers, then
// handed to the sink in order (the prologue, held until the first region
// fills in its leas, and each rung's IL starts).
class Regions {
 public:
  Regions(uint32_t image_size, as::Block<Instruction> prologue, std::vector<std::vector<uint32_t>>& il_items,
          const X86BlockSink& sink)
      : plan_(image_size), prologue_(std::move(prologue)), il_items_(il_items), sink_(sink) {}

  // a rung's block; `target`: it starts with labels that jumps name
  void add(as::Block<Instruction>& b, std::vector<uint32_t>& starts, bool target) {
    if (target) flush(), target_ = true;
    refs_.add(b);
    blocks_.push_back(std::move(b));
    starts_.push_back(std::move(starts));
    if (!spare_.empty()) b = std::move(spare_.back()), spare_.pop_back();  // reuse a sunk block's storage
    if (!spare_starts_.empty()) starts = std::move(spare_starts_.back()), spare_starts_.pop_back();
    if (refs_.ops.size() >= kRegionOps) flush();
  }
  void finish() { flush(); }

 private:
  void flush() {
    if (blocks_.empty() && !prologue_) return;
    bool free = prologue_.has_value();
    if (target_) arrive(blocks_[0]);
    std::array<bool, kNumBases> lea = plan_.plan(refs_.ops, free);
    if (free) {
      for (Item& it : prologue_->items)
        for (int r = 0; r < kNumBases; r++)
          if (it.kind == as::ItemKind::Instruction && it.inst.mnemonic == M::Lea && it.inst.ops[0].reg == r64(kBaseRegs[r]))
            it.inst.ops[1].mem.disp = int32_t(plan_.k(r));
      sink_(*prologue_);
      prologue_.reset();
    }
    std::array<bool, kNumBases> reloaded{};
    plan_.rewrite(refs_, reloaded);
    if (!free && !blocks_.empty()) {  // the leas, after the first block's labels
      std::vector<Item>& items = blocks_[0].items;
      size_t at = 0;
      while (at < items.size() && items[at].kind == as::ItemKind::Label) at++;
      std::vector<Item>& leas = leas_;
      leas.clear();
      for (int r = 0; r < kNumBases; r++)
        if (lea[size_t(r)]) leas.push_back(Item::instr(base_lea(kBaseRegs[r], int32_t(plan_.k(r)))));
      items.insert(items.begin() + ptrdiff_t(at), leas.begin(), leas.end());
      for (uint32_t& s : starts_[0]) s += uint32_t(leas.size());
    }
    depart();  // before the reloads make a register known
    for (int r = 0; r < kNumBases; r++)
      if (reloaded[size_t(r)] && !plan_.known(r)) plan_.set(r, kBaseKMin);
    for (size_t i = 0; i < blocks_.size(); i++) {
      il_items_.push_back(std::move(starts_[i]));
      sink_(blocks_[i]);
      if (il_items_.back().empty() && spare_starts_.size() < kSpareBlocks)  // the sink is done with it
        spare_starts_.push_back(std::move(il_items_.back()));
      if (spare_.size() < kSpareBlocks) spare_.push_back(std::move(blocks_[i]));
    }
    blocks_.clear();
    starts_.clear();
    refs_.clear();
    target_ = false;
  }

  // The region's jumps to the rungs' global labels (all forward, so all made
  // before their target's region): the registers' K at each, -1 where not known.
  void depart() {
    std::array<int64_t, kNumBases> now;
    for (int r = 0; r < kNumBases; r++) now[size_t(r)] = plan_.known(r) ? plan_.k(r) : -1;
    for (uint32_t label : refs_.jumps) {
      auto [at, fresh] = at_jumps_.emplace(label, now);
      if (!fresh)
        for (int r = 0; r < kNumBases; r++)
          if (at->second[size_t(r)] != now[size_t(r)]) at->second[size_t(r)] = -1;
    }
  }
  // A region that starts at jump targets keeps a register's K only where
  // every jump to them brings the same K as the code falling through.
  void arrive(const as::Block<Instruction>& b) {
    for (const Item& it : b.items) {
      if (it.kind != as::ItemKind::Label) break;
      auto at = at_jumps_.find(it.label.id());
      if (at == at_jumps_.end()) continue;
      for (int r = 0; r < kNumBases; r++)
        if (at->second[size_t(r)] != (plan_.known(r) ? plan_.k(r) : -1)) plan_.forget(r);
      at_jumps_.erase(at);
    }
  }

  BasePlan plan_;
  std::map<uint32_t, std::array<int64_t, kNumBases>> at_jumps_;  // by label name id
  std::optional<as::Block<Instruction>> prologue_;
  std::vector<std::vector<uint32_t>>& il_items_;
  const X86BlockSink& sink_;
  std::vector<as::Block<Instruction>> blocks_;  // the region's
  std::vector<std::vector<uint32_t>> starts_;
  RegionRefs refs_;  // the blocks' operands, reloads and jumps
  std::vector<Item> leas_;  // flush's, kept from region to region
  bool target_ = false;  // the region's first block is a jump target
  // Blocks sunk, their items' storage for rungs to come: enough for a region's
  // blocks, so that a rung's items seldom grow a new vector from nothing.
  static constexpr size_t kSpareBlocks = 64;
  std::vector<as::Block<Instruction>> spare_;
  std::vector<std::vector<uint32_t>> spare_starts_;  // the same for the il_items entries the sink cleared
};

// The blocks of a program in order (block 0 the prologue, one per rung, the
// epilogue, the shared routines if any are called), each handed to `sink`.
class Blocks {
 public:
  // A program with a LOOP gets -O2 without its base registers: their plans
  // carry each register's K forward only, and the loader's code check proves
  // a back edge only where no base register is set (docs/x86.md, "Loops").
  // The facts are loop-proof: a LOOP forgets as a JMP does, its head is a
  // label, which forgets what was known.
  Blocks(const Program& p, const Layout& layout, int opt_level, bool notes)
      : p_(p), layout_(layout), loops_(has_loop(p)), opt_(opt_level), o2_(opt_ >= 2), notes_(notes) {
    if (o2_) facts_ = scan_facts(p_, layout_, kNumSlots), consts_ = RealConsts::of(p_);
    shared_ = facts_ ? facts_->shared : shares_stack(p);
  }

  as::Block<Instruction> prologue() const {
    // keep rbx/rbp for the caller, 16-byte stack alignment for calls
    as::Block<Instruction> pro;
    pro.source_line = p_.rungs.empty() ? 0 : p_.rungs[0].line;
    pro.items.push_back(Item::note(o2_ ? "scan(image): rbp = image+" + std::to_string(kImageBias) + ", bit stack in bl r12b r13b (or ebx), bases rdi r15 r14 (-O2)"
                                         : "scan(image): rbx = image, ebp = bit stack"));
    for (const Instruction& i : scan_prologue(o2_)) pro.items.push_back(Item::instr(i));
    if (loops_) {  // no loop taken yet
      std::vector<Item> reset{Item::instr(make(M::Mov, {Dw(kSysLoops), I(0)}))};
      if (o2_) to_o2_frame(reset);
      pro.items.push_back(reset[0]);
    }
    if (o2_ && !loops_)
      for (RegNum r : as::x86::kBaseRegs) pro.items.push_back(Item::instr(as::x86::base_lea(r, 0)));  // K: Regions::flush
    for (const Instruction& i : consts_.loads()) pro.items.push_back(Item::instr(i));
    return pro;
  }

  // Rung r's block into b (its items replaced); starts: where each IL instruction's code starts.
  void rung(size_t ri, as::Block<Instruction>& b, std::vector<uint32_t>& starts) {
    const Rung& r = p_.rungs[ri];
    b.source_line = r.line;
    b.items.clear();
    starts.clear();
    starts.reserve(r.code.size());
    for (const auto& l : r.labels) b.items.push_back(Item::label_def(x86_label_name(l), true));
    if (notes_) b.items.push_back(Item::note("rung, line " + std::to_string(r.line) + (r.title.empty() ? "" : ": " + r.title)));
    bool slots = o2_ && facts_->fits[ri];  // the rung's stack in the slot registers (none where shared_)
    known_.reset();
    Gen g(layout_, b.items, slots, o2_, &used_, known_, opt_ == 1, !loops_);
    g.use_consts(&consts_);
    if (o2_) g.use_cold(&cold_, &cold_count_);
    uint8_t keep = slots ? 0xff : uint8_t(~kUnread);  // an unread entry is still shifted into ebp
    for (size_t k = 0; k < r.code.size(); k++) {
      const ldc::Instr& in = r.code[k];
      const bool cj = slots && k + 2 < r.code.size() && Gen::is_compare_jump(in, r.code[k + 1], r.code[k + 2]);
      if (k + 2 < r.code.size() && (cj || Gen::is_select(in, r.code[k + 1], r.code[k + 2])) && plain(ri, k, 3)) {
        starts.push_back(uint32_t(b.items.size()));
        if (notes_) b.items.push_back(Item::note(instr_text(in) + "; " + instr_text(r.code[k + 1]) + "; " + instr_text(r.code[k + 2])));
        if (cj) g.compare_jump(in, r.code[k + 1], r.code[k + 2]);
        else g.select(in, r.code[k + 1], r.code[k + 2]);
        starts.push_back(uint32_t(b.items.size()));
        starts.push_back(uint32_t(b.items.size()));
        k += 2;
        continue;
      }
      if (in.op == ldc::Op::TIDX || in.op == ldc::Op::LOOP) g.set_il_offset(il_offset(ri, k));
      g.set_next(in.op == ldc::Op::TIDX && compiled_access(ri, k + 1) ? &r.code[k + 1] : nullptr);
      starts.push_back(uint32_t(b.items.size()));
      if (notes_) b.items.push_back(Item::note(instr_text(in)));
      if (!facts_) { g.instr(in); continue; }
      const ldc::Instr* alt = facts_->replacement(ri, k);
      g.instr(alt ? *alt : in, facts_->at(ri, k) & keep, facts_->reuse(ri, k), facts_->quotient_to(ri, k));
    }
    g.close_typed_run();
    if (opt_ >= 1 && !slots) peephole(b.items, starts, shared_);
    if (!o2_) return;
    to_o2_frame(b.items);
    drop_unreachable(b.items, starts);
    eax_.run(b.items, starts);
    BytesFromRegisters::run(b.items, starts);
    DeadStores::run(b.items, starts);
  }

  // Is instruction k of rung ri an LDX / STX compiled as it stands (no fact
  // drops or replaces it)?  An IDX right before it leaves it its check.
  bool compiled_access(size_t ri, size_t k) const {
    const Rung& r = p_.rungs[ri];
    if (k >= r.code.size() || (r.code[k].op != ldc::Op::TLDX && r.code[k].op != ldc::Op::TSTX)) return false;
    return !facts_ || (!(facts_->at(ri, k) & (kDeadStore | kUnread | kHeld)) && !facts_->replacement(ri, k));
  }

  // -O2: the IDX fault records out of line (Gen::cold_fault), after the last
  // rung, which jumps over them to the epilogue
  std::optional<as::Block<Instruction>> cold() {
    if (cold_.empty()) return std::nullopt;
    as::Block<Instruction> c;
    c.source_line = p_.rungs.empty() ? 0 : p_.rungs.back().line;
    if (notes_) c.items.push_back(Item::note("out of line: the fault records of the IDX instructions"));
    c.items.push_back(Item::instr(far(make(M::Jmp, {Operand::l(kX86ExitLabel)}))));
    for (Item& it : cold_) c.items.push_back(std::move(it));
    cold_.clear();
    to_o2_frame(c.items);
    return c;
  }

  as::Block<Instruction> epilogue() const {
    as::Block<Instruction> epi;
    epi.source_line = p_.rungs.empty() ? 0 : p_.rungs.back().line;
    for (const auto& l : p_.end_labels) epi.items.push_back(Item::label_def(x86_label_name(l), true));
    epi.items.push_back(Item::label_def(kX86ExitLabel, true));
    for (const Instruction& i : scan_epilogue(o2_)) epi.items.push_back(Item::instr(i));
    return epi;
  }

  // the shared timer and counter routines the rungs call, after the epilogue (empty if none)
  std::optional<as::Block<Instruction>> routines() const {
    if (!used_.any()) return std::nullopt;
    as::Block<Instruction> rt;
    rt.source_line = p_.rungs.empty() ? 0 : p_.rungs.back().line;
    as::x86::RoutineAreas areas = x86_routine_areas(layout_);
    for (int k = 0; k < int(as::x86::Routine::Count); k++) {
      if (!used_.test(size_t(k))) continue;
      std::string name(as::x86::routine_name(as::x86::Routine(k)));
      rt.items.push_back(Item::label_def(name, true));
      for (const Instruction& i : as::x86::scan_routine(as::x86::Routine(k), areas)) rt.items.push_back(Item::instr(i));
    }
    return rt;
  }

  void run(std::vector<std::vector<uint32_t>>& il_items, const X86BlockSink& sink) {
    il_items.reserve(p_.rungs.size());
    as::Block<Instruction> b;
    std::vector<uint32_t> starts;
    if (o2_ && !loops_) {
      Regions regions(layout_.size, prologue(), il_items, sink);
      for (size_t r = 0; r < p_.rungs.size(); r++) {
        rung(r, b, starts);
        regions.add(b, starts, !p_.rungs[r].labels.empty());
      }
      regions.finish();
    } else {
      b = prologue();
      sink(b);
      for (size_t r = 0; r < p_.rungs.size(); r++) {
        rung(r, b, starts);
        il_items.push_back(std::move(starts));
        sink(b);
        if (il_items.back().empty()) starts = std::move(il_items.back());  // the sink is done with it
      }
    }
    if (auto c = cold()) sink(*c);
    b = epilogue();
    sink(b);
    if (auto rt = routines()) sink(*rt);
  }

 private:
  // The IL byte offset of rung ri's instruction k in the image's IL section
  // (encode_il's instr_offset): an IDX's fault record names it.  Encoded once,
  // for the first IDX.
  uint32_t il_offset(size_t ri, size_t k) {
    if (il_offsets_.empty()) {
      il_offsets_ = encode_il(p_).instr_offset;
      size_t n = 0;
      for (const Rung& r : p_.rungs) rung_first_.push_back(n), n += r.code.size();
    }
    return il_offsets_[rung_first_[ri] + k];
  }

  // no -O2 fact and no replacement for rung ri's instructions k .. k+n-1
  bool plain(size_t ri, size_t k, size_t n) const {
    if (!facts_) return true;
    for (size_t i = k; i < k + n; i++)
      if (facts_->at(ri, i) || facts_->replacement(ri, i) || facts_->reuse(ri, i) || facts_->quotient_to(ri, i)) return false;
    return true;
  }

  const Program& p_;
  const Layout& layout_;
  std::vector<uint32_t> il_offsets_;
  std::vector<size_t> rung_first_;
  bool loops_;
  int opt_;
  bool o2_, notes_;
  bool shared_;  // shares_stack(p): the stack lives in ebp from rung to rung
  std::bitset<8> used_;
  std::optional<ScanFacts> facts_;  // -O2: what the scan cannot observe
  RealConsts consts_;  // -O2: the constants kept in xmm8..xmm15
  std::vector<Item> cold_;  // -O2: the IDX fault records out of line (Gen::cold_fault)
  int cold_count_ = 0;
  WordInEax eax_;                   // -O2: the word eax holds, from rung to rung
  KnownStack known_;                // a rung's Gen's (its storage kept)
};

}  // namespace

std::vector<std::string> x86_globals(const Program& p) {
  std::vector<std::string> g;
  g.push_back(kX86ExitLabel);
  for (int k = 0; k < int(as::x86::Routine::Count); k++)
    g.push_back(std::string(as::x86::routine_name(as::x86::Routine(k))));
  for (const Rung& r : p.rungs)
    for (const auto& l : r.labels) g.push_back(x86_label_name(l));
  for (const auto& l : p.end_labels) g.push_back(x86_label_name(l));
  int idx = 0;  // at most one out-of-line fault record per IDX (Gen::cold_fault)
  for (const Rung& r : p.rungs)
    for (const ldc::Instr& in : r.code) idx += in.op == ldc::Op::TIDX;
  for (int k = 0; k < idx; k++) g.push_back(idx_fault_label(k));
  return g;
}

void generate_x86_blocks(const Program& p, const Layout& layout, int opt_level, bool notes, const X86BlockSink& sink,
                         std::vector<std::vector<uint32_t>>& il_items) {
  Blocks(p, layout, opt_level, notes).run(il_items, sink);
}

std::vector<std::vector<uint32_t>> generate_x86_blocks(const Program& p, const Layout& layout, int opt_level, bool notes,
                                                       const X86BlockSink& sink) {
  std::vector<std::vector<uint32_t>> il_items;
  generate_x86_blocks(p, layout, opt_level, notes, sink, il_items);
  return il_items;
}

X86Code generate_x86(const Program& p, const Layout& layout, int opt_level, bool notes) {
  X86Code out;
  out.program.globals = x86_globals(p);
  out.program.blocks.reserve(p.rungs.size() + 3);
  out.il_items = generate_x86_blocks(p, layout, opt_level, notes,
                                     [&](as::Block<Instruction>& b) { out.program.blocks.push_back(std::move(b)); });
  return out;
}

}  // namespace ldc
