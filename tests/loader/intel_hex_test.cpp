// Tests of the Intel HEX writer and reader.
#include <gtest/gtest.h>

#include <random>

#include "loader/loader.h"

namespace ldc {
namespace {

std::string refusal(std::string_view text) {
  try {
    read_intel_hex(text, "t.hex");
  } catch (const ImageError& e) {
    return e.what();
  }
  return "";
}

std::span<const uint8_t> as_bytes(const std::string& s) {
  return {reinterpret_cast<const uint8_t*>(s.data()), s.size()};
}

TEST(IntelHex, KnownRecords) {
  std::vector<uint8_t> b(20);
  for (size_t i = 0; i < b.size(); i++) b[i] = uint8_t(i);
  EXPECT_EQ(write_intel_hex(b),
            ":10000000000102030405060708090A0B0C0D0E0F78\n"
            ":0400100010111213A6\n"
            ":00000001FF\n");
  EXPECT_EQ(write_intel_hex({}), ":00000001FF\n");
  EXPECT_TRUE(read_intel_hex(":00000001FF\n", "t.hex").empty());
}

TEST(IntelHex, ExtendedLinearAddressPast64KiB) {
  std::vector<uint8_t> b(0x20010);
  std::mt19937 rng(7);
  for (auto& x : b) x = uint8_t(rng());
  std::string hex = write_intel_hex(b);
  EXPECT_NE(hex.find(":020000040001F9\n"), std::string::npos);
  EXPECT_NE(hex.find(":020000040002F8\n"), std::string::npos);
  EXPECT_EQ(hex.find(":020000040000"), std::string::npos);  // none needed for the first 64 KiB
  EXPECT_EQ(read_intel_hex(hex, "t.hex"), b);
}

TEST(IntelHex, ReaderAcceptsCrlfLowercaseAndOtherLengths) {
  EXPECT_EQ(read_intel_hex("\r\n:0300000001020FEB\r\n:02000300AABB96\r\n:00000001ff\r\n\n", "t.hex"),
            (std::vector<uint8_t>{1, 2, 0x0F, 0xAA, 0xBB}));
}

TEST(IntelHex, BadChecksum) {
  EXPECT_EQ(refusal(":0300000001020FEC\n:00000001FF\n"), "t.hex:1:16: error: bad checksum EC (expected EB)");
}

TEST(IntelHex, BadDigit) {
  EXPECT_EQ(refusal(":00000001FF\n"), "");
  EXPECT_EQ(refusal(":03000000010G0FEB\n:00000001FF\n"), "t.hex:1:13: error: bad hex digit 'G'");
  EXPECT_EQ(refusal(":0300000001020FE\n:00000001FF\n"), "t.hex:1:17: error: odd number of hex digits");
}

TEST(IntelHex, MissingEof) {
  EXPECT_EQ(refusal(":0300000001020FEB\n"), "t.hex:1:1: error: missing end-of-file record (:00000001FF)");
  EXPECT_EQ(refusal(""), "t.hex:1:1: error: missing end-of-file record (:00000001FF)");
}

TEST(IntelHex, OtherRefusals) {
  EXPECT_EQ(refusal("0300000001020FEB\n"), "t.hex:1:1: error: expected ':' to start a record");
  EXPECT_EQ(refusal(":0400000001020FEA\n:00000001FF\n"),
            "t.hex:1:2: error: record length field says 4 data bytes, the record has 3");
  EXPECT_EQ(refusal(":00000001FF\n:00000001FF\n"), "t.hex:2:1: error: text after the end-of-file record");
  EXPECT_EQ(refusal(":0100000300FC\n:00000001FF\n"), "t.hex:1:8: error: unsupported record type 03 (only 00, 01 and 04)");
  EXPECT_EQ(refusal(":0100050001F9\n:00000001FF\n"),
            "t.hex:1:4: error: data at address 0x5, expected 0x0 (a gap; images are contiguous)");
  EXPECT_EQ(refusal(":0100000001FE\n:0100000001FE\n:00000001FF\n"),
            "t.hex:2:4: error: data at address 0x0, expected 0x1 (an overlap; images are contiguous)");
  EXPECT_EQ(refusal(":" + std::string(600, '0') + "\n"), "t.hex:1:1: error: record too long (more than 255 data bytes)");
  EXPECT_EQ(refusal(":FF\n"), "t.hex:1:1: error: record too short (1 bytes; at least 5)");
  EXPECT_EQ(refusal(":0100000001FE\n:01000001AA54\n"), "t.hex:2:2: error: end-of-file record with data");
}

TEST(IntelHex, LooksLikeIntelHex) {
  EXPECT_TRUE(looks_like_intel_hex(as_bytes(" \r\n\t:00000001FF")));
  EXPECT_FALSE(looks_like_intel_hex(as_bytes("  LDCIMG")));
  EXPECT_FALSE(looks_like_intel_hex(as_bytes("   ")));
  EXPECT_FALSE(looks_like_intel_hex({}));
}

TEST(IntelHex, RandomTextNeverCrashes) {
  std::mt19937 rng(3);
  const std::string good = write_intel_hex(std::vector<uint8_t>(100, 0x5A));
  const char alphabet[] = ":0123456789ABCDEFabcdefG\r\n ";
  for (int iter = 0; iter < 5000; iter++) {
    std::string s = good;
    for (int k = 0, n = 1 + int(rng() % 3); k < n; k++) s[rng() % s.size()] = alphabet[rng() % (sizeof alphabet - 1)];
    try {
      read_intel_hex(s, "r.hex");
    } catch (const ImageError&) {
    }
  }
}

}  // namespace
}  // namespace ldc
