// tests/driver/targets_test.cpp -- the table of targets (driver/targets.h).
#include <gtest/gtest.h>

#include <set>

#include "driver/driver.h"
#include "driver/targets.h"
#include "frontend/frontend.h"

namespace ldc {
namespace {

Program program() {
  return parse_il_text(".rung line 1\n    LOAD X1\n    AND X2\n    OUT Y0\n.rung line 2\n    LOAD X3\n    OUT Y1\n.end\n",
                       "t.il");
}

TEST(Targets, NamesKindsAndEnginesAreUnique) {
  std::set<std::string_view> names, engines;
  std::set<ImageTarget> kinds;
  for (const Target& t : targets()) {
    EXPECT_TRUE(names.insert(t.name).second) << t.name;
    EXPECT_TRUE(kinds.insert(t.image_kind).second) << t.name;
    EXPECT_EQ(find_target(t.name), &t);
    EXPECT_EQ(&target_of(t.image_kind), &t);
    for (const TargetEngine& e : t.engines) {
      EXPECT_TRUE(engines.insert(e.name).second) << e.name;
      EXPECT_EQ(find_engine(e.name).target, &t);
    }
  }
  EXPECT_EQ(find_target("no-such-target"), nullptr);
  EXPECT_EQ(find_engine("interp").engine, nullptr);  // the IL engines belong to no target
  EXPECT_TRUE(host_target().host);
  EXPECT_EQ(&targets().front(), &host_target());  // the default target runs here
}

// The loader knows every target's kind of code, and nothing else: one row of
// image_kinds() per row of targets(), found by its header byte.
TEST(Targets, EveryTargetHasItsImageKindAndNoMore) {
  for (const Target& t : targets()) {
    const ImageKind* k = find_image_kind(uint8_t(t.image_kind));
    ASSERT_NE(k, nullptr) << t.name;
    EXPECT_EQ(k->id, t.image_kind);
  }
  EXPECT_EQ(image_kinds().size(), targets().size());
  EXPECT_EQ(find_image_kind(0), nullptr);
  EXPECT_EQ(find_image_kind(0xFF), nullptr);
}

// Every row's hooks agree: the image passes the row's code check and its
// disassembly, runs on the row's engines like the reference interpreter, and
// each rung's line entries point into the rung's block.
TEST(Targets, EveryRowMakesAnImageItsHooksAccept) {
  Program p = program();
  for (const Target& t : targets())
    for (int opt = 0; opt <= 2; opt++) {
      SCOPED_TRACE(std::string(t.name) + " -O" + std::to_string(opt));
      TargetCode c = t.generate(p, "t.il", opt, true);
      ASSERT_EQ(c.rung_blocks.size(), p.rungs.size());
      Image img = target_image(t, p, "t.il", opt);
      EXPECT_EQ(img.target, t.image_kind);
      EXPECT_EQ(find_image_kind(uint8_t(t.image_kind))->check(img.code, img.entry, img.layout, nullptr), "");
      EXPECT_EQ(read_image(write_image(img), "t.bin"), img);
      for (const LineEntry& l : img.lines) {
        uint32_t b = c.rung_blocks[l.rung];
        EXPECT_GE(l.code_offset, c.assembled.block_offsets[b]);
        EXPECT_LE(l.code_offset, b + 1 < c.assembled.block_offsets.size() ? c.assembled.block_offsets[b + 1] : img.code.size());
      }
      EXPECT_NE(t.disassemble(img).find("; rung 2, line 6\n;   LOAD X3"), std::string::npos);
      EXPECT_NE(t.gnu_as(p, "t.il", opt).find("t.il"), std::string::npos);
      EXPECT_FALSE(t.listing(p, "t.il", opt).empty());
      for (const TargetEngine& e : t.engines) {
        Memory m(img.layout), ref(img.layout);
        auto reference = make_interp_engine(img.il, img.layout);
        auto eng = e.make(img);
        for (int scan = 0; scan < 8; scan++) {
          for (Memory* x : {&m, &ref})
            for (uint32_t i = 1; i <= 3; i++) x->set_bit(Area::X, i, (scan >> (i - 1)) & 1);
          eng->scan(m.bytes);
          reference->scan(ref.bytes);
          EXPECT_EQ(m.get_bit(Area::Y, 0), ref.get_bit(Area::Y, 0)) << e.name << " scan " << scan;
          EXPECT_EQ(m.get_bit(Area::Y, 1), ref.get_bit(Area::Y, 1)) << e.name << " scan " << scan;
        }
        EXPECT_EQ(eng->last_cost().has_value(), !t.host) << e.name;  // simulated engines count cycles
      }
    }
}

TEST(Targets, AssemblyErrorsNameTheSourceLine) {
  as::Result r;
  r.errors.push_back({-1, 7, "bad operand"});
  try {
    throw_assembly_errors(r, "p.ld");
    ADD_FAILURE() << "no error";
  } catch (const UserError& e) {
    EXPECT_STREQ(e.what(), "p.ld:7:1: error: bad operand");
  }
}

}  // namespace
}  // namespace ldc
