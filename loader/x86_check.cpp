// loader/x86_check.cpp -- the x86-64 code check of the loader: every byte
// decodes with our disassembler, every memory operand is [rbx+disp] (the -O2
// frame: [rbp+disp], or a base register's) inside the memory image, every
// direct branch lands on an instruction boundary inside the code and goes
// forward, and the only division is the guarded one (docs/image-format.md,
// "The x86-64 code check").  The registers an instruction writes are its
// form's row in the assembler's form table (x86.h, Effects).  The check holds
// a few bits per byte of code, never a record per instruction: it decodes
// again where it looks (docs/image-format.md, "What the loader allocates").
#include <algorithm>
#include <array>
#include <cstdio>
#include <optional>

#include "assembler/x86.h"
#include "ir/mathfn.h"
#include "loader/checks.h"
#include "loader/loader.h"

namespace ldc {

namespace detail {

namespace {

namespace x86 = ldc::as::x86;

std::string hex(uint64_t v) {
  char buf[24];
  std::snprintf(buf, sizeof buf, "0x%llx", static_cast<unsigned long long>(v));
  return buf;
}

std::string text_of(const x86::Instruction& in) {
  try {
    return "'" + x86::print(in) + "'";
  } catch (const std::exception&) {
    return "'" + std::string(x86::mnemonic_name(in.mnemonic, in.cond)) + " ...'";
  }
}

uint32_t width(x86::Size s) {
  switch (s) {
    case x86::Size::Byte: return 1;
    case x86::Size::Dword: return 4;
    case x86::Size::Qword: return 8;
    case x86::Size::Word: return 2;
    case x86::Size::None: return 1;
  }
  return 1;
}

// The -O2 frame's base registers (as::x86::kBaseRegs), set when its prologue
// points all of them into the image; absent under the -O0 frame.  No value is
// tracked: every write of a base register is `lea reg, [rbp+K]` with K in
// [kBaseKMin, size - kBaseKTop] and every access through one is [reg+d] with
// d in [-128, 127] and at most 8 bytes, so [K+d, K+d+8) lies inside the image
// whatever K a path brought (docs/image-format.md, "The x86-64 code check").
struct Bases {
  bool set = false;
  // which base register r is (0, 1, 2), or -1
  static int which(const x86::Reg& r) {
    if (r.cls != x86::RegClass::Gp64) return -1;
    for (int i = 0; i < x86::kNumBases; i++)
      if (r.num == x86::kBaseRegs[i]) return i;
    return -1;
  }
};
using x86::kBaseKMin;  // K-128 >= 0
using x86::kBaseKTop;  // K+127+8 <= size

// Is `in` of the form `lea reg, [img+k]` for base register i (any k)?
bool is_base_lea(const x86::Instruction& in, int i, x86::Reg img) {
  return in.mnemonic == x86::Mnemonic::Lea && in.num_operands == 2 && in.ops[0].kind == x86::OperandKind::Reg &&
         in.ops[0].reg == x86::r64(x86::kBaseRegs[i]) && in.ops[1].kind == x86::OperandKind::Mem &&
         in.ops[1].mem.base == img && !in.ops[1].mem.index.valid();
}

// "" if base register i's lea `in` (is_base_lea) sets a K every [reg+d8] access stays inside the image from
// (bias: where the image register points into the image, as::x86::kImageBias)
std::string base_k_error(const x86::Instruction& in, int i, uint32_t image_size, int32_t bias) {
  int64_t k = int64_t(in.ops[1].mem.disp) + bias;
  if (k >= kBaseKMin && k <= int64_t(image_size) - kBaseKTop) return "";
  return "sets " + std::string(x86::reg_name(x86::r64(x86::kBaseRegs[i]))) + " = " +
         std::string(x86::reg_name(in.ops[1].mem.base)) + "+" + std::to_string(in.ops[1].mem.disp) +
         (bias ? " (image offset " + std::to_string(k) + ")" : "") +
         ", outside [" + std::to_string(kBaseKMin) + ", " + std::to_string(int64_t(image_size) - kBaseKTop) +
         "] (a base register's K must keep every [reg-0x80] .. [reg+0x7f] access of up to 8 bytes inside the memory image [0, " +
         hex(image_size) + "))";
}

// "" if the memory operand is [img+disp] (img: rbx, or rbp under the -O2
// frame, pointing `bias` bytes into the image) with [bias+disp, bias+disp+width)
// inside the image, or, under the -O2 frame, [rdi/r15/r14+disp] with disp in
// [-128, 127].  An indexed operand [img+reg*s+disp] only where `indexed_checked`:
// the body's rules found its bounds check right before it (BodyRules::indexed).
std::string check_mem(const x86::Mem& m, uint32_t image_size, const Bases& bases, x86::Reg img, int32_t bias,
                      bool indexed_checked = false) {
  const x86::Reg& base = m.base;
  const std::string img_name(x86::reg_name(img)), only = " (only [" + img_name + "+disp] may address memory)";
  if (int b = Bases::which(base); b >= 0 && bases.set) {
    if (m.index.valid())
      return "indexed memory operand (index " + std::string(x86::reg_name(m.index)) + "): its address cannot be checked";
    static_assert(kBaseKTop >= 127 + 8);
    if (m.disp < -128 || m.disp > 127 || width(m.size) > 8)
      return "memory operand [" + std::string(x86::reg_name(base)) + (m.disp < 0 ? "-" : "+") +
             hex(m.disp < 0 ? -int64_t(m.disp) : m.disp) + "]: a base register of the -O2 frame takes a displacement in [-0x80, 0x7f] only";
    return "";
  }
  if (base.cls == x86::RegClass::Rip) return "rip-relative memory operand" + only;
  if (!base.valid()) return "absolute memory operand" + only;
  if (base.cls == x86::RegClass::Gp64 && (base.num == x86::SP || (base.num == x86::BP && base != img)))
    return "stack-relative memory operand based on " + std::string(x86::reg_name(base)) + only;
  if (base != img) return "memory operand based on " + std::string(x86::reg_name(base)) + ", not " + img_name;
  if (m.index.valid() && indexed_checked) return "";
  if (m.index.valid())
    return "indexed memory operand (index " + std::string(x86::reg_name(m.index)) +
           "): its address cannot be checked";
  int64_t lo = int64_t(m.disp) + bias, hi = lo + width(m.size);
  if (lo < 0 || hi > int64_t(image_size))
    return "memory operand [" + img_name + std::string(m.disp < 0 ? "-" : "+") + hex(m.disp < 0 ? -int64_t(m.disp) : m.disp) +
           "] (" + std::to_string(width(m.size)) + " bytes" + (bias ? ", image offset " + std::to_string(lo) : "") +
           ") outside the memory image [0, " + hex(image_size) + ")";
  return "";
}

// The forms of division ldc emits, each its divisor's tests right before it,
// so it cannot raise #DE: x86gen divmod's (the divisor in ecx, tested for 0
// and -1, the two divisions that fault), -O2's safe_divisor, and the typed
// instructions' (docs/x86.md, "Typed instructions"): the same at 64 bits
// (cqo; idiv rcx), and the unsigned div after its test of 0 with edx cleared,
// whose quotient then always fits.
using Seq = std::vector<x86::Instruction>;
const std::array<Seq, 5>& guarded_divisions() {
  using M = x86::Mnemonic;
  using O = x86::Operand;
  static const std::array<Seq, 5> seqs = [] {
    auto signed_form = [](x86::Reg c, M extend) {
      return Seq{x86::make(M::Test, {O::r(c), O::r(c)}), x86::make_cc(M::Jcc, x86::Cond::E, {O::a(0)}),
                 x86::make(M::Cmp, {O::r(c), O::i(-1)}), x86::make_cc(M::Jcc, x86::Cond::E, {O::a(0)}),
                 x86::make(extend), x86::make(M::Idiv, {O::r(c)})};
    };
    auto unsigned_form = [](x86::Reg c) {
      const O edx = O::r(x86::r32(x86::DX));
      return Seq{x86::make(M::Test, {O::r(c), O::r(c)}), x86::make_cc(M::Jcc, x86::Cond::E, {O::a(0)}),
                 x86::make(M::Xor, {edx, edx}), x86::make(M::Div, {O::r(c)})};
    };
    Seq safe(x86::safe_divisor().begin(), x86::safe_divisor().end());
    safe.push_back(x86::make(M::Cdq));
    safe.push_back(x86::make(M::Idiv, {O::r(x86::r32(x86::CX))}));
    return std::array<Seq, 5>{signed_form(x86::r32(x86::CX), M::Cdq), safe, signed_form(x86::r64(x86::CX), M::Cqo),
                              unsigned_form(x86::r32(x86::CX)), unsigned_form(x86::r64(x86::CX))};
  }();
  return seqs;
}

// Does the window (the body's last instructions, oldest first) end with the
// instructions of seq (branch displacements aside)?
bool ends_with(std::span<const x86::Instruction> window, const Seq& seq) {
  if (window.size() < seq.size()) return false;
  window = window.last(seq.size());
  for (size_t j = 0; j < seq.size(); j++) {
    x86::Instruction a = window[j];
    a.long_branch = false;
    if (a.mnemonic == x86::Mnemonic::Jcc && a.num_operands == 1 && a.ops[0].kind == x86::OperandKind::Address) a.ops[0].imm = 0;
    if (a.num_operands == 2 && a.ops[1].kind == x86::OperandKind::Imm) a.ops[1].imm = int32_t(a.ops[1].imm);  // decoded 0xffffffff
    if (!(a == seq[j])) return false;
  }
  return true;
}

// The guarded division the window ends with, its idiv / div last (branch
// targets aside), or nullptr.
const Seq* guarded_division(std::span<const x86::Instruction> window) {
  for (const Seq& seq : guarded_divisions())
    if (ends_with(window, seq)) return &seq;
  return nullptr;
}

// The body's last six instructions seen, oldest first, and their offsets:
// what the division check looks back on.
class Window {
 public:
  static constexpr size_t kSpan = 6;
  void push(const x86::Decoded& d) {
    if (n_ == kSpan) {
      std::move(insts_.begin() + 1, insts_.end(), insts_.begin());
      std::move(offs_.begin() + 1, offs_.end(), offs_.begin());
      n_--;
    }
    insts_[n_] = d.inst;
    offs_[n_] = d.offset;
    n_++;
  }
  std::span<const x86::Instruction> insts() const { return {insts_.data(), n_}; }
  uint32_t offset(size_t back) const { return offs_[n_ - 1 - back]; }  // back 0: the newest

