// tests/fuzz/fuzz_common.h -- shared by the fuzz harnesses (docs/fuzzing.md).
// Each harness defines LLVMFuzzerTestOneInput; the documented error types of
// a reader are normal outcomes, anything else escapes and is a bug.
#pragma once
#include <cstddef>
#include <cstdint>
#include <string_view>

#define LDC_FUZZ_TEXT(data, size) std::string_view(reinterpret_cast<const char*>(data), size)
