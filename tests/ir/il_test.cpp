// IL text and binary forms, the validator, and lowering limits.
#include <gtest/gtest.h>

#include <cctype>
#include <cmath>
#include <thread>

#include "ir/ir.h"

using namespace ldc;

namespace {

const char* kAll =
    ".edges 3\n.alias start X0\n.label top\n.rung line 4 \"all \\\"ops\\\"\"\n"
    "LOAD X0\nLOADN Y1\nAND M2\nANDN K3\nOR S0\nORN T4\nLOADP C5 E0\nLOADF X6 E1\nTRUE\nANDBLK\nORBLK\n"
    "MPS\nMRD\nMPP\nOUT Y0\nOUTN M1\nSET K2\nRST S0\nLDEQ D0 5\nLDNE F1 2.5\nLDLT WX0 WY1\nLDLE T0 C0\n"
    "LDGT D1 -7\nLDGE F2 1e+30\nMOV D0 F0\nADD D0 D1 D2\nSUB 1 2 D3\nMUL F0 F1 F2\nDIV D0 3 WY0\nMOD D0 3 D4\n"
    "WAND D0 255 D5\nWOR D0 1 D6\nWXOR D0 1 D7\nWNOT D0 D8\nSHL D0 3 D9\nSHR D0 3 D10\nSIN F0 F3\nCOS F0 F4\n"
    "TAN F0 F5\nSQRT F0 F6\nEXP F0 F7\nLN F0 F8\nABS D0 D11\nTON T0 100\nTOF T1 D0\nTP T2 5\nRSTT T3\n"
    "MTON T4 0\nMTOF T5 D0\nMTP T6 5\n"
    "CTU C0 10 E2\nCTD C1 D3\n"
    "MOVE.INT -5 D20\nADD.DINT D20 7 D21\nSUB.LINT D22 -9000000000 D24\nMUL.LREAL D26 1.5e-09 D28\n"
    "DIV.UINT D20 3 D30\nMOD.SINT D20 3 D31\nMIN.REAL F0 2.5 F9\nMAX.TIME D22 3500000 D32\nEXPT.REAL F0 2 F10\n"
    "AND.BOOL M0 1 M1\nOR.WORD D20 255 D33\nXOR.LWORD D22 1 D34\nNOT.BYTE D20 D36\nSHL.WORD.INT D20 3 D37\n"
    "SHR.DWORD.USINT D20 D20 D38\nROL.BYTE.DINT D20 -1 D39\nROR.LWORD.UDINT D22 65 D40\nNEG.LINT D22 D42\n"
    "ABS.INT D20 D44\nSQRT.REAL F0 F11\nLN.LREAL D26 D46\nLOG.REAL F0 F12\nEXP.REAL F0 F13\nSIN.LREAL D26 D48\n"
    "COS.REAL F0 F14\nTAN.REAL F0 F15\nASIN.REAL F0 F16\nACOS.REAL F0 F17\nATAN.LREAL D26 D50\n"
    "CONV.DINT.REAL F0 D52\nTRUNC.INT.LREAL D26 D53\nEQ.INT D20 -5\nNE.BOOL M0 X1\nLT.ULINT D22 18446744073709551615\n"
    "LE.DT D22 D24\nGT.TOD D22 0\nGE.USINT D20 200\nIDX.DINT D21 1 10\nLDX.INT D100 2 D54\nIDX.UINT D20 0 3\n"
    "STX.BOOL M3 M10 1\n"
    "LEN.INT.STRING D300 D60\nLEFT.STRING.INT D300 3 D340\nRIGHT.STRING.DINT D300 D21 D340\n"
    "CONCAT.STRING D300 D340 D380\nFIND.UINT.STRING D300 D340 D61\nARGS.DINT 1 2\nMID.STRING D300 D380\n"
    "ARGS.INT 1 D62\nDELETE.STRING D300 D380\nARGS.DINT 0 2\nINSERT.STRING D300 D340 D380\n"
    "ARGS.LINT 1 2\nREPLACE.STRING D300 D340 D380\n";

// A label operand's name is interned: equal text, equal (4-byte) names, and
// the text comes back, from several threads at once.
TEST(LabelText, InternedNamesKeepTheirText) {
  static_assert(sizeof(LabelText) == 4 && sizeof(Operand) == 12 && sizeof(Instr) == 48);
  EXPECT_TRUE(LabelText{}.empty());
  EXPECT_TRUE(Operand{OpdKind::Label}.label.empty());
  EXPECT_TRUE(LabelText("").empty());
  EXPECT_EQ(LabelText("").str(), "");
  std::vector<std::vector<LabelText>> made(4);
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; t++)
    threads.emplace_back([&made, t] {
      for (int i = 0; i < 3000; i++) made[size_t(t)].push_back(LabelText("lbl" + std::to_string((i * 7 + t) % 2500)));
    });
  for (auto& th : threads) th.join();
  for (int t = 0; t < 4; t++)
    for (int i = 0; i < 3000; i++) {
      const LabelText& l = made[size_t(t)][size_t(i)];
      ASSERT_EQ(l.str(), "lbl" + std::to_string((i * 7 + t) % 2500));
      EXPECT_EQ(l, LabelText(l.str()));
      EXPECT_FALSE(l == LabelText(l.str() + "x"));
    }
}

