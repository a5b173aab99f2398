// ir/scanopt.h: the dead stores, unread stack entries, folded constants and
// repeated divisions of one scan, and the typed results already held, rule by rule, with the
// cases that must stay live beside each.
#include <gtest/gtest.h>

#include <string>

#include "ir/scanopt.h"

using namespace ldc;

namespace {

// The facts of an IL program given as rungs ("|" separates instructions).
struct Facts {
  Program prog;
  ScanFacts f;
  explicit Facts(const std::string& body, int slots = 3)
      : prog(parse_il_text(".edges 4\n" + body + ".end\n", "t.il")), f(scan_facts(prog, prog.layout(), slots)) {}
  uint8_t at(size_t rung, size_t k) const { return f.at(rung, k); }
  bool dead(size_t rung, size_t k) const { return at(rung, k) & kDeadStore; }
  bool unread(size_t rung, size_t k) const { return at(rung, k) & kUnread; }
  // the device the division at (rung, k) takes its result from ("q D5": a
  // remainder from the quotient in D5), "" if it divides
  std::string reused(size_t rung, size_t k) const {
    const DivReuse* r = f.reuse(rung, k);
    if (!r) return "";
    if (r->stored_early) return "early";
    Instr mov{Op::MOV, Ty::None, Ty::None, {r->from, r->from}, {}};
    std::string text = instr_text(mov);  // "MOV D5 D5": the device's name twice
    return (r->remainder_from_quotient ? "q " : "") + text.substr(text.rfind(' ') + 1);
  }
  std::string replaced(size_t rung, size_t k) const {
    const Instr* in = f.replacement(rung, k);
    return in ? instr_text(*in) : "";
  }
};

std::string rung(const std::string& code, const std::string& labels = "") {
  std::string s = labels;
  s += ".rung line 1\n";
  size_t at = 0;
  while (at <= code.size()) {
    size_t bar = code.find('|', at);
    if (bar == std::string::npos) bar = code.size();
    s += code.substr(at, bar - at) + "\n";
    at = bar + 1;
  }
  return s;
}

TEST(ScanFacts, AnOutputOverwrittenUnreadIsDead) {
  Facts t(rung("LOAD X0|OUT Y0") + rung("LOAD X1|OUT Y0"));
  EXPECT_TRUE(t.dead(0, 1));
  EXPECT_FALSE(t.dead(1, 1));  // the last store is what the scan leaves
  // the contact that fed it is read by nothing now
  EXPECT_TRUE(t.unread(0, 0));
  EXPECT_FALSE(t.unread(1, 0));
}

TEST(ScanFacts, AReadBetweenKeepsTheStore) {
  Facts t(rung("LOAD X0|OUT Y0") + rung("LOAD Y0|OUT Y1") + rung("LOAD X1|OUT Y0"));
  EXPECT_FALSE(t.dead(0, 1));
  Facts words(rung("LOAD X0|MOV 5 D0") + rung("LDGT D0 3|OUT Y1") + rung("TRUE|MOV 6 D0"));
  EXPECT_FALSE(words.dead(0, 1));
  Facts timer(rung("LOAD X0|MOV 5 T0") + rung("LOAD X1|TON T0 100") + rung("TRUE|MOV 6 T0"));
  EXPECT_FALSE(timer.dead(0, 1));  // the timer reads its elapsed time
}

TEST(ScanFacts, AJumpOrEndBetweenKeepsTheStore) {
  Facts jmp(rung("LOAD X0|OUT Y0") + rung("LOAD X2|JMP L") + rung("LOAD X1|OUT Y0") + rung("LOAD X3|OUT Y3", ".label L\n"));
  EXPECT_FALSE(jmp.dead(0, 1));
  // the store the jump skips is overwritten on its own path: a label needs nothing
  Facts skipped(rung("LOAD X2|JMP L") + rung("LOAD X0|OUT Y0") + rung("LOAD X1|OUT Y0", ".label L\n"));
  EXPECT_TRUE(skipped.dead(1, 1));
  Facts end(rung("LOAD X0|OUT Y0") + rung("LOAD X2|END") + rung("LOAD X1|OUT Y0"));
  EXPECT_FALSE(end.dead(0, 1));
}

TEST(ScanFacts, OnlyACertainStoreKills) {
  Facts set(rung("LOAD X0|OUT Y0") + rung("LOAD X1|SET Y0"));
  EXPECT_FALSE(set.dead(0, 1));  // SET writes only with power
  Facts set_first(rung("LOAD X0|SET Y0") + rung("LOAD X1|OUTN Y0"));
  EXPECT_TRUE(set_first.dead(0, 1));
  Facts gated(rung("LOAD X0|MOV 5 D0") + rung("LOAD X1|MOV 6 D0"));
  EXPECT_FALSE(gated.dead(0, 1));  // the power of the second MOV is not known
  Facts powered(rung("LOAD X0|MOV 5 D0") + rung("TRUE|ADD D1 D2 D0"));
  EXPECT_TRUE(powered.dead(0, 1));
  Facts div(rung("LOAD X0|MOV 5 D0") + rung("TRUE|DIV D1 D2 D0"));
  EXPECT_FALSE(div.dead(0, 1));  // a zero divisor keeps D0
  Facts div_dead(rung("TRUE|DIV D1 D2 D0") + rung("TRUE|MOV 6 D0"));
  EXPECT_FALSE(div_dead.dead(0, 1));  // and may set S0
}

TEST(ScanFacts, UnreadStackEntries) {
  Facts mpp(rung("LOAD X0|LDGT D1 5|MPP|OUT Y0"));
  EXPECT_TRUE(mpp.unread(0, 1));
  EXPECT_FALSE(mpp.unread(0, 0));
  Facts tail(rung("LOAD X0|OUT Y0|LOAD X1|AND X2"));
  EXPECT_TRUE(tail.unread(0, 2));
  EXPECT_TRUE(tail.unread(0, 3));
  Facts edge(rung("LOADP X0 E0|LOAD X1|OUT Y0"));
  EXPECT_TRUE(edge.unread(0, 0));  // flagged; the code generator keeps the edge update
  Facts block(rung("LOAD X0|LOAD X1|LOAD X2|ORBLK|ANDBLK|OUT Y0"));
  for (size_t k = 0; k < 6; k++) EXPECT_EQ(block.at(0, k), 0) << k;
  Facts mrd(rung("LOAD X0|MPS|AND X1|OUT Y0|MRD|AND X2|OUT Y1|MPP|OUT Y2"));
  for (size_t k = 0; k < 9; k++) EXPECT_EQ(mrd.at(0, k), 0) << k;
}

TEST(ScanFacts, NoUnreadFlagsWhereTheStackIsNotPrivate) {
  std::string deep = "LOAD X0|LOAD X1|LOAD X2|LOAD X3|ANDBLK|ANDBLK|ANDBLK|OUT Y0|LOAD X4";
  Facts three(rung(deep), 3);
  EXPECT_FALSE(three.unread(0, 8));  // four live entries do not fit three slots
  Facts five(rung(deep), 5);
  EXPECT_TRUE(five.unread(0, 8));
}

TEST(ScanFacts, ConstantsFoldByTheInterpreter) {
  Facts t(rung("LOAD X0|ADD 2 3 D0|SHL 1 31 D1|DIV 7 2 D2|DIV 7 0 D3|MOD -7 2 D4|SQRT 4.0 F0|SIN 1.0 F1|"
               "ADD 1.5 2 D5|MUL 2147483647 2 D6|MOV 3 D7"));
  EXPECT_EQ(t.replaced(0, 1), "MOV 5 D0");
  EXPECT_EQ(t.replaced(0, 2), "MOV -2147483648 D1");
  EXPECT_EQ(t.replaced(0, 3), "MOV 3 D2");
  EXPECT_EQ(t.replaced(0, 4), "");  // sets S0
  EXPECT_EQ(t.replaced(0, 5), "MOV -1 D4");
  EXPECT_EQ(t.replaced(0, 6), "MOV 2.0 F0");
  EXPECT_EQ(t.replaced(0, 7), "");  // the running machine's sinf decides
  EXPECT_EQ(t.replaced(0, 8), "MOV 3 D5");  // REAL 3.5, truncated
  EXPECT_EQ(t.replaced(0, 9), "MOV -2 D6");
  EXPECT_EQ(t.replaced(0, 10), "");  // already a constant move
}

TEST(ScanFacts, KnownWordsAfterACertainStore) {
  Facts t(rung("TRUE|MOV 7 D1|MOV 2.5 F1") + rung("LOAD X0|ADD D1 1 D2|MUL F1 D9 D3|MOV D1 F4"));
  EXPECT_EQ(t.replaced(1, 1), "MOV 8 D2");
  EXPECT_EQ(t.replaced(1, 2), "MUL 2.5 D9 D3");
  EXPECT_EQ(t.replaced(1, 3), "MOV 7.0 F4");
  Facts gated(rung("LOAD X1|MOV 7 D1") + rung("LOAD X0|ADD D1 1 D2"));
  EXPECT_EQ(gated.replaced(1, 1), "");  // D1 was written only with power
  Facts label(rung("TRUE|MOV 7 D1") + rung("LOAD X2|JMP L") + rung("LOAD X0|ADD D1 1 D2", ".label L\n"));
  EXPECT_EQ(label.replaced(2, 1), "");  // a jump lands here from before the store
  Facts overwritten(rung("TRUE|MOV 7 D1") + rung("LOAD X1|ADD D5 D6 D1") + rung("LOAD X0|ADD D1 1 D2"));
  EXPECT_EQ(overwritten.replaced(2, 1), "");
  Facts timer(rung("TRUE|MOV 7 T0") + rung("LOAD X1|TON T0 100") + rung("LOAD X0|ADD T0 1 D2"));
  EXPECT_EQ(timer.replaced(2, 1), "");
  Facts chain(rung("TRUE|MOV 7 D1|ADD D1 D1 D2|MUL D2 D1 D3") + rung("LOAD X0|MOV D3 D4"));
  EXPECT_EQ(chain.replaced(0, 3), "MOV 98 D3");
  EXPECT_EQ(chain.replaced(1, 1), "MOV 98 D4");
}

TEST(ScanFacts, ARepeatedDivisionTakesTheEarlierResult) {
  Facts t(rung("TRUE|DIV WX0 WX1 D1|DIV WX0 WX1 D2|MOD WX0 WX1 D3|MOD WX0 WX1 D4|MOD WX2 WX3 D5|DIV WX2 WX3 D6"));
  EXPECT_EQ(t.reused(0, 2), "D1");
  EXPECT_EQ(t.reused(0, 3), "q D2");  // a - q*b: the latest quotient
  EXPECT_EQ(t.reused(0, 4), "D3");    // the same remainder
  EXPECT_EQ(t.reused(0, 6), "early");  // a DIV after a MOD: the MOD stores the quotient too
  Facts gated(rung("LOAD X0|DIV WX0 WX1 D1") + rung("TRUE|DIV WX0 WX1 D2"));
  EXPECT_EQ(gated.reused(1, 1), "");  // D1 was written only with power
  Facts written(rung("TRUE|DIV D0 WX1 D1|MOV WX5 D0|DIV D0 WX1 D2|DIV WX0 WX1 D3|ADD D3 1 D3|DIV WX0 WX1 D4"));
  EXPECT_EQ(written.reused(0, 3), "");  // an operand written since
  EXPECT_EQ(written.reused(0, 6), "");  // the earlier destination written since
  Facts self(rung("TRUE|DIV D0 WX1 D0|DIV D0 WX1 D2"));
  EXPECT_EQ(self.reused(0, 2), "");  // the destination was an operand
  Facts s0(rung("TRUE|DIV WX0 WX1 D1|RST S0|DIV WX0 WX1 D2"));
  EXPECT_EQ(s0.reused(0, 3), "");  // a zero divisor must set S0 again
  Facts label(rung("TRUE|DIV WX0 WX1 D1") + rung("LOAD X2|JMP L") + rung("TRUE|DIV WX0 WX1 D2", ".label L\n"));
  EXPECT_EQ(label.reused(2, 1), "");  // a jump lands here from before the division
  Facts early(rung("TRUE|MOD WX0 WX1 D1|ADD D7 1 D8|DIV WX0 WX1 D2"));
  EXPECT_EQ(early.reused(0, 3), "early");  // the MOD stores the quotient into D2 too
  ASSERT_NE(early.f.quotient_to(0, 1), nullptr);
  EXPECT_EQ(early.f.quotient_to(0, 1)->index, 2u);
  for (const char* between : {"MOV D2 D9", "MOV 1 D2", "LOAD X1|JMP L", "LOAD X1|END"}) {
    Facts touched(rung(std::string("TRUE|MOD WX0 WX1 D1|") + between + "|TRUE|DIV WX0 WX1 D2") + rung("TRUE", ".label L\n"));
    EXPECT_EQ(touched.reused(0, 3 + (std::string(between).find('|') != std::string::npos)), "") << between;
    EXPECT_EQ(touched.f.quotient_to(0, 1), nullptr) << between;
  }
  Facts copy(rung("TRUE|MOD WX0 WX1 D1|MOD WX0 WX1 D3|DIV WX0 WX1 D2"));
  EXPECT_EQ(copy.reused(0, 2), "D1");
  EXPECT_EQ(copy.reused(0, 3), "");  // the latest MOD is a copy: it has no quotient to store
  Facts own(rung("TRUE|MOD WX0 WX1 D1|DIV WX0 WX1 D1"));
  EXPECT_EQ(own.reused(0, 2), "");  // the MOD's own destination
  Facts real(rung("TRUE|DIV WX0 WX1 F1|DIV WX0 WX1 D2|DIV WX0 WX1 F2"));
  EXPECT_EQ(real.reused(0, 2), "");  // F1 holds the quotient converted
  EXPECT_EQ(real.reused(0, 3), "");  // into a REAL: not taken
}

// kHeld: a typed instruction identical to one that ran with power on for
// certain earlier in the scan, neither its sources nor that destination
// written since, stores what the destination holds.
TEST(ScanFacts, ATypedResultTheDestinationHoldsNeedsNoCode) {
  auto held = [](const Facts& t, size_t r, size_t k) { return (t.at(r, k) & kHeld) != 0; };
  Facts t(rung("TRUE|ADD.INT D0 D2 D4|MUL.LREAL D6 D8 D10|CONV.DINT.LREAL D6 D12") +
          rung("LOAD X0|ADD.INT D0 D2 D4|MUL.LREAL D6 D8 D10|CONV.DINT.LREAL D6 D12|DIV.LREAL D6 D8 D14") +
          rung("TRUE|DIV.LREAL D6 D8 D14|DIV.LREAL D6 D8 D14|DIV.INT D0 D2 D16|DIV.INT D0 D2 D16|MOD.DINT D0 D2 D17|MOD.DINT D0 D2 D17"));
  EXPECT_TRUE(held(t, 1, 1));   // with power or without: the same bits
  EXPECT_TRUE(held(t, 1, 2));   // an LREAL
  EXPECT_TRUE(held(t, 1, 3));   // a conversion
  EXPECT_FALSE(held(t, 1, 4));  // its first with power unknown: it may not have run
  EXPECT_FALSE(held(t, 2, 1));  // the one before was gated
  EXPECT_TRUE(held(t, 2, 2));   // a real DIV has no other effect
  EXPECT_FALSE(held(t, 2, 4));  // an integer DIV or MOD may set S0
  EXPECT_FALSE(held(t, 2, 6));
  EXPECT_FALSE(held(t, 0, 1));  // the first of each
  // what kills it: a source or the destination written (typed or not, one
  // byte of a 64-bit value), the destination one of the sources, a label
  struct Case {
    const char* between;
    bool int_held, real_held;  // ADD.INT D0 D2 D4, MUL.LREAL D6 D8 D10 (D6..D11)
  };
  for (const Case& c : {Case{"MOV 5 D2", false, true}, Case{"ADD.INT D0 1 D0", false, true}, Case{"MOV 5 D4", false, true},
                        Case{"MOVE.SINT D20 D4", false, true}, Case{"MOVE.LINT D20 D1", false, true},  // D1..D2
                        Case{"MOV 1 D9", true, false},            // D8's second cell
                        Case{"MOVE.LINT D20 D7", true, false},    // D6's second cell
                        Case{"MOV 1 D11", true, false},           // the destination's second cell
                        Case{"MOVE.LINT D20 D12", true, true},    // next to both
                        Case{"IDX.INT D30 0 3|STX.DINT D31 D0 1", false, true},  // any of D0..D3
                        Case{"LOAD X1|END", true, true}}) {  // leaves before either: nothing to kill
    Facts k(rung("TRUE|ADD.INT D0 D2 D4|MUL.LREAL D6 D8 D10") + rung(std::string("TRUE|") + c.between) +
            rung("TRUE|ADD.INT D0 D2 D4|MUL.LREAL D6 D8 D10"));
    EXPECT_EQ(held(k, 2, 1), c.int_held) << c.between;
    EXPECT_EQ(held(k, 2, 2), c.real_held) << c.between;
  }
  Facts self(rung("TRUE|ADD.INT D5 1 D5|ADD.INT D5 1 D5"));
  EXPECT_FALSE(held(self, 0, 2));  // the destination is a source: it changed
  Facts label(rung("TRUE|ADD.INT D0 D2 D4") + rung("LOAD X2|JMP L") + rung("TRUE|ADD.INT D0 D2 D4", ".label L\n"));
  EXPECT_FALSE(held(label, 2, 1));  // a jump lands here from before it ran
  Facts other(rung("TRUE|ADD.INT D0 D2 D4|ADD.DINT D0 D2 D4|SUB.INT D0 D2 D6|SUB.INT D2 D0 D6"));
  EXPECT_FALSE(held(other, 0, 2));  // not the same instruction: another type
  EXPECT_FALSE(held(other, 0, 4));  // nor other operands
  Facts array(rung("TRUE|MOVE.LREAL D40 D50|MOVE.LREAL D40 D60") + rung("TRUE|IDX.INT D30 0 3|STX.LREAL D20 D50 2") +
              rung("TRUE|MOVE.LREAL D40 D50|MOVE.LREAL D40 D60"));
  EXPECT_FALSE(held(array, 2, 1));  // STX may store into D50..D57
  EXPECT_TRUE(held(array, 2, 2));   // not into D60
  Facts cmp(rung("TRUE|LT.INT D0 5|OUT Y0|LT.INT D0 5|OUT Y1"));
  EXPECT_EQ(cmp.at(0, 3) & kHeld, 0);  // a compare pushes: it keeps its code
}

}  // namespace
