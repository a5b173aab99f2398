// Fuzz the trace CSV reader: read_trace with a couple of aliases.
#include <stdexcept>
#include <vector>

#include "runtime/runtime.h"
#include "tests/fuzz/fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const std::vector<ldc::Alias> aliases = [] {
    std::vector<ldc::Alias> a(2);
    a[0].name = "start";
    a[0].dev = {ldc::Dev::X, 0};
    a[1].name = "speed";
    a[1].dev = {ldc::Dev::D, 3};
    return a;
  }();
  try {
    (void)ldc::read_trace(LDC_FUZZ_TEXT(data, size), "fuzz.csv", aliases);
  } catch (const std::runtime_error&) {  // documented: located runtime_error
  }
  return 0;
}