// An operand's constant and label share a union: == compares the one its kind has.
TEST(Operand, EqualityComparesTheValueOfItsKind) {
  auto k = [](OpdKind kind) { return Operand{kind}; };
  Operand i5 = k(OpdKind::ConstInt), i6 = k(OpdKind::ConstInt), r = k(OpdKind::ConstReal), r2 = k(OpdKind::ConstReal);
  i5.ival = 5, i6.ival = 6;
  EXPECT_EQ(i5, i5);
  EXPECT_FALSE(i5 == i6);
  r.fval = 0.0f, r2.fval = -0.0f;
  EXPECT_EQ(r, r2);  // as floats: -0 == 0
  r.fval = r2.fval = std::nanf("");
  EXPECT_FALSE(r == r2);  // and NaN is unequal to itself, as before
  Operand a = k(OpdKind::Label), b = k(OpdKind::Label);
  EXPECT_EQ(a, b);
  a.label = "x";
  EXPECT_FALSE(a == b);
  b.label = std::string("x");
  EXPECT_EQ(a, b);
  Operand zero_int = k(OpdKind::ConstInt), zero_real = k(OpdKind::ConstReal);
  zero_real.fval = 0;
  EXPECT_FALSE(zero_int == zero_real);  // the kinds differ
  Operand d = k(OpdKind::Int);
  d.area = Area::D, d.index = 3;
  Operand d4 = d;
  d4.index = 4;
  EXPECT_FALSE(d == d4);
}

TEST(IlText, EveryMnemonicRoundTrips) {
  // CTD above lacks its edge operand: the reader must say so
  EXPECT_THROW(parse_il_text(std::string(kAll) + ".end\n", "a.il"), CompileError);
  std::string text = std::string(kAll);
  text.replace(text.find("CTD C1 D3"), 9, "CTD C1 D3 E2");
  text += "RSTC C1\nJMP out\nEND\nLOOP top\n.label out\n.end\n";
  Program p = parse_il_text(text, "a.il");
  // IDX twice: before LDX and before STX; ARGS four times: before MID, DELETE, INSERT, REPLACE
  EXPECT_EQ(p.rungs[0].code.size(), size_t(kOpCount) + 1 + 3);
  std::string printed = print_il_text(p);
  Program q = parse_il_text(printed, "a.il");
  EXPECT_EQ(print_il_text(q), printed);
  ASSERT_EQ(q.rungs.size(), 1u);
  EXPECT_EQ(q.rungs[0].code, p.rungs[0].code);
  EXPECT_EQ(q.rungs[0].title, "all \"ops\"");
  EXPECT_EQ(q.aliases, p.aliases);
  // binary: encode, validate, decode back every instruction
  BinaryIl b = encode_il(p);
  EXPECT_EQ(validate_il(b.code, p.layout()), "");
  uint32_t off = 0;
  for (const Instr& in : p.rungs[0].code) {
    Instr got;
    off = decode_instr(b.code, off, got);
    if (in.op != Op::JMP && in.op != Op::LOOP) {  // a label decodes as its offset
      EXPECT_EQ(instr_text(got), instr_text(in));
    }
  }
  EXPECT_EQ(off, b.code.size());
}

