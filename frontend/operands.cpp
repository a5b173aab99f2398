// frontend/operands.cpp -- device spellings, IEC addresses, aliases, constants
// and durations, and the typed operands of every element (docs/format.md).
#include "frontend/operands.h"

#include "frontend/frontend.h"

#include <cctype>
#include <cmath>
#include <cstdlib>

namespace ldc {

char upper_ascii(char c) { return c >= 'a' && c <= 'z' ? char(c - 'a' + 'A') : c; }

std::string upper(std::string_view s) {
  std::string u(s);
  for (char& c : u) c = upper_ascii(c);
  return u;
}

bool iequals(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); i++)
    if (upper_ascii(a[i]) != upper_ascii(b[i])) return false;
  return true;
}

std::vector<std::string_view> source_line_views(std::string_view text) {
  if (text.size() > kMaxSourceBytes) throw CompileError(1, 1, "source file too large (at most 64 MiB)");
  std::vector<std::string_view> lines;
  size_t pos = 0;
  while (pos < text.size()) {
    size_t nl = text.find('\n', pos);
    std::string_view l = text.substr(pos, nl == std::string_view::npos ? std::string_view::npos : nl - pos);
    if (!l.empty() && l.back() == '\r') l.remove_suffix(1);
    lines.push_back(l);
    pos = nl == std::string_view::npos ? text.size() : nl + 1;
  }
  return lines;
}

std::vector<std::string> source_lines(std::string_view text) {
  std::vector<std::string> lines;
  for (std::string_view l : source_line_views(text)) lines.emplace_back(l);
  return lines;
}

DeviceRef resolve_device(const std::string& text, int col, const std::map<std::string, DeviceRef>& names,
                         const std::string& what) {
  auto it = names.find(upper(text));
  if (it != names.end()) return it->second;
  return resolve_device_spelling(text, col, what.c_str());
}

DeviceRef resolve_device_spelling(std::string_view text, int col, const char* what) {
  std::string why;
  DeviceRef d;
  if (auto p = parse_device(text)) d = *p;
  else if (auto q = parse_iec_address(text, why)) d = *q;
  else throw CompileError(0, col, why.empty() ? "unknown " + std::string(what) + " '" + std::string(text) + "'" : why);
  return device_in_range(d, text, col);
}

DeviceRef device_in_range(DeviceRef d, std::string_view text, int col) {
  if (d.index >= device_count(d.dev))
    throw CompileError(0, col, "index out of range: " + std::string(text) + " (" + dev_name(d.dev) + "0.." + dev_name(d.dev) +
                                   std::to_string(device_count(d.dev) - 1) + ")");
  return d;
}

bool is_identifier(std::string_view s) {
  if (s.empty() || !(std::isalpha((unsigned char)s[0]) || s[0] == '_')) return false;
  for (char c : s)
    if (!std::isalnum((unsigned char)c) && c != '_') return false;
  return true;
}

// duration = ["T#" | "TIME#"] { NUMBER unit } | NUMBER unit     unit = d h m s ms
// Returns milliseconds; sets why and returns false on a malformed duration.
// `shown` is the constant as the source wrote it (for the messages).
static bool parse_duration(std::string_view text, std::string_view shown, int64_t& ms, std::string& why) {
  std::string u = upper(text);
  size_t i = 0;
  if (u.rfind("T#", 0) == 0) i = 2;
  else if (u.rfind("TIME#", 0) == 0) i = 5;
  double total = 0;
  int parts = 0;
  while (i < u.size()) {
    if (u[i] == '_') { i++; continue; }
    size_t start = i;
    while (i < u.size() && (std::isdigit((unsigned char)u[i]) || u[i] == '.')) i++;
    if (start == i) { why = "malformed duration '" + std::string(shown) + "'"; return false; }
    double v = std::strtod(u.substr(start, i - start).c_str(), nullptr);
    double scale;
    if (u.compare(i, 2, "MS") == 0) { scale = 1; i += 2; }
    else if (i < u.size() && u[i] == 'D') { scale = 86400000; i++; }
    else if (i < u.size() && u[i] == 'H') { scale = 3600000; i++; }
    else if (i < u.size() && u[i] == 'M') { scale = 60000; i++; }
    else if (i < u.size() && u[i] == 'S') { scale = 1000; i++; }
    else if (i == u.size() || u[i] == '_') { why = "duration '" + std::string(shown) + "' needs a unit (ms, s, m, h, d)"; return false; }
    else {
      size_t e = i;
      while (e < u.size() && std::isalpha((unsigned char)u[e])) e++;
      std::string unit(text.substr(i, std::max<size_t>(e - i, 1)));
      why = "unknown unit '" + unit + "' in duration '" + std::string(shown) + "' (the units are ms, s, m, h, d)";
      return false;
    }
    total += v * scale;
    parts++;
  }
  if (parts == 0) { why = "empty duration"; return false; }
  if (total != std::floor(total)) { why = "duration '" + std::string(shown) + "' is not a whole number of ms"; return false; }
  if (total > 2147483647.0) { why = "duration '" + std::string(shown) + "' is too long (at most 2147483647 ms)"; return false; }
  ms = int64_t(total);
  return true;
}

