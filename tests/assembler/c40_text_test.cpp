// Parser, printer and disassembler behaviour beyond the golden rows.
#include <gtest/gtest.h>

#include <random>

#include "c40_test_util.h"

using namespace ldc::as;
using namespace ldc::as::c40;
using namespace ldc::as::c40::test;

namespace {

TEST(C40Text, SpellingsOfTheSameInstruction) {
  struct Pair {
    const char* a;
    const char* b;
  } pairs[] = {
      {"ldi @01h, r0", "LDI @0x1, R0"},           // TI hex, case
      {"LDPK 08000h", "LDPK 0x8000"},             // paper Fig. 6
      {"OR 0fffh,R11", "OR 0xfff, R11"},          // paper Fig. 6
      {"ldi *+ar1, r2", "LDI *+AR1(1), R2"},      // displacement 1 by default
      {"ldi *ar1++, r2", "LDI *AR1++(1), R2"},
      {"ldi *+ar0(0), r0", "LDI *AR0, R0"},       // as GNU as: a 0 displacement is *ARn
      {"ldi *ar0++(0)%, r0", "LDI *AR0, R0"},
      {"ldi 0xffff, r0", "LDI -1, R0"},           // 16-bit pattern of a signed field
      {"ldf 1, f1", "LDF 1.0, R1"},               // integer spelling of a float, F aliases
      {"b x", "BU x"},  {"bd x", "BUD x"},  {"rets", "RETSU"},  {"db ar0, x", "DBU AR0, x"},
      {"bz x", "BEQ x"}, {"bnzd x", "BNED x"}, {"bc x", "BLO x"}, {"bnc x", "BHS x"},
      {"bn x", "BLT x"}, {"bl x", "BLT x"}, {"bp x", "BGT x"}, {"bnn x", "BGE x"},
      {"ldiz r0, r1", "LDIEQ R0, R1"}, {"callnz x", "CALLNE x"},
      {"LDI R0,R1 ; comment", "LDI R0, R1"},
      {"  addi3  *+ar0 ( 3 ) ,r1 , r2 ", "ADDI3 *+AR0(3), R1, R2"},
  };
  for (const Pair& p : pairs) {
    SCOPED_TRACE(p.a);
    Instruction a = parse(p.a), b = parse(p.b);
    EXPECT_TRUE(a == b) << print(a) << " vs " << print(b);
    EXPECT_EQ(print(a), p.b);
  }
}

TEST(C40Text, ParserErrors) {
  for (const char* text :
       {"", "FOO R0, R1", "LDI R12, R0", "LDI *AR8, R0", "LDI *+AR0(256), R0", "LDI *+AR0(-1), R0",
        "LDI 65536, R0", "LDI -32769, R0", "OR -1, R0", "LDI @-1, R0", "LDI @0x10000, R0",
        "LDF 0.1, R0", "LDF 256.0, R0", "LDF 1e-3, R0", "LDI 1.5, R0", "ADDI3 -129, R1, R2",
        "LDI R0,, R1", "LDI R0, R1, R2, R3", "LDI *AR0++(IR0)%B, R0", "LDI *AR0B, R0",
        "LDI *+AR0(IR0)B, R0", "LDI *AR0%, R0", "LDI 1x, R0", "BU 1.5", "LDI a b, R0",
        "LDIQQ R0, R1", "BQQ x", "LDF R0, R1 || STF R2, *AR0", "x: LDI R0, R1", ".word 1.5",
        ".word 0x100000000"}) {
    SCOPED_TRACE(text);
    bool refused = false;
    try {
      Instruction in = parse(text);
      encode(in);
    } catch (const AsmError& e) {
      refused = true;
      EXPECT_FALSE(std::string(e.what()).empty());
    }
    EXPECT_TRUE(refused);
  }
}

TEST(C40Text, Lines) {
  Line l = parse_line("LD001:  BR LD002 ; to the next");
  EXPECT_EQ(l.label, "LD001");
  ASSERT_TRUE(l.inst);
  EXPECT_EQ(print(*l.inst), "BR LD002");
  EXPECT_EQ(l.comment, "to the next");
  l = parse_line("only:");
  EXPECT_EQ(l.label, "only");
  EXPECT_FALSE(l.inst);
  l = parse_line("; just a comment");
  EXPECT_FALSE(l.inst);
  EXPECT_EQ(l.comment, "just a comment");
  EXPECT_THROW(parse_line("AR0: NOP"), AsmError);  // a register is no label
  EXPECT_THROW(parse_line("1x: NOP"), AsmError);
}

TEST(C40Text, ShortFloats) {
  EXPECT_EQ(*short_float_from_double(0.0), 0x8000);
  EXPECT_EQ(*short_float_from_double(1.0), 0x0000);
  EXPECT_EQ(*short_float_from_double(1.5), 0x0400);
  EXPECT_EQ(*short_float_from_double(-2.0), 0x0800);  // GNU as: ldf -2.0, r1 = 07610800
  EXPECT_EQ(*short_float_from_double(-1.0), 0xf800);  // -2 * 2^-1
  EXPECT_EQ(*short_float_from_double(0.5), 0xf000);
  EXPECT_FALSE(short_float_from_double(0.1));
  EXPECT_FALSE(short_float_from_double(256.0));
  for (unsigned b = 0; b < 0x10000; ++b) {
    double v = short_float_to_double(uint16_t(b));
    auto back = short_float_from_double(v);
    ASSERT_TRUE(back) << b;
    if ((b >> 12) == 8) EXPECT_EQ(*back, 0x8000);  // every exponent -8 value is zero
    else EXPECT_EQ(*back, b) << v;
  }
}

TEST(C40Decode, ReportsWordsOutsideTheSubsetWithTheirAddress) {
  struct Case {
    uint32_t w;
    const char* why;
  } cases[] = {
      {0x0c800001, "NOP R1"},        {0x08400000, "*+AR0(0): GNU as writes *ARn"},
      {0x0840d000, "indirect mod 0x1a"}, {0x08404001, "mod > 7 with a displacement"},
      {0x08000020, "register 32 (IVTP)"}, {0x15000000, "STIK"}, {0x6a0b0000, "cond 11"},
      {0x68600000, "BcondAT"},       {0x63000000, "LAJ"},       {0x80000000, "parallel"},
      {0xffffffff, "garbage"},       {0x31220109, "type 2 ADDI3 of a type 1 operand"},
      {0x6c000000, "DBcond with a register"}, {0x1e950000, "LDA to ST"},
      {0x0f200001, "PUSH with low bits"}, {0x07000008, "LDF from AR0"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.why);
    DecodeError e;
    EXPECT_FALSE(decode_word(c.w, 0x1234, &e)) << print(*decode_word(c.w, 0x1234));
    EXPECT_EQ(e.address, 0x1234);
    EXPECT_FALSE(e.message.empty());
  }
  std::vector<uint8_t> bytes = {0x00, 0x00, 0x01, 0x08, 0xff, 0xff, 0xff, 0xff, 0x00, 0x00};
  Disassembly d = disassemble_bytes(bytes, 0x100);
  ASSERT_EQ(d.insts.size(), 1u);
  EXPECT_EQ(print(d.insts[0].inst), "LDI R0, R1");
  ASSERT_EQ(d.errors.size(), 2u);
  EXPECT_EQ(d.errors[0].address, 0x101);
  EXPECT_EQ(d.errors[1].address, 0x102);  // the truncated word
}

TEST(C40Decode, RandomWordsNeverCrashAndRoundTrip) {
  std::mt19937 rng(40);
  size_t decoded = 0;
  for (int i = 0; i < 200000; ++i) {
    uint32_t w = rng();
    if (i % 4 == 0) w &= 0x3fffffff;  // more of the opcode space we cover
    auto in = decode_word(w, 0x1000);
    if (!in) continue;
    ++decoded;
    ASSERT_EQ(encode_at(*in, 0x1000), w) << print(*in);
    ASSERT_TRUE(parse(print(*in)) == *in) << print(*in) << " " << hex_word(w);
  }
  EXPECT_GT(decoded, 10000u);
}

}  // namespace
