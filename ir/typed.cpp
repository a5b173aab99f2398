// ir/typed.cpp -- what the IL's readers and writers need of the typed
// instructions: type names, which types an op takes (ops.def's types column),
// which devices a typed operand may be, and the spelling of typed constants.
#include <charconv>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "ir/typed.h"

namespace ldc {

static bool iequal(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); i++) {
    char x = a[i], y = b[i];
    if (x >= 'a' && x <= 'z') x = char(x - 32);
    if (y >= 'a' && y <= 'z') y = char(y - 32);
    if (x != y) return false;
  }
  return true;
}

std::optional<Ty> ty_from_name(std::string_view name) {
  for (int i = 0; i < kTyCount; i++)
    if (iequal(name, kTys[i].name)) return Ty(i);
  static const struct { const char* name; Ty ty; } kLong[] = {
      {"TIME_OF_DAY", Ty::TOD}, {"DATE_AND_TIME", Ty::DT}, {"LTOD", Ty::TOD}, {"LTIME_OF_DAY", Ty::TOD},
      {"LDT", Ty::DT}, {"LDATE_AND_TIME", Ty::DT}, {"LDATE", Ty::DATE}};
  for (const auto& l : kLong)
    if (iequal(name, l.name)) return l.ty;
  return std::nullopt;
}

std::string alias_type_problem(const Alias& a) {
  if (a.ty == Ty::None) return "";
  if (int(a.ty) > kTyCount) return "unknown type " + std::to_string(int(a.ty));
  const TyInfo& t = ty_info(a.ty);
  std::string what = std::string(t.name) + " alias '" + a.name + "' on " + dev_name(a.dev.dev) + std::to_string(a.dev.index);
  if (t.cells == 0) return bit_area(a.dev.dev) == Area::Count ? what + ": a BOOL names a bit device" : "";
  if (word_area(a.dev.dev) == Area::Count) return what + ": a " + t.name + " names a word device";
  if (uint64_t(a.dev.index) + uint64_t(t.cells) > device_count(a.dev.dev))
    return what + ": its " + std::to_string(t.cells) + " cells run past " + dev_name(a.dev.dev) + std::to_string(device_count(a.dev.dev) - 1);
  return "";
}

std::optional<Op> typed_op_from_name(std::string_view spelling) {
  if (spelling.empty() || spelling.size() > 15) return std::nullopt;
  auto op = op_from_name("T" + std::string(spelling));
  if (!op || !op_info(*op).typed) return std::nullopt;
  return op;
}

bool op_takes(Op op, Ty t, Ty u) {
  const OpInfo& oi = op_info(op);
  if (!oi.typed || t == Ty::None || int(t) >= kTyCount) return false;
  const char* bar = std::strchr(oi.types, '|');
  std::string_view ts(oi.types, bar ? size_t(bar - oi.types) : std::strlen(oi.types));
  if (ts.find(ty_letter(t)) == std::string_view::npos) return false;
  if (oi.typed == 1) return u == Ty::None;
  if (u == Ty::None || int(u) >= kTyCount || !bar) return false;
  if (std::strchr(bar + 1, ty_letter(u)) == nullptr) return false;
  return op != Op::TCONV || (t != Ty::STRING && u != Ty::STRING) || typed::conv_string_ok(t, u);
}

std::string op_spelling(const Instr& in) {
  const OpInfo& oi = op_info(in.op);
  if (!oi.typed) return oi.name;
  std::string s = std::string(oi.name + 1) + "." + (in.ty == Ty::None ? "?" : ty_info(in.ty).name);
  if (oi.typed == 2) s += std::string(".") + (in.src == Ty::None ? "?" : ty_info(in.src).name);
  return s;
}

Ty operand_type(const Instr& in, int i) {
  char sig = op_info(in.op).operands[i];
  if (sig == 'x') return in.src;
  if (sig == 's' || sig == 'r' || sig == 'a') return in.ty;
  return Ty::None;
}

bool typed_area_ok(char sig, Ty t, Area a, uint32_t idx, const Layout& L) {
  if (sig == 'k') return false;
  if (t == Ty::BOOL) return operand_area_ok(sig == 'r' ? 'w' : 'b', a, idx) && idx < L.count[int(a)];
  if (!operand_area_ok(sig == 'r' ? 'd' : 'v', a, idx)) return false;
  return uint64_t(idx) + uint64_t(ty_info(t).cells) <= L.count[int(a)];
}

std::string typed_const_text(Ty t, uint64_t v) {
  if (typed::is_real(t)) {
    if (ty_info(t).bits == 32) return real_text(typed::f32(v));
    char buf[48];
    std::snprintf(buf, sizeof buf, "%.17g", typed::f64(v));
    std::string s = buf;
    if (s.find_first_of(".eEn") == std::string::npos) s += ".0";
    return s;
  }
  return typed::is_signed(t) ? std::to_string(int64_t(v)) : std::to_string(v);
}

std::optional<uint64_t> parse_typed_const(Ty t, std::string_view s, std::string& why) {
  if (s.empty()) return why = "empty constant", std::nullopt;
  if (t == Ty::STRING) return why = "a STRING operand is a device; a literal is moved into its cells", std::nullopt;
  if (typed::is_real(t)) {
    std::string z(s);
    char* end = nullptr;
    double d = std::strtod(z.c_str(), &end);
    if (end != z.c_str() + z.size() || !(z[0] == '-' || z[0] == '+' || z[0] == '.' || (z[0] >= '0' && z[0] <= '9')))
      return why = "expected a " + std::string(ty_info(t).name) + " constant, found '" + z + "'", std::nullopt;
    return typed::real_bits(t, d);
  }
  bool neg = s[0] == '-';
  std::string_view digits = neg || s[0] == '+' ? s.substr(1) : s;
  uint64_t mag = 0;
  auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), mag);
  if (digits.empty() || ec != std::errc() || end != digits.data() + digits.size())
    return why = "expected a " + std::string(ty_info(t).name) + " constant, found '" + std::string(s) + "'", std::nullopt;
  uint64_t v = neg ? 0 - mag : mag;
  bool fits = neg ? typed::is_signed(t) && mag <= (uint64_t(1) << 63) : true;
  if (fits && typed::norm(t, v) != v) fits = false;
  if (fits && !neg && typed::is_signed(t) && int64_t(v) < 0) fits = false;
  if (!fits) return why = "constant " + std::string(s) + " outside the range of " + ty_info(t).name, std::nullopt;
  return v;
}

}  // namespace ldc
