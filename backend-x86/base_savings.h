// The bytes a region's choice of base-register windows saves (x86gen.cpp's
// BasePlan), in O(1) a choice.  Internal to backend-x86 (and its test).
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>

namespace ldc::x86gen {

// Operands counted by the set of windows covering each (a mask of at most
// kMaxWindows bits).  After sum_subsets(), saved(rdi, other) is what the
// per-operand rule gives: 3 bytes an operand covered by a window in `rdi`,
// else 3 (REX anyway) or 2 one covered by a window in `other`, else 0.
// The two counts of a set share one word (rdi's bytes in the low half, the
// others' in the high half: neither comes near 2^32), so that the subset sums
// add both at once.
class BaseSavings {
 public:
  static constexpr size_t kMaxWindows = 6;

  void clear(size_t windows) {
    full_ = (1u << windows) - 1;
    std::fill_n(sums_.begin(), full_ + 1, 0);
  }
  void add(uint32_t mask, bool rex) { sums_[mask] += 3 | uint64_t(rex ? 3 : 2) << 32; }

  // Each entry becomes the sum over its subsets (the zeta transform, bit by bit).
  void sum_subsets() {
    for (uint32_t bit = 1; bit <= full_; bit <<= 1)
      for (uint32_t x = bit; x <= full_; x = (x + 1) | bit)  // the sets with `bit`, in order
        sums_[x] += sums_[x ^ bit];
  }

  // Operands meeting rdi: all less those inside its complement; operands
  // missing rdi but meeting other: those inside ~rdi less those inside ~(rdi|other).
  int64_t saved(uint32_t rdi, uint32_t other) const {
    const uint32_t not_rdi = full_ & ~rdi, neither = full_ & ~(rdi | other);
    return rdi_sum(full_) - rdi_sum(not_rdi) + other_sum(not_rdi) - other_sum(neither);
  }

 private:
  int64_t rdi_sum(uint32_t set) const { return int64_t(uint32_t(sums_[set])); }
  int64_t other_sum(uint32_t set) const { return int64_t(sums_[set] >> 32); }

  uint32_t full_ = 0;
  std::array<uint64_t, size_t(1) << kMaxWindows> sums_{};
};

}  // namespace ldc::x86gen
