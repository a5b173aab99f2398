// tests/ir/ladder_test.cpp -- raising IL to rung trees and drawing them
// (ir/ladder.h): exact round trips through the grid reader, refusals, and the
// geometry the monitor draws from.
#include <gtest/gtest.h>

#include "frontend/frontend.h"
#include "ir/ladder.h"

using namespace ldc;

namespace {

std::string grid_of(const Program& p) { return print_ladder(draw_ladder(raise_to_tree(p)), "t.il"); }

// IL text without line numbers (they name the source's lines, not the grid's)
std::string il_body(Program p) {
  for (Rung& r : p.rungs) r.line = 0;
  p.source = "";
  return print_il_text(p);
}

void expect_round_trip(const std::string& il) {
  Program p = parse_il_text(il, "t.il");
  std::string grid = grid_of(p);
  Program q = lower_to_il(parse_ld(grid, "t.ld"));
  EXPECT_EQ(il_body(p), il_body(q)) << grid;
  // lowered rung by rung as it is read: the same IL, line numbers, labels and edge slots included
  EXPECT_EQ(print_il_text(q), print_il_text(parse_ld_to_il(grid, "t.ld"))) << grid;
}

std::string refusal(const std::string& il) {
  Program p = parse_il_text(il, "t.il");
  try {
    grid_of(p);
  } catch (CompileError& e) { return e.what(); }
  return "(drawn)";
}

}  // namespace

TEST(Ladder, SeriesParallelForks) {
  expect_round_trip(
      ".rung line 1\n LOAD X1\n LOAD X2\n LOAD X3\n AND X4\n ORBLK\n ANDBLK\n OUT Y1\n"
      ".rung line 2\n LOAD X1\n MPS\n AND X2\n OUT Y1\n MRD\n ANDN X2\n OUT Y2\n MPP\n SET M5\n"
      ".rung line 3\n TRUE\n OUT Y3\n TRUE\n OUT Y4\n LOAD X5\n OUT Y5\n.end\n");
}

TEST(Ladder, NestedParallelsOfSeries) {
  // (X0 (X1 | X2) | X3 (X4 | X5 X6)) -- parallels side by side and one below another
  expect_round_trip(
      ".rung line 1\n LOAD X0\n LOAD X1\n OR X2\n ANDBLK\n LOAD X3\n LOAD X4\n LOAD X5\n AND X6\n ORBLK\n"
      " ANDBLK\n ORBLK\n LOAD X7\n OR X8\n ANDBLK\n OUT Y0\n.end\n");
}

TEST(Ladder, AlwaysClosedContactInSeries) {
  // an SFC transition TRUE: TRUE then AND -- drawn as [TRUE]
  Program p = parse_il_text(".rung line 1\n TRUE\n AND M1\n OUT Y0\n.end\n", "t.il");
  EXPECT_NE(grid_of(p).find("|--[TRUE]--[M1]--(Y0)"), std::string::npos) << grid_of(p);
  expect_round_trip(".rung line 1\n TRUE\n AND M1\n OUT Y0\n.end\n");
}

TEST(Ladder, ElementsJumpsTimersAndAliases) {
  expect_round_trip(
      ".edges 2\n.alias start X0\n.alias count D7\n.retain D7\n"
      ".rung line 1 \"first\"\n LOADP X0 E0\n CTU C0 10 E1\n"
      ".rung line 2\n LDGE D7 1.5\n MOV 2.5 F1\n"
      ".rung line 3\n LOAD X1\n JMP skip\n"
      ".rung line 4\n LOAD X2\n TON T0 500\n"
      ".label skip\n.rung line 5\n LOAD T0\n RSTT T0\n WAND D1 255 D2\n.end\n");
  Program p = parse_il_text(".alias start X0\n.rung line 1\n LOADN X0\n OUT Y0\n.end\n", "t.il");
  EXPECT_NE(grid_of(p).find("[/start]"), std::string::npos);
}

TEST(Ladder, RefusedByName) {
  EXPECT_NE(refusal(".rung line 1\n LOAD X0\n OUT Y0\n OR X1\n OUT Y1\n.end\n").find("instruction 3 'OR X1'"),
            std::string::npos);
  EXPECT_NE(refusal(".rung line 1\n LOAD X0\n OUT Y0\n.rung line 2\n OUT Y1\n.end\n")
                .find("rung 2, instruction 1 'OUT Y1': it reads the bit stack an earlier rung left"),
            std::string::npos);
  EXPECT_NE(refusal(".rung line 1\n LOAD X0\n MPS\n OUT Y0\n OUT Y1\n.end\n").find("MPS without its MPP"),
            std::string::npos);
  EXPECT_NE(refusal(".rung line 1\n LOAD X0\n LOAD X1\n.end\n").find("has no ladder form"), std::string::npos);
}

TEST(Ladder, GeometryMatchesTheText) {
  Program p = parse_il_text(
      ".rung line 1\n LOAD X1\n LOAD X2\n LOAD X3\n AND X4\n ORBLK\n ANDBLK\n MPS\n OUT Y1\n MPP\n AND X5\n OUT Y2\n.end\n",
      "t.il");
  Ladder l = draw_ladder(raise_to_tree(p));
  ASSERT_EQ(l.rungs.size(), 1u);
  const LadderRung& r = l.rungs[0];
  ASSERT_EQ(r.elems.size(), 7u);
  for (const LadderElem& e : r.elems) {
    EXPECT_EQ(r.rows[size_t(e.row)].substr(size_t(e.col), size_t(e.width)), e.text);
    if (!e.output) {
      EXPECT_NE(e.in_net, e.out_net);
    }
  }
  for (const LadderWire& w : r.wires)
    for (int c = w.col0; c <= w.col1; c++) EXPECT_NE(std::string("-+").find(r.rows[size_t(w.row)][size_t(c)]), std::string::npos);
  for (const LadderLink& k : r.links)
    for (int row = k.row0; row <= k.row1; row++) EXPECT_NE(std::string("|+").find(r.rows[size_t(row)][size_t(k.col)]), std::string::npos);
  // X2 and X3 (in parallel) leave the same net and arrive at the same one
  const LadderElem *x2 = nullptr, *x4 = nullptr, *x5 = nullptr;
  for (const LadderElem& e : r.elems) {
    if (e.text == "[X2]") x2 = &e;
    if (e.text == "[X4]") x4 = &e;
    if (e.text == "[X5]") x5 = &e;
  }
  ASSERT_TRUE(x2 && x4 && x5);
  EXPECT_EQ(x2->out_net, x4->out_net);
  EXPECT_NE(x5->in_net, 0);
}
