// The disassembler: whole buffers, errors with offsets, robustness.
#include <gtest/gtest.h>

#include "test_util.h"

using namespace ldc::as;
using namespace ldc::as::test;

namespace {

TEST(X86Decode, DisassemblesABufferWithAbsoluteTargets) {
  // 0: jmp 0x7 ; 2: je 0x0 ; 4: nop ; 5: call 0xa ; a: ret
  std::vector<uint8_t> code = from_hex("eb03" "74fc" "90" "e800000000" "c3");
  auto d = x86::disassemble(code);
  ASSERT_FALSE(d.error) << d.error->message;
  ASSERT_EQ(d.insts.size(), 5u);
  EXPECT_EQ(x86::print(d.insts[0].inst), "jmp 0x5");
  EXPECT_EQ(x86::print(d.insts[1].inst), "je 0x0");
  EXPECT_EQ(x86::print(d.insts[3].inst), "call 0xa");
  EXPECT_EQ(d.insts[3].offset, 5u);
  EXPECT_EQ(d.insts[4].offset, 10u);
}

TEST(X86Decode, LongFormThatCouldBeShortIsMarked) {
  std::vector<uint8_t> code = from_hex("90" "e900000000" "0f8400000000");
  auto d = x86::disassemble(code);
  ASSERT_FALSE(d.error);
  ASSERT_EQ(d.insts.size(), 3u);
  EXPECT_TRUE(d.insts[1].inst.long_branch);
  EXPECT_EQ(x86::print(d.insts[1].inst), "{disp32} jmp 0x6");
  EXPECT_EQ(x86::print(d.insts[2].inst), "{disp32} je 0xc");
}

TEST(X86Decode, ReportsUnknownBytesWithOffset) {
  struct Case {
    const char* hex;
    uint32_t offset;
  } cases[] = {
      {"90" "0f0b", 1},            // ud2
      {"c3" "c3" "f4", 2},         // hlt
      {"8bc3", 0},                 // mov eax, ebx in the 8B form: not canonical
      {"8b4400" "00", 0},          // disp8 0 where none is needed
      {"48" "50", 0},              // push with a useless REX.W
      {"41" "90", 0},              // REX on nop
      {"0f94c4", 0},               // sete ah
      {"c5f858c1", 0},             // VEX vaddps
      {"f2" "0f7cc1", 0},          // haddps: not in the subset (the F2 prefix is, for the sd forms)
      {"66" "89d8", 0},            // 16-bit mov
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.hex);
    auto d = x86::disassemble(from_hex(c.hex));
    ASSERT_TRUE(d.error.has_value());
    EXPECT_EQ(d.error->offset, c.offset);
    EXPECT_FALSE(d.error->message.empty());
  }
}

TEST(X86Decode, TruncatedInstructionsAreErrors) {
  for (const Row& r : load_rows()) {
    std::vector<uint8_t> full = from_hex(r.hex);
    for (size_t n = 1; n < full.size(); ++n) {
      // Exactly sized heap copies so that ASan catches any over-read.
      std::vector<uint8_t> part(full.begin(), full.begin() + long(n));
      x86::DecodeError err;
      auto d = x86::decode(part, 0, &err);
      if (d) {
        // A prefix of the bytes may itself be a valid instruction only if
        // it is shorter than what was given.
        EXPECT_LE(d->length, n) << r.text;
      }
    }
  }
  x86::DecodeError err;
  EXPECT_FALSE(x86::decode(std::vector<uint8_t>{}, 0, &err));
  EXPECT_FALSE(x86::decode(from_hex("90"), 5, &err));
}

// Whatever the encoder produces, the decoder reads back exactly.
TEST(X86Decode, EveryEncodableVariantDecodes) {
  auto all = all_row_variants();
  EXPECT_GT(all.size(), 5000u);
  for (const auto& in : all) {
    auto bytes = x86::encode_at(in, 0);
    x86::DecodeError err;
    auto d = x86::decode(bytes, 0, &err);
    ASSERT_TRUE(d) << x86::print(in) << " (" << to_hex(bytes) << "): " << err.message;
    EXPECT_EQ(d->length, bytes.size()) << x86::print(in);
    EXPECT_EQ(to_hex(x86::encode_at(d->inst, 0)), to_hex(bytes)) << x86::print(in);
    EXPECT_TRUE(x86::parse(x86::print(d->inst)) == d->inst) << x86::print(d->inst);
  }
}

// Random bytes: the decoder never crashes, and whatever it accepts
// re-encodes to exactly the bytes it consumed.
TEST(X86Decode, RandomBytesNeverCrash) {
  uint64_t seed = 0x9E3779B97F4A7C15ull;
  auto next = [&] {
    seed ^= seed << 13;
    seed ^= seed >> 7;
    seed ^= seed << 17;
    return seed;
  };
  const uint8_t interesting[] = {0x0f, 0x40, 0x41, 0x44, 0x48, 0x4c, 0x66, 0xf3, 0x89, 0x8b,
                                 0x83, 0x81, 0xc7, 0xf7, 0xff, 0x24, 0x25, 0x04, 0x05, 0x45};
  size_t accepted = 0;
  for (int iter = 0; iter < 200000; ++iter) {
    size_t n = 1 + next() % 12;
    std::vector<uint8_t> buf(n);
    for (auto& b : buf) b = (next() & 1) ? interesting[next() % sizeof interesting] : uint8_t(next());
    size_t at = next() % n;
    auto d = x86::decode(buf, at);
    if (!d) continue;
    ++accepted;
    ASSERT_LE(at + d->length, n);
    auto again = x86::encode_at(d->inst, at);
    ASSERT_EQ(to_hex(again), to_hex(std::vector<uint8_t>(buf.begin() + long(at),
                                                        buf.begin() + long(at + d->length))));
  }
  EXPECT_GT(accepted, 1000u);
}

}  // namespace
