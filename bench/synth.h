// bench/synth.h -- synthetic programs for paper 003's evaluation (docs/BENCHMARKS.md).
//
// Paper 003 measures programs of N_exe IL instructions (300, 600, ..., 3000)
// with a share P_basic of basic bit instructions (68.9% in its real programs,
// Fig. 9), the rest application instructions (compare, move, arithmetic,
// REAL functions, timers, counters).  These generators make such programs as
// IL text (docs/il.md, read back with parse_il_text), so that N_exe and the
// class counts are exact: a ladder grid cannot make a compare or an ADD
// without the LOAD/MPS/... the lowering adds around it.  Every rung is a
// condition (LOAD/AND/OR/... or a compare) followed by its outputs, as lowered
// ladder code is, and every program is valid IL.
//
// The devices the programs read and write are fixed (SynthDevices) so that a
// benchmark can write the same random inputs into every engine's image before
// each scan.  The same seed always gives the same text, on every platform.
//
// synth_plant_ld makes a realistic large ladder program as .ld text (motor
// starters, conveyors with timers, part counters, alarms, totals), the input
// for measuring the whole compiler pipeline.
#pragma once

#include <array>
#include <cstdint>
#include <string>

#include "ir/ir.h"

namespace ldc::synth {

// The devices the synthetic programs use.  Inputs are written by the bench's
// trace before every scan; the rest is the program's own state.
struct SynthDevices {
  static constexpr int kInX = 64;        // X0..X63: input bits
  static constexpr int kInWX = 16;       // WX0..WX15: INT32 inputs
  static constexpr int kInFPos = 4;      // F0..F3: REAL inputs in [0.1, 8] (SQRT, LN)
  static constexpr int kInF = 8;         // F4..F7: REAL inputs in [-8, 8]
  static constexpr int kBitsM = 512;     // M0..M511 internal relays
  static constexpr int kBitsY = 256;     // Y0..Y255 outputs
  static constexpr int kWordsD = 256;    // D0..D255 data words
  static constexpr int kFirstFOut = 8;   // F8..F63: REAL results (never read back
  static constexpr int kLastFOut = 63;   //   as REAL sources: no runaway values)
  static constexpr int kWordsWY = 32;    // WY0..WY31
};

// Shares of the application classes among the non-basic instructions, indexed
// by OpClass (Basic and Flow are ignored).
using AppMix = std::array<double, kOpClassCount>;
// Our assumption for the split of the 31.1% application instructions (paper
// 003's Fig. 9 gives it only as a chart): compare 28%, move 25%, arithmetic
// 17%, word logic 5%, REAL functions 5%, timers 12%, counters 8%.
AppMix typical_app_mix();
constexpr double kTypicalPBasic = 0.689;

struct SynthOptions {
  int n_exe = 3000;                 // IL instructions, exactly
  double p_basic = kTypicalPBasic;  // share of basic instructions (0..1)
  AppMix mix = typical_app_mix();
  uint64_t seed = 1;
};

// A program with exactly o.n_exe instructions, round(p_basic * n_exe) of them
// basic and the rest split over the classes by o.mix (largest remainder).
std::string synth_il(const SynthOptions& o);

// A program of one class (paper 003's Fig. 8): `n` instructions of class `c`.
// Basic: ordinary bit rungs.  Compare: n compares (each pushes).  The
// application classes: one `TRUE` (powered) or one `LOAD M8191` (never set:
// every instruction is skipped) and then n instructions of the class; timers and
// counters run either way, with IN = 1 or 0.  Every result goes to a device of
// its own (no store is overwritten by a later one) and INT32 sources are the WX
// inputs.
std::string synth_class_il(OpClass c, int n, uint64_t seed, bool powered = true);

// Counts of a program: instructions per class.
struct ClassCounts {
  std::array<int, kOpClassCount> n{};
  int total() const;
  double p_basic() const;
};
ClassCounts count_classes(const Program& p);

// A plant of `rungs` rungs as .ld text: repeating groups of motor starters with
// seal-in and fault latches, conveyors with TON/TOF, part counters with edge
// contacts, analog alarms with compares, and production totals.
std::string synth_plant_ld(int rungs, uint64_t seed = 1);

}  // namespace ldc::synth

namespace ldc::synth {

// A typed program (issue 25) of `instances` instances of one function block,
// expanded inline per instance as the IEC front ends expand them: a scaling
// and filtering block over INT, DINT and LREAL (an INT sample counter that
// wraps at 16 bits, a DINT raw value scaled to LREAL engineering units, a
// first-order filter in LREAL, a DINT total, a lookup in a shared INT table
// and a ring buffer of DINT through IDX + LDX / STX, limit alarms as compares
// driving outputs), as IL text.  Each instance reads its own WX input and X
// enable bit (the same SynthDevices inputs as synth_il) and owns
// kTypedCells D cells and one Y.  The same count always gives the same text.
std::string synth_typed_il(int instances);
constexpr int kTypedCells = 32;   // D cells of one instance
constexpr int kTypedBase = 256;   // its first at D256 + 32 k (after SynthDevices' D0..D255)
constexpr int kTypedTable = 240;  // the shared INT table, D240..D255 (16 entries)
constexpr int kTypedMaxInstances = (8192 - kTypedBase) / kTypedCells;

}  // namespace ldc::synth
