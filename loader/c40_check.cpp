// loader/c40_check.cpp -- the C40 code check (c40_check.h).
//
// Two passes over the words, both decoding as they go, so that the check
// keeps about two bytes and one bit per word whatever the code holds:
//  1. each word alone: it decodes, its operands are ones the check can
//     follow, its targets are instructions of the code, its delay slots are
//     well formed;
//  2. a flow analysis from the entry that follows, per word, the data page
//     (DP) and the words pushed on the stack since the routine's return
//     address, so that every RETS returns to a return address that a CALL
//     (or the runtime) pushed and every direct operand addresses the memory
//     image.
// Words the flow never reaches are never executed, so pass 2 judges them
// not at all; pass 1 judges every word.
#include "loader/c40_check.h"

#include <bit>
#include <cstdio>
#include <vector>

#include "assembler/c40.h"
#include "loader/c40_map.h"

namespace ldc {
namespace {

using namespace as::c40;

std::string hex(uint64_t v) {
  char b[24];
  std::snprintf(b, sizeof b, "0x%llx", (unsigned long long)v);
  return b;
}

// A refusal: the word and the reason (check_c40_code formats it).
struct Refusal {
  uint32_t word;
  std::string why;
};

// The words pass 2 still has to visit, lowest first: one bit per word and a
// summary bit per 64 and per 4096 words, so the set costs n/8 bytes (a plain
// work list could hold n 4-byte entries).
class PendingWords {
 public:
  explicit PendingWords(uint32_t n) : l0_((n + 63) / 64), l1_((l0_.size() + 63) / 64), l2_((l1_.size() + 63) / 64) {}
  void add(uint32_t i) {
    l0_[i / 64] |= uint64_t(1) << (i % 64);
    l1_[i / 4096] |= uint64_t(1) << (i / 64 % 64);
    l2_[i / 262144] |= uint64_t(1) << (i / 4096 % 64);
  }
  // The lowest pending word, removed from the set; false if none is left.
  bool take(uint32_t& i) {
    size_t a = 0;
    while (a < l2_.size() && !l2_[a]) a++;
    if (a == l2_.size()) return false;
    size_t b = a * 64 + size_t(std::countr_zero(l2_[a]));
    size_t c = b * 64 + size_t(std::countr_zero(l1_[b]));
    i = uint32_t(c * 64 + size_t(std::countr_zero(l0_[c])));
    if (!(l0_[c] &= l0_[c] - 1)) {
      if (!(l1_[b] &= l1_[b] - 1)) l2_[a] &= l2_[a] - 1;
    }
    return true;
  }

 private:
  std::vector<uint64_t> l0_, l1_, l2_;
};

// The data page classes of the flow analysis, one byte per word.
constexpr uint8_t kDpUnseen = 0;   // the word is not reached (yet)
constexpr uint8_t kDpUnknown = 1;  // DP not set by LDPK on some path
constexpr uint8_t kDpOutside = 2;  // set by LDPK to a page no word of the memory image is in
constexpr uint8_t kDpFirstPage = 3;  // kDpFirstPage + k: page kDataPage + k

// The stack byte of a word: the words pushed since the return address of
// the routine it runs in (generated code pushes one at a time and pops it
// right away), and whether it runs in a routine that a CALL entered.
constexpr uint8_t kDepthMask = 0x3F;
constexpr uint8_t kCalled = 0x80;
constexpr unsigned kMaxDepth = 32;

bool names_reg(const Instruction& in, Reg r) {
  for (unsigned k = 0; k < in.num_operands; k++)
    if (in.ops[k].kind == OperandKind::Reg && in.ops[k].reg == r) return true;
  return false;
}

// LDPK, or DP in any operand: generated code never names DP, so the check
// need not tell a read of it from a write and takes either as a write.
bool writes_dp(const Instruction& in) { return in.mnemonic == Mnemonic::Ldpk || names_reg(in, Reg::DP); }

bool is_call(Mnemonic m) { return m == Mnemonic::Call || m == Mnemonic::Callc; }

bool is_rom_entry(int64_t t) {
  for (int f = 0; f < c40map::kRomFnCount; f++)
    if (t == int64_t(c40map::rom_entry(c40map::RomFn(f)))) return true;
  return false;
}

// The operand that holds a control instruction's target, or nullptr (RETS).
const as::c40::Operand* target_operand(const Instruction& in) {
  switch (in.mnemonic) {
    case Mnemonic::Br: case Mnemonic::Brd: case Mnemonic::Call: case Mnemonic::Bc: case Mnemonic::Bcd:
    case Mnemonic::Callc:
      return &in.ops[0];
    case Mnemonic::Dbc: case Mnemonic::Dbcd: return &in.ops[1];
    default: return nullptr;
  }
}

// A delayed branch that transfers always (BRD, BUD, and no DBcondD: it counts).
bool always_taken(const Instruction& in) {
  return in.mnemonic == Mnemonic::Brd || (in.mnemonic == Mnemonic::Bcd && in.cond == Cond::U);
}

class C40Check {
 public:
  C40Check(std::span<const uint8_t> code, uint32_t entry, const Layout& layout)
      : code_(code), n_(uint32_t(code.size() / 4)), entry_(entry / 4), w_(c40map::C40Layout::of(layout)) {}

