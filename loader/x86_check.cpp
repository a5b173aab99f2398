// loader/x86_check.cpp -- the x86-64 code check of the loader: every byte
// decodes with our disassembler, every memory operand is [rbx+disp] (the -O2
// frame: [rbp+disp], or a base register's) inside the memory image, every
// direct branch lands on an instruction boundary inside the code and goes
// forward, and the only division is the guarded one (docs/image-format.md,
// "The x86-64 code check").
#include <algorithm>
#include <array>
#include <cstdio>

#include "assembler/x86.h"
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
// [-128, 127].
std::string check_mem(const x86::Mem& m, uint32_t image_size, const Bases& bases, x86::Reg img, int32_t bias) {
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

// The one form of division ldc emits (x86gen divmod): the divisor in ecx,
// tested for 0 and -1 (the two divisions that raise #DE) right before it.
const std::array<x86::Instruction, 6>& guarded_division() {
  using M = x86::Mnemonic;
  using O = x86::Operand;
  static const std::array<x86::Instruction, 6> seq = {
      x86::make(M::Test, {O::r(x86::r32(x86::CX)), O::r(x86::r32(x86::CX))}),
      x86::make_cc(M::Jcc, x86::Cond::E, {O::a(0)}),
      x86::make(M::Cmp, {O::r(x86::r32(x86::CX)), O::i(-1)}),
      x86::make_cc(M::Jcc, x86::Cond::E, {O::a(0)}),
      x86::make(M::Cdq),
      x86::make(M::Idiv, {O::r(x86::r32(x86::CX))})};
  return seq;
}

// The -O2 form (as::x86::safe_divisor): a divisor of 0 or -1 replaced by 1.
const std::array<x86::Instruction, 6>& safe_division() {
  using M = x86::Mnemonic;
  static const std::array<x86::Instruction, 6> seq = [] {
    std::array<x86::Instruction, 6> s;
    std::span<const x86::Instruction> guard = x86::safe_divisor();
    std::copy(guard.begin(), guard.end(), s.begin());
    s[4] = x86::make(M::Cdq);
    s[5] = x86::make(M::Idiv, {x86::Operand::r(x86::r32(x86::CX))});
    return s;
  }();
  return seq;
}

// Does insts[k] end the instructions of seq (branch displacements aside)?
bool ends_with(const std::vector<x86::Decoded>& insts, size_t k, size_t body_first,
               const std::array<x86::Instruction, 6>& seq) {
  if (k < body_first + seq.size() - 1) return false;
  for (size_t j = 0; j < seq.size(); j++) {
    x86::Instruction a = insts[k + 1 - seq.size() + j].inst;
    a.long_branch = false;
    if (a.mnemonic == x86::Mnemonic::Jcc && a.num_operands == 1 && a.ops[0].kind == x86::OperandKind::Address) a.ops[0].imm = 0;
    if (a.num_operands == 2 && a.ops[1].kind == x86::OperandKind::Imm) a.ops[1].imm = int32_t(a.ops[1].imm);  // decoded 0xffffffff
    if (!(a == seq[j])) return false;
  }
  return true;
}

// Is insts[k] an idiv that ends a whole guarded division, of either form
// (branch targets aside)?
bool is_guarded_division(const std::vector<x86::Decoded>& insts, size_t k, size_t body_first) {
  static_assert(std::tuple_size_v<std::remove_cvref_t<decltype(guarded_division())>> == 6);
  return ends_with(insts, k, body_first, guarded_division()) || ends_with(insts, k, body_first, safe_division());
}

}  // namespace

