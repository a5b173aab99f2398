// backend-c40sim/machine/c40machine.cpp -- the board that runs scans (c40machine.h).
#include "backend-c40sim/machine/c40machine.h"

#include <stdexcept>

namespace ldc::c40gen {

c40sim::Config board_config(const C40Layout& w, uint32_t code_words, uint32_t il_words) {
  c40sim::Config cfg;
  // Instructions run from the code and the ROM only, and never store into
  // them: whatever the loader's check missed stays inside the code it checked
  // (docs/c40.md, "Stops").  The IL is read-only data for the interpreter.
  constexpr bool kExec = true, kData = false, kWritable = true, kReadOnly = false;
  cfg.regions = {  // the data first: the simulator looks regions up in order
      {"data", kDataBase, w.words, kDataWaitStates, kData, kWritable},
      {"code", kCodeBase, std::max<uint32_t>(code_words, 1), 0, kExec, kReadOnly},
      {"il", kIlBase, std::max<uint32_t>(il_words, 1), 0, kData, kReadOnly},
      {"rom", kRomBase, kRomWords, 0, kExec, kReadOnly},
      {"stack", kStackBase, kStackWords, 0, kData, kWritable},
  };
  cfg.ns_per_cycle = kNsPerCycle;
  cfg.max_instructions = UINT64_MAX;
  return cfg;
}

C40Machine::C40Machine(const Layout& layout, std::span<const uint32_t> code, uint32_t entry,
                       std::span<const uint32_t> il)
    : max_cycles(kBudgetBase + kBudgetPerWord * (uint64_t(code.size()) + il.size())),
      layout_(layout), w_(C40Layout::of(layout)), entry_(entry) {
  if (code.size() > kCodeMaxWords) throw std::runtime_error("C40 code larger than the code SRAM");
  if (il.size() > kIlMaxWords) throw std::runtime_error("C40 IL larger than its SRAM");
  sim_ = std::make_unique<c40sim::C40Sim>(board_config(w_, uint32_t(code.size()), uint32_t(il.size())));
  sim_->load(code, kCodeBase);
  if (!il.empty()) sim_->load(il, kIlBase);
  rom_.install(*sim_);
  c40sim::C40Sim* s = sim_.get();
  sim_->set_trace([this, s](const c40sim::TraceEntry& t) {
    rom_.on_instruction(*s, t.pc);
    if (observer) observer(t);
  });
  buf_.assign(w_.words, 0);
  in_.resize(w_.words);
}

ScanCost C40Machine::scan(uint8_t* mem) {
  bytes_to_words(layout_, w_, mem, in_.data());
  for (uint32_t i = 0; i < w_.words; i++)  // buf_ holds what the simulator's memory holds
    if (in_[i] != buf_[i]) sim_->write(kDataBase + i, buf_[i] = in_[i]);
  sim_->set_reg(as::c40::Reg::SP, kStackBase);
  c40sim::RunResult r = sim_->call(entry_, max_cycles);
  if (!r.ok())
    throw std::runtime_error("C40 simulator: " + std::string(c40sim::stop_name(r.stop)) + ": " + r.error);
  for (uint32_t i = 0; i < w_.words; i++) buf_[i] = sim_->read(kDataBase + i);
  words_to_bytes(layout_, w_, buf_.data(), mem);
  return {r.cycles, r.instructions};
}

}  // namespace ldc::c40gen