  void run() {
    if (n_ > c40map::kCodeMaxWords)
      throw Refusal{c40map::kCodeMaxWords, "the code has " + std::to_string(n_) + " words, the board's code memory holds " +
                                               std::to_string(c40map::kCodeMaxWords)};
    if (uint32_t pages = ((c40map::kDataBase + w_.words - 1) >> 16) - c40map::kDataPage + 1; pages > 0xFF - kDpFirstPage)
      throw Refusal{0, "the memory image spans " + std::to_string(pages) + " data pages, the check follows at most " +
                           std::to_string(0xFF - kDpFirstPage)};  // the loader's edge limit keeps it under 20
    interior_.assign(n_, false);
    for (uint32_t i = 0; i < n_; i++) word_alone(i);
    flow();
  }

 private:
  std::span<const uint8_t> code_;
  uint32_t n_, entry_;
  c40map::C40Layout w_;
  uint32_t last_delayed_ = UINT32_MAX;  // pass 1: the last delayed branch seen
  std::vector<uint8_t> dp_, stack_;     // pass 2: per word, before it runs
  std::vector<bool> interior_;          // words 2..8 of a checked indexed access (checked_access)

  uint32_t word(uint32_t i) const {
    const uint8_t* p = code_.data() + 4 * size_t(i);
    return uint32_t(p[0]) | uint32_t(p[1]) << 8 | uint32_t(p[2]) << 16 | uint32_t(p[3]) << 24;
  }
  std::optional<Instruction> decode(uint32_t i, DecodeError* e = nullptr) const { return decode_word(word(i), i, e); }
  static std::string quote(const Instruction& in) { return "'" + print(in) + "': "; }

  // The delayed branch whose slots hold word t, if any.
  std::optional<uint32_t> slot_of(uint32_t t) const {
    for (uint32_t s = 1; s <= 3 && s <= t; s++) {
      auto in = decode(t - s);
      if (in && is_delayed(in->mnemonic)) return t - s;
    }
    return std::nullopt;
  }

  // ---- pass 1: one word alone
  void word_alone(uint32_t i) {
    DecodeError e;
    std::optional<Instruction> d = decode(i, &e);
    if (!d) throw Refusal{i, "word " + hex(word(i)) + " does not decode: " + e.message};
    const Instruction& in = *d;
    if (in.mnemonic == Mnemonic::Word) throw Refusal{i, "word " + hex(word(i)) + " is data, not an instruction"};
    operands(i, in);
    if (is_control(in.mnemonic)) target(i, in);
    if (last_delayed_ != UINT32_MAX && i - last_delayed_ <= 3 && is_control(in.mnemonic))
      throw Refusal{i, quote(in) + "in the delay slot of the delayed branch at word " + hex(last_delayed_)};
    if (is_delayed(in.mnemonic)) {
      if (n_ - i <= 3) throw Refusal{i, quote(in) + "its delay slots run past the end of the code"};
      last_delayed_ = i;
    }
  }