 private:
  std::array<x86::Instruction, kSpan> insts_{};
  std::array<uint32_t, kSpan> offs_{};
  size_t n_ = 0;
};

// The code as the check walks it.  A first pass decodes every instruction
// once and keeps only where each starts (OffsetBits, a bit per byte); the
// steps after it decode again where they look, forward or back.  So the check
// holds no record per instruction: its memory is a few bits per byte of code
// (docs/image-format.md, "What the loader allocates").
class Code {
 public:
  explicit Code(std::span<const uint8_t> bytes) : bytes_(bytes), starts_(bytes.size()) {}

  // Decodes the whole code, marking each start; the first error, if any.
  std::optional<x86::DecodeError> scan() {
    for (size_t pos = 0; pos < bytes_.size();) {
      x86::DecodeError err;
      std::optional<x86::Decoded> d = x86::decode(bytes_, pos, &err);
      if (!d) return err;
      starts_.add(uint32_t(pos));
      pos += d->length;
    }
    return std::nullopt;
  }
  uint32_t size() const { return uint32_t(bytes_.size()); }
  const OffsetBits& starts() const { return starts_; }
  OffsetBits take_starts() { return std::move(starts_); }
  // The instruction at `off`, an instruction start.
  x86::Decoded at(uint32_t off) const { return *x86::decode(bytes_, off); }
  // The start of the instruction `n` instructions before `off` (a start or the
  // end of the code), if it lies at or after `floor`.
  std::optional<uint32_t> back(uint32_t off, size_t n, uint32_t floor) const {
    for (; n > 0; n--) {
      int64_t b = starts_.before(off);
      if (b < int64_t(floor)) return std::nullopt;
      off = uint32_t(b);
    }
    return off;
  }
  // Do the instructions from `off` on equal seq (the long form of a branch
  // aside)?  `end`: where the instructions that may match stop.
  bool matches(uint32_t off, std::span<const x86::Instruction> seq, uint32_t end) const {
    for (const x86::Instruction& want : seq) {
      if (off >= end) return false;
      x86::Decoded d = at(off);
      d.inst.long_branch = false;
      if (!(d.inst == want)) return false;
      off += d.length;
    }
    return true;
  }
  // The offset after `n` instructions from `off` (at most the end).
  uint32_t skip(uint32_t off, size_t n) const {
    for (; n > 0 && off < size(); n--) off += at(off).length;
    return off;
  }

