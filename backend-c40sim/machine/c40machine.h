// backend-c40sim/machine/c40machine.h -- the simulated C40 board that runs scans:
// code (native scan code, or the C40-hosted interpreter and its IL) in
// zero-wait SRAM, the math ROM, a stack, and the memory image in SRAM with one
// wait state (c40layout.h).  Each scan copies the byte image of docs/il.md in
// (c40layout.h's conversion), CALLs the entry and copies the words back.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <vector>

#include "backend-c40sim/machine/c40layout.h"
#include "backend-c40sim/machine/mathrom.h"
#include "backend-c40sim/machine/sim.h"

namespace ldc::c40gen {

struct ScanCost {
  uint64_t cycles = 0;
  uint64_t instructions = 0;
  double us() const { return double(cycles) * kNsPerCycle / 1000.0; }
};

class C40Machine {
 public:
  // `code` is loaded at kCodeBase, `il` (if any) at kIlBase.
  C40Machine(const Layout& layout, std::span<const uint32_t> code, uint32_t entry,
             std::span<const uint32_t> il = {});
  // One scan over the byte image.  Throws std::runtime_error if the simulator
  // stops for any reason but the return (fault, illegal word, cycle limit).
  ScanCost scan(uint8_t* mem);

  c40sim::C40Sim& sim() { return *sim_; }
  const C40Layout& words() const { return w_; }
  RomService& rom() { return rom_; }
  // The cycle budget of one scan: the C40 code check (loader/c40_check.h) does
  // not refuse backward branches (the division routines loop), so a hostile
  // image could loop; a scan that runs past this stops with an error.  Code
  // ldc makes runs each word at most once per scan, besides the division
  // loops (<= 32 steps) and the math ROM (a few hundred cycles per call), so
  // it stays far below: docs/c40.md, "The loader's C40 code check".
  static constexpr uint64_t kBudgetBase = 100000, kBudgetPerWord = 1000;
  uint64_t max_cycles;  // per scan: kBudgetBase + kBudgetPerWord * (code + IL words)
  // Called for every executed instruction (after the math ROM service), e.g.
  // to attribute cycles to IL instructions (bench/c40bench.cpp).
  std::function<void(const c40sim::TraceEntry&)> observer;

 private:
  Layout layout_;
  C40Layout w_;
  uint32_t entry_;
  std::unique_ptr<c40sim::C40Sim> sim_;
  RomService rom_;
  std::vector<uint32_t> buf_, in_;
};

// The regions of the board for a program of `code_words` code words and
// `il_words` IL words (both at least 1 word).
c40sim::Config board_config(const C40Layout& w, uint32_t code_words, uint32_t il_words);

}  // namespace ldc::c40gen
