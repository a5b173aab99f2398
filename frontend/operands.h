// frontend/operands.h -- internal: spellings of devices, addresses and constants.
#pragma once

#include <optional>
#include <string>
#include <string_view>

#include "ir/ir.h"

namespace ldc {

std::string upper(std::string_view s);
bool is_identifier(std::string_view s);
// 42, -7, 16#FF, 0xFF, 2#1010, 1.5, -2.0e3, 500ms, 2s, T#1m30s (durations in ms).
std::optional<Operand> parse_constant(std::string_view s, std::string& why);

}  // namespace ldc
