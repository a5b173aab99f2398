// stack_fits_slots (ir/ir.h) against a plain reading of its contract on random
// rungs of 1 to 80 instructions (its events live on the stack up to 32
// instructions and on the heap beyond: both sides are crossed).
#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "ir/ir.h"

using namespace ldc;

namespace {

// The contract, quadratically: the stack never goes below the rung's first
// push nor above kMaxStackDepth, and at every point between instructions the
// positions whose next event is a read lie within one window of `slots`.
bool fits_reference(const std::vector<Instr>& code, int slots) {
  struct Ev { size_t at; int pos; bool write; };
  std::vector<Ev> ev;
  int d = 0;
  for (size_t i = 0; i < code.size(); i++) {
    auto rd = [&](int p) { ev.push_back({i, p, false}); return p >= 0; };
    auto wr = [&](int p) { ev.push_back({i, p, true}); };
    switch (code[i].op) {
      case Op::LOAD: case Op::TRUE: wr(d++); if (d > kMaxStackDepth) return false; break;
      case Op::ANDBLK: case Op::ORBLK: if (!rd(d - 1) || !rd(d - 2)) return false; wr(d - 2); d--; break;
      case Op::MPS: if (!rd(d - 1)) return false; wr(d); d++; if (d > kMaxStackDepth) return false; break;
      case Op::MRD: if (!rd(d - 2)) return false; wr(d - 1); break;
      case Op::MPP: if (--d < 0) return false; break;
      default: if (!rd(d - 1)) return false; break;
    }
  }
  for (size_t at = 0; at <= code.size(); at++) {
    int lo = 1 << 20, hi = -1;
    for (int p = 0; p <= kMaxStackDepth; p++) {
      for (const Ev& e : ev) {
        if (e.at < at || e.pos != p) continue;
        if (!e.write) lo = std::min(lo, p), hi = std::max(hi, p);
        break;  // the first event of p at or after the point decides
      }
    }
    if (hi >= 0 && hi - lo >= slots) return false;
  }
  return true;
}

TEST(StackSlots, EqualsItsContractOnRandomRungs) {
  std::mt19937 rng(15);
  const Op ops[] = {Op::LOAD, Op::LOAD, Op::TRUE, Op::AND, Op::OR, Op::ANDBLK, Op::ORBLK,
                    Op::MPS, Op::MRD, Op::MPP, Op::OUT};
  int fits = 0, long_fits = 0;
  for (int round = 0; round < 20000; round++) {
    std::vector<Instr> code(1 + rng() % 80);
    int d = 0;
    for (Instr& in : code) {  // mostly well formed: a push when the stack is empty
      in.op = d == 0 && rng() % 8 ? Op::LOAD : ops[rng() % std::size(ops)];
      d += in.op == Op::LOAD || in.op == Op::TRUE || in.op == Op::MPS ? 1
           : in.op == Op::ANDBLK || in.op == Op::ORBLK || in.op == Op::MPP ? -1 : 0;
      d = std::max(d, 0);
    }
    for (int slots : {2, 3, 4}) {
      bool want = fits_reference(code, slots);
      ASSERT_EQ(stack_fits_slots(code, slots), want) << "round " << round << ", " << code.size() << " instructions";
      fits += want, long_fits += want && code.size() > 32;
    }
  }
  EXPECT_GT(fits, 1000);  // both answers are exercised, on both sides of 32 instructions
  EXPECT_GT(long_fits, 100);
}

}  // namespace