 private:
  std::span<const uint8_t> bytes_;
  OffsetBits starts_;
};

std::string at(uint64_t off) { return "at code offset " + hex(off) + ": "; }

std::string undecodable(std::span<const uint8_t> code, const x86::DecodeError& e) {
  std::string bytes;
  for (size_t i = e.offset; i < code.size() && i < size_t(e.offset) + 8; i++) {
    char buf[4];
    std::snprintf(buf, sizeof buf, "%s%02x", bytes.empty() ? "" : " ", code[i]);
    bytes += buf;
  }
  return at(e.offset) + "undecodable bytes " + bytes + (code.size() - e.offset > 8 ? " ..." : "") + " (" + e.message + ")";
}

// The general registers an instruction writes by its form's row (x86.h,
// Effects): the operands it marks written and the implicit writes, as a set of
// RegNum bits.  A call's callee is not in it (the caller adds what that writes).
uint16_t written_registers(const x86::Instruction& in, const x86::Effects& fx) {
  uint16_t w = fx.writes;
  for (unsigned i = 0; i < in.num_operands && i < in.ops.size(); i++) {
    const x86::Operand& o = in.ops[i];
    if (x86::writes_operand(fx.ops[i]) && o.kind == x86::OperandKind::Reg && o.reg.cls != x86::RegClass::Xmm &&
        o.reg.cls != x86::RegClass::Rip)
      w |= uint16_t(1u << o.reg.num);
  }
  return w;
}

// A register an instruction writes, named as the instruction names it: an
// operand in its width, an implicit write in 32 bits, a callee's in 64.
struct Written {
  x86::Reg reg;
  bool by_callee = false;
};
// Every general register an instruction writes, each once, in that order.
class Writes {
 public:
  // its operands and implicit writes by the form table, then, for a call,
  // what the callee may write (`callee`, bits)
  Writes(const x86::Instruction& in, const x86::Effects& fx, uint16_t callee) {
    for (unsigned i = 0; i < in.num_operands && i < in.ops.size(); i++) {
      const x86::Operand& o = in.ops[i];
      if (x86::writes_operand(fx.ops[i]) && o.kind == x86::OperandKind::Reg && o.reg.cls != x86::RegClass::Xmm &&
          o.reg.cls != x86::RegClass::Rip)
        add({o.reg});
    }
    for (unsigned r = 0; r < 16; r++)
      if (fx.writes >> r & 1) add({x86::r32(r)});
    for (unsigned r = 0; r < 16; r++)
      if (callee >> r & 1) add({x86::r64(r), true});
  }
  const Written* begin() const { return w_.data(); }
  const Written* end() const { return w_.data() + n_; }