  void operands(uint32_t i, const Instruction& in) {
    for (unsigned k = 0; k < in.num_operands; k++) {
      const as::c40::Operand& o = in.ops[k];
      if (o.kind == OperandKind::Ind && in.mnemonic != Mnemonic::Nop) {
        checked_access(i, in);
        continue;
      }
      if (o.kind == OperandKind::Ind)
        throw Refusal{i, quote(in) + (in.mnemonic == Mnemonic::Nop ? "NOP with an address update"
                                                                    : "indirect memory operand (its address cannot be checked)")};
      if (o.kind != OperandKind::Reg) continue;
      if (o.reg == Reg::SP)
        throw Refusal{i, quote(in) + "names the stack pointer (only PUSH, POP, CALL and RETS may move it)"};
      if (is_control(in.mnemonic) && in.mnemonic != Mnemonic::Dbc && in.mnemonic != Mnemonic::Dbcd)
        throw Refusal{i, quote(in) + "branch or call through a register"};
    }
  }

  // The one indirect operand the check accepts: the code generator's checked
  // indexed access (the typed LDX / STX, docs/c40.md "Typed instructions"),
  // the eight words in a row
  //   LDHI limit_hi, R1; OR limit_lo, R1; CMPI R1, R0; LDIHI R1, R0
  //   LDHI base_hi, AR0; OR base_lo, AR0; ADDI R0, AR0; LDI *AR0, Rn | STI Rn, *AR0
  // in which R0 is clamped (unsigned) to limit before it is added to base, so
  // the access is inside base..base + limit, which must lie in the memory
  // image; and no path enters words 2..8 but from the word before (reach).
  void checked_access(uint32_t i, const Instruction& in) {
    auto refuse = [&](const std::string& why) {
      throw Refusal{i, quote(in) + "indirect memory operand (its address cannot be checked): " + why};
    };
    const bool load = in.mnemonic == Mnemonic::Ldi && in.num_operands == 2 && in.ops[0].kind == OperandKind::Ind &&
                      in.ops[1].kind == OperandKind::Reg;
    const bool store = in.mnemonic == Mnemonic::Sti && in.num_operands == 2 && in.ops[1].kind == OperandKind::Ind;
    if (!load && !store) refuse("only LDI *AR0, Rn and STI Rn, *AR0 may address the image indirectly");
    const Ind& ind = in.ops[load ? 0 : 1].ind;
    if (!(ind == as::c40::parse("LDI *AR0, R0").ops[0].ind)) refuse("only *AR0 without an update");
    if (i < 7) refuse("not preceded by its bounds check");
    uint32_t imm[4];
    const Reg regs[4] = {Reg::R1, Reg::R1, ar(0), ar(0)};
    const uint32_t at[4] = {i - 7, i - 6, i - 3, i - 2};
    for (int k = 0; k < 4; k++) {
      auto w = decode(at[k]);
      Mnemonic m = k % 2 == 0 ? Mnemonic::Ldhi : Mnemonic::Or;
      if (!w || w->mnemonic != m || w->num_operands != 2 || w->ops[0].kind != OperandKind::Imm ||
          w->ops[1].kind != OperandKind::Reg || w->ops[1].reg != regs[k])
        refuse("not preceded by its bounds check (word " + hex(at[k]) + ")");
      imm[k] = uint32_t(w->ops[0].imm) & 0xFFFF;
    }
    const Instruction fixed[3] = {make(Mnemonic::Cmpi, {as::c40::Operand::r(Reg::R1), as::c40::Operand::r(Reg::R0)}),
                                  make_cc(Mnemonic::Ldic, Cond::HI, {as::c40::Operand::r(Reg::R1), as::c40::Operand::r(Reg::R0)}),
                                  make(Mnemonic::Addi, {as::c40::Operand::r(Reg::R0), as::c40::Operand::r(ar(0))})};
    const uint32_t fixed_at[3] = {i - 5, i - 4, i - 1};
    for (int k = 0; k < 3; k++)
      if (word(fixed_at[k]) != encode_word(fixed[k]))
        refuse("not preceded by its bounds check (word " + hex(fixed_at[k]) + ")");
    uint64_t limit = uint64_t(imm[0]) << 16 | imm[1], base = uint64_t(imm[2]) << 16 | imm[3];
    if (base < c40map::kDataBase || base + limit >= uint64_t(c40map::kDataBase) + w_.words)
      refuse("its range " + hex(base) + ".." + hex(base + limit) + " is not inside the memory image " + image_range());
    for (uint32_t k = i - 6; k <= i; k++) interior_[k] = true;
  }
  static uint32_t encode_word(const Instruction& x) {
    auto e = as::c40::encode(x);
    return uint32_t(e.bytes[0]) | uint32_t(e.bytes[1]) << 8 | uint32_t(e.bytes[2]) << 16 | uint32_t(e.bytes[3]) << 24;
  }

