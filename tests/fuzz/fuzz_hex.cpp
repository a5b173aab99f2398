// Fuzz the Intel HEX reader: read_intel_hex, and read_image on what it accepts.
#include "loader/loader.h"
#include "tests/fuzz/fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  (void)ldc::looks_like_intel_hex(std::span<const uint8_t>(data, size));
  try {
    std::vector<uint8_t> bytes = ldc::read_intel_hex(LDC_FUZZ_TEXT(data, size), "fuzz.hex");
    (void)ldc::read_image(bytes, "fuzz.hex");
  } catch (const ldc::ImageError&) {
  }
  return 0;
}