 private:
  void add(Written w) {
    if (named_ >> w.reg.num & 1) return;
    named_ |= uint16_t(1u << w.reg.num);
    w_[n_++] = w;
  }
  std::array<Written, 16> w_{};
  size_t n_ = 0;
  uint16_t named_ = 0;
};

// What a call through the REAL function table may change: the caller-saved
// registers of System V.
uint16_t caller_saved_registers() {
  uint16_t w = 0;
  for (unsigned r = 0; r < 16; r++)
    if (x86::caller_saved(x86::RegNum(r))) w |= uint16_t(1u << r);
  return w;
}

// The parts of the code the check found, as offsets: [entry, body) the
// prologue (and the -O2 base registers' leas), [body, exit) the scan body,
// [exit, routines) the epilogue, [routines, end) the shared routines.
struct Frame {
  bool slots = false, o2 = false;
  int32_t bias = 0;  // where the image register points into the image
  x86::Reg img;      // the image register: nothing in the body writes it
  Bases bases;
  uint32_t entry = 0, body = 0, exit = 0, routines = 0;
  std::vector<uint32_t> routine_entries;  // ascending
  uint16_t routine_writes = 0;            // the registers the routines write (bit RegNum), from the form table
};

// The bodies as::x86::scan_routine makes for this layout and frame, each a
// routine the code may end with.
std::vector<std::vector<x86::Instruction>> routine_bodies(const Layout& layout, const Frame& f) {
  x86::RoutineAreas areas;
  areas.tw = int32_t(layout.addr(Area::TW, 0));
  areas.tq = int32_t(layout.addr(Area::TQ, 0));
  areas.ti = int32_t(layout.addr(Area::TI, 0));
  areas.cw = int32_t(layout.addr(Area::CW, 0));
  areas.cq = int32_t(layout.addr(Area::CQ, 0));
  areas.dt = int32_t(kSysDt);
  areas.e = int32_t(layout.addr(Area::E, 0));
  areas.e_count = int32_t(layout.count[int(Area::E)]);
  // the mask keeps numbers below 256: every area a routine indexes has 256 elements
  bool full = layout.count[int(Area::TW)] >= 256 && layout.count[int(Area::TQ)] >= 256 &&
              layout.count[int(Area::TI)] >= 256 && layout.count[int(Area::CW)] >= 256 &&
              layout.count[int(Area::CQ)] >= 256;
  std::vector<std::vector<x86::Instruction>> bodies;
  if (full)
    for (int r = 0; r < int(x86::Routine::Count); r++) {
      bool counter = x86::Routine(r) == x86::Routine::Ctu || x86::Routine(r) == x86::Routine::Ctd;
      if (counter && f.o2 && areas.e_count < 1) continue;  // its edge slots: none to keep an access inside
      bodies.push_back(x86::scan_routine(x86::Routine(r), areas, x86::RegNum(f.img.num), f.bias));
    }
  return bodies;
}

// The frame: the scan function starts with a canonical prologue at the entry
// and ends with the matching epilogue, then the shared routines; only they
// push, pop or return.  "" and `f` filled, or why not.
std::string find_frame(const Code& code, uint32_t entry, const Layout& layout, Frame& f) {
  const uint32_t end = code.size();
  f.entry = entry;
  // the -O2 frame (rbp the image, kImageBias bytes into it), the same with rbp
  // at the image's start (images made before the bias) or with rbx the image
  // (before bl was a slot), or the -O0 frame (rbx the image, ebp the stack)
  const bool biased = code.matches(entry, x86::scan_prologue(true), end);
  f.o2 = biased || code.matches(entry, x86::scan_prologue_unbiased(), end);  // rbp the image
  f.slots = f.o2 || code.matches(entry, x86::scan_prologue_rbx_slots(), end);
  f.bias = biased ? x86::kImageBias : 0;
  if (!f.slots && !code.matches(entry, x86::scan_prologue(false), end))
    return at(entry) + "the entry is not the scan function's prologue (push rbx; push rbp; ...; mov rbx, rdi, or lea rbp, [rdi+0x40] at -O2)";
  f.img = x86::r64(x86::image_reg(f.o2));
  f.body = code.skip(entry, x86::scan_prologue(f.slots).size());
  // The -O2 frame may then set its base registers (lea rdi, [img+K0]; lea
  // r15, [img+K1]; lea r14, [img+K2]), each K in range; without all, it is the
  // frame before compact addressing, whose body may not address memory through them.
  if (f.slots) {
    bool all = true;
    uint32_t off = f.body;
    for (int i = 0; i < x86::kNumBases && all; i++) {
      all = off < end && is_base_lea(code.at(off).inst, i, f.img);
      if (all) off += code.at(off).length;
    }
    if (all) {
      off = f.body;
      for (int i = 0; i < x86::kNumBases; i++) {
        const x86::Decoded l = code.at(off);
        if (std::string why = base_k_error(l.inst, i, layout.size, f.bias); !why.empty()) return at(l.offset) + text_of(l.inst) + ": " + why;
        off += l.length;
      }
      f.bases.set = true;
      f.body = off;
    }
  }
  const std::span<const x86::Instruction> epilogue = x86::scan_epilogue(f.slots);
  // After the epilogue: the shared timer/counter routines, each exactly one of
  // the bodies as::x86::scan_routine makes for this layout (branch-free, one
  // `ret`, the index masked by its first instruction), found from the end.
  uint32_t routines = end;
  const std::vector<std::vector<x86::Instruction>> bodies = routine_bodies(layout, f);
  for (bool found = true; found;) {
    found = false;
    for (const auto& b : bodies) {
      // room for the routine and the epilogue after the prologue
      if (!code.back(routines, b.size() + epilogue.size(), f.body)) continue;
      uint32_t from = *code.back(routines, b.size(), f.body);
      if (!code.matches(from, b, end)) continue;
      routines = from;
      f.routine_entries.push_back(from);
      for (const x86::Instruction& in : b) f.routine_writes |= written_registers(in, x86::effects(in));
      found = true;
      break;
    }
  }
  std::reverse(f.routine_entries.begin(), f.routine_entries.end());  // found from the end: make them ascending
  std::optional<uint32_t> exit = code.back(routines, epilogue.size(), f.body);
  if (!exit || !code.matches(*exit, epilogue, end))
    return at(uint64_t(code.starts().before(end))) + "the code does not end with the scan function's epilogue (pop ...; ret)";
  f.exit = *exit;
  f.routines = routines;
  if (f.entry > f.exit) return at(entry) + "the prologue is not before the epilogue";
  return "";
}

// The rules on the body's instructions: the stack, the registers it writes
// (by the form table: the image register and rsp never, the -O2 base
// registers only by their lea, r12-r15 only in the frame that saves them),
// the guarded division, calls and branches.  One instruction at a time, in
// order.
class BodyRules {
 public:
  BodyRules(const Code& code, const Layout& layout, const Frame& f, OffsetBits& guarded)
      : code_(code), layout_(layout), f_(f), guarded_(guarded), img_name_(x86::reg_name(f.img)) {}

