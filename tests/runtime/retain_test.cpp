// The retentive file (runtime/retain.cpp): round trip, every corruption
// refused, the atomic replacement.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <random>

#include "driver/driver.h"
#include "runtime/plc.h"

namespace ldc::plc {
namespace {

RetainSnapshot sample() {
  RetainSnapshot s;
  s.sequence = 42;
  s.saved_ns = 1234567890123ull;
  s.records.push_back(RetainRecord{"", Area::K, 0, 16, std::vector<uint8_t>(16, 1)});
  std::vector<uint8_t> d(8);
  for (int i = 0; i < 8; i++) d[i] = uint8_t(i * 7);
  s.records.push_back(RetainRecord{"fast", Area::D, 10, 2, d});
  return s;
}

TEST(Retain, RoundTrip) {
  RetainSnapshot s = sample();
  std::vector<uint8_t> b = encode_retain(s);
  RetainSnapshot back = decode_retain(b, "r");
  EXPECT_EQ(back.sequence, 42u);
  EXPECT_EQ(back.saved_ns, s.saved_ns);
  EXPECT_EQ(back.records, s.records);
}

TEST(Retain, EveryTruncationAndEveryBitFlipIsRefused) {
  std::vector<uint8_t> b = encode_retain(sample());
  for (size_t n = 0; n < b.size(); n++) {
    std::vector<uint8_t> t(b.begin(), b.begin() + n);
    EXPECT_THROW(decode_retain(t, "r"), std::runtime_error) << "truncated to " << n;
  }
  std::mt19937 rng(7);
  for (size_t i = 0; i < b.size(); i++) {
    std::vector<uint8_t> f = b;
    f[i] ^= uint8_t(1u << (rng() % 8));
    EXPECT_THROW(decode_retain(f, "r"), std::runtime_error) << "flip at " << i;
  }
}

TEST(Retain, MessagesNameTheFileAndTheProblem) {
  std::vector<uint8_t> b = encode_retain(sample());
  b[40] ^= 1;
  try {
    decode_retain(b, "plant.ret");
    FAIL();
  } catch (std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("plant.ret: error: retentive file is corrupt: checksum"), std::string::npos) << e.what();
  }
}

TEST(Retain, WriteReplacesTheFileAndLeavesNoTemporary) {
  std::string dir = make_temp_dir();
  std::string f = dir + "/state.ret";
  RetainSnapshot s = sample();
  ASSERT_EQ(write_retain_file(f, s), "");
  s.sequence = 43;
  ASSERT_EQ(write_retain_file(f, s), "");
  std::ifstream in(f, std::ios::binary);
  std::vector<uint8_t> b((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(decode_retain(b, f).sequence, 43u);
  struct stat st;
  EXPECT_NE(stat((f + ".tmp").c_str(), &st), 0);
  EXPECT_NE(write_retain_file(dir + "/no/such/dir/x.ret", s), "");
  remove_tree(dir);
}

}  // namespace
}  // namespace ldc::plc
