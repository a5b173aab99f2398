// frontend/operands.h -- internal: spellings of devices, addresses and constants.
#pragma once

#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "ir/ir.h"

namespace ldc {

// ASCII upper case (names and keywords are ASCII; no locale).
char upper_ascii(char c);
std::string upper(std::string_view s);
// The lines of a source file, a '\r' before each '\n' dropped; throws
// CompileError(1, 1) above kMaxSourceBytes (frontend.h).
std::vector<std::string> source_lines(std::string_view text);
// The same lines as views into `text` (no copies).
std::vector<std::string_view> source_line_views(std::string_view text);
// A name of `names` (upper-case keys), a device spelling or an IEC address,
// range-checked; else CompileError(0, col, "unknown <what> '<text>'" or why).
DeviceRef resolve_device(const std::string& text, int col, const std::map<std::string, DeviceRef>& names,
                         const std::string& what);
// The same without names: a device spelling or an IEC address, range-checked.
DeviceRef resolve_device_spelling(std::string_view text, int col, const char* what);
// d, spelled `text`, if its index is in range; else CompileError(0, col, ...).
DeviceRef device_in_range(DeviceRef d, std::string_view text, int col);
// ASCII case-insensitive equality (names and keywords).
bool iequals(std::string_view a, std::string_view b);
bool is_identifier(std::string_view s);
// 42, -7, 16#FF, 0xFF, 2#1010, 1.5, -2.0e3, 500ms, 2s, T#1m30s (durations in ms).
std::optional<Operand> parse_constant(std::string_view s, std::string& why);

// Names as the source spelled them, by (Dev, index): the importers' --emit=tree text.
using Spellings = std::map<std::pair<int, uint32_t>, std::string>;
// An operand as its source spelled its device (`spelled`), else operand_text.
std::string spell_operand(const Operand& o, const Spellings& spelled);

}  // namespace ldc