  std::string check(const x86::Decoded& di) {
    const x86::Instruction& in = di.inst;
    if (di.offset < f_.entry) return at(di.offset) + text_of(in) + ": code before the scan function's entry";
    window_.push(di);
    auto here = [&] { return at(di.offset) + text_of(in) + ": "; };  // for a refusal only: it prints the instruction
    using S = x86::StackUse;
    if (di.effects.stack == S::Push || di.effects.stack == S::Pop || di.effects.stack == S::Ret)
      return here() + "the stack is touched only by the prologue and the epilogue";
    const Writes writes(in, di.effects, callee_writes(di));
    // img holds the image base and rsp the frame: no instruction of the body may change them
    for (const Written& w : writes)
      if (w.reg.num == f_.img.num || w.reg.num == x86::SP)
        return here() + (w.by_callee ? "calls code that writes " : "writes ") + std::string(x86::reg_name(w.reg)) +
               " (the image base and the stack pointer are fixed in the scan body)";
    // the base registers of the -O2 body: only `lea reg, [img+K]` with K in range may set one
    if (f_.bases.set)
      for (const Written& w : writes) {
        int b = Bases::which(x86::r64(w.reg.num));
        if (b < 0 || w.by_callee) continue;  // a callee's writes: the reload after the call, below
        std::string reg(x86::reg_name(x86::r64(x86::kBaseRegs[b])));
        if (!is_base_lea(in, b, f_.img))
          return here() + "writes " + std::string(x86::reg_name(w.reg)) + ", a base register of the -O2 frame (only 'lea " + reg +
                 ", [" + img_name_ + "+K]' may set one)";
        if (std::string why = base_k_error(in, b, layout_.size, f_.bias); !why.empty()) return here() + why;
      }
    if (std::string why = reload_after_call(di, writes); !why.empty()) return why;
    // r12-r15 belong to the caller (System V) unless the frame saved them
    if (!f_.slots)
      for (const Written& w : writes)
        if (w.reg.num >= x86::R12)
          return here() + (w.by_callee ? "calls code that writes " : "writes ") + std::string(x86::reg_name(w.reg)) +
                 ", which the caller owns: only the -O2 frame saves r12-r15";
    using M = x86::Mnemonic;
    if (in.mnemonic == M::Idiv || in.mnemonic == M::Div) {
      const Seq* seq = guarded_division(window_.insts());
      if (!seq)
        return here() +
               "a division not guarded against 0 and -1 (only 'test ecx, ecx; je; cmp ecx, -1; je; cdq; idiv ecx', "
               "'lea edx, [rcx+1]; cmp edx, 1; mov edx, 1; cmovbe ecx, edx; cdq; idiv ecx', the same with rcx and cqo, "
               "or 'test ecx, ecx; je; xor edx, edx; div ecx' and the same with rcx)";
      for (size_t back = 0; back + 1 < seq->size(); back++) guarded_.add(window_.offset(back));
    }
    if (std::string why = indexed(di); !why.empty()) return here() + why;
    if (in.mnemonic == M::Call && in.num_operands && in.ops[0].kind == x86::OperandKind::Address &&
        !std::binary_search(f_.routine_entries.begin(), f_.routine_entries.end(), uint32_t(in.ops[0].imm)))
      return here() +
             "a direct call not to the entry of one of the code's routines (generated code calls only those and "
             "the REAL function table)";
    if (std::string why = loop_counter_write(di); !why.empty()) return here() + why;
    // branches go forward, inside the body or to the epilogue, so a scan always
    // ends; the one backward branch is a loop's counted back edge (back_edge)
    if ((in.mnemonic == M::Jmp || in.mnemonic == M::Jcc) && in.num_operands && in.ops[0].kind == x86::OperandKind::Address) {
      int64_t t = in.ops[0].imm;
      if (t <= int64_t(di.offset))
        if (std::string why = back_edge(di, t); !why.empty()) return here() + why;
      if (t < int64_t(f_.body) || t > int64_t(f_.exit)) return here() + "branch target " + hex(uint64_t(t)) + " outside the scan body";
    }
    return "";
  }

