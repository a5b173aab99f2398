// tests/driver/line_map_test.cpp -- the line map of an image made while
// assembling (build_x86 without notes: each block's item layout dropped after
// its line offsets are taken) equals the one made afterwards from every
// block's item layout (loader.h, line_offsets), on every example and many
// random programs at every level.
#include <gtest/gtest.h>

#include "driver/targets.h"
#include "driver/x86_target.h"
#include "tests/loader/programs.h"

namespace ldc {
namespace {

TEST(LineMap, MadeWhileAssemblingEqualsMadeFromEveryItem) {
  int n = 0;
  for (const Program& p : test::examples_and_random_programs(60, 40))
    for (int level : {0, 1, 2}) {
      SCOPED_TRACE(p.source + " -O" + std::to_string(level));
      NativeBuild streamed = build_x86(p, p.source, as::Mode::Blockwise, level, false);
      EXPECT_TRUE(streamed.asm_result.items.empty());
      EXPECT_TRUE(streamed.gen.il_items.empty());
      X86Code gen = generate_x86(p, p.layout(), level, false);
      as::Result whole = as::assemble(as::x86::target(), gen.program, as::Mode::Blockwise);
      ASSERT_TRUE(whole.ok());
      std::vector<uint32_t> expected = line_offsets(whole, gen.il_items, rung_blocks(gen));
      EXPECT_EQ(streamed.line_offsets, expected);
      EXPECT_EQ(streamed.asm_result.code, whole.code);
      EXPECT_EQ(make_x86_image(p, streamed), make_image(ImageTarget::X86_64, p, whole, gen.il_items, rung_blocks(gen)));
      n++;
    }
  EXPECT_GE(n, 180);
}

}  // namespace
}  // namespace ldc
