// ir/scanopt.h -- what one scan cannot observe, for the -O2 code generators
// (docs/x86.md, "Words at -O2").  Nothing but the memory image at the end of
// a scan is observable (the runtime, the monitor, Modbus and the other tasks
// see the image between scans only), so within a scan:
//  * a store the scan overwrites for certain before anything reads it, and
//    before any JMP or END could leave it, is dead (kDeadStore): OUT, OUTN,
//    SET, RST and the application instructions whose only effect is that
//    store need no code;
//  * a stack entry nothing reads is dead too (kUnread): the contact, compare
//    or combine that writes it needs no code (an edge contact keeps its edge
//    update);
//  * an application instruction whose sources are constants, or words that
//    a store earlier in the same scan made constant for certain, is computed
//    while compiling, by the reference interpreter itself (folded: a MOV of
//    the result), unless it has another effect (a zero divisor sets S0) or
//    calls a C library function (its result is the running machine's);
//  * an INT32 DIV or MOD with power on for certain whose two word operands
//    were divided so before in the same scan, with neither they nor that
//    division's destination written since, takes the earlier result
//    (ScanFacts::reused): a copy of the same quotient or remainder, or the
//    remainder from the quotient (a - q*b), unless the divisor is 0 (then the
//    destination keeps its value, and S0 is still set from the first); a DIV
//    after a MOD of the pair takes no code where nothing has touched its
//    destination since the MOD and no JMP or END lies between: the MOD
//    stores the quotient there too (ScanFacts::early_quotient);
//  * a typed instruction that computes exactly what an identical instruction
//    earlier in the scan stored in the same destination, with power on for
//    certain there, neither its sources nor that destination written since
//    and no rung that jumps land on between, stores the bits the destination
//    already holds (kHeld): it needs no code, with power or without.
#pragma once

#include <algorithm>
#include <cstdint>
#include <utility>
#include <vector>

#include "ir/ir.h"

namespace ldc {

enum ScanFlag : uint8_t {
  kDeadStore = 1,  // its only effect is a store the scan overwrites unread: no code
  kUnread = 2,     // the stack entry it writes is never read: no code but an edge update
  kHeld = 4,       // a typed instruction whose destination already holds its result: no code
};

// What an INT32 DIV or MOD takes from an earlier one (docs/x86.md, "Words at
// -O2"): `from` holds the earlier quotient (DIV) or remainder (MOD); if the
// divisor is not 0, the destination becomes `from` (the same operation) or
// a - from * b (a MOD after a DIV); if it is 0, the destination keeps its
// value (S0 is 1 since the earlier division, which nothing has cleared).
struct DivReuse {
  Operand from;
  bool remainder_from_quotient = false;
  bool stored_early = false;  // a DIV whose quotient the earlier MOD stored: no code
};

// The entry of `v` (sorted by index) for instruction i, or nullptr.
template <class T>
const T* entry_at(const std::vector<std::pair<uint32_t, T>>& v, uint32_t i) {
  auto it = std::lower_bound(v.begin(), v.end(), i, [](const std::pair<uint32_t, T>& e, uint32_t x) { return e.first < x; });
  return it != v.end() && it->first == i ? &it->second : nullptr;
}

struct ScanFacts {
  std::vector<uint32_t> first;  // per rung: the index of its first instruction
  std::vector<char> fits;       // per rung: its stack is private and fits the slots (no kUnread elsewhere)
  std::vector<uint8_t> flags;   // per IL instruction of the program, in order
  // (index, the instruction to compile in its place), by index: sources
  // replaced by their known constants, or a MOV of the folded result
  std::vector<std::pair<uint32_t, Instr>> replaced;
  std::vector<std::pair<uint32_t, DivReuse>> reused;  // by index, of the instruction replaced or not
  // by index: a MOD that also stores its quotient (where the divisor is not 0) into this word
  std::vector<std::pair<uint32_t, Operand>> early_quotient;
  bool shared = false;          // shares_stack(p): some rung reads what an earlier one left

  uint8_t at(size_t rung, size_t k) const { return flags[first[rung] + k]; }
  // nullptr if none (inline: the code generators ask them of every instruction)
  const Instr* replacement(size_t rung, size_t k) const { return entry_at(replaced, first[rung] + uint32_t(k)); }
  const DivReuse* reuse(size_t rung, size_t k) const { return entry_at(reused, first[rung] + uint32_t(k)); }
  const Operand* quotient_to(size_t rung, size_t k) const { return entry_at(early_quotient, first[rung] + uint32_t(k)); }
  size_t count(ScanFlag f) const;
};

// The facts of a whole program (stores die across rungs).  Rungs whose stack
// is not private (stack_fits_slots(code, slots) false, or any rung of the
// program reads what an earlier one left: shares_stack) get no kUnread flags.
ScanFacts scan_facts(const Program& p, const Layout& layout, int slots);

}  // namespace ldc