 private:
  // The loop counter, Sys kSysLoops (docs/image-format.md, "Loops"): inside a
  // loop (from a back edge's target to the back edge) the only writes of its
  // bytes are `add dword [img+kSysLoops], n` with n >= 1; any other write (the
  // reset `mov dword [img+kSysLoops], 0` before the loops, or anything else)
  // is recorded and refused there by back_edge.
  bool counter_mem(const x86::Mem& m) const {
    return m.base == f_.img && !m.index.valid() && int64_t(m.disp) + f_.bias == int64_t(kSysLoops) && m.size == x86::Size::Dword;
  }
  std::string loop_counter_write(const x86::Decoded& di) {
    const x86::Instruction& in = di.inst;
    for (unsigned i = 0; i < in.num_operands && i < in.ops.size(); i++) {
      const x86::Operand& o = in.ops[i];
      if (o.kind != x86::OperandKind::Mem || (di.effects.ops[i] != x86::Use::W && di.effects.ops[i] != x86::Use::RW)) continue;
      const x86::Mem& m = o.mem;
      if (m.base != f_.img) continue;  // a base register's write: no loop in the -O2 frame (back_edge)
      int64_t first = int64_t(m.disp) + f_.bias, end = first + width(m.size);
      if (m.index.valid()) continue;   // an indexed access: its extent is checked against the counter in indexed()
      if (end <= int64_t(kSysLoops) || first >= int64_t(kSysLoops) + 4) continue;
      const bool imm = in.num_operands == 2 && in.ops[1].kind == x86::OperandKind::Imm;
      if (counter_mem(m) && in.mnemonic == x86::Mnemonic::Add && imm && in.ops[1].imm >= 1) return "";
      return lowers_counter(di.offset);
    }
    return "";
  }
  // A write that may lower the loop counter (its reset, or any other write of
  // its bytes): none may lie inside a loop (back_edge).
  std::string lowers_counter(uint32_t at) {
    if (resets_.size() >= kMaxResets) return "more than " + std::to_string(kMaxResets) + " writes of the loop counter";
    resets_.push_back(at);
    return "";
  }
  // A backward branch: `add dword [img+kSysLoops], 1; cmp dword [img+kSysLoops],
  // B; jae <forward>; jmp <back>` with 1 <= B <= kLoopBudget, no branch landing
  // on the cmp, the jae or the jmp (guarded), and no reset of the counter in
  // the loop it closes: every back edge of a scan counts, and at most
  // kLoopBudget - 1 of them are taken between resets.
  std::string back_edge(const x86::Decoded& di, int64_t target) {
    using M = x86::Mnemonic;
    const std::string want = "backward branch: only a loop's counted back edge goes back ('add dword [" + img_name_ + "+" +
                             std::to_string(kSysLoops) + "], 1; cmp dword [" + img_name_ + "+" + std::to_string(kSysLoops) +
                             "], B; jae; jmp', docs/image-format.md)";
    if (di.inst.mnemonic != M::Jmp || f_.bases.set) return want;
    const std::span<const x86::Instruction> w = window_.insts();
    if (w.size() < 4) return want;
    const x86::Instruction &add = w[w.size() - 4], &cmp = w[w.size() - 3], &jae = w[w.size() - 2];
    auto on_counter = [&](const x86::Instruction& i) {
      return i.num_operands == 2 && i.ops[0].kind == x86::OperandKind::Mem && counter_mem(i.ops[0].mem) &&
             i.ops[1].kind == x86::OperandKind::Imm;
    };
    const bool shape = add.mnemonic == M::Add && on_counter(add) && add.ops[1].imm == 1 && cmp.mnemonic == M::Cmp &&
                       on_counter(cmp) && cmp.ops[1].imm >= 1 && cmp.ops[1].imm <= int64_t(kLoopBudget) &&
                       jae.mnemonic == M::Jcc && jae.cond == x86::Cond::AE && jae.num_operands &&
                       jae.ops[0].kind == x86::OperandKind::Address && jae.ops[0].imm > int64_t(window_.offset(1));
    if (!shape) return want;
    for (uint32_t r : resets_)
      if (int64_t(r) >= target && r <= di.offset) return "a write of the loop counter at " + hex(r) + " inside the loop it closes";
    for (size_t back = 0; back < 3; back++) guarded_.add(window_.offset(back));  // the cmp, the jae, the jmp
    return "";
  }
  static bool writes_mem(const x86::Decoded& di) {
    for (unsigned i = 0; i < di.inst.num_operands && i < di.inst.ops.size(); i++)
      if (di.inst.ops[i].kind == x86::OperandKind::Mem && (di.effects.ops[i] == x86::Use::W || di.effects.ops[i] == x86::Use::RW))
        return true;
    return false;
  }
  static constexpr size_t kMaxResets = 64;
  std::vector<uint32_t> resets_;  // offsets of the loop counter's resets so far

