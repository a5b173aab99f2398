// loader/c40_check.cpp -- the C40 code check (c40_check.h).
#include "loader/c40_check.h"

#include <cstdio>
#include <deque>
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

// The data page state of the flow analysis.
constexpr int32_t kUnseen = -2;   // not reached yet
constexpr int32_t kUnknown = -1;  // DP not set by LDPK on some path

bool writes_dp(const Instruction& in) {
  if (in.mnemonic == Mnemonic::Ldpk) return false;
  for (unsigned k = 0; k < in.num_operands; k++)
    if (in.ops[k].kind == OperandKind::Reg && in.ops[k].reg == Reg::DP) return true;
  return false;
}

}  // namespace

std::string check_c40_code(std::span<const uint8_t> code, uint32_t entry, const Layout& layout) {
  using c40map::C40Layout;
  const uint32_t n = uint32_t(code.size() / 4);
  const C40Layout w = C40Layout::of(layout);
  auto at = [](uint32_t i) { return "at word " + hex(i) + ": "; };
  // 1. every word decodes; targets and operands we can check without flow
  std::vector<Instruction> insts(n);
  for (uint32_t i = 0; i < n; i++) {
    uint32_t word = uint32_t(code[4 * i]) | uint32_t(code[4 * i + 1]) << 8 | uint32_t(code[4 * i + 2]) << 16 |
                    uint32_t(code[4 * i + 3]) << 24;
    DecodeError e;
    auto in = decode_word(word, i, &e);
    if (!in) return at(i) + "word " + hex(word) + " does not decode: " + e.message;
    insts[i] = *in;
    for (unsigned k = 0; k < in->num_operands; k++) {
      const as::c40::Operand& o = in->ops[k];
      if (o.kind == OperandKind::Ind && in->mnemonic != Mnemonic::Nop)
        return at(i) + "'" + print(*in) + "': indirect memory operand (its address cannot be checked)";
      if (o.kind == OperandKind::Ind) return at(i) + "'" + print(*in) + "': NOP with an address update";
      if (is_control(in->mnemonic) && o.kind == OperandKind::Reg && in->mnemonic != Mnemonic::Dbc &&
          in->mnemonic != Mnemonic::Dbcd)
        return at(i) + "'" + print(*in) + "': branch or call through a register";
      if (o.kind == OperandKind::Address) {
        int64_t t = o.imm;
        bool rom = false;
        for (int f = 0; f < c40map::kRomFnCount; f++)
          rom |= (in->mnemonic == Mnemonic::Call || in->mnemonic == Mnemonic::Callc) &&
                 t == int64_t(c40map::rom_entry(c40map::RomFn(f)));
        if (!rom && (t < 0 || t >= int64_t(n)))
          return at(i) + "'" + print(*in) + "': target " + hex(uint64_t(t)) + " outside the code (" +
                 std::to_string(n) + " words)";
      }
    }
    if (is_delayed(in->mnemonic)) {
      if (i + 3 >= n) return at(i) + "'" + print(*in) + "': its delay slots run past the end of the code";
    }
  }
  for (uint32_t i = 0; i < n; i++)
    if (is_delayed(insts[i].mnemonic))
      for (uint32_t s = 1; s <= 3; s++)
        if (is_control(insts[i + s].mnemonic))
          return at(i + s) + "'" + print(insts[i + s]) + "' in the delay slot of a delayed branch";
  // 2. the data page, by a flow analysis from the entry
  std::vector<int32_t> dp(n, kUnseen);  // DP before each instruction
  std::deque<uint32_t> work;
  auto flow = [&](uint32_t to, int32_t state) {
    if (to >= n) return;
    int32_t& d = dp[to];
    int32_t next = d == kUnseen ? state : d == state ? d : kUnknown;
    if (next != d) {
      d = next;
      work.push_back(to);
    }
  };
  // a delayed branch at i transfers after i + 3: targets[i + 3]
  std::vector<int64_t> delayed_target(n, -1);
  std::vector<bool> delayed_cond(n, false);
  for (uint32_t i = 0; i < n; i++)
    if (is_delayed(insts[i].mnemonic)) {
      const as::c40::Operand& t = insts[i].ops[insts[i].mnemonic == Mnemonic::Brd || insts[i].mnemonic == Mnemonic::Bcd ? 0 : 1];
      delayed_target[i + 3] = t.imm;
      delayed_cond[i + 3] = !(insts[i].mnemonic == Mnemonic::Brd ||
                              (insts[i].mnemonic == Mnemonic::Bcd && insts[i].cond == Cond::U));
    }
  if (entry / 4 < n) flow(entry / 4, kUnknown);
  while (!work.empty()) {
    uint32_t i = work.front();
    work.pop_front();
    const Instruction& in = insts[i];
    int32_t out = dp[i];
    if (in.mnemonic == Mnemonic::Ldpk) out = int32_t(in.ops[0].imm);
    else if (writes_dp(in)) out = kUnknown;
    for (unsigned k = 0; k < in.num_operands; k++) {
      if (in.ops[k].kind != OperandKind::Direct) continue;
      if (dp[i] < 0)
        return at(i) + "'" + print(in) + "': direct operand with the data page not set by LDPK on every path";
      uint64_t a = uint64_t(uint32_t(dp[i]) & 0xFFFF) << 16 | uint64_t(in.ops[k].imm);
      if (a < c40map::kDataBase || a >= uint64_t(c40map::kDataBase) + w.words)
        return at(i) + "'" + print(in) + "': word " + hex(a) + " is outside the memory image (" + hex(c40map::kDataBase) +
               ".." + hex(c40map::kDataBase + w.words - 1) + ")";
    }
    bool falls = true;
    switch (in.mnemonic) {
      case Mnemonic::Br: flow(uint32_t(in.ops[0].imm), out); falls = false; break;
      case Mnemonic::Bc: flow(uint32_t(in.ops[0].imm), out); falls = in.cond != Cond::U; break;
      case Mnemonic::Call: case Mnemonic::Callc:  // the routine starts with the caller's DP and keeps it
        if (in.ops[0].imm < int64_t(n)) flow(uint32_t(in.ops[0].imm), out);
        break;
      case Mnemonic::Dbc: flow(uint32_t(in.ops[1].imm), out); break;
      case Mnemonic::Retsc: falls = in.cond != Cond::U; break;
      default: break;
    }
    if (delayed_target[i] >= 0) {
      flow(uint32_t(delayed_target[i]), out);
      falls = delayed_cond[i];
    }
    if (falls) flow(i + 1, out);
  }
  return "";
}

}  // namespace ldc
