// The image's `vars` section (id 10, docs/image-format.md): what an online
// download carries variables by.  It round-trips, an image without it is
// what it always was, and the validator refuses every field out of place:
// its version, counts, names, areas and rows, with the section and offset.
#include <gtest/gtest.h>

#include <functional>

#include "test_image.h"

namespace ldc::test {
namespace {

Image with_vars() {
  Image im = tiny_image();
  im.vars = {{"tank", "Tank#0123456789abcdef", Area::M, 3, 2, Area::D, 10, 4},
             {"r", "REAL", Area::Count, 0, 0, Area::F, 1, 1},
             {"__rtc_clock", "DT", Area::Count, 0, 0, Area::D, 20, 2}};
  return im;
}

TEST(VarsSection, RoundTripsAndKeepsImagesWithoutOne) {
  Image plain = tiny_image();
  std::vector<uint8_t> a = write_image(plain);
  EXPECT_EQ(get32(a, 20), 7u);  // seven sections, as before the section existed
  EXPECT_EQ(find_section(a, 10), -1);
  Image im = with_vars();
  std::vector<uint8_t> b = write_image(im);
  EXPECT_EQ(get32(b, 20), 8u);
  EXPECT_EQ(get32(b, entry_at(7)), 10u);  // the 8th entry is `vars` (no config, no regions)
  EXPECT_EQ(read_image(b, "t.bin"), im);
  EXPECT_TRUE(read_image(a, "t.bin").vars.empty());
  // With a configuration table too: ids 1..8 and 10 in order.
  im.config = IoConfig{};
  im.config->block_size = 16;
  im.config->rows = {{Area::X, 0, kBlockRead, kNoProcessor, 0}, {Area::Y, 0, kBlockWrite | kBlockWritten, 0, 0}};
  std::vector<uint8_t> c = write_image(im);
  EXPECT_EQ(get32(c, 20), 9u);
  EXPECT_EQ(get32(c, entry_at(7)), 8u);
  EXPECT_EQ(get32(c, entry_at(8)), 10u);
  EXPECT_EQ(read_image(c, "t.bin"), im);
}

// The refusal of an image whose `vars` were edited as given ("" if accepted).
std::string refusal_after(const std::function<void(Image&)>& edit) {
  Image im = with_vars();
  edit(im);
  try {
    read_image(write_image(im), "t.bin");
  } catch (ImageError& e) {
    return e.what();
  }
  return "";
}

TEST(VarsSection, RefusesEveryFieldOutOfPlace) {
  auto refused = [](const std::function<void(Image&)>& edit, const std::string& why) {
    std::string e = refusal_after(edit);
    EXPECT_NE(e.find("section 'vars'"), std::string::npos) << e;
    EXPECT_NE(e.find(why), std::string::npos) << e;
  };
  EXPECT_EQ(refusal_after([](Image&) {}), "");
  refused([](Image& im) { im.vars[1].name = ""; }, "variable 1 at file offset 0x");
  refused([](Image& im) { im.vars[1].name = ""; }, "empty name");
  refused([](Image& im) { im.vars[2].name = "tank"; }, "second variable named 'tank'");
  refused([](Image& im) { im.vars[0].type = ""; }, "'tank' has an empty type");
  refused([](Image& im) { im.vars[0].bits = Area::X; }, "area 2 cannot hold its bits (M or K)");
  refused([](Image& im) { im.vars[0].cells = Area::WY; }, "area 10 cannot hold its cells (D or F)");
  refused([](Image& im) { im.vars[0].cells = Area::E; }, "cannot hold its cells");
  refused([](Image& im) { im.vars[0].cell_first = 8190; }, "cells D8190+4 outside D0..D8191");
  refused([](Image& im) { im.vars[0].bit_first = 0xFFFFFFFFu; }, "outside M0..M8191");  // first + count wraps in 32 bits
  refused([](Image& im) { im.vars[1].cell_first = 1024; }, "cells F1024+1 outside F0..F1023");
  refused([](Image& im) { im.vars[0].bit_count = 0; }, "bits M3+0 outside");
  refused([](Image& im) { im.vars[1].bit_first = 5; }, "'r': no bits area but a row 5+0");
  refused([](Image& im) { im.vars[1].cells = Area::Count, im.vars[1].cell_first = 0, im.vars[1].cell_count = 0; }, "'r' has no place");
}

// Byte-level edits the writer cannot make: the version, the count, a
// truncated entry, trailing bytes, an unknown area byte.
TEST(VarsSection, RefusesBadVersionCountsAndLengths) {
  std::vector<uint8_t> b = write_image(with_vars());
  int e = find_section(b, 10);
  ASSERT_GE(e, 0);
  uint32_t off = get32(b, entry_at(e) + 4), size = get32(b, entry_at(e) + 8);
  auto refusal = [&](const std::function<void(std::vector<uint8_t>&)>& edit) -> std::string {
    std::vector<uint8_t> x = b;
    edit(x);
    reseal(x);
    try {
      read_image(x, "t.bin");
    } catch (ImageError& err) {
      return err.what();
    }
    return "";
  };
  auto expect = [&](const std::string& e2, const std::string& why) {
    EXPECT_NE(e2.find("section 'vars' at offset"), std::string::npos) << e2;
    EXPECT_NE(e2.find(why), std::string::npos) << e2;
  };
  expect(refusal([&](std::vector<uint8_t>& x) { put32(x, off, 2); }), "version 2, this loader reads version 1");
  expect(refusal([&](std::vector<uint8_t>& x) { put32(x, off + 4, 0xFFFFFFFFu); }), "variable count 4294967295 does not fit in the section");
  expect(refusal([&](std::vector<uint8_t>& x) { put32(x, off + 4, 4); }), "");  // a fourth entry that is not there
  expect(refusal([&](std::vector<uint8_t>& x) { put32(x, off + 4, 2); }), "unexpected bytes");  // the third is left over
  expect(refusal([&](std::vector<uint8_t>& x) { put32(x, entry_at(e) + 8, size - 1); }), "");  // cut inside the last entry
  // The first entry's name length past the section.
  expect(refusal([&](std::vector<uint8_t>& x) { put32(x, off + 8, 1000); }), "");
  // The first entry's bits area byte (after its two strings): unknown area 200.
  size_t area_at = off + 8 + 4 + 4 + 4 + 21;  // "tank", "Tank#0123456789abcdef"
  ASSERT_EQ(b[area_at], uint8_t(Area::M));
  expect(refusal([&](std::vector<uint8_t>& x) { x[area_at] = 200; }), "area 200 cannot hold its bits");
}

// Every single-byte change of the section is refused or reads back as an
// image that passes the checks again (no crash, no half-read section).
TEST(VarsSection, EveryByteFlipIsRefusedOrConsistent) {
  std::vector<uint8_t> b = write_image(with_vars());
  int e = find_section(b, 10);
  uint32_t off = get32(b, entry_at(e) + 4), size = get32(b, entry_at(e) + 8);
  size_t refused = 0, accepted = 0;
  for (uint32_t i = off; i < off + size; i++)
    for (uint8_t bit = 0; bit < 8; bit++) {
      std::vector<uint8_t> x = b;
      x[i] ^= uint8_t(1u << bit);
      reseal(x);
      try {
        Image im = read_image(x, "t.bin");
        accepted++;
        EXPECT_EQ(read_image(write_image(im), "t.bin"), im);  // what was accepted is an image the checks pass again
      } catch (ImageError&) {
        refused++;
      }
    }
  EXPECT_GT(refused, 0u);
  EXPECT_GT(accepted, 0u);  // a flipped letter of a name is still a name
}

}  // namespace
}  // namespace ldc::test