  // What the callee of a call may write: a direct call goes to one of the
  // routines (or is refused below), which write what their bodies' forms write;
  // a call through memory goes to a REAL function (or is refused with its
  // operand), which may change every caller-saved register; a call through a
  // register is refused with its operand.
  uint16_t callee_writes(const x86::Decoded& di) const {
    if (di.effects.stack != x86::StackUse::Call || !di.inst.num_operands) return 0;
    if (di.inst.ops[0].kind == x86::OperandKind::Address) return f_.routine_writes;
    static const uint16_t abi = caller_saved_registers();
    return di.inst.ops[0].kind == x86::OperandKind::Mem ? abi : 0;
  }

  // An indexed memory operand [img + r*s + disp] (an LDX or STX of the typed
  // instructions) comes right after its bounds check `cmp r, n; ja` on the
  // same 64-bit register r, with n >= 0 and every byte of [img + disp,
  // img + disp + n*s + width) inside the image; no branch may land on the
  // ja or the access (they join the guarded offsets), so the check is never
  // skipped.  r is then in [0, n] unsigned, whatever the code before did.
  std::string indexed(const x86::Decoded& di) {
    const x86::Instruction& in = di.inst;
    using M = x86::Mnemonic;
    if (in.mnemonic == M::Call || in.mnemonic == M::Jmp) return "";  // no indexed branch: refused with its operand
    const x86::Mem* m = nullptr;
    for (unsigned i = 0; i < in.num_operands && i < in.ops.size(); i++)
      if (in.ops[i].kind == x86::OperandKind::Mem && in.ops[i].mem.index.valid() && di.effects.ops[i] != x86::Use::Addr)
        m = &in.ops[i].mem;
    if (!m) return "";
    const std::span<const x86::Instruction> w = window_.insts();
    const std::string r(x86::reg_name(m->index));
    const std::string want = "indexed memory operand without its bounds check right before it ('cmp " + r +
                             ", n; ja' with n >= 0, docs/image-format.md)";
    if (m->base != f_.img) return "indexed memory operand based on " + std::string(x86::reg_name(m->base)) + ", not " + img_name_;
    if (w.size() < 3) return want;
    const x86::Instruction &cmp = w[w.size() - 3], &ja = w[w.size() - 2];
    const bool check = cmp.mnemonic == x86::Mnemonic::Cmp && cmp.num_operands == 2 && cmp.ops[0].kind == x86::OperandKind::Reg &&
                       cmp.ops[0].reg == m->index && cmp.ops[1].kind == x86::OperandKind::Imm && cmp.ops[1].imm >= 0 &&
                       ja.mnemonic == x86::Mnemonic::Jcc && ja.cond == x86::Cond::A;
    if (!check) return want;
    const int64_t first = int64_t(m->disp) + f_.bias, last = first + cmp.ops[1].imm * m->scale + width(m->size);
    if (first < 0 || last > int64_t(layout_.size))
      return "indexed memory operand: its bounds check lets it reach image offsets [" + std::to_string(first) + ", " +
             std::to_string(last) + "), outside the memory image [0, " + hex(layout_.size) + ")";
    if (first < int64_t(kSysLoops) + 4 && last > int64_t(kSysLoops) && writes_mem(di))
      if (std::string why = lowers_counter(di.offset); !why.empty()) return why;
    guarded_.add(window_.offset(1));  // the ja
    guarded_.add(window_.offset(0));  // the access
    return "";
  }

  // A callee may change a base register: the leas resetting each one it may
  // write (kBaseRegs order) follow the call at once.
  std::string reload_after_call(const x86::Decoded& di, const Writes& writes) const {
    if (!f_.bases.set) return "";
    uint32_t next = di.offset + di.length;
    std::string want;
    const bool table = di.inst.num_operands && di.inst.ops[0].kind == x86::OperandKind::Mem;
    for (int b = 0; b < x86::kNumBases; b++) {
      bool clobbered = std::any_of(writes.begin(), writes.end(),
                                   [&](const Written& w) { return w.by_callee && w.reg.num == x86::kBaseRegs[b]; });
      if (!clobbered) continue;
      std::string reg(x86::reg_name(x86::r64(x86::kBaseRegs[b])));
      want += std::string(want.empty() ? "" : "; ") + "lea " + reg + ", [" + img_name_ + "+K]";
      if (next >= f_.exit || !is_base_lea(code_.at(next).inst, b, f_.img))
        return at(di.offset) + text_of(di.inst) + ": a call " + (table ? "through the REAL function table" : "to a routine") +
               " not followed at once by '" + want + "' (the call may change " + reg + ", a base register of the -O2 frame)";
      next += code_.at(next).length;
    }
    return "";
  }

