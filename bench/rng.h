// bench/rng.h -- splitmix64 for the program generators (ldgen, synth): tiny,
// fast, and the same numbers on every platform, so a seed names a program.
#pragma once

#include <cstddef>
#include <cstdint>
#include <initializer_list>

namespace ldc {

class Rng {
 public:
  explicit Rng(uint64_t seed) : s_(seed) {}
  uint64_t next() {
    uint64_t z = (s_ += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  int below(int n) { return n <= 1 ? 0 : int(next() % uint64_t(n)); }
  int range(int lo, int hi) { return lo + below(hi - lo + 1); }
  bool pct(int p) { return below(100) < p; }
  // An index into `weights`, drawn in proportion to them (all zero: 0).
  int pick(std::initializer_list<int> weights) {
    int total = 0;
    for (int w : weights) total += w;
    if (total <= 0) return 0;
    int x = below(total), i = 0;
    for (int w : weights) {
      if (x < w) return i;
      x -= w;
      i++;
    }
    return 0;
  }
  template <size_t N>
  const char* of(const char* const (&a)[N]) { return a[below(int(N))]; }

 private:
  uint64_t s_;
};

}  // namespace ldc