  // A target is an instruction of the code outside every delay slot, or (for
  // a call) the entry of a math ROM routine.
  void target(uint32_t i, const Instruction& in) const {
    const as::c40::Operand* t = target_operand(in);
    if (!t || t->kind != OperandKind::Address) return;
    if (is_call(in.mnemonic) && is_rom_entry(t->imm)) return;
    if (t->imm < 0 || t->imm >= int64_t(n_))
      throw Refusal{i, quote(in) + "target " + hex(uint64_t(t->imm)) + " outside the code (" + std::to_string(n_) + " words)"};
    if (auto d = slot_of(uint32_t(t->imm)))
      throw Refusal{i, quote(in) + "target " + hex(uint64_t(t->imm)) + " is in the delay slots of the delayed branch at word " +
                           hex(*d) + " (the slots would run without their branch)"};
  }

  // ---- pass 2: the flow of DP and the stack from the entry
  void flow() {
    if (entry_ >= n_) throw Refusal{entry_, "the entry point is outside the code"};  // read_image names the entry section first
    if (auto d = slot_of(entry_))
      throw Refusal{entry_, "the entry point is in the delay slots of the delayed branch at word " + hex(*d)};
    dp_.assign(n_, kDpUnseen);
    stack_.assign(n_, 0);
    PendingWords pending(n_);
    reach(entry_, entry_, kDpUnknown, 0, pending);
    for (uint32_t i; pending.take(i);) step(i, pending);
  }

  // One word: its direct operands against DP, then DP and the stack after
  // it, then where control goes.
  void step(uint32_t i, PendingWords& pending) {
    const Instruction in = *decode(i);
    uint8_t dp = dp_[i], st = stack_[i];
    direct_operands(i, in, dp);
    if (writes_dp(in)) {
      if (st & kCalled)
        throw Refusal{i, quote(in) + (in.mnemonic == Mnemonic::Ldpk ? "sets" : "names") +
                             " the data page inside a routine that a CALL enters (its callers keep their DP across the call)"};
      dp = in.mnemonic == Mnemonic::Ldpk ? page_class(uint32_t(in.ops[0].imm)) : kDpUnknown;
    }
    st = stack_after(i, in, st);
    bool falls = true;
    const as::c40::Operand* t = target_operand(in);
    switch (in.mnemonic) {
      case Mnemonic::Br: reach(i, uint32_t(t->imm), dp, st, pending); falls = false; break;
      case Mnemonic::Bc: case Mnemonic::Dbc:
        reach(i, uint32_t(t->imm), dp, st, pending);
        falls = in.mnemonic == Mnemonic::Dbc || in.cond != Cond::U;
        break;
      case Mnemonic::Call: case Mnemonic::Callc:  // the routine starts with nothing pushed, and the caller's DP
        if (t->imm < int64_t(n_)) reach(i, uint32_t(t->imm), dp, kCalled, pending);
        break;
      case Mnemonic::Retsc:
        if (st & kDepthMask)
          throw Refusal{i, quote(in) + "returns with " + words(st & kDepthMask) +
                               " pushed since the return address: it would return to a pushed value, not to its caller"};
        falls = in.cond != Cond::U;
        break;
      default: break;
    }
    // a delayed branch transfers after its third slot
    if (i >= 3) {
      auto b = decode(i - 3);
      if (b && is_delayed(b->mnemonic)) {
        reach(i, uint32_t(target_operand(*b)->imm), dp, st, pending);
        falls = !always_taken(*b);
      }
    }
    if (falls) {
      if (i + 1 >= n_)
        throw Refusal{i, quote(in) + (is_call(in.mnemonic) ? "its return point is past the end of the code"
                                                            : "execution runs past the end of the code")};
      reach(i, i + 1, dp, st, pending);
    }
  }