  const Code& code_;
  const Layout& layout_;
  const Frame& f_;
  OffsetBits& guarded_;  // offsets inside guarded divisions: no branch may land there
  const std::string img_name_;
  Window window_;
};

// The rules on every operand of the code before the routines (the routines
// were matched whole): memory operands, indirect and direct branch targets.
// The one rule it cannot apply in order, that no branch lands inside a guarded
// division (known only once the division is seen), it leaves to the caller:
// every target it accepts is added to `targets`.
std::string check_operands(const x86::Decoded& di, uint32_t code_size, const OffsetBits& starts, const Frame& f,
                           const Layout& layout, OffsetBits& targets) {
  const x86::Instruction& in = di.inst;
  bool branch = in.mnemonic == x86::Mnemonic::Jmp || in.mnemonic == x86::Mnemonic::Jcc || in.mnemonic == x86::Mnemonic::Call;
  for (unsigned i = 0; i < in.num_operands && i < in.ops.size(); i++) {
    const x86::Operand& o = in.ops[i];
    if (o.kind == x86::OperandKind::Mem && di.effects.ops[i] == x86::Use::Addr) {
      continue;  // lea is arithmetic: it computes an address but touches no memory
    } else if (o.kind == x86::OperandKind::Mem) {
      if (in.mnemonic == x86::Mnemonic::Call) {
        // the one indirect branch: a call through the read-only table of REAL
        // functions below the image (ir.h, kCallTableDisp)
        const x86::Mem& m = o.mem;
        const int64_t off = int64_t(m.disp) + f.bias;  // from the image's start
        // (and the typed instructions' math table right below it, kMathTableDisp,
        // and the STRING routine's slot below that, kStrSlotDisp)
        bool table = m.base == f.img && !m.index.valid() && m.size == x86::Size::Qword && off >= kStrSlotDisp &&
                     off < kCallTableDisp + 8 * kCallSlots && (off - kStrSlotDisp) % 8 == 0;
        if (!table) return at(di.offset) + text_of(in) + ": indirect call not through the REAL function table";
        continue;
      }
      if (branch) return at(di.offset) + text_of(in) + ": indirect branch through memory";
      // an indexed operand in the body passed BodyRules::indexed (its bounds check) already
      const bool body = di.offset >= f.body && di.offset < f.exit;
      if (std::string why = check_mem(o.mem, layout.size, f.bases, f.img, f.bias, body); !why.empty())
        return at(di.offset) + text_of(in) + ": " + why;
    } else if (o.kind == x86::OperandKind::Reg && branch) {
      return at(di.offset) + text_of(in) + ": indirect branch through a register";
    } else if (o.kind == x86::OperandKind::Address) {
      int64_t t = o.imm;
      if (t < 0 || uint64_t(t) >= code_size)
        return at(di.offset) + text_of(in) + ": branch target " + (t < 0 ? "-" + hex(uint64_t(-(t + 1)) + 1) : hex(uint64_t(t))) +
               " outside the code (" + std::to_string(code_size) + " bytes)";
      if (!starts.has(uint64_t(t)))
        return at(di.offset) + text_of(in) + ": branch target " + hex(uint64_t(t)) +
               " is inside an instruction, not on an instruction boundary";
      targets.add(uint32_t(t));
    } else if (o.kind == x86::OperandKind::Label) {
      return at(di.offset) + text_of(in) + ": unresolved label operand";
    }
  }
  return "";
}

// The message for the first instruction before `stop` with a branch target
// inside a guarded division, or "".
std::string first_branch_into_guard(const Code& code, uint32_t stop, const OffsetBits& guarded) {
  for (uint32_t off = 0; off < stop;) {
    const x86::Decoded di = code.at(off);
    for (unsigned i = 0; i < di.inst.num_operands && i < di.inst.ops.size(); i++) {
      const x86::Operand& o = di.inst.ops[i];
      if (o.kind == x86::OperandKind::Address && o.imm >= 0 && guarded.has(uint64_t(o.imm)))
        return at(di.offset) + text_of(di.inst) + ": branch target " + hex(uint64_t(o.imm)) +
               " is inside a guarded division (past its test of the divisor) or an indexed access's bounds check";
    }
    off += di.length;
  }
  return "";
}

}  // namespace

// Two passes over the code, each decoding an instruction at a time: the first
// finds where instructions start, the second applies the rules.  The body's
// rules come before the operands' (a refusal names the first instruction that
// breaks one of the body's rules, else the first that breaks an operand's),
// as when each was a loop of its own.
std::string check_x86(std::span<const uint8_t> bytes, uint32_t entry, const Layout& layout, OffsetBits* starts_out) {
  Code code(bytes);
  if (std::optional<x86::DecodeError> e = code.scan()) return undecodable(bytes, *e);
  if (entry >= bytes.size())
    return "entry point " + hex(entry) + " is outside the code (" + std::to_string(bytes.size()) + " bytes)";
  if (!code.starts().has(entry)) return "entry point " + hex(entry) + " is inside an instruction, not on an instruction boundary";
  Frame f;
  if (std::string why = find_frame(code, entry, layout, f); !why.empty()) return why;

  OffsetBits guarded(bytes.size()), targets(bytes.size());
  BodyRules body(code, layout, f, guarded);
  std::string operand_error;  // the first instruction's that breaks an operand rule
  uint32_t operand_error_at = f.routines;
  for (uint32_t off = 0; off < f.routines;) {
    const x86::Decoded di = code.at(off);
    const bool prologue = off >= f.entry && off < f.body;
    if (!prologue && off < f.exit)
      if (std::string why = body.check(di); !why.empty()) return why;
    if (operand_error.empty())
      if (operand_error = check_operands(di, code.size(), code.starts(), f, layout, targets); !operand_error.empty())
        operand_error_at = off;
    off += di.length;
  }
  if (guarded.meets(targets))
    if (std::string why = first_branch_into_guard(code, operand_error_at, guarded); !why.empty()) return why;
  if (!operand_error.empty()) return operand_error;
  if (starts_out) *starts_out = code.take_starts();
  return "";
}

}  // namespace detail

std::string check_x86_code(std::span<const uint8_t> code, uint32_t entry, const Layout& layout) {
  return detail::check_x86(code, entry, layout, nullptr);
}

}  // namespace ldc
