// Golden C40 encodings: encode(parse(text)) == word, decode(word) prints
// text that parses back to the same instruction. LDC_UPDATE=1 rewrites the
// hex column of c40_encode.rows from our encoder.
#include <gtest/gtest.h>

#include <cstdlib>
#include <set>

#include "c40_test_util.h"

using namespace ldc::as;
using namespace ldc::as::c40;
using namespace ldc::as::c40::test;

namespace {

TEST(C40Encode, RowsFileIsReadable) {
  auto rows = load_rows();
  ASSERT_GT(rows.size(), 300u) << "cannot read " << LDC_C40_ROWS;
  for (const Row& r : rows) EXPECT_FALSE(r.source.empty()) << "row " << r.line << " cites no source";
}

TEST(C40Encode, Rows) {
  auto rows = load_rows();
  const char* upd = std::getenv("LDC_UPDATE");
  bool update = upd && std::string(upd) == "1";
  std::vector<std::string> hexes;
  for (const Row& r : rows) {
    SCOPED_TRACE("c40_encode.rows:" + std::to_string(r.line) + ": " + r.text);
    Instruction in;
    uint32_t w = 0;
    try {
      in = parse(r.text);
      w = encode_at(in, 0);
    } catch (const AsmError& e) {
      ADD_FAILURE() << e.what();
      hexes.push_back(r.hex);
      continue;
    }
    hexes.push_back(hex_word(w));
    if (!update) {
      EXPECT_EQ(hex_word(w), r.hex);
    }
    uint32_t golden = update ? w : uint32_t(std::stoul(r.hex, nullptr, 16));
    // The one-word Encoding agrees with encode_at for rows without targets.
    Encoding e = encode(in);
    ASSERT_EQ(e.size, 4);
    if (e.num_fixups == 0) {
      uint32_t ew = uint32_t(e.bytes[0]) | uint32_t(e.bytes[1]) << 8 | uint32_t(e.bytes[2]) << 16 |
                    uint32_t(e.bytes[3]) << 24;
      EXPECT_EQ(hex_word(ew), hex_word(w));
    }
    DecodeError err;
    auto d = decode_word(golden, 0, &err);
    if (!d) {
      ADD_FAILURE() << "decode: " << err.message;
      continue;
    }
    EXPECT_EQ(print(*d), print(in));
    EXPECT_TRUE(*d == in) << "decoded as " << print(*d);
    Instruction again = parse(print(*d));
    EXPECT_TRUE(again == in) << "reparsed as " << print(again);
  }
  if (update) {
    rewrite_rows(hexes);
    std::printf("rewrote %zu rows in %s\n", hexes.size(), LDC_C40_ROWS);
  }
}

// Every mnemonic, and every condition of each conditional form, has a row.
TEST(C40Encode, RowsCoverEveryMnemonic) {
  std::set<std::string> seen;
  std::set<std::pair<int, int>> conds;
  for (const Row& r : load_rows()) {
    auto in = parse(r.text);
    seen.insert(mnemonic_name(in.mnemonic, Cond::U));
    conds.insert({int(in.mnemonic), int(in.cond)});
  }
  for (unsigned m = 0; m < unsigned(Mnemonic::Count_); ++m) {
    if (Mnemonic(m) == Mnemonic::Word) continue;
    EXPECT_TRUE(seen.count(mnemonic_name(Mnemonic(m), Cond::U)))
        << mnemonic_name(Mnemonic(m)) << " has no golden row";
  }
  for (unsigned c = 0; c <= 20; ++c)
    if (valid_cond(c)) {
      EXPECT_TRUE(conds.count({int(Mnemonic::Bc), int(c)})) << "B" << cond_name(Cond(c));
    }
}

TEST(C40Encode, FixupsForLabels) {
  struct Case {
    const char* text;
    uint32_t word;
    FixupKindId kind;
  } cases[] = {
      {"BR far", 0x60000000, Disp24},     {"BRD far", 0x61000000, Disp24D},
      {"CALL far", 0x62000000, Disp24},   {"BNE near", 0x6a060000, Disp16},
      {"BNED near", 0x6a260000, Disp16D}, {"CALLLT near", 0x72070000, Disp16},
      {"DBGE AR2, near", 0x6e8a0000, Disp16}, {"DBUD AR0, near", 0x6e200000, Disp16D},
      {".word table", 0, Abs32},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.text);
    Instruction in = parse(c.text);
    Encoding e = encode(in);
    ASSERT_EQ(e.size, 4);
    uint32_t w = uint32_t(e.bytes[0]) | uint32_t(e.bytes[1]) << 8 | uint32_t(e.bytes[2]) << 16 |
                 uint32_t(e.bytes[3]) << 24;
    EXPECT_EQ(hex_word(w), hex_word(c.word));
    ASSERT_EQ(e.num_fixups, 1);
    EXPECT_EQ(e.fixups[0].offset, 0u);
    EXPECT_EQ(e.fixups[0].kind, c.kind);
    EXPECT_EQ(e.fixups[0].label, in.ops[in.num_operands - 1].label);
  }
  const auto& k = target().fixup_kinds;
  ASSERT_EQ(k.size(), 5u);
  EXPECT_EQ(k[Disp16].pc_bias, 1);
  EXPECT_EQ(k[Disp16D].pc_bias, 3);
  EXPECT_EQ(k[Disp24].bit_width, 24);
  EXPECT_EQ(k[Disp24D].pc_bias, 3);
  EXPECT_FALSE(k[Abs32].pc_relative);
  for (const FixupKind& f : k) {
    EXPECT_EQ(f.scale, 4);
    EXPECT_EQ(f.container_bytes, 4);
    EXPECT_EQ(f.relax_to, -1);
  }
}