// constant = INT | "16#" HEX | "0x" HEX | "2#" BIN | "8#" OCT | REAL | duration
// Underscores between digits are allowed (IEC: 1_000).
std::optional<Operand> parse_constant(std::string_view text, std::string& why) {
  std::string s;
  for (char c : text)
    if (c != '_') s += c;
  if (s.empty()) return std::nullopt;
  std::string u = upper(s);
  bool neg = false;
  std::string body = u;
  std::string_view written = s;  // the body as written (the case kept), for durations' messages
  if (body[0] == '-' || body[0] == '+') { neg = body[0] == '-'; body = body.substr(1); written.remove_prefix(1); }
  if (body.empty()) return std::nullopt;
  auto with_base = [&](const std::string& digits, int base) -> std::optional<Operand> {
    if (digits.empty()) { why = "missing digits in '" + std::string(text) + "'"; return std::nullopt; }
    uint64_t v = 0;
    for (char c : digits) {
      int d = std::isdigit((unsigned char)c) ? c - '0' : (c >= 'A' && c <= 'F') ? c - 'A' + 10 : 99;
      if (d >= base) { why = "bad digit '" + std::string(1, c) + "' in '" + std::string(text) + "'"; return std::nullopt; }
      v = v * base + uint64_t(d);
      if (v > 0xFFFFFFFFull) { why = "constant '" + std::string(text) + "' does not fit in 32 bits"; return std::nullopt; }
    }
    // Based literals are bit patterns: 16#FFFFFFFF is -1.
    if (base != 10) {
      Operand o{OpdKind::ConstInt};
      o.ival = int32_t(uint32_t(neg ? 0u - uint32_t(v) : uint32_t(v)));
      return o;
    }
    int64_t sv = neg ? -int64_t(v) : int64_t(v);
    if (sv < INT32_MIN || sv > INT32_MAX) { why = "constant '" + std::string(text) + "' is out of the INT32 range"; return std::nullopt; }
    Operand o{OpdKind::ConstInt};
    o.ival = int32_t(sv);
    return o;
  };
  if (body.rfind("16#", 0) == 0) return with_base(body.substr(3), 16);
  if (body.rfind("0X", 0) == 0) return with_base(body.substr(2), 16);
  if (body.rfind("2#", 0) == 0) return with_base(body.substr(2), 2);
  if (body.rfind("8#", 0) == 0) return with_base(body.substr(2), 8);
  if (body.rfind("T#", 0) == 0 || body.rfind("TIME#", 0) == 0) {
    int64_t ms;
    if (neg) { why = "a duration cannot be negative"; return std::nullopt; }
    if (!parse_duration(written, text, ms, why)) return std::nullopt;
    Operand o{OpdKind::ConstInt};
    o.ival = int32_t(ms);
    return o;
  }
  if (!std::isdigit((unsigned char)body[0]) && body[0] != '.') return std::nullopt;
  bool all_digits = true;
  for (char c : body) all_digits &= bool(std::isdigit((unsigned char)c));
  if (all_digits) return with_base(body, 10);
  // REAL: digits, '.', exponent
  {
    char* end = nullptr;
    std::string num = (neg ? "-" : "") + body;
    double d = std::strtod(num.c_str(), &end);
    if (end && *end == '\0' && body.find_first_of(".E") != std::string::npos) {
      if (std::isinf(float(d)) && !std::isinf(d)) { why = "REAL constant '" + std::string(text) + "' is out of range"; return std::nullopt; }
      if (std::isinf(d)) { why = "REAL constant '" + std::string(text) + "' is out of range"; return std::nullopt; }
      Operand o{OpdKind::ConstReal};
      o.fval = float(d);
      return o;
    }
  }
  // number with a unit: 500ms, 2s, 1m30s
  int64_t ms;
  std::string dwhy;
  if (!neg && parse_duration(written, text, ms, dwhy)) {
    Operand o{OpdKind::ConstInt};
    o.ival = int32_t(ms);
    return o;
  }
  why = dwhy.empty() ? "malformed constant '" + std::string(text) + "'" : dwhy;
  return std::nullopt;
}

// The device kind an operand's area belongs to (a timer's or counter's bit,
// word or instance is its T or C), -1 for none.
static int operand_dev(const Operand& o) {
  switch (o.kind) {
    case OpdKind::Timer: return int(Dev::T);
    case OpdKind::Counter: return int(Dev::C);
    case OpdKind::Bit:
      return o.area == Area::X ? int(Dev::X) : o.area == Area::Y ? int(Dev::Y) : o.area == Area::M ? int(Dev::M)
             : o.area == Area::TQ ? int(Dev::T) : o.area == Area::CQ ? int(Dev::C) : -1;
    case OpdKind::Int:
    case OpdKind::Real:
      return o.area == Area::D ? int(Dev::D) : o.area == Area::TW ? int(Dev::T) : o.area == Area::CW ? int(Dev::C)
             : o.area == Area::WX ? int(Dev::WX) : o.area == Area::WY ? int(Dev::WY) : o.area == Area::F ? int(Dev::F) : -1;
    default: return -1;
  }
}

std::string spell_operand(const Operand& o, const Spellings& spelled) {
  if (int dev = operand_dev(o); dev >= 0)
    if (auto it = spelled.find({dev, o.index}); it != spelled.end()) return it->second;
  return operand_text(o);
}

}  // namespace ldc
