// The configuration system (loader/config.h) and the image's 'config'
// section: what the IL reads and writes, blocks, conflicts, the section's
// round trip and the loader's refusals.
#include <gtest/gtest.h>

#include "driver/driver.h"
#include "driver/x86_target.h"
#include "loader/config.h"
#include "loader/loader.h"

namespace ldc {
namespace {

Program il(const std::string& text) { return parse_il_text(text, "t.il"); }

Image image_of(const Program& p) { return make_x86_image(p, build_x86(p, p.source)); }

const char* kProg =
    ".edges 1\n"
    ".rung line 1\n"
    "LOAD X3\nOR Y0\nANDN M17\nOUT Y0\n"
    ".rung line 2\n"
    "LOAD K5\nMOV WX2 D0\nADD WX40 D0 WY7\n"
    ".rung line 3\n"
    "LOADP X100 E0\nSET M17\n"
    ".end\n";

TEST(Config, AccessesOfSharedAreasOnly) {
  std::vector<IoAccess> a = io_accesses(encode_il(il(kProg)).code);
  std::vector<std::pair<std::string, bool>> got;
  for (const IoAccess& x : a) got.emplace_back(point_name(x.area, x.index), x.write);
  std::vector<std::pair<std::string, bool>> want = {{"X3", false},  {"Y0", false},   {"M17", false}, {"Y0", true},
                                                    {"K5", false},  {"WX2", false},  {"WX40", false}, {"WY7", true},
                                                    {"X100", false}, {"M17", true}};
  EXPECT_EQ(got, want);  // D0 is private: not an access
}

TEST(Config, OwnRowsMergeIntoBlocks) {
  auto acc = io_accesses(encode_il(il(kProg)).code);
  std::vector<ConfigRow> r16 = own_rows(acc, 16);
  std::vector<std::string> got;
  for (const ConfigRow& r : r16) got.push_back(block_name(r.area, r.block, 16) + ":" + std::to_string(r.flags));
  EXPECT_EQ(got, (std::vector<std::string>{"X0..X15:1", "X96..X111:1", "Y0..Y15:3", "M16..M31:3", "K0..K15:1",
                                           "WX0..WX15:1", "WX32..WX47:1", "WY0..WY15:2"}));
  std::vector<ConfigRow> r128 = own_rows(acc, 128);
  EXPECT_EQ(r128.size(), 6u);  // X0..X127 holds X3 and X100; WX0..WX127 holds WX2 and WX40
  EXPECT_EQ(block_name(Area::WY, 7, 144), "WY1008..WY1023");  // the last block is cut at the area's end
}

ConfigTask task(std::string name, uint32_t proc, const char* text, bool exclusive = false) {
  ConfigTask t;
  t.program = t.task = std::move(name);
  t.processor = proc;
  t.period_us = 1000 * (proc + 1);
  t.exclusive = exclusive;
  t.accesses = io_accesses(encode_il(il(text)).code);
  return t;
}

TEST(Config, WritersOnTwoProcessorsConflict) {
  const char* a = ".rung line 1\nLOAD X0\nOUT Y1\n.end\n";
  const char* b = ".rung line 1\nLOAD X1\nOUT Y15\nOUT Y16\n.end\n";
  SystemConfig same = configure({task("a", 0, a), task("b", 0, b)}, 16);
  EXPECT_TRUE(same.conflicts.empty());
  SystemConfig two = configure({task("a", 0, a), task("b", 1, b)}, 16);
  ASSERT_EQ(two.conflicts.size(), 1u);
  EXPECT_EQ(block_name(two.conflicts[0].area, two.conflicts[0].block, 16), "Y0..Y15");
  EXPECT_EQ(two.conflicts[0].first, 0u);
  EXPECT_EQ(two.conflicts[0].second, 1u);
  ASSERT_EQ(two.conflicts[0].second_writes.size(), 1u);
  EXPECT_EQ(two.conflicts[0].second_writes[0].index, 15u);
  SystemConfig wide = configure({task("a", 0, a), task("b", 1, b)}, 32);
  EXPECT_EQ(wide.conflicts.size(), 1u);  // Y0..Y31
  SystemConfig excl = configure({task("a", 0, a, true), task("b", 0, b)}, 16);
  EXPECT_EQ(excl.conflicts.size(), 1u);
  // Reading another processor's block is always allowed.
  const char* c = ".rung line 1\nLOAD Y1\nOUT Y40\n.end\n";
  EXPECT_TRUE(configure({task("a", 0, a), task("c", 1, c)}, 16).conflicts.empty());
}

TEST(Config, SystemTableMarksEachTasksOwnUse) {
  const char* a = ".rung line 1\nLOAD X0\nOUT Y1\n.end\n";
  const char* c = ".rung line 1\nLOAD Y1\nOUT Y40\n.end\n";
  SystemConfig sc = configure({task("a", 0, a), task("c", 1, c)}, 16);
  ASSERT_EQ(sc.system.size(), 3u);  // X0..15, Y0..15, Y32..47
  ASSERT_EQ(sc.per_task.size(), 2u);
  const IoConfig& ca = sc.per_task[0];
  EXPECT_EQ(ca.rows.size(), 3u);
  EXPECT_EQ(ca.rows[1].flags, kBlockWrite | kBlockWritten);  // Y0..15: a writes it
  EXPECT_EQ(sc.per_task[1].rows[1].flags, kBlockRead | kBlockWritten);  // c reads it, processor 0 writes it
  EXPECT_EQ(sc.per_task[1].rows[1].writer, 0u);
  EXPECT_EQ(sc.per_task[1].rows[1].period_us, 1000u);  // the faster user's period
  EXPECT_EQ(check_io_config(ca, encode_il(il(a)).code), "");
  EXPECT_EQ(check_io_config(sc.per_task[1], encode_il(il(c)).code), "");
}

IoConfig config_for(const Program& p) {
  ConfigTask t;
  t.program = "p", t.task = "t", t.resource = "r";
  t.processor = 2;
  t.period_us = 500;
  t.accesses = io_accesses(encode_il(p).code);
  return configure({t}, 16).per_task[0];
}

TEST(ConfigSection, RoundTripsAndKeepsImagesWithoutOne) {
  Program p = il(kProg);
  Image im = image_of(p);
  std::vector<uint8_t> plain = write_image(im);
  EXPECT_EQ(plain[20], 7);  // seven sections, as before
  im.config = config_for(p);
  std::vector<uint8_t> with = write_image(im);
  EXPECT_EQ(with[20], 8);
  Image back = read_image(with, "t.bin");
  ASSERT_TRUE(back.config.has_value());
  EXPECT_EQ(*back.config, *im.config);
  EXPECT_EQ(back, im);
  EXPECT_FALSE(read_image(plain, "t.bin").config.has_value());
}

// Rewrites the config section's bytes (found by its table entry) and reseals.
std::string refusal_after(const Image& im, const std::function<void(IoConfig&)>& edit) {
  Image bad = im;
  edit(*bad.config);
  try {
    read_image(write_image(bad), "t.bin");
  } catch (ImageError& e) {
    return e.what();
  }
  return "";
}

TEST(ConfigSection, RefusesATableThatDisagreesWithTheIl) {
  Program p = il(kProg);
  Image im = image_of(p);
  im.config = config_for(p);
  EXPECT_NE(refusal_after(im, [](IoConfig& c) { c.rows.erase(c.rows.begin()); }).find("X0..X15 is read by the IL but missing"),
            std::string::npos);
  EXPECT_NE(refusal_after(im, [](IoConfig& c) { c.rows[2].flags &= ~kBlockWrite; })
                .find("block Y0..Y15 is read and written by the IL, the table says read"),
            std::string::npos);
  EXPECT_NE(refusal_after(im, [](IoConfig& c) { c.block_size = 24; }).find("not a multiple of 16"), std::string::npos);
  EXPECT_NE(refusal_after(im, [](IoConfig& c) { std::swap(c.rows[0], c.rows[1]); }).find("out of order"), std::string::npos);
  EXPECT_NE(refusal_after(im, [](IoConfig& c) { c.rows[0].area = Area::D; }).find("not a shared area"), std::string::npos);
  EXPECT_NE(refusal_after(im, [](IoConfig& c) { c.rows[0].flags |= kBlockWritten; }).find("written flag and the writer"),
            std::string::npos);
  EXPECT_NE(refusal_after(im, [](IoConfig& c) { c.rows[2].writer = 7; }).find("names processor 7"), std::string::npos);
  EXPECT_NE(refusal_after(im, [](IoConfig& c) { c.rows.back().block = 9999; }).find("does not exist"), std::string::npos);
  // A row another task uses (no own flags) is fine.
  EXPECT_EQ(refusal_after(im, [](IoConfig& c) { c.rows.push_back(ConfigRow{Area::WY, 60, 0, kNoProcessor, 10}); }), "");
}

TEST(ConfigSection, TruncatedAndReservedFieldsAreRefused) {
  Program p = il(kProg);
  Image im = image_of(p);
  im.config = config_for(p);
  std::vector<uint8_t> b = write_image(im);
  // The config section is the last one written: its table entry is the 8th.
  size_t entry = 168 + 7 * 12;
  uint32_t off = b[entry + 4] | b[entry + 5] << 8 | b[entry + 6] << 16 | uint32_t(b[entry + 7]) << 24;
  uint32_t size = b[entry + 8] | b[entry + 9] << 8 | b[entry + 10] << 16 | uint32_t(b[entry + 11]) << 24;
  auto reseal = [](std::vector<uint8_t>& x) {
    for (int i = 0; i < 4; i++) x[24 + i] = 0;
    uint32_t c = crc32(x);
    for (int i = 0; i < 4; i++) x[24 + i] = uint8_t(c >> (8 * i));
  };
  std::vector<uint8_t> r = b;
  r[off + size - 16 + 2] = 1;  // the last row's reserved u16
  reseal(r);
  try {
    read_image(r, "t.bin");
    FAIL() << "accepted";
  } catch (ImageError& e) {
    EXPECT_NE(std::string(e.what()).find("section 'config'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("reserved field"), std::string::npos) << e.what();
  }
  std::vector<uint8_t> t = b;
  t[off + 16 + 4 + 1 + 4 + 1 + 4 + 1] = 0xFF;  // the row count (after 4 u32 and three 1-byte names) becomes huge
  reseal(t);
  try {
    read_image(t, "t.bin");
    FAIL() << "accepted";
  } catch (ImageError& e) {
    EXPECT_NE(std::string(e.what()).find("does not fit"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace ldc
