// tests/backend-c40sim/machine/mathrom_test.cpp -- the math ROM (backend-c40sim/machine/mathrom.h):
// our C40 routines are real implementations whose cycles the simulator
// counts, so they must be accurate in their primary ranges on their own (the
// host service switched off); with the service on, a call returns the host's
// IEEE result exactly.  Prints the cycle range of every routine (docs/c40.md).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "backend-c40sim/machine/c40machine.h"
#include "backend-c40sim/machine/mathrom.h"

namespace {

using namespace ldc;
using namespace ldc::c40gen;
namespace fp = ldc::c40sim::fp;

struct Caller {
  // CALL rom_entry(f); RETSU
  Caller(RomFn f) : code(words(f)), m(Layout::standard(0), code, 0) {}
  static std::vector<uint32_t> words(RomFn f) {
    using namespace as::c40;
    return {encode_at(make(Mnemonic::Call, {as::c40::Operand::a(rom_entry(f))}), 0), encode_at(parse("RETSU"), 1)};
  }
  double run(double x, uint64_t* cycles) {
    m.sim().set_ext(as::c40::Reg::R0, fp::from_double(x).v);
    m.sim().set_reg(as::c40::Reg::SP, kStackBase);
    c40sim::RunResult r = m.sim().call(0, 100000);  // no image to copy: the routine alone
    EXPECT_TRUE(r.ok()) << r.error;
    *cycles = r.cycles - 4 - 4 - 4;  // not the CALL, its RETS or ours
    return fp::to_double(m.sim().ext(as::c40::Reg::R0));
  }
  std::vector<uint32_t> code;
  C40Machine m;
};

struct Range {
  RomFn f;
  double lo, hi;
  bool log;        // log-uniform
  bool relative;   // relative error, else absolute (relative above 1 in magnitude)
  double bound;
};

TEST(MathRom, RoutinesAreAccurateInTheirPrimaryRanges) {
  const Range ranges[] = {
      {RomFn::Sin, -10, 10, false, false, 2e-7},   {RomFn::Cos, -10, 10, false, false, 2e-7},
      {RomFn::Tan, -1.4, 1.4, false, true, 1e-6},  {RomFn::Sqrt, 1e-30, 1e30, true, true, 5e-7},
      {RomFn::Exp, -80, 80, false, true, 5e-7},    {RomFn::Ln, 1e-30, 1e30, true, false, 5e-7},
  };
  std::mt19937 rng(2024);
  for (const Range& r : ranges) {
    Caller c(r.f);
    c.m.rom().set_host_results(false);
    double worst = 0;
    uint64_t lo = UINT64_MAX, hi = 0;
    for (int i = 0; i < 3000; i++) {
      double u = std::uniform_real_distribution<double>(0, 1)(rng);
      double x = r.log ? std::exp(std::log(r.lo) + u * (std::log(r.hi) - std::log(r.lo))) : r.lo + u * (r.hi - r.lo);
      x = double(float(x));
      uint64_t cyc = 0;
      double y = c.run(x, &cyc), want = double(rom_host(r.f, float(x)));
      double err = std::fabs(y - want) / (r.relative ? std::fabs(want) : std::max(1.0, std::fabs(want)));
      worst = std::max(worst, err);
      lo = std::min(lo, cyc), hi = std::max(hi, cyc);
    }
    EXPECT_LE(worst, r.bound) << rom_name(r.f);
    std::printf("%-4s: worst %s error %.2e over [%g, %g]; %llu..%llu cycles\n", rom_name(r.f),
                r.relative ? "relative" : "absolute (relative above 1)", worst, r.lo, r.hi, (unsigned long long)lo,
                (unsigned long long)hi);
    EXPECT_GT(lo, 30u) << rom_name(r.f);
    EXPECT_LT(hi, 120u) << rom_name(r.f);
  }
}

TEST(MathRom, TheServiceReturnsTheHostResult) {
  for (int k = 0; k < kRomFnCount; k++) {
    Caller c{RomFn(k)};
    for (double x : {0.5, 1.0, 2.0, 3.0, -0.75, 100.0, 1e-3}) {
      uint64_t cyc = 0;
      double y = c.run(x, &cyc);
      EXPECT_EQ(y, fp::to_double(rom_result(RomFn(k), fp::from_double(x).v))) << rom_name(RomFn(k)) << " " << x;
    }
    EXPECT_EQ(c.m.rom().calls(RomFn(k)), 7u);
  }
  // outside the format: sqrt(-1) is NaN on the host, the C40 gets the saturated value
  Caller s{RomFn::Sqrt};
  uint64_t cyc = 0;
  double y = s.run(-1.0, &cyc);
  EXPECT_TRUE(std::fabs(y) > 1e38) << y;
}

TEST(MathRom, EveryRoutineHasOneExitAndFitsItsSlot) {
  const MathRom& rom = math_rom();
  for (int k = 0; k < kRomFnCount; k++) {
    EXPECT_GT(rom.exit[k], rom_entry(RomFn(k)));
    EXPECT_LT(rom.exit[k], rom_entry(RomFn(k)) + kRomStride);
  }
}

}  // namespace
