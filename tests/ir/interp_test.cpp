// The reference interpreter against docs/il.md, one rule at a time.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>

#include "ir/ir.h"

using namespace ldc;

namespace {

// A program from IL text, run scan by scan over one memory image.
struct Scan {
  Program prog;
  BinaryIl bin;
  Memory mem;
  explicit Scan(const std::string& il)
      : prog(parse_il_text(il, "t.il")), bin(encode_il(prog)), mem(prog.layout()) {
    EXPECT_EQ(validate_il(bin.code, prog.layout()), "");
  }
  void scan(int32_t dt = 10) {
    std::memcpy(mem.data() + kSysDt, &dt, 4);
    Interpreter(bin.code, prog.layout()).scan(mem.data());
  }
  void x(uint32_t i, bool v) { mem.set_bit(Area::X, i, v); }
  int y(uint32_t i) const { return mem.get_bit(Area::Y, i); }
  int32_t d(uint32_t i) const { return mem.get_int(Area::D, i); }
};

TEST(Interp, BitLogicAndBlocks) {
  // Y1 = X1 AND (X2 OR (X3 AND X4))
  Scan r(".rung line 1\nLOAD X1\nLOAD X2\nLOAD X3\nAND X4\nORBLK\nANDBLK\nOUT Y1\n.end\n");
  for (int m = 0; m < 16; m++) {
    bool x1 = m & 1, x2 = m & 2, x3 = m & 4, x4 = m & 8;
    r.x(1, x1); r.x(2, x2); r.x(3, x3); r.x(4, x4);
    r.scan();
    EXPECT_EQ(r.y(1), x1 && (x2 || (x3 && x4))) << m;
  }
}

TEST(Interp, NegatedFormsAndCoils) {
  Scan r(".rung line 1\nLOADN X0\nORN X1\nANDN X2\nOUT Y0\nOUTN Y1\nSET M0\nRST M1\n.end\n");
  r.mem.set_bit(Area::M, 1, true);
  r.x(0, 1); r.x(1, 1); r.x(2, 0);
  r.scan();
  EXPECT_EQ(r.y(0), 0);
  EXPECT_EQ(r.y(1), 1);
  EXPECT_EQ(r.mem.get_bit(Area::M, 1), 1);  // RST needs power
  r.x(1, 0);
  r.scan();
  EXPECT_EQ(r.y(0), 1);
  EXPECT_EQ(r.mem.get_bit(Area::M, 0), 1);
  EXPECT_EQ(r.mem.get_bit(Area::M, 1), 0);
}

TEST(Interp, MpsMrdMpp) {
  Scan r(".rung line 1\nLOAD X0\nMPS\nAND X1\nOUT Y0\nMRD\nANDN X1\nOUT Y1\nMPP\nOUT Y2\n.end\n");
  r.x(0, 1); r.x(1, 0);
  r.scan();
  EXPECT_EQ(r.y(0), 0); EXPECT_EQ(r.y(1), 1); EXPECT_EQ(r.y(2), 1);
  r.x(0, 0);
  r.scan();
  EXPECT_EQ(r.y(1), 0); EXPECT_EQ(r.y(2), 0);
}

TEST(Interp, EdgesFireOnce) {
  Scan r(".edges 2\n.rung line 1\nLOADP X0 E0\nOUT Y0\nLOADF X0 E1\nOUT Y1\n.end\n");
  int seq[] = {0, 1, 1, 0, 0};
  int rise[] = {0, 1, 0, 0, 0}, fall[] = {0, 0, 0, 1, 0};
  for (int i = 0; i < 5; i++) {
    r.x(0, seq[i]);
    r.scan();
    EXPECT_EQ(r.y(0), rise[i]) << i;
    EXPECT_EQ(r.y(1), fall[i]) << i;
  }
}

TEST(Interp, TonStartsTimingOnTheRisingScan) {
  Scan r(".rung line 1\nLOAD X0\nTON T0 30\nLOAD T0\nOUT Y0\n.end\n");
  r.x(0, 1);
  int32_t et[] = {0, 10, 20, 30, 30};
  int q[] = {0, 0, 0, 1, 1};
  for (int i = 0; i < 5; i++) {
    r.scan();
    EXPECT_EQ(r.mem.get_int(Area::TW, 0), et[i]) << i;
    EXPECT_EQ(r.y(0), q[i]) << i;
  }
  r.x(0, 0);
  r.scan();
  EXPECT_EQ(r.mem.get_int(Area::TW, 0), 0);
  EXPECT_EQ(r.y(0), 0);
}

TEST(Interp, TonPresetZeroAndNegativeWord) {
  Scan r(".rung line 1\nLOAD X0\nTON T0 D0\n.end\n");
  r.mem.set_int(Area::D, 0, -5);
  r.x(0, 1);
  r.scan();
  EXPECT_EQ(r.mem.get_bit(Area::TQ, 0), 1);
}

TEST(Interp, TofHoldsThenDrops) {
  Scan r(".rung line 1\nLOAD X0\nTOF T1 20\n.end\n");
  int in[] = {1, 0, 0, 0, 1, 0, 0};
  int q[] = {1, 1, 1, 0, 1, 1, 1};
  int32_t et[] = {0, 0, 10, 20, 0, 0, 10};
  for (int i = 0; i < 7; i++) {
    r.x(0, in[i]);
    r.scan();
    EXPECT_EQ(r.mem.get_bit(Area::TQ, 1), q[i]) << i;
    EXPECT_EQ(r.mem.get_int(Area::TW, 1), et[i]) << i;
  }
}

TEST(Interp, TpIgnoresRetrigger) {
  Scan r(".rung line 1\nLOAD X0\nTP T2 30\n.end\n");
  int in[] = {1, 0, 1, 0, 0, 0, 1};
  int q[] = {1, 1, 1, 0, 0, 0, 1};
  for (int i = 0; i < 7; i++) {
    r.x(0, in[i]);
    r.scan();
    EXPECT_EQ(r.mem.get_bit(Area::TQ, 2), q[i]) << i;
  }
}

TEST(Interp, TimerDoesNotOverflow) {
  Scan r(".rung line 1\nLOAD X0\nTON T0 2147483647\n.end\n");
  r.x(0, 1);
  r.scan();
  r.scan(2147483000);
  r.scan(2147483000);
  EXPECT_EQ(r.mem.get_int(Area::TW, 0), 2147483647);
  EXPECT_EQ(r.mem.get_bit(Area::TQ, 0), 1);
}

TEST(Interp, CountersCountRisingEdges) {
  Scan r(".edges 2\n.rung line 1\nLOAD X0\nCTU C0 3 E0\n.rung line 2\nLOAD X1\nCTD C0 3 E1\n.rung line 3\nLOAD X2\nRSTC C0\n.end\n");
  int up[] = {1, 1, 0, 1, 0, 1};
  int32_t cv[] = {1, 1, 1, 2, 2, 3};
  for (int i = 0; i < 6; i++) {
    r.x(0, up[i]);
    r.scan();
    EXPECT_EQ(r.mem.get_int(Area::CW, 0), cv[i]) << i;
  }
  // the CTD rung runs last and decides the done bit: CV <= 0
  EXPECT_EQ(r.mem.get_bit(Area::CQ, 0), 0);
  r.x(2, 1);
  r.scan();
  EXPECT_EQ(r.mem.get_int(Area::CW, 0), 0);
  EXPECT_EQ(r.mem.get_bit(Area::CQ, 0), 0);
  r.x(2, 0);
  r.scan();
  EXPECT_EQ(r.mem.get_bit(Area::CQ, 0), 1);  // CTD: 0 <= 0
}

TEST(Interp, CounterSaturates) {
  Scan r(".edges 1\n.rung line 1\nLOAD X0\nCTU C0 5 E0\n.end\n");
  r.mem.set_int(Area::CW, 0, std::numeric_limits<int32_t>::max());
  r.x(0, 1);
  r.scan();
  EXPECT_EQ(r.mem.get_int(Area::CW, 0), std::numeric_limits<int32_t>::max());
}

TEST(Interp, IntArithmeticWrapsAndDivisionByZero) {
  Scan r(".rung line 1\nTRUE\nADD D0 1 D1\nMUL D0 2 D2\nDIV D3 D4 D5\nMOD D3 D4 D6\nDIV D0 -1 D7\nSUB D8 1 D8\n.end\n");
  r.mem.set_int(Area::D, 0, std::numeric_limits<int32_t>::max());
  r.mem.set_int(Area::D, 3, 7);
  r.mem.set_int(Area::D, 5, 42);
  r.mem.set_int(Area::D, 6, 43);
  r.mem.set_int(Area::D, 8, std::numeric_limits<int32_t>::min());
  r.scan();
  EXPECT_EQ(r.d(1), std::numeric_limits<int32_t>::min());
  EXPECT_EQ(r.d(2), -2);
  EXPECT_EQ(r.d(5), 42);  // unchanged
  EXPECT_EQ(r.d(6), 43);
  EXPECT_EQ(r.mem.get_bit(Area::S, kBitError), 1);
  EXPECT_EQ(r.d(7), -std::numeric_limits<int32_t>::max());
  EXPECT_EQ(r.d(8), std::numeric_limits<int32_t>::max());
}

TEST(Interp, IntMinDividedByMinusOne) {
  Scan r(".rung line 1\nTRUE\nDIV D0 -1 D1\nMOD D0 -1 D2\nDIV -7 2 D3\nMOD -7 2 D4\n.end\n");
  r.mem.set_int(Area::D, 0, std::numeric_limits<int32_t>::min());
  r.mem.set_int(Area::D, 2, 9);
  r.scan();
  EXPECT_EQ(r.d(1), std::numeric_limits<int32_t>::min());
  EXPECT_EQ(r.d(2), 0);
  EXPECT_EQ(r.d(3), -3);
  EXPECT_EQ(r.d(4), -1);
  EXPECT_EQ(r.mem.get_bit(Area::S, kBitError), 0);
}

TEST(Interp, ShiftsOutOfRangeGiveZero) {
  Scan r(".rung line 1\nTRUE\nSHL 1 31 D0\nSHL 1 32 D1\nSHR -1 28 D2\nSHR 5 -1 D3\nWNOT 0 D4\nWXOR 12 10 D5\n.end\n");
  r.mem.set_int(Area::D, 1, 99);
  r.scan();
  EXPECT_EQ(r.d(0), std::numeric_limits<int32_t>::min());
  EXPECT_EQ(r.d(1), 0);
  EXPECT_EQ(r.d(2), 15);
  EXPECT_EQ(r.d(3), 0);
  EXPECT_EQ(r.d(4), -1);
  EXPECT_EQ(r.d(5), 6);
}

TEST(Interp, RealConversions) {
  Scan r(".rung line 1\nTRUE\nMOV 3.75 D0\nMOV -3.75 D1\nMOV 1e+20 D2\nMOV -1e+20 D3\nMOV F0 D4\nMOV 7 F1\nADD D5 0.5 F2\n.end\n");
  r.mem.set_real(0, std::nanf(""));
  r.mem.set_int(Area::D, 5, 2);
  r.scan();
  EXPECT_EQ(r.d(0), 3);
  EXPECT_EQ(r.d(1), -3);
  EXPECT_EQ(r.d(2), std::numeric_limits<int32_t>::max());
  EXPECT_EQ(r.d(3), std::numeric_limits<int32_t>::min());
  EXPECT_EQ(r.d(4), 0);
  EXPECT_EQ(r.mem.get_real(1), 7.0f);
  EXPECT_EQ(r.mem.get_real(2), 2.5f);
}

TEST(Interp, RealDivisionByZeroAndNanCompares) {
  Scan r(".rung line 1\nTRUE\nDIV 1.0 -0.0 F1\n.rung line 2\nLDEQ F0 F0\nOUT Y0\nLDNE F0 F0\nOUT Y1\nLDLT F0 1.0\nOUT Y2\n.end\n");
  r.mem.set_real(0, std::nanf(""));
  r.mem.set_real(1, 5.0f);
  r.scan();
  EXPECT_EQ(r.mem.get_real(1), 5.0f);
  EXPECT_EQ(r.mem.get_bit(Area::S, kBitError), 1);
  EXPECT_EQ(r.y(0), 0);
  EXPECT_EQ(r.y(1), 1);
  EXPECT_EQ(r.y(2), 0);
}

TEST(Interp, MixedCompareIsReal) {
  Scan r(".rung line 1\nLDGT D0 1.5\nOUT Y0\nLDEQ D0 2\nOUT Y1\n.end\n");
  r.mem.set_int(Area::D, 0, 2);
  r.scan();
  EXPECT_EQ(r.y(0), 1);
  EXPECT_EQ(r.y(1), 1);
}

TEST(Interp, SpecialFunctions) {
  Scan r(".rung line 1\nTRUE\nSQRT 16 F0\nABS -2.5 F1\nABS D0 D1\nEXP 0.0 F2\nLN 1.0 F3\nSIN 0.0 F4\nCOS 0.0 F5\n.end\n");
  r.mem.set_int(Area::D, 0, std::numeric_limits<int32_t>::min());
  r.scan();
  EXPECT_EQ(r.mem.get_real(0), 4.0f);
  EXPECT_EQ(r.mem.get_real(1), 2.5f);
  EXPECT_EQ(r.d(1), std::numeric_limits<int32_t>::min());
  EXPECT_EQ(r.mem.get_real(2), 1.0f);
  EXPECT_EQ(r.mem.get_real(3), 0.0f);
  EXPECT_EQ(r.mem.get_real(4), 0.0f);
  EXPECT_EQ(r.mem.get_real(5), 1.0f);
}

TEST(Interp, ApplicationInstructionsNeedPower) {
  Scan r(".rung line 1\nLOAD X0\nMOV 5 D0\nDIV 1 0 D1\n.end\n");
  r.scan();
  EXPECT_EQ(r.d(0), 0);
  EXPECT_EQ(r.mem.get_bit(Area::S, kBitError), 0);
}

TEST(Interp, JumpSkipsRungsAndEndStopsTheScan) {
  Scan r(".rung line 1\nLOAD X0\nJMP L\n.rung line 2\nTRUE\nOUT Y0\n.label L\n.rung line 3\nLOAD X1\nEND\n.rung line 4\nTRUE\nOUT Y1\n.end\n");
  r.x(0, 1);
  r.scan();
  EXPECT_EQ(r.y(0), 0);
  EXPECT_EQ(r.y(1), 1);
  r.x(0, 0); r.x(1, 1);
  r.mem.set_bit(Area::Y, 1, 0);
  r.scan();
  EXPECT_EQ(r.y(0), 1);
  EXPECT_EQ(r.y(1), 0);
}

}  // namespace
