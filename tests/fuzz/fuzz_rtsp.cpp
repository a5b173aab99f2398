// Fuzz the RTSP reader (paper 000's language, docs/rtsp.md): preprocess and
// parse, then print, lower and encode the trees of what it accepts.
#include "frontend/frontend.h"
#include "tests/fuzz/fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    ldc::TreeProgram t = ldc::parse_rtsp(LDC_FUZZ_TEXT(data, size), "fuzz.rtsp");
    (void)ldc::print_tree(t);
    ldc::Program p = ldc::lower_to_il(t);
    ldc::BinaryIl bin = ldc::encode_il(p);
    if (!ldc::validate_il(bin.code, p.layout()).empty()) __builtin_trap();  // the reader made invalid IL
  } catch (const ldc::CompileError&) {
  }
  return 0;
}