// op_from_name's hash table (ir.cpp): every mnemonic in any case, and
// near misses (an extra letter, too long, empty) refused, a letter less
// found only when it is another mnemonic.
TEST(IlText, OpFromNameFindsEveryMnemonicAndNothingElse) {
  for (int i = 0; i < kOpCount; i++) {
    std::string name = kOps[i].name, lower = name;
    for (char& c : lower) c = char(std::tolower((unsigned char)c));
    EXPECT_EQ(op_from_name(name), Op(i)) << name;
    EXPECT_EQ(op_from_name(lower), Op(i)) << lower;
    EXPECT_EQ(op_from_name(name + "Q"), std::nullopt) << name;
    for (const std::string& miss : {name.substr(1), name.substr(0, name.size() - 1)}) {
      auto got = op_from_name(miss);  // only the op of exactly that name, if any
      if (got) {
        EXPECT_EQ(std::string(kOps[int(*got)].name), miss);
      }
    }
  }
  EXPECT_EQ(op_from_name(""), std::nullopt);
  EXPECT_EQ(op_from_name("LOADLOADLOADLOADL"), std::nullopt);
  EXPECT_EQ(op_from_name("LOA"), std::nullopt);
  EXPECT_EQ(op_from_name(std::string_view("AND\0", 4)), std::nullopt);  // the length is part of the key
  EXPECT_EQ(op_from_name(std::string_view("AN\0", 3)), std::nullopt);
}

// parse_device: every device name in either case, with its index.
TEST(IlText, ParseDeviceReadsEveryName) {
  for (int d = 0; d <= int(Dev::F); d++) {
    std::string name = dev_name(Dev(d)), lower = name;
    for (char& c : lower) c = char(std::tolower((unsigned char)c));
    for (const std::string& n : {name, lower}) {
      auto r = parse_device(n + "12");
      ASSERT_TRUE(r.has_value()) << n;
      EXPECT_EQ(r->dev, Dev(d));
      EXPECT_EQ(r->index, 12u);
    }
  }
  EXPECT_EQ(parse_device("Q1"), std::nullopt);
  EXPECT_EQ(parse_device("WZ1"), std::nullopt);
  EXPECT_EQ(parse_device("X"), std::nullopt);
  EXPECT_EQ(parse_device("D999999999")->index, 999999999u);
  EXPECT_EQ(parse_device("d0000000000")->index, UINT32_MAX);  // ten digits: out of range
  EXPECT_EQ(parse_device("X99999999999999999999")->index, UINT32_MAX);
  EXPECT_EQ(parse_device("D12a"), std::nullopt);
  EXPECT_EQ(parse_device("XYZ1"), std::nullopt);
}

TEST(IlText, ErrorsCarryLineAndColumn) {
  try {
    parse_il_text(".rung line 1\nLOAD X0\nOUT X1\n.end\n", "b.il");
    FAIL();
  } catch (CompileError& e) {
    EXPECT_EQ(e.line, 3);
    EXPECT_EQ(e.col, 5);
  }
  EXPECT_THROW(parse_il_text(".rung line 1\nFOO X0\n.end\n", "b.il"), CompileError);
  EXPECT_THROW(parse_il_text(".rung line 1\nLOAD X9000\n.end\n", "b.il"), CompileError);
  EXPECT_THROW(parse_il_text(".rung line 1\nMOD F0 1 D0\n.end\n", "b.il"), CompileError);
  EXPECT_THROW(parse_il_text(".rung line 1\nLOAD X0\n", "b.il"), CompileError);  // no .end
  EXPECT_THROW(parse_il_text(".label a\n.rung line 1\nLOAD X0\nJMP a\n.end\n", "b.il"), CompileError);
  EXPECT_THROW(parse_il_text(".rung line 1\nLOAD X0\nJMP nowhere\n.end\n", "b.il"), CompileError);
}

