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
//    calls a C library function (its result is the running machine's).
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
};

struct ScanFacts {
  std::vector<uint32_t> first;  // per rung: the index of its first instruction
  std::vector<char> fits;       // per rung: its stack is private and fits the slots (no kUnread elsewhere)
  std::vector<uint8_t> flags;   // per IL instruction of the program, in order
  // (index, the instruction to compile in its place), by index: sources
  // replaced by their known constants, or a MOV of the folded result
  std::vector<std::pair<uint32_t, Instr>> replaced;
  bool shared = false;          // shares_stack(p): some rung reads what an earlier one left

  uint8_t at(size_t rung, size_t k) const { return flags[first[rung] + k]; }
  // nullptr if none (inline: the code generators ask it of every instruction)
  const Instr* replacement(size_t rung, size_t k) const {
    const uint32_t i = first[rung] + uint32_t(k);
    auto it = std::lower_bound(replaced.begin(), replaced.end(), i,
                               [](const std::pair<uint32_t, Instr>& e, uint32_t v) { return e.first < v; });
    return it != replaced.end() && it->first == i ? &it->second : nullptr;
  }
  size_t count(ScanFlag f) const;
};

// The facts of a whole program (stores die across rungs).  Rungs whose stack
// is not private (stack_fits_slots(code, slots) false, or any rung of the
// program reads what an earlier one left: shares_stack) get no kUnread flags.
ScanFacts scan_facts(const Program& p, const Layout& layout, int slots);

}  // namespace ldc
