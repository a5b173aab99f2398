// tests/fuzz/limits_test.cpp -- the readers' resource limits (docs/fuzzing.md):
// oversized input is refused with a located error, never a crash.
#include <cstdio>
#include <string>

#include "frontend/frontend.h"

static int failures = 0;

static void expect_error(const std::string& what, const std::string& text, const std::string& needle) {
  try {
    (void)ldc::lower_to_il(ldc::parse_ld(text, "limits.ld"));
    std::printf("FAIL %s: accepted\n", what.c_str());
    failures++;
  } catch (const ldc::CompileError& e) {
    if (std::string(e.what()).find(needle) == std::string::npos) {
      std::printf("FAIL %s: wrong message: %s\n", what.c_str(), e.what());
      failures++;
    } else {
      std::printf("ok   %s: %d:%d: %s\n", what.c_str(), e.line, e.col, e.what());
    }
  }
}

int main() {
  std::string rungs;
  for (size_t i = 0; i <= ldc::kMaxRungs; i++) rungs += "|--[X0]--(Y0)\n\n";
  expect_error("rung count", rungs, "too many rungs");
  std::string tall;
  for (int i = 0; i <= ldc::kMaxRungRows; i++) tall += i == 0 ? "|--[X0]--+--(Y0)\n" : "|        |\n";
  expect_error("rung rows", tall, "rung too tall");
  expect_error("row width", "|--[X0]" + std::string(ldc::kMaxRowWidth, '-') + "(Y0)\n", "too wide");
  return failures ? 1 : 0;
}
