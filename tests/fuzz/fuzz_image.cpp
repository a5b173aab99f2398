// Fuzz the image loader: read_image; the IL of an accepted image is re-validated.
#include "loader/loader.h"
#include "tests/fuzz/fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    ldc::Image img = ldc::read_image(std::span<const uint8_t>(data, size), "fuzz.bin");
    (void)ldc::write_image(img);
  } catch (const ldc::ImageError&) {
  }
  return 0;
}
