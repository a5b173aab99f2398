// backend-c40sim/machine/sim.h -- ldc_c40sim: a cycle-counting instruction-set simulator for the TMS320C40
// subset of assembler/c40.h. See docs/c40.md for the semantics, the float
// format and the cycle model (and what it does not model).
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "assembler/c40.h"
#include "backend-c40sim/machine/c40float.h"

namespace ldc::c40sim {

using as::c40::Reg;

// ------------------------------------------------------------ simulator

struct Region {
  std::string name;
  uint32_t base = 0;
  uint32_t size = 0;        // words
  unsigned wait_states = 0;  // extra cycles per access (fetch, read or write)
  // What instructions may do here (the host's load/write always may): a
  // fetch from a region that is not executable and a store into one that is
  // not writable stop the run with a MemoryFault.  The board
  // (c40machine.h) makes its code and ROM executable and read-only, the
  // rest writable data.
  bool executable = true;
  bool writable = true;
};

struct Config {
  std::vector<Region> regions;
  double ns_per_cycle = 50.0;              // TMS320C40-40
  uint32_t return_address = 0xFFFFFFFFu;  // call() returns here; must not be code
  uint64_t max_instructions = 100000000;  // runaway guard besides max_cycles
};

enum class Stop : uint8_t {
  Returned,          // RETS came back to Config::return_address
  CycleLimit,
  InstructionLimit,
  MemoryFault,       // access outside every region, a fetch outside the executable ones, a store into a read-only one
  IllegalInstruction,
  Unsupported,       // e.g. circular addressing, a branch in a delay slot
};

struct RunResult {
  Stop stop = Stop::Returned;
  uint64_t cycles = 0;
  uint64_t instructions = 0;
  uint32_t pc = 0;
  std::string error;  // empty when stop == Returned
  double ns = 0;      // cycles * ns_per_cycle
  bool ok() const { return stop == Stop::Returned; }
};

struct TraceEntry {
  uint32_t pc;
  const as::c40::Instruction* inst;
  uint64_t cycles_before;
  unsigned cycles;  // this instruction, stalls and wait states included
};

class C40Sim {
 public:
  explicit C40Sim(Config config);

  // Copies words into memory at base. Throws std::out_of_range if any word
  // falls outside the regions.
  void load(std::span<const uint32_t> words, uint32_t base);
  void write(uint32_t address, uint32_t value);  // throws std::out_of_range
  uint32_t read(uint32_t address) const;         // throws std::out_of_range

  // Integer view of a register (bits 31-0); setting an extended register
  // keeps its exponent.
  void set_reg(Reg r, uint32_t value);
  uint32_t reg(Reg r) const;
  // Extended registers R0-R11 as 40-bit values (others: std::invalid_argument).
  void set_ext(Reg r, Ext value);
  Ext ext(Reg r) const;
  void set_float(Reg r, double v) { set_ext(r, fp::from_double(v).v); }
  double get_float(Reg r) const { return fp::to_double(ext(r)); }
  uint32_t st() const { return reg(Reg::ST); }

  // Pushes Config::return_address (SP is incremented first, as CALL does),
  // jumps to entry and runs until RETS returns there, or a limit or an error
  // stops it. Cycles count the executed instructions only.
  RunResult call(uint32_t entry, uint64_t max_cycles);

  void set_trace(std::function<void(const TraceEntry&)> t) { trace_ = std::move(t); }
  const Config& config() const { return cfg_; }

 private:
  // The decode cache: per region, direct-mapped on the word address, at most
  // kCacheWords entries, so that its memory is a constant however large the
  // code (an entry is about 190 bytes; code words are 4).
  struct Cached {
    uint32_t pc = 0, word = 0;
    bool valid = false, ok = false;
    as::c40::Instruction inst;
  };
  static constexpr uint32_t kCacheWords = 1u << 16;
  struct Fault {
    Stop stop;
    std::string message;
  };
  size_t region_index(uint32_t address) const;  // SIZE_MAX: none
  Region* region(uint32_t address);
  const Region* region(uint32_t address) const;
  uint32_t mem_read(uint32_t address);
  void mem_write(uint32_t address, uint32_t value);
  const Cached& fetch(uint32_t pc);
  unsigned execute(const as::c40::Instruction& in, uint32_t pc);

  Config cfg_;
  std::vector<std::vector<uint32_t>> mem_;
  std::vector<std::vector<Cached>> cache_;  // per region, allocated at its first fetch
  uint32_t r32_[as::c40::kNumRegs] = {};
  Ext ext_[12];
  // per instruction
  unsigned waits_ = 0;
  bool taken_ = false;
  uint32_t target_ = 0;
  uint32_t nextPc_ = 0;
  std::function<void(const TraceEntry&)> trace_;
};

std::string_view stop_name(Stop s);

}  // namespace ldc::c40sim

