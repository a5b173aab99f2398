// backend-c40sim/machine/mathrom.h -- the math ROM of the simulated C40 board.
//
// SIN COS TAN SQRT EXP LN have no C40 instruction (SQRT would need RSQRF,
// outside our assembler's subset).  Generated code and the C40-hosted
// interpreter CALL a routine at a fixed ROM address with the argument in R0
// (C40 float) and get the result in R0.  Each routine is real C40 code of ours
// (mathrom.c40s: range reduction and polynomials), assembled into the ROM
// region, and it runs in the simulator, so a call costs its own measured cycles.
// Its result is then replaced by the host's IEEE binary32 function (sinf, ...)
// of the argument converted with TOIEEE, converted back with FRIEEE: the
// simulator "services the call on the host" when the routine's RETS executes,
// so REAL functions mean exactly what they mean in the reference interpreter.
// Registers R0-R7 and AR0 are clobbered (docs/c40.md, "Math ROM").
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "backend-c40sim/machine/c40layout.h"
#include "backend-c40sim/machine/sim.h"

namespace ldc::c40gen {

// RomFn, rom_entry and rom_of are the image format's (loader/c40_map.h, via c40layout.h).
const char* rom_name(RomFn f);      // "sin", ...
float rom_host(RomFn f, float x);   // sinf cosf tanf sqrtf expf logf

struct MathRom {
  std::vector<uint32_t> words;            // kRomWords words from kRomBase
  uint32_t exit[kRomFnCount] = {};        // address of each routine's single RETS
  std::string source;                     // mathrom.c40s
};
// Assembles mathrom.c40s once (throws std::logic_error if it does not assemble).
const MathRom& math_rom();

// Loads the ROM into a simulator and services its calls: call install() once,
// then on_instruction() for every executed instruction (from the simulator's
// trace hook).  At a routine's entry it takes R0 as the argument; when the
// routine's RETS has executed it puts the host result into R0.
class RomService {
 public:
  void install(c40sim::C40Sim& sim) const;
  void on_instruction(c40sim::C40Sim& sim, uint32_t pc);
  uint64_t calls(RomFn f) const { return calls_[int(f)]; }
  // false: leave the routine's own result (tests of the routines' accuracy)
  void set_host_results(bool on) { host_ = on; }

 private:
  bool host_ = true;
  c40sim::Ext arg_[kRomFnCount] = {};
  uint64_t calls_[kRomFnCount] = {};
};

// The host side of one call, as the service and the C40 model compute it:
// FRIEEE(f(TOIEEE(x))).
c40sim::Ext rom_result(RomFn f, c40sim::Ext x);

}  // namespace ldc::c40gen
