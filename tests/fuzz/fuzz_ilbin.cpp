// Fuzz the binary IL validator: validate_il, then run valid code one scan in
// the reference interpreter.  Byte 0 picks the edge-slot count of the layout.
#include <vector>

#include "ir/ir.h"
#include "tests/fuzz/fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  ldc::Layout layout = ldc::Layout::standard(data[0]);
  std::span<const uint8_t> code(data + 1, size - 1);
  if (!ldc::validate_il(code, layout).empty()) return 0;
  std::vector<uint8_t> mem(layout.size);
  ldc::Interpreter interp(code, layout);
  interp.scan(mem.data());
  interp.scan(mem.data());
  return 0;
}
