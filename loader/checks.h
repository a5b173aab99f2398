// loader/checks.h -- internal: the code checks shared by read_image and
// check_x86_code.  Not a public header.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "ir/ir.h"
#include "loader/loader.h"

namespace ldc::detail {

// "" if the x86-64 code passes (see check_x86_code), else "at code offset 0x..: why".
// If it passes and `starts` is given, `starts` becomes the set of offsets where
// an instruction starts.
std::string check_x86(std::span<const uint8_t> code, uint32_t entry, const Layout& layout, OffsetBits* starts);

}  // namespace ldc::detail