// INT32 constants are what strtoll (base 10) takes whole, inside INT32: one
// sign, '+' included; mnemonics are found in any case; labels are unique.
TEST(IlText, ConstantsMnemonicsAndLabels) {
  auto constant = [](const std::string& c) {
    Program p = parse_il_text(".rung line 1\nLOAD X0\nMOV " + c + " D0\n.end\n", "c.il");
    return p.rungs[0].code[1].a[0];
  };
  EXPECT_EQ(constant("+7").ival, 7);
  EXPECT_EQ(constant("-2147483648").ival, INT32_MIN);
  EXPECT_EQ(constant("2147483647").ival, INT32_MAX);
  EXPECT_EQ(constant("007").ival, 7);
  // either side of the one-pass reading of '-' and 1 to 9 digits (parse_number)
  EXPECT_EQ(constant("-0").ival, 0);
  EXPECT_EQ(constant("999999999").ival, 999999999);
  EXPECT_EQ(constant("-999999999").ival, -999999999);
  EXPECT_EQ(constant("1000000000").ival, 1000000000);
  EXPECT_EQ(constant("-0000000001").ival, -1);
  EXPECT_EQ(constant("1e3").kind, OpdKind::ConstReal);
  EXPECT_EQ(constant("-.5").fval, -0.5f);
  for (const char* bad : {"2147483648", "-2147483649", "5-", "1-2", "+-5", "++5", "--5", "-+5", "+", "-", "0x10", "5x", "99999999999999999999"})
    EXPECT_THROW(constant(bad), CompileError) << bad;
  EXPECT_EQ(parse_il_text(".rung line 1\nlOaD X0\nout Y0\n.end\n", "c.il").rungs[0].code[1].op, Op::OUT);
  EXPECT_THROW(parse_il_text(".rung line 1\nLOADNOTANOPCODE X0\n.end\n", "c.il"), CompileError);
  EXPECT_THROW(parse_il_text(".label a\n.rung line 1\nLOAD X0\n.label a\n.rung line 2\nLOAD X0\n.end\n", "c.il"),
               CompileError);
  Program p = parse_il_text(".rung line 1\nLOAD X0\nJMP b\n.label a\n.rung line 2\nLOAD X1\nJMP b\n.label b\n.end\n", "c.il");
  EXPECT_EQ(p.end_labels, std::vector<std::string>{"b"});
  EXPECT_EQ(p.rungs[1].labels, std::vector<std::string>{"a"});
}

// .retain Dn (docs/il.md): printed after the aliases, read back once per word;
// anything but an existing D word is refused.
TEST(IlText, RetainRoundTripsAndRefusesNonDWords) {
  Program p = parse_il_text(".retain D5\n.retain d7\n.retain D5\n.rung line 1\nTRUE\nOUT Y0\n.end\n", "r.il");
  std::vector<DeviceRef> want = {{Dev::D, 5}, {Dev::D, 7}};
  EXPECT_EQ(p.retain, want);
  std::string text = print_il_text(p);
  EXPECT_NE(text.find(".retain D5\n.retain D7\n"), std::string::npos) << text;
  EXPECT_EQ(parse_il_text(text, "r.il").retain, want);
  for (const char* bad : {".retain M5\n", ".retain D8192\n", ".retain\n", ".retain D1 D2\n", ".retain WY3\n"}) {
    try {
      parse_il_text(std::string(bad) + ".rung line 1\nTRUE\nOUT Y0\n.end\n", "r.il");
      ADD_FAILURE() << bad;
    } catch (CompileError& e) {
      EXPECT_EQ(e.line, 1) << bad;
      EXPECT_STREQ(e.what(), ".retain needs a D word (D0..D8191)") << bad;
    }
  }
}

// The typed IEC IL reader names the scalars of structured variables
// (docs/iec-il.md "Where values live"); `ldc --emit=il` prints them as
// aliases, and the text reads back (found by tests/diff's POU programs).
TEST(IlText, AliasesOfStructuredVariablesRoundTrip) {
  const char* text = ".alias s.inner.m0 D14\n.alias sa[-1].flag M3\n.alias grid[1,0] D20\n.alias go X0\n"
                     ".rung line 1\nTRUE\nOUT Y0\n.end\n";
  Program p = parse_il_text(text, "a.il");
  ASSERT_EQ(p.aliases.size(), 4u);
  EXPECT_EQ(p.aliases[1].name, "sa[-1].flag");
  EXPECT_EQ(parse_il_text(print_il_text(p), "a.il").aliases, p.aliases);
  for (const char* bad : {".alias 1x D0\n", ".alias .m D0\n", ".alias a+b D0\n", ".alias [1] D0\n"}) {
    try {
      parse_il_text(std::string(bad) + ".rung line 1\nTRUE\nOUT Y0\n.end\n", "a.il");
      ADD_FAILURE() << bad;
    } catch (CompileError& e) {
      EXPECT_EQ(e.line, 1) << bad;
    }
  }
}