std::string check_x86(std::span<const uint8_t> code, uint32_t entry, const Layout& layout,
                      std::vector<uint32_t>* starts_out) {
  auto at = [](uint64_t off) { return "at code offset " + hex(off) + ": "; };
  x86::Disassembly d = x86::disassemble(code);
  if (d.error) {
    const x86::DecodeError& e = *d.error;
    std::string bytes;
    for (size_t i = e.offset; i < code.size() && i < size_t(e.offset) + 8; i++) {
      char buf[4];
      std::snprintf(buf, sizeof buf, "%s%02x", bytes.empty() ? "" : " ", code[i]);
      bytes += buf;
    }
    return at(e.offset) + "undecodable bytes " + bytes + (code.size() - e.offset > 8 ? " ..." : "") + " (" + e.message + ")";
  }
  std::vector<uint32_t> starts;
  starts.reserve(d.insts.size());
  for (const x86::Decoded& di : d.insts) starts.push_back(di.offset);

  if (entry >= code.size())
    return "entry point " + hex(entry) + " is outside the code (" + std::to_string(code.size()) + " bytes)";
  if (!std::binary_search(starts.begin(), starts.end(), entry))
    return "entry point " + hex(entry) + " is inside an instruction, not on an instruction boundary";

  // The frame: the scan function starts with a canonical prologue at the entry
  // and ends with the matching epilogue; only they push, pop or return.
  size_t first = size_t(std::lower_bound(starts.begin(), starts.end(), entry) - starts.begin());
  auto matches = [&](size_t at, std::span<const x86::Instruction> seq) {
    if (at + seq.size() > d.insts.size()) return false;
    for (size_t k = 0; k < seq.size(); k++) {
      x86::Instruction a = d.insts[at + k].inst;
      a.long_branch = false;
      if (!(a == seq[k])) return false;
    }
    return true;
  };
  // the -O2 frame (rbp the image, kImageBias bytes into it), the same with rbp
  // at the image's start (images made before the bias) or with rbx the image
  // (before bl was a slot), or the -O0 frame (rbx the image, ebp the stack)
  const bool at_entry = first < d.insts.size() && d.insts[first].offset == entry;
  const bool biased = at_entry && matches(first, x86::scan_prologue(true));
  const bool o2 = biased || (at_entry && matches(first, x86::scan_prologue_unbiased()));  // rbp the image
  const bool slots = o2 || (at_entry && matches(first, x86::scan_prologue_rbx_slots()));
  const int32_t bias = biased ? x86::kImageBias : 0;  // where the image register points into the image
  if (!slots && !(at_entry && matches(first, x86::scan_prologue(false))))
    return at(entry) + "the entry is not the scan function's prologue (push rbx; push rbp; ...; mov rbx, rdi, or lea rbp, [rdi+0x40] at -O2)";
  const x86::Reg img = x86::r64(x86::image_reg(o2));  // the image register: nothing in the body writes it
  const std::string img_name(x86::reg_name(img));
  size_t body_first = first + x86::scan_prologue(slots).size();
  Bases bases;
  // The -O2 frame may then set its base registers (lea rdi, [img+K0]; lea
  // r15, [img+K1]; lea r14, [img+K2]), each K in range; without all, it is the
  // frame before compact addressing, whose body may not address memory through them.
  if (slots && body_first + x86::kNumBases <= d.insts.size()) {
    bool all = true;
    for (int i = 0; i < x86::kNumBases && all; i++) all = is_base_lea(d.insts[body_first + size_t(i)].inst, i, img);
    if (all) {
      for (int i = 0; i < x86::kNumBases; i++) {
        const x86::Decoded& l = d.insts[body_first + size_t(i)];
        if (std::string why = base_k_error(l.inst, i, layout.size, bias); !why.empty()) return at(l.offset) + text_of(l.inst) + ": " + why;
      }
      bases.set = true;
      body_first += x86::kNumBases;
    }
  }
  size_t epi = x86::scan_epilogue(slots).size();
  // After the epilogue: the shared timer/counter routines, each exactly one of
  // the bodies as::x86::scan_routine makes for this layout (branch-free, one
  // `ret`, the index masked by its first instruction), found from the end.
  std::vector<uint32_t> routine_entries;
  size_t code_end = d.insts.size();
  {
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
        if (counter && o2 && areas.e_count < 1) continue;  // its edge slots: none to keep an access inside
        bodies.push_back(x86::scan_routine(x86::Routine(r), areas, x86::RegNum(img.num), bias));
      }
    for (bool found = true; found;) {
      found = false;
      for (const auto& b : bodies) {
        if (code_end < b.size() + body_first + epi || !matches(code_end - b.size(), b)) continue;
        code_end -= b.size();
        routine_entries.push_back(d.insts[code_end].offset);
        found = true;
        break;
      }
    }
    std::sort(routine_entries.begin(), routine_entries.end());
  }
  if (code_end < body_first + epi || !matches(code_end - epi, x86::scan_epilogue(slots)))
    return at(d.insts.empty() ? 0 : d.insts.back().offset) + "the code does not end with the scan function's epilogue (pop ...; ret)";
  size_t body_end = code_end - epi;
  if (first > body_end) return at(entry) + "the prologue is not before the epilogue";
  uint32_t body_lo = body_first < d.insts.size() ? d.insts[body_first].offset : uint32_t(code.size());
  uint32_t exit_at = d.insts[body_end].offset;
  std::vector<uint32_t> guarded;  // offsets inside guarded divisions: no branch may land there
  for (size_t k = 0; k < d.insts.size(); k++) {
    if (k >= first && k < body_first) continue;  // the prologue
    if (k >= body_end) break;                    // the epilogue
    const x86::Decoded& di = d.insts[k];
    const x86::Instruction& in = di.inst;
    if (k < first) return at(di.offset) + text_of(in) + ": code before the scan function's entry";
    using M = x86::Mnemonic;
    if (in.mnemonic == M::Push || in.mnemonic == M::Pop || in.mnemonic == M::Ret)
      return at(di.offset) + text_of(in) + ": the stack is touched only by the prologue and the epilogue";
    // img holds the image base and rsp the frame: no instruction of the body may change them
    bool writes_first = in.num_operands > 0 && in.mnemonic != M::Cmp && in.mnemonic != M::Test &&
                        in.mnemonic != M::Ucomiss && in.mnemonic != M::Jmp && in.mnemonic != M::Jcc &&
                        in.mnemonic != M::Call;
    if (writes_first && in.ops[0].kind == x86::OperandKind::Reg && in.ops[0].reg.cls != x86::RegClass::Xmm &&
        (in.ops[0].reg.num == img.num || in.ops[0].reg.num == x86::SP))
      return at(di.offset) + text_of(in) + ": writes " + std::string(x86::reg_name(in.ops[0].reg)) +
             " (the image base and the stack pointer are fixed in the scan body)";
    // the base registers of the -O2 body: only `lea reg, [img+K]` with K in range may set one
    if (bases.set && writes_first && in.ops[0].kind == x86::OperandKind::Reg && in.ops[0].reg.cls != x86::RegClass::Xmm) {
      for (int b = 0; b < x86::kNumBases; b++) {
        if (in.ops[0].reg.num != x86::kBaseRegs[b]) continue;
        std::string reg(x86::reg_name(x86::r64(x86::kBaseRegs[b])));
        if (!is_base_lea(in, b, img))
          return at(di.offset) + text_of(in) + ": writes " + std::string(x86::reg_name(in.ops[0].reg)) +
                 ", a base register of the -O2 frame (only 'lea " + reg + ", [" + img_name + "+K]' may set one)";
        if (std::string why = base_k_error(in, b, layout.size, bias); !why.empty()) return at(di.offset) + text_of(in) + ": " + why;
      }
    }
    // a call through the REAL function table may change the caller-saved base
    // registers: the leas resetting each of them (kBaseRegs order) follow it at once
    if (bases.set && in.mnemonic == M::Call && in.num_operands && in.ops[0].kind == x86::OperandKind::Mem) {
      size_t j = k + 1;
      std::string want;
      for (int b = 0; b < x86::kNumBases; b++) {
        if (!x86::caller_saved(x86::kBaseRegs[b])) continue;
        std::string reg(x86::reg_name(x86::r64(x86::kBaseRegs[b])));
        want += std::string(want.empty() ? "" : "; ") + "lea " + reg + ", [" + img_name + "+K]";
        if (j >= body_end || !is_base_lea(d.insts[j].inst, b, img))
          return at(di.offset) + text_of(in) + ": a call through the REAL function table not followed at once by '" + want +
                 "' (the call may change " + reg + ", a base register of the -O2 frame)";
        j++;
      }
    }
    // r12-r15 belong to the caller (System V) unless the frame saved them
    if (writes_first && !slots && in.ops[0].kind == x86::OperandKind::Reg && in.ops[0].reg.cls != x86::RegClass::Xmm &&
        in.ops[0].reg.num >= x86::R12)
      return at(di.offset) + text_of(in) + ": writes " + std::string(x86::reg_name(in.ops[0].reg)) +
             ", which the caller owns: only the -O2 frame saves r12-r15";
    if (in.mnemonic == M::Idiv) {
      if (!is_guarded_division(d.insts, k, body_first))
        return at(di.offset) + text_of(in) +
               ": a division not guarded against 0 and -1 (only 'test ecx, ecx; je; cmp ecx, -1; je; cdq; idiv ecx' or "
               "'lea edx, [rcx+1]; cmp edx, 1; mov edx, 1; cmovbe ecx, edx; cdq; idiv ecx')";
      for (size_t j = k + 2 - guarded_division().size(); j <= k; j++) guarded.push_back(d.insts[j].offset);
    }
    if (in.mnemonic == M::Call && in.num_operands && in.ops[0].kind == x86::OperandKind::Address &&
        !std::binary_search(routine_entries.begin(), routine_entries.end(), uint32_t(in.ops[0].imm)))
      return at(di.offset) + text_of(in) +
             ": a direct call not to the entry of one of the code's routines (generated code calls only those and "
             "the REAL function table)";
    // branches go forward, inside the body or to the epilogue, so a scan always ends
    if ((in.mnemonic == M::Jmp || in.mnemonic == M::Jcc) && in.num_operands && in.ops[0].kind == x86::OperandKind::Address) {
      int64_t t = in.ops[0].imm;
      if (t <= int64_t(di.offset)) return at(di.offset) + text_of(in) + ": backward branch (a scan runs straight through)";
      if (t < int64_t(body_lo) || t > int64_t(exit_at))
        return at(di.offset) + text_of(in) + ": branch target " + hex(uint64_t(t)) + " outside the scan body";
    }
  }

  for (size_t k = 0; k < code_end; k++) {  // the routines were matched whole
    const x86::Decoded& di = d.insts[k];
    const x86::Instruction& in = di.inst;
    bool branch = in.mnemonic == x86::Mnemonic::Jmp || in.mnemonic == x86::Mnemonic::Jcc || in.mnemonic == x86::Mnemonic::Call;
    for (unsigned i = 0; i < in.num_operands && i < in.ops.size(); i++) {
      const x86::Operand& o = in.ops[i];
      if (o.kind == x86::OperandKind::Mem && in.mnemonic == x86::Mnemonic::Lea) {
        continue;  // lea is arithmetic: it computes an address but touches no memory
      } else if (o.kind == x86::OperandKind::Mem) {
        if (in.mnemonic == x86::Mnemonic::Call) {
          // the one indirect branch: a call through the read-only table of REAL
          // functions below the image (ir.h, kCallTableDisp)
          const x86::Mem& m = o.mem;
          const int64_t off = int64_t(m.disp) + bias;  // from the image's start
          bool table = m.base == img && !m.index.valid() && m.size == x86::Size::Qword && off >= kCallTableDisp &&
                       off < kCallTableDisp + 8 * kCallSlots && (off - kCallTableDisp) % 8 == 0;
          if (!table) return at(di.offset) + text_of(in) + ": indirect call not through the REAL function table";
          continue;
        }
        if (branch) return at(di.offset) + text_of(in) + ": indirect branch through memory";
        if (std::string why = check_mem(o.mem, layout.size, bases, img, bias); !why.empty()) return at(di.offset) + text_of(in) + ": " + why;
      } else if (o.kind == x86::OperandKind::Reg && branch) {
        return at(di.offset) + text_of(in) + ": indirect branch through a register";
      } else if (o.kind == x86::OperandKind::Address) {
        int64_t t = o.imm;
        if (t < 0 || uint64_t(t) >= code.size())
          return at(di.offset) + text_of(in) + ": branch target " + (t < 0 ? "-" + hex(uint64_t(-(t + 1)) + 1) : hex(uint64_t(t))) +
                 " outside the code (" + std::to_string(code.size()) + " bytes)";
        if (!std::binary_search(starts.begin(), starts.end(), uint32_t(t)))
          return at(di.offset) + text_of(in) + ": branch target " + hex(uint64_t(t)) +
                 " is inside an instruction, not on an instruction boundary";
        if (std::binary_search(guarded.begin(), guarded.end(), uint32_t(t)))
          return at(di.offset) + text_of(in) + ": branch target " + hex(uint64_t(t)) +
                 " is inside a guarded division (past its test of the divisor)";
      } else if (o.kind == x86::OperandKind::Label) {
        return at(di.offset) + text_of(in) + ": unresolved label operand";
      }
    }
  }
  if (entry >= code.size())
    return "entry point " + hex(entry) + " is outside the code (" + std::to_string(code.size()) + " bytes)";
  if (!std::binary_search(starts.begin(), starts.end(), entry))
    return "entry point " + hex(entry) + " is inside an instruction, not on an instruction boundary";
  if (starts_out) *starts_out = std::move(starts);
  return "";
}

}  // namespace detail

std::string check_x86_code(std::span<const uint8_t> code, uint32_t entry, const Layout& layout) {
  return detail::check_x86(code, entry, layout, nullptr);
}

}  // namespace ldc