  void direct_operands(uint32_t i, const Instruction& in, uint8_t dp) const {
    for (unsigned k = 0; k < in.num_operands; k++) {
      if (in.ops[k].kind != OperandKind::Direct) continue;
      if (dp == kDpUnknown)
        throw Refusal{i, quote(in) + "direct operand with the data page not set by LDPK on every path"};
      if (dp == kDpOutside)
        throw Refusal{i, quote(in) + "the data page set by LDPK is outside the memory image " + image_range()};
      uint64_t a = uint64_t(c40map::kDataPage + dp - kDpFirstPage) << 16 | uint64_t(in.ops[k].imm);
      if (a < c40map::kDataBase || a >= uint64_t(c40map::kDataBase) + w_.words)
        throw Refusal{i, quote(in) + "word " + hex(a) + " is outside the memory image " + image_range()};
    }
  }

  uint8_t stack_after(uint32_t i, const Instruction& in, uint8_t st) const {
    unsigned depth = st & kDepthMask;
    switch (in.mnemonic) {
      case Mnemonic::Push: case Mnemonic::Pushf:
        if (depth == kMaxDepth) throw Refusal{i, quote(in) + "more than " + words(kMaxDepth) + " pushed in one routine"};
        return uint8_t(st + 1);
      case Mnemonic::Pop: case Mnemonic::Popf:
        if (depth == 0) throw Refusal{i, quote(in) + "pops the return address (nothing was pushed since it)"};
        return uint8_t(st - 1);
      default: return st;
    }
  }

  // Control reaches word `to` from word `from` with DP class `dp` and stack
  // byte `st`: a word's stack depth is the same on every path; DP classes
  // that differ meet in kDpUnknown; a word in a called routine stays one.
  void reach(uint32_t from, uint32_t to, uint8_t dp, uint8_t st, PendingWords& pending) {
    if (interior_[to] && from + 1 != to)
      throw Refusal{from, (from == to ? std::string("the entry point ") : quote(*decode(from))) + "enters word " + hex(to) +
                              " inside a checked indexed access, past its bounds check"};
    uint8_t& d = dp_[to];
    uint8_t& s = stack_[to];
    if (d == kDpUnseen) {
      d = dp, s = st;
      pending.add(to);
      return;
    }
    if ((s & kDepthMask) != (st & kDepthMask))
      throw Refusal{from, quote(*decode(from)) + "reaches word " + hex(to) + " with " + words(st & kDepthMask) +
                              " pushed, another path reaches it with " + words(s & kDepthMask)};
    uint8_t nd = d == dp ? d : kDpUnknown, ns = uint8_t(s | (st & kCalled));
    if (nd != d || ns != s) {
      d = nd, s = ns;
      pending.add(to);
    }
  }

  uint8_t page_class(uint32_t page) const {
    uint32_t last = (c40map::kDataBase + w_.words - 1) >> 16;
    if (page < c40map::kDataPage || page > last) return kDpOutside;
    return uint8_t(page - c40map::kDataPage + kDpFirstPage);
  }
  std::string image_range() const {
    return "(" + hex(c40map::kDataBase) + ".." + hex(c40map::kDataBase + w_.words - 1) + ")";
  }
  static std::string words(unsigned k) { return std::to_string(k) + (k == 1 ? " word" : " words"); }
};

}  // namespace

std::string check_c40_code(std::span<const uint8_t> code, uint32_t entry, const Layout& layout) {
  try {
    C40Check(code, entry, layout).run();
  } catch (const Refusal& r) {
    return "at word " + hex(r.word) + " (code offset " + hex(uint64_t(r.word) * 4) + "): " + r.why;
  }
  return "";
}

}  // namespace ldc