TEST(BinaryIl, ValidatorRefusesBadCode) {
  Program p = parse_il_text(".edges 1\n.rung line 1\nLOAD X0\nJMP a\n.rung line 2\nLOADP X1 E0\nOUT Y0\n.label a\n.end\n", "c.il");
  BinaryIl b = encode_il(p);
  Layout L = p.layout();
  ASSERT_EQ(validate_il(b.code, L), "");
  auto bad = [&](auto mutate) {
    std::vector<uint8_t> c = b.code;
    mutate(c);
    return validate_il(c, L);
  };
  EXPECT_NE(bad([](auto& c) { c[0] = 200; }), "");                       // opcode
  EXPECT_NE(bad([](auto& c) { c.resize(c.size() - 1); }), "");            // truncated
  EXPECT_NE(bad([](auto& c) { c[2] = 0xFF; c[3] = 0xFF; }), "");           // X65535
  EXPECT_NE(bad([](auto& c) { c[5] = 2; }), "");                          // jump target into an operand
  EXPECT_NE(bad([](auto& c) { c[5] = 0; }), "");                          // backward jump
  EXPECT_NE(bad([](auto& c) { c[1] = 0x10 + uint8_t(Area::D); }), "");    // a word where a bit is wanted
  Layout small = Layout::standard(0);
  EXPECT_NE(validate_il(b.code, small), "");                              // edge slot outside the area
}

TreeNode leaf(uint32_t x) {
  TreeNode n;
  n.kind = TreeNode::Kind::Leaf;
  n.elem.op = Op::LOAD;
  n.elem.a[0] = Operand{OpdKind::Bit, Area::X, x};
  return n;
}

TEST(Lower, RefusesRungsDeeperThanTheBitStack) {
  // (x0 | (x1 & (x2 | (x3 & ...)))) nests one push per level
  auto build = [](int levels) {
    TreeNode n = leaf(0);
    for (int i = 1; i < levels; i++) {
      TreeNode s;
      s.kind = (i % 2) ? TreeNode::Kind::Series : TreeNode::Kind::Parallel;
      TreeNode inner;
      inner.kind = (i % 2) ? TreeNode::Kind::Parallel : TreeNode::Kind::Series;
      inner.kids = {leaf(uint32_t(i)), std::move(n)};
      s.kids = {leaf(uint32_t(100 + i)), std::move(inner)};
      n = std::move(s);
    }
    TreeProgram tp;
    TreeRung r;
    r.root.kind = TreeNode::Kind::Then;
    TreeNode out;
    out.kind = TreeNode::Kind::Output;
    out.elem.op = Op::OUT;
    out.elem.a[0] = Operand{OpdKind::Bit, Area::Y, 0};
    r.root.kids = {std::move(n), std::move(out)};
    tp.rungs.push_back(std::move(r));
    return tp;
  };
  EXPECT_NO_THROW(lower_to_il(build(10)));
  EXPECT_THROW(lower_to_il(build(40)), CompileError);
}

}  // namespace

// `.alias NAME DEVICE TYPE` (docs/il.md): read, printed back, and refused
// where the type cannot live at the device, naming why at the type's column.
TEST(IlText, TypedAliases) {
  Program p = parse_il_text(".alias big D0 LINT\n.alias on M3 bool\n.alias r F1 REAL\n.alias w D9\n.rung line 1\nLOAD X0\nOUT Y0\n.end\n", "t.il");
  ASSERT_EQ(p.aliases.size(), 4u);
  EXPECT_EQ(p.aliases[0].ty, Ty::LINT);
  EXPECT_EQ(p.aliases[1].ty, Ty::BOOL);
  EXPECT_EQ(p.aliases[3].ty, Ty::None);
  EXPECT_EQ(parse_il_text(print_il_text(p), "t.il").aliases, p.aliases);
  auto error = [](const std::string& alias) -> std::string {
    try {
      parse_il_text(alias + "\n.rung line 1\nLOAD X0\nOUT Y0\n.end\n", "t.il");
    } catch (CompileError& e) {
      return std::to_string(e.col) + ": " + e.what();
    }
    return "accepted";
  };
  EXPECT_EQ(error(".alias b D0 BOOL"), "13: BOOL alias 'b' on D0: a BOOL names a bit device");
  EXPECT_EQ(error(".alias n M0 INT"), "13: INT alias 'n' on M0: a INT names a word device");
  EXPECT_EQ(error(".alias n D8191 LREAL"), "16: LREAL alias 'n' on D8191: its 2 cells run past D8191");
  EXPECT_EQ(error(".alias n D0 INT16"), "13: unknown type 'INT16'");
  EXPECT_EQ(error(".alias n D0 INT x"), "1: .alias needs a name, a device and optionally a type");
}
