// Golden encodings: encode(parse(text)) == hex, and print(decode(hex))
// parses back to the same instruction. LDC_UPDATE=1 rewrites the hex column
// of x86_encode.rows from our encoder.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <random>
#include <set>
#include <thread>

#include "test_util.h"

using namespace ldc::as;
using namespace ldc::as::test;

namespace {

TEST(X86Encode, RowsFileIsReadable) {
  auto rows = load_rows();
  ASSERT_GT(rows.size(), 400u) << "cannot read " << LDC_X86_ROWS;
}

TEST(X86Encode, Rows) {
  auto rows = load_rows();
  const char* upd = std::getenv("LDC_UPDATE");
  bool update = upd && std::string(upd) == "1";
  std::vector<std::string> hexes;
  for (const Row& r : rows) {
    SCOPED_TRACE("x86_encode.rows:" + std::to_string(r.line) + ": " + r.text);
    x86::Instruction in;
    try {
      in = x86::parse(r.text);
    } catch (const AsmError& e) {
      ADD_FAILURE() << "parse: " << e.what();
      hexes.push_back(r.hex);
      continue;
    }
    std::vector<uint8_t> bytes;
    try {
      bytes = x86::encode_at(in, 0);
    } catch (const AsmError& e) {
      ADD_FAILURE() << "encode: " << e.what();
      hexes.push_back(r.hex);
      continue;
    }
    hexes.push_back(to_hex(bytes));
    if (!update) {
      EXPECT_EQ(to_hex(bytes), r.hex);
    }

    // Decode the golden bytes back.
    std::vector<uint8_t> golden = update ? bytes : from_hex(r.hex);
    x86::DecodeError err;
    auto d = x86::decode(golden, 0, &err);
    if (!d) {
      ADD_FAILURE() << "decode: " << err.message << " at " << err.offset;
      continue;
    }
    EXPECT_EQ(d->length, golden.size());
    EXPECT_EQ(x86::print(d->inst), x86::print(in));
    EXPECT_TRUE(d->inst == in) << "decoded as " << x86::print(d->inst);
    // The printed text parses back to the same instruction.
    x86::Instruction again = x86::parse(x86::print(d->inst));
    EXPECT_TRUE(again == in) << "reparsed as " << x86::print(again);
  }
  if (update) {
    rewrite_rows(hexes);
    std::printf("rewrote %zu rows in %s\n", hexes.size(), LDC_X86_ROWS);
  }
}

// The encoder remembers the form it found for each shape of operands (a cache
// of the thread's own): every row encodes the same after all the others, in
// reverse and in a shuffled order, each on a fresh thread, as in table order.
TEST(X86Encode, RowsEncodeTheSameInAnyOrder) {
  auto rows = load_rows();
  std::vector<std::pair<x86::Instruction, std::string>> ins;
  for (const Row& r : rows) {
    try {
      x86::Instruction in = x86::parse(r.text);
      ins.emplace_back(in, to_hex(x86::encode_at(in, 0)));
    } catch (const AsmError&) {
    }
  }
  ASSERT_GT(ins.size(), 400u);
  std::vector<size_t> order(ins.size());
  for (size_t i = 0; i < order.size(); i++) order[i] = i;
  auto check = [&](const std::vector<size_t>& ord) {
    std::thread t([&] {
      for (size_t i : ord)
        for (bool long_form : {false, true}) {
          Encoding e = x86::encode(ins[i].first, long_form), f = x86::encode(ins[i].first, long_form);
          EXPECT_EQ(e.view().size(), f.view().size());
          EXPECT_TRUE(std::equal(e.view().begin(), e.view().end(), f.view().begin(), f.view().end()));
        }
      for (size_t i : ord) EXPECT_EQ(to_hex(x86::encode_at(ins[i].first, 0)), ins[i].second) << x86::print(ins[i].first);
    });
    t.join();
  };
  std::reverse(order.begin(), order.end());
  check(order);
  std::mt19937 rng(15);
  std::shuffle(order.begin(), order.end(), rng);
  check(order);
}

// Every table form shows up in the rows (so every form is checked by as).
TEST(X86Encode, RowsCoverEveryMnemonicAndCondition) {
  std::set<std::string> seen;
  for (const Row& r : load_rows()) {
    auto in = x86::parse(r.text);
    seen.insert(std::string(x86::mnemonic_name(in.mnemonic, in.cond)));
  }
  for (unsigned m = 0; m < unsigned(x86::Mnemonic::Count_); ++m) {
    auto mn = x86::Mnemonic(m);
    bool cc = mn == x86::Mnemonic::Setcc || mn == x86::Mnemonic::Cmovcc || mn == x86::Mnemonic::Jcc;
    for (unsigned c = 0; c < (cc ? 16u : 1u); ++c) {
      std::string name(x86::mnemonic_name(mn, x86::Cond(c)));
      EXPECT_TRUE(seen.count(name)) << name << " has no golden row";
    }
  }
}

TEST(X86Encode, FixupsForLabels) {
  auto in = x86::parse("jne done");
  Encoding e = x86::encode(in, false);
  ASSERT_EQ(e.size, 2);
  EXPECT_EQ(e.bytes[0], 0x75);
  ASSERT_EQ(e.num_fixups, 1);
  EXPECT_EQ(e.fixups[0].offset, 1u);
  EXPECT_EQ(e.fixups[0].kind, x86::Rel8);
  EXPECT_EQ(e.fixups[0].label, "done");
  EXPECT_EQ(x86::target().fixup_kinds[x86::Rel8].relax_to, x86::Rel32);

  e = x86::encode(in, true);
  ASSERT_EQ(e.size, 6);
  EXPECT_EQ(e.bytes[0], 0x0f);
  EXPECT_EQ(e.bytes[1], 0x85);
  ASSERT_EQ(e.num_fixups, 1);
  EXPECT_EQ(e.fixups[0].offset, 2u);
  EXPECT_EQ(e.fixups[0].kind, x86::Rel32);

  e = x86::encode(x86::parse("call helper"), false);
  ASSERT_EQ(e.size, 5);
  EXPECT_EQ(e.fixups[0].kind, x86::Rel32);
}

TEST(X86Encode, RejectsOperandsOutsideTheSubset) {
  for (const char* text : {"mov eax, rbx", "add dword ptr [rax], rbx", "add [rax], 0x1",
                           "mov eax, 0x100000000", "mov byte ptr [rax], 0x100", "imul rax, ebx",
                           "shl eax, 0x100", "push eax", "lea eax, ebx", "movss xmm0, eax",
                           "andps xmm0, dword ptr [rax]", "sete eax", "call ecx", "jmp eax",
                           "movzx rax, bl", "add rax, 0x80000000", "ret 0x1"}) {
    SCOPED_TRACE(text);
    x86::Instruction in;
    try {
      in = x86::parse(text);
    } catch (const AsmError&) {
      continue;  // rejected by the parser: fine too
    }
    EXPECT_THROW(x86::encode(in), AsmError);
  }
}

TEST(X86Encode, EncodeAtResolvesAddresses) {
  auto in = x86::parse("jmp 0x100");
  EXPECT_EQ(to_hex(x86::encode_at(in, 0x90)), "eb6e");        // 0x100 - 0x92
  EXPECT_EQ(to_hex(x86::encode_at(in, 0x7f)), "eb7f");        // 0x100 - 0x81
  EXPECT_EQ(to_hex(x86::encode_at(in, 0x7e)), "e97d000000");  // 0x100 - 0x83
  EXPECT_THROW(x86::encode_at(x86::parse("jmp somewhere")), AsmError);
}

}  // namespace