TEST(C40Encode, EncodeAtResolvesAddressesAndChecksRange) {
  EXPECT_EQ(hex_word(encode_at(parse("BU 0x10"), 0x20)), "6a00ffef");  // 0x10 - 0x21
  EXPECT_EQ(hex_word(encode_at(parse("BUD 0x10"), 0x20)), "6a20ffed");  // 0x10 - 0x23
  EXPECT_EQ(hex_word(encode_at(parse("BU 0x8000"), 0)), "6a007fff");
  EXPECT_THROW(encode_at(parse("BU 0x8001"), 0), AsmError);
  EXPECT_EQ(hex_word(encode_at(parse("BU -0x7fff"), 0)), "6a008000");
  EXPECT_THROW(encode_at(parse("BU -0x8000"), 0), AsmError);
  EXPECT_EQ(hex_word(encode_at(parse("BR 0x800000"), 0)), "607fffff");
  EXPECT_THROW(encode_at(parse("BR 0x800001"), 0), AsmError);
  EXPECT_THROW(encode_at(parse("BR somewhere")), AsmError);
  EXPECT_EQ(hex_word(encode_at(parse(".word 0x12345678"))), "12345678");
  EXPECT_EQ(hex_word(encode_at(parse(".word -1"))), "ffffffff");
}

TEST(C40Encode, RejectsOperandsOutsideTheSubset) {
  for (const char* text :
       {"LDI R0", "LDI R0, R1, R2", "LDF AR0, R1", "LDF R0, AR1", "STI 5, @0x1",
        "STI R0, R1", "STF AR0, @0x1", "LDA R0, R1", "LDA R0, ST", "FRIEEE R0, R1",
        "ADDI3 R1, 5, R2", "ADDF3 1, R1, R2", "SUBI3 R1, *+AR0(5), R2", "ADDI3 *+AR0(32), R1, R2",
        "ADDI3 *AR0++(2), R1, R2", "PUSHF AR0", "POPF ST", "BR R0", "BR", "DBU R0, x",
        "RETSU R0", "NOP R1", "LDPK -1", "LDHI 0x10000, R0", "CMPI3 R1, R2, R3", "PUSH 1",
        "LDI @0x10000, R0", "ADDI3 128, R1, R2", "BU 1.5"}) {
    SCOPED_TRACE(text);
    Instruction in;
    try {
      in = parse(text);
    } catch (const AsmError&) {
      continue;  // refused by the parser: fine too
    }
    EXPECT_THROW(encode(in), AsmError);
  }
}

}  // namespace
