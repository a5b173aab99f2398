// x86gen::BaseSavings (backend-x86/base_savings.h): the bytes a choice of
// base-register windows saves, from subset sums, equal to counting operand by
// operand (the rule it replaced) on random operands and every choice.
#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "backend-x86/base_savings.h"

using ldc::x86gen::BaseSavings;

namespace {

struct Operand {
  uint32_t mask;  // the windows covering it
  bool rex;
};

int64_t by_operand(const std::vector<Operand>& ops, uint32_t rdi, uint32_t other) {
  int64_t saved = 0;
  for (const Operand& o : ops)
    if (o.mask & rdi) saved += 3;
    else if (o.mask & other) saved += o.rex ? 3 : 2;
  return saved;
}

TEST(BaseSavings, EqualsCountingOperandByOperand) {
  std::mt19937 rng(15);
  BaseSavings sv;
  for (int round = 0; round < 400; round++) {
    const size_t windows = 1 + rng() % BaseSavings::kMaxWindows;
    const uint32_t full = (1u << windows) - 1;
    std::vector<Operand> ops(rng() % 80);
    sv.clear(windows);
    for (Operand& o : ops) {
      o = {1 + uint32_t(rng()) % full, rng() % 2 == 0};
      sv.add(o.mask, o.rex);
    }
    sv.sum_subsets();
    for (uint32_t rdi = 0; rdi <= full; rdi++)
      for (uint32_t other = 0; other <= full; other++)
        ASSERT_EQ(sv.saved(rdi, other), by_operand(ops, rdi, other)) << "round " << round << " rdi " << rdi << " other " << other;
  }
}

TEST(BaseSavings, ClearForgetsTheLastRegion) {
  BaseSavings sv;
  sv.clear(6);
  sv.add(63, true);
  sv.sum_subsets();
  EXPECT_EQ(sv.saved(1, 0), 3);
  sv.clear(3);
  sv.sum_subsets();
  EXPECT_EQ(sv.saved(1, 6), 0);
}

}  // namespace
