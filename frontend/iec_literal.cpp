// frontend/iec_literal.cpp -- IEC 61131-3 literals with their types (iec_literal.h).
#include "frontend/iec_literal.h"

#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "ir/typed.h"

namespace ldc {

namespace {

std::string upper_of(std::string_view s) {
  std::string u(s);
  for (char& c : u) c = char(std::toupper((unsigned char)c));
  return u;
}

// Digits in `base` (underscores between them allowed) into v; false if
// malformed or beyond 64 bits.
bool digits_value(std::string_view d, int base, uint64_t& v) {
  v = 0;
  bool any = false;
  for (char c : d) {
    if (c == '_') continue;
    int x = std::isdigit((unsigned char)c) ? c - '0' : (c >= 'A' && c <= 'F') ? c - 'A' + 10 : 99;
    if (x >= base) return false;
    if (v > (UINT64_MAX - uint64_t(x)) / uint64_t(base)) return false;
    v = v * uint64_t(base) + uint64_t(x);
    any = true;
  }
  return any;
}

// An integer with an optional sign and base (16#FF, 2#1010, 8#17, 42) as a
// magnitude and a sign.
bool integer_text(std::string_view u, bool& neg, uint64_t& mag, bool& based) {
  neg = false;
  based = false;
  if (!u.empty() && (u[0] == '-' || u[0] == '+')) neg = u[0] == '-', u = u.substr(1);
  if (u.empty() || !std::isdigit((unsigned char)u[0])) return false;
  size_t hash = u.find('#');
  if (hash == std::string_view::npos) return digits_value(u, 10, mag);
  std::string_view b = u.substr(0, hash);
  based = true;
  int base = b == "16" ? 16 : b == "8" ? 8 : b == "2" ? 2 : 0;
  return base && digits_value(u.substr(hash + 1), base, mag);
}

bool real_text(std::string_view u, double& d) {
  std::string s;
  for (char c : u)
    if (c != '_') s += c;
  if (s.empty()) return false;
  size_t i = s[0] == '-' || s[0] == '+' ? 1 : 0;
  if (i >= s.size() || !(std::isdigit((unsigned char)s[i]) || s[i] == '.')) return false;
  char* end = nullptr;
  d = std::strtod(s.c_str(), &end);
  return end == s.c_str() + s.size();
}

// d h m s ms us ns, each a number with an optional fraction, in that order of
// size (IEC lets the first one overflow: T#25h); a leading '-'.
std::optional<int64_t> duration_ns(std::string_view u) {
  bool neg = false;
  if (!u.empty() && (u[0] == '-' || u[0] == '+')) neg = u[0] == '-', u = u.substr(1);
  long double total = 0;
  size_t i = 0;
  int parts = 0;
  while (i < u.size()) {
    if (u[i] == '_') { i++; continue; }
    size_t start = i;
    while (i < u.size() && (std::isdigit((unsigned char)u[i]) || u[i] == '.' || u[i] == '_')) i++;
    if (start == i) return std::nullopt;
    std::string num;
    for (size_t k = start; k < i; k++)
      if (u[k] != '_') num += u[k];
    char* end = nullptr;
    long double v = std::strtold(num.c_str(), &end);
    if (end != num.c_str() + num.size()) return std::nullopt;
    long double scale;
    if (u.substr(i, 2) == "MS") scale = 1e6L, i += 2;
    else if (u.substr(i, 2) == "US") scale = 1e3L, i += 2;
    else if (u.substr(i, 2) == "NS") scale = 1, i += 2;
    else if (i < u.size() && u[i] == 'D') scale = 86400e9L, i++;
    else if (i < u.size() && u[i] == 'H') scale = 3600e9L, i++;
    else if (i < u.size() && u[i] == 'M') scale = 60e9L, i++;
    else if (i < u.size() && u[i] == 'S') scale = 1e9L, i++;
    else return std::nullopt;
    total += v * scale;
    parts++;
  }
  if (!parts) return std::nullopt;
  total = std::round(total);  // below a nanosecond: the nearest (MatIEC keeps ns)
  if (total >= 9.2e18L) return std::nullopt;
  return neg ? -int64_t(total) : int64_t(total);
}

// Days since 1970-01-01 of a civil date (proleptic Gregorian).
int64_t days_from_civil(int64_t y, unsigned m, unsigned d) {
  y -= m <= 2;
  const int64_t era = (y >= 0 ? y : y - 399) / 400;
  const unsigned yoe = unsigned(y - era * 400);
  const unsigned doy = (153 * (m + (m > 2 ? -3 : 9)) + 2) / 5 + d - 1;
  const unsigned doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
  return era * 146097 + int64_t(doe) - 719468;
}

std::optional<int64_t> date_ns(std::string_view u) {
  int y, m, d;
  char tail;
  if (std::sscanf(std::string(u).c_str(), "%d-%d-%d%c", &y, &m, &d, &tail) != 3) return std::nullopt;
  if (m < 1 || m > 12 || d < 1 || d > 31 || y < 1 || y > 9999) return std::nullopt;
  return days_from_civil(y, unsigned(m), unsigned(d)) * typed::kNsPerDay;
}

std::optional<int64_t> tod_ns(std::string_view u) {
  std::string s(u);
  int h, m;
  double sec = 0;
  int n = 0;
  if (std::sscanf(s.c_str(), "%d:%d%n", &h, &m, &n) != 2) return std::nullopt;
  if (size_t(n) < s.size()) {
    if (s[size_t(n)] != ':') return std::nullopt;
    char* end = nullptr;
    std::string rest = s.substr(size_t(n) + 1);
    sec = std::strtod(rest.c_str(), &end);
    if (rest.empty() || end != rest.c_str() + rest.size()) return std::nullopt;
  }
  if (h < 0 || h > 23 || m < 0 || m > 59 || sec < 0 || sec >= 60) return std::nullopt;
  return int64_t(h) * 3600000000000LL + int64_t(m) * 60000000000LL + int64_t(std::llround(sec * 1e9));
}

}  // namespace

double IecLiteral::real() const { return typed::real_value(type, bits); }

Ty iec_type_named(std::string_view name) {
  std::string u = upper_of(name);
  if (u == "TIME_OF_DAY") return Ty::TOD;
  if (u == "DATE_AND_TIME") return Ty::DT;
  for (int i = 0; i < kTyCount; i++)
    if (u == ty_info(Ty(i)).name) return Ty(i);
  return Ty::None;
}

std::optional<IecLiteral> parse_iec_literal(std::string_view text, std::string& why) {
  why.clear();
  std::string u = upper_of(text);
  auto bad = [&](const std::string& m) -> std::optional<IecLiteral> { why = m; return std::nullopt; };
  std::string quoted = "'" + std::string(text) + "'";
  if (u == "TRUE" || u == "FALSE") return IecLiteral{Ty::BOOL, true, u == "TRUE"};
  size_t hash = u.find('#');
  std::string prefix = hash == std::string::npos ? "" : u.substr(0, hash), body = hash == std::string::npos ? u : u.substr(hash + 1);
  // durations, dates, times of day
  if (prefix == "T" || prefix == "TIME" || prefix == "LT" || prefix == "LTIME") {
    auto ns = duration_ns(body);
    if (!ns) return bad("malformed duration " + quoted);
    return IecLiteral{prefix[0] == 'L' ? Ty::LTIME : Ty::TIME, true, uint64_t(*ns)};
  }
  if (prefix == "D" || prefix == "DATE") {
    auto ns = date_ns(body);
    if (!ns) return bad("malformed date " + quoted);
    return IecLiteral{Ty::DATE, true, uint64_t(*ns)};
  }
  if (prefix == "TOD" || prefix == "TIME_OF_DAY") {
    auto ns = tod_ns(body);
    if (!ns) return bad("malformed time of day " + quoted);
    return IecLiteral{Ty::TOD, true, uint64_t(*ns)};
  }
  if (prefix == "DT" || prefix == "DATE_AND_TIME") {
    size_t dash = body.size() > 10 ? 10 : std::string::npos;
    if (dash == std::string::npos || body[dash] != '-') return bad("malformed date and time " + quoted);
    auto d = date_ns(body.substr(0, dash));
    auto t = tod_ns(body.substr(dash + 1));
    if (!d || !t) return bad("malformed date and time " + quoted);
    return IecLiteral{Ty::DT, true, uint64_t(*d + *t)};
  }
  Ty t = Ty::None;
  bool typed = false;
  if (!prefix.empty() && !std::isdigit((unsigned char)prefix[0]) && prefix[0] != '-' && prefix[0] != '+') {
    t = iec_type_named(prefix);
    if (t == Ty::None) return std::nullopt;  // NAME#... is not a literal ldc knows; the caller says what it is
    if (t == Ty::TIME || t == Ty::LTIME || t == Ty::DATE || t == Ty::TOD || t == Ty::DT) return bad("malformed literal " + quoted);
    typed = true;
    u = body;
  }
  if (t == Ty::BOOL) {
    if (u == "TRUE" || u == "1") return IecLiteral{Ty::BOOL, true, 1};
    if (u == "FALSE" || u == "0") return IecLiteral{Ty::BOOL, true, 0};
    return bad("malformed BOOL literal " + quoted);
  }
  if (u.empty() || !(std::isdigit((unsigned char)u[0]) || u[0] == '-' || u[0] == '+' || u[0] == '.')) {
    if (typed) return bad("malformed literal " + quoted);
    return std::nullopt;
  }
  bool neg, based;
  uint64_t mag;
  if (integer_text(u, neg, mag, based)) {
    if (t != Ty::None && typed::is_real(t)) {
      double d = neg ? -double(mag) : double(mag);
      return IecLiteral{t, true, typed::real_bits(t, d)};
    }
    Ty tt = t == Ty::None ? Ty::LINT : t;
    uint64_t v = neg ? 0 - mag : mag;
    // a based literal is a bit pattern of its type (16#FFFF is a WORD's all ones);
    // a decimal one must fit
    bool fits;
    if (based && t != Ty::None) fits = !neg && (ty_info(t).bits == 64 || mag < (uint64_t(1) << ty_info(t).bits));
    else if (tt == Ty::LINT && t == Ty::None) fits = neg ? mag <= (uint64_t(1) << 63) : true;
    else fits = typed::is_signed(tt) ? (neg ? mag <= (uint64_t(1) << (ty_info(tt).bits - 1))
                                            : mag < (uint64_t(1) << (ty_info(tt).bits - 1)))
                                     : !neg && (ty_info(tt).bits == 64 || mag < (uint64_t(1) << ty_info(tt).bits));
    if (!fits) return bad("literal " + quoted + " is outside the range of " + ty_info(tt).name);
    if (t == Ty::None && !neg && mag > uint64_t(INT64_MAX)) tt = Ty::ULINT;
    return IecLiteral{tt, typed, typed::norm(tt, v), based};
  }
  double d;
  if (real_text(u, d)) {
    if (t != Ty::None && !typed::is_real(t)) return bad("literal " + quoted + " is not a whole number, as " + ty_info(t).name + " needs");
    Ty rt = t == Ty::None ? Ty::LREAL : t;
    return IecLiteral{rt, typed, typed::real_bits(rt, d)};
  }
  return bad("malformed literal " + quoted);
}

}  // namespace ldc
