// runtime/trace.cpp -- input traces, watched outputs and the scan loop.
#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <optional>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <stdexcept>

#include "ir/model.h"
#include "ir/typed.h"
#include "runtime/runtime.h"

namespace ldc {
namespace {

std::string upper(std::string_view s) {
  std::string u(s);
  for (char& c : u) c = char(std::toupper((unsigned char)c));
  return u;
}
std::string trim(std::string_view s) {
  size_t a = s.find_first_not_of(" \t\r"), b = s.find_last_not_of(" \t\r");
  return a == std::string_view::npos ? std::string() : std::string(s.substr(a, b - a + 1));
}

class InterpEngine : public Engine {
 public:
  InterpEngine(std::vector<uint8_t> il, const Layout& l) : il_(std::move(il)), interp_(il_, l) {}
  void scan(ImageBytes& mem) override { interp_.scan(mem.data()); }
 private:
  std::vector<uint8_t> il_;
  Interpreter interp_;
};

// Decimal, or hex with 0x; never octal (a leading 0 is just a 0).
}  // namespace

long long trace_cell_int(const std::string& v, char** end) {
  bool neg = !v.empty() && v[0] == '-';
  size_t at = (neg || (!v.empty() && v[0] == '+')) ? 1 : 0;
  if (v.size() > at + 2 && v[at] == '0' && (v[at + 1] == 'x' || v[at + 1] == 'X')) {
    long long x = std::strtoll(v.c_str() + at + 2, end, 16);
    return neg ? -x : x;
  }
  return std::strtoll(v.c_str(), end, 10);
}

namespace {
bool ty_is_real(Ty t) { return ty_info(t).kind == TyKind::Real; }
bool ty_is_unsigned(Ty t) { return ty_info(t).kind == TyKind::Unsigned || ty_info(t).kind == TyKind::Bits; }

// Decimal, or hex with 0x after the sign; never octal.
int cell_base(const std::string& v) {
  size_t at = !v.empty() && (v[0] == '-' || v[0] == '+') ? 1 : 0;
  return v.size() > at + 2 && v[at] == '0' && (v[at + 1] == 'x' || v[at + 1] == 'X') ? 16 : 10;
}

// A cell written as an IEC literal (T#1s500ms, TOD#12:00:00, 16#FF, TRUE,
// 'text'): its value at type t, through the literal reader of the typed
// programs (ir/model.h), so a trace takes what the program's source takes.
// A TIME column takes a T# literal and an LTIME column either kind; a DATE
// column a DT# too, the form a DATE not at midnight is shown in.
std::optional<model::Lit> literal_cell(Ty t, const std::string& v, std::string& why) {
  std::string lwhy;
  std::optional<model::ParsedLit> p = model::parse_literal(v, lwhy);
  if (!p) {  // the reader's reason ends with the text, already given here
    if (lwhy.size() > v.size() + 2 && lwhy.ends_with(": " + v)) lwhy.resize(lwhy.size() - v.size() - 2);
    return why = "bad " + std::string(ty_info(t).name) + " '" + v + "'" + (lwhy.empty() ? "" : ": " + lwhy), std::nullopt;
  }
  bool typed = !p->untyped_int && !p->untyped_real;
  if (typed && ty_info(t).kind == TyKind::Time && ty_info(p->lit.ty).kind == TyKind::Time) return model::Lit{t, p->lit.bits};
  if (typed && t == Ty::DATE && p->lit.ty == Ty::DT) return model::Lit{t, p->lit.bits};  // a DATE not at midnight shows as DT#
  std::optional<model::Lit> l = model::literal_as(*p, t, lwhy);
  if (!l) return why = lwhy + ": '" + v + "'", std::nullopt;
  return l;
}

// Is the cell a plain number (sign, digits, 0x hex, a C real), read by strto*?
bool plain_number(const std::string& v) {
  size_t at = !v.empty() && (v[0] == '-' || v[0] == '+') ? 1 : 0;
  return at < v.size() && (std::isdigit((unsigned char)v[at]) || v[at] == '.') && v.find('#') == std::string::npos;
}

// A cell of a typed column: its value at the type (integers in its range,
// times and dates in ns); nullopt and `why` if it is not one.  A plain
// number is read as before (decimal or 0x hex, times and dates in ns, reals
// in C notation); anything else must be an IEC literal of the type.
std::optional<uint64_t> typed_cell(Ty t, const std::string& v, std::string& why) {
  const TyInfo& ti = ty_info(t);
  char* end = nullptr;
  errno = 0;
  if (ty_is_real(t) && !v.empty()) {  // C notation, inf and nan as shown
    double d = std::strtod(v.c_str(), &end);
    if (!*end && end != v.c_str()) return t == Ty::REAL ? uint64_t(typed::bits_of(float(d))) : typed::bits_of(d);
  }
  if (t == Ty::STRING || !plain_number(v)) {
    std::optional<model::Lit> l = literal_cell(t, v, why);
    return l ? std::optional<uint64_t>(l->bits) : std::nullopt;
  }
  if (ty_is_real(t)) {
    double d = std::strtod(v.c_str(), &end);
    if (*end || end == v.c_str()) return why = "bad " + std::string(ti.name) + " '" + v + "'", std::nullopt;
    if (t == Ty::REAL) {
      float f = float(d);
      uint32_t b;
      std::memcpy(&b, &f, 4);
      return b;
    }
    uint64_t b;
    std::memcpy(&b, &d, 8);
    return b;
  }
  bool neg = !v.empty() && v[0] == '-';
  if (ty_is_unsigned(t) && !neg) {
    unsigned long long x = std::strtoull(v.c_str(), &end, cell_base(v));
    if (*end || end == v.c_str()) return why = "bad " + std::string(ti.name) + " '" + v + "'", std::nullopt;
    if (errno == ERANGE || (ti.bits < 64 && x >> ti.bits))
      return why = "value out of the " + std::string(ti.name) + " range: '" + v + "'", std::nullopt;
    return uint64_t(x);
  }
  long long x = std::strtoll(v.c_str(), &end, cell_base(v));
  if (*end || end == v.c_str()) return why = "bad " + std::string(ti.name) + " '" + v + "'", std::nullopt;
  bool fits = errno != ERANGE && !ty_is_unsigned(t);
  if (t == Ty::BOOL) fits = x == 0 || x == 1;
  else if (fits && ti.bits < 64) fits = x >= -(1LL << (ti.bits - 1)) && x < (1LL << (ti.bits - 1));
  if (!fits) return why = "value out of the " + std::string(ti.name) + " range: '" + v + "'", std::nullopt;
  return uint64_t(x);
}
}  // namespace

std::string check_trace_cell(const Probe& p, const std::string& v) {
  std::string why;
  if (p.ty != Ty::None && !typed_cell(p.ty, v, why)) return why;
  return "";
}

std::string trace_cell_problem(const Probe& p, const std::string& v) {
  if (p.ty != Ty::None) {
    std::string why = check_trace_cell(p, v);
    return why.empty() ? why : why + " for " + p.name;
  }
  char* end = nullptr;
  if (p.area == Area::F) {
    std::strtof(v.c_str(), &end);
  } else {
    long long x = trace_cell_int(v, &end);
    if (!*end && area_is_bit(p.area) && p.area != Area::Sys && x != 0 && x != 1) return "a bit is 0 or 1, not '" + v + "'";
    if (!*end && (x < INT32_MIN || x > INT32_MAX)) return "value out of the INT32 range: '" + v + "'";
    if (!*end && p.area == Area::Sys && x < 0) return "dt cannot be negative";
  }
  if (*end || end == v.c_str()) return "bad value '" + v + "' for " + p.name;
  return "";
}

void put_trace_cell(uint8_t* base, const Layout& L, const Probe& p, const std::string& v) {
  uint8_t* at = base + L.addr(p.area, p.index);
  std::string why;
  if (p.ty != Ty::None && !area_is_bit(p.area)) {  // held extended in one cell, or two cells low first
    if (p.ty == Ty::STRING) {  // the length cell and the bytes (docs/il.md, "Strings")
      std::string bytes = model::string_literal_bytes(v, why).value_or("");
      std::vector<uint32_t> cells = model::string_cells(bytes);
      std::memcpy(at, cells.data(), cells.size() * 4);
      return;
    }
    uint64_t b = typed_cell(p.ty, v, why).value_or(0);
    if (ty_info(p.ty).cells == 1 && !ty_is_real(p.ty) && !ty_is_unsigned(p.ty)) b = uint64_t(int64_t(int32_t(uint32_t(b))));
    std::memcpy(at, &b, size_t(ty_info(p.ty).cells) * 4);
    return;
  }
  if (p.area == Area::F) {
    float f = std::strtof(v.c_str(), nullptr);
    std::memcpy(at, &f, 4);
  } else if (area_is_bit(p.area)) {
    *at = trace_cell_int(v) != 0;
  } else {
    int32_t x = int32_t(trace_cell_int(v));
    std::memcpy(at, &x, 4);
  }
}

uint32_t probe_width(const Probe& p, const Layout& L) {
  if (p.ty != Ty::None && !area_is_bit(p.area)) return 4 * uint32_t(std::max(1, ty_info(p.ty).cells));
  return L.elem_size(p.area);
}

std::unique_ptr<Engine> make_interp_engine(std::vector<uint8_t> il, const Layout& layout) {
  return std::make_unique<InterpEngine>(std::move(il), layout);
}

std::vector<std::pair<std::string, int>> split_cells(std::string_view line) {
  std::vector<std::pair<std::string, int>> cells;
  size_t s = 0;
  int depth = 0;
  char quote = 0;
  for (size_t i = 0;; i++) {
    if (i == line.size() || (line[i] == ',' && depth == 0 && !quote)) {
      cells.emplace_back(trim(line.substr(s, i - s)), int(s) + 1);
      if (i == line.size()) break;
      s = i + 1;
    } else if (quote) {
      if (line[i] == '$' && quote == '\'' && i + 1 < line.size()) i++;  // $' inside a STRING
      else if (line[i] == quote) quote = 0;
    } else if (line[i] == '\'' || line[i] == '"') {
      quote = line[i];
    } else if (line[i] == '[') {
      depth++;
    } else if (line[i] == ']' && depth > 0) {
      depth--;
    }
  }
  return cells;
}

std::string csv_name(const std::string& name) {
  return name.find(',') != std::string::npos && name.front() != '"' ? '"' + name + '"' : name;
}

std::vector<std::string> split_names(std::string_view list) {
  std::vector<std::string> names;
  for (auto& c : split_cells(list)) names.push_back(std::move(c.first));
  return names;
}

// A name as it is compared: without blanks and double quotes (a header cell
// "a[1,2]"), upper case (IEC names are case-insensitive).
static std::string name_key(std::string_view name) {
  std::string k;
  for (char c : name)
    if (!std::isspace((unsigned char)c) && c != '"') k += char(std::toupper((unsigned char)c));
  return k;
}

// A program's name wins over a device spelling: a variable `s2` is the
// variable, not the system bit S2 (docs/format.md, "Traces").
Probe resolve_probe(std::string_view name, const std::vector<Alias>& aliases) {
  std::string n = trim(name);
  if (n.size() >= 2 && n.front() == '"' && n.back() == '"') n = trim(n.substr(1, n.size() - 2));
  std::string key = name_key(n);
  std::optional<DeviceRef> d;
  Ty ty = Ty::None;
  for (const Alias& a : aliases)
    if (name_key(a.name) == key) {
      d = a.dev, ty = a.ty;
      break;  // the first of a name, as the program's own operands are spelled
    }
  if (!d) d = parse_device(n);
  std::string why;
  if (!d) d = parse_iec_address(n, why);
  if (!d) throw std::runtime_error("unknown device or alias '" + n + "'");
  if (d->index >= device_count(d->dev)) throw std::runtime_error("index out of range: '" + n + "'");
  Area a = (d->dev == Dev::T || d->dev == Dev::C) && ty != Ty::BOOL ? word_area(d->dev) : bit_area(d->dev);
  if (a == Area::Count) a = word_area(d->dev);
  return Probe{n, a, d->index, ty};
}

Trace read_trace(std::string_view text, const std::string& file, const std::vector<Alias>& aliases) {
  Trace t;
  size_t pos = 0;
  int line = 0;
  bool header = false;
  auto fail = [&](int col, const std::string& msg) {
    throw std::runtime_error(file + ":" + std::to_string(line) + ":" + std::to_string(col) + ": error: " + msg);
  };
  while (pos < text.size()) {
    size_t nl = text.find('\n', pos);
    std::string_view l = text.substr(pos, nl == std::string_view::npos ? std::string_view::npos : nl - pos);
    pos = nl == std::string_view::npos ? text.size() : nl + 1;
    line++;
    std::string tl = trim(l);
    if (tl.empty() || tl[0] == '#') continue;
    std::vector<std::pair<std::string, int>> cells = split_cells(l);
    if (!header) {
      header = true;
      t.header_line = line;
      for (size_t i = 0; i < cells.size(); i++) {
        t.column_col.push_back(cells[i].second);
        if (upper(cells[i].first) == "DT") {
          if (t.dt_column >= 0) fail(cells[i].second, "two dt columns");
          t.dt_column = int(i);
          t.columns.push_back(Probe{"dt", Area::Sys, 0});
          continue;
        }
        try {
          t.columns.push_back(resolve_probe(cells[i].first, aliases));
        } catch (std::exception& e) { fail(cells[i].second, e.what()); }
      }
      continue;
    }
    if (cells.size() != t.columns.size())
      fail(1, "expected " + std::to_string(t.columns.size()) + " values, found " + std::to_string(cells.size()));
    std::vector<std::string> row;
    for (size_t i = 0; i < cells.size(); i++) {
      const std::string& v = cells[i].first;
      const Probe& p = t.columns[i];
      if (!v.empty())
        if (std::string why = trace_cell_problem(p, v); !why.empty()) fail(cells[i].second, why);
      row.push_back(v);
    }
    t.rows.push_back(std::move(row));
    t.row_line.push_back(line);
  }
  if (!header) throw std::runtime_error(file + ":1:1: error: empty trace (the first line names the columns)");
  return t;
}

// REAL and LREAL in the fewest digits that read back to the same value
// (std::to_chars' shortest round trip: 0.1, 14.142136, 1e+20); inf, -inf, nan.
template <typename F>
static std::string shortest(F x) {
  char buf[64];
  auto r = std::to_chars(buf, buf + sizeof buf, x);
  return std::string(buf, r.ptr);
}

// A duration as an IEC literal: the non-zero parts d h m s ms us ns, largest
// first (T#1h2m3s500ms, T#-1d12h, T#0s); exact, and the literal reader reads
// it back to the same nanoseconds.
static std::string iec_duration(int64_t ns, const char* prefix) {
  std::string s = prefix;
  if (ns == 0) return s + "0s";
  if (ns < 0) s += '-';
  uint64_t u = ns < 0 ? uint64_t(0) - uint64_t(ns) : uint64_t(ns);
  static const struct { uint64_t ns; const char* unit; } kUnits[] = {
      {86400000000000ULL, "d"}, {3600000000000ULL, "h"}, {60000000000ULL, "m"}, {1000000000ULL, "s"},
      {1000000ULL, "ms"}, {1000ULL, "us"}, {1ULL, "ns"}};
  for (const auto& k : kUnits)
    if (uint64_t q = u / k.ns) s += std::to_string(q) + k.unit, u %= k.ns;
  return s;
}

// A point in time as an IEC literal: D#2024-01-31, TOD#12:30:00.5,
// DT#2024-01-31-12:30:00.25 (the fraction of a second exact, its trailing
// zeros dropped), by MatIEC's calendar (ir/typed.h).  A TIME_OF_DAY outside
// one day has no literal: it prints as its nanoseconds, which a trace reads back.
static std::string iec_date(Ty t, int64_t ns) {
  int64_t sec = ns / 1000000000, frac = ns % 1000000000;
  if (frac < 0) frac += 1000000000, sec--;
  if (t == Ty::TOD && (ns < 0 || sec >= 86400)) return std::to_string(ns);
  typed::Tm tm = typed::seconds_to_date(sec);
  char buf[96];
  if (t == Ty::DATE && sec % 86400 == 0 && frac == 0) {
    std::snprintf(buf, sizeof buf, "D#%d-%02d-%02d", tm.year, tm.mon, tm.day);
    return buf;
  }
  if (t == Ty::TOD) std::snprintf(buf, sizeof buf, "TOD#%02d:%02d:%02d", tm.hour, tm.min, tm.sec);
  else std::snprintf(buf, sizeof buf, "DT#%d-%02d-%02d-%02d:%02d:%02d", tm.year, tm.mon, tm.day, tm.hour, tm.min, tm.sec);
  std::string s = buf;
  if (frac) {
    std::snprintf(buf, sizeof buf, ".%09lld", (long long)frac);
    std::string f = buf;
    while (f.back() == '0') f.pop_back();
    s += f;
  }
  return s;
}

// A typed alias's value at its type (docs/format.md, "Traces"): integers in
// decimal (unsigned ones unsigned), REAL and LREAL shortest, TIME and the
// dates as IEC literals, STRING quoted.
static std::string format_typed(const uint8_t* at, Ty t) {
  const TyInfo& ti = ty_info(t);
  if (t == Ty::STRING) {  // 'text' with $-escapes ($2C for a comma, $22 and $5C for " and \\: a CSV cell, a JSON string); the length clamped to 126
    uint32_t n;
    std::memcpy(&n, at, 4);
    std::string s = "'";
    for (uint32_t i = 0; i < std::min<uint32_t>(n, 126); i++) {
      unsigned char c = at[4 + i];
      char hex[4];
      std::snprintf(hex, sizeof hex, "$%02X", c);
      s += c == '$' ? std::string("$$") : c == '\'' ? std::string("$'") : (c < 32 || c > 126 || c == ',' || c == '"' || c == '\\') ? std::string(hex) : std::string(1, char(c));
    }
    return s + "'";
  }
  uint64_t b = 0;
  std::memcpy(&b, at, size_t(ti.cells) * 4);
  if (t == Ty::REAL) {
    float f;
    std::memcpy(&f, at, 4);
    return shortest(f);
  }
  if (t == Ty::LREAL) {
    double d;
    std::memcpy(&d, &b, 8);
    return shortest(d);
  }
  if (ti.kind == TyKind::Time) return iec_duration(int64_t(b), t == Ty::LTIME ? "LTIME#" : "T#");
  if (ti.kind == TyKind::Date) return iec_date(t, int64_t(b));
  if (ty_is_unsigned(t)) return std::to_string(ti.cells == 1 ? uint64_t(uint32_t(b)) : b);
  return std::to_string(ti.cells == 1 ? int64_t(int32_t(uint32_t(b))) : int64_t(b));
}

std::string format_probe(const uint8_t* base, const Layout& layout, const Probe& p) {
  const uint8_t* at = base + layout.addr(p.area, p.index);
  if (area_is_bit(p.area)) return *at ? "1" : "0";
  if (p.ty != Ty::None) return format_typed(at, p.ty);
  if (p.area == Area::F) {  // a device, not a variable: %g as always (a typed REAL prints exactly)
    float f;
    std::memcpy(&f, at, 4);
    char buf[64];
    std::snprintf(buf, sizeof buf, "%g", double(f));
    return buf;
  }
  int32_t v;
  std::memcpy(&v, at, 4);
  return std::to_string(v);
}

std::string format_probe(const Memory& mem, const Probe& p) { return format_probe(mem.bytes.data(), mem.layout, p); }

std::vector<ScanFault> run_trace(Engine& engine, const Layout& layout, const Trace* trace, const std::string&,
                                 const RunOptions& opt, std::string& out) {
  std::vector<ScanFault> faults;
  Memory mem(layout);
  int scans = opt.scans >= 0 ? opt.scans : trace ? int(trace->rows.size()) : 1;
  out += "scan";
  for (const Probe& p : opt.watch) out += "," + csv_name(p.name);
  out += "\n";
  // A cell is written before its scan; an empty cell writes nothing, so the
  // device keeps its value.  dt keeps its last value too (the period at first).
  int32_t dt = opt.period_ms;
  for (int k = 1; k <= scans; k++) {
    if (trace && size_t(k - 1) < trace->rows.size()) {
      const auto& row = trace->rows[k - 1];
      for (size_t i = 0; i < row.size(); i++) {
        const std::string& v = row[i];
        if (v.empty()) continue;
        const Probe& p = trace->columns[i];
        if (int(i) == trace->dt_column) dt = int32_t(trace_cell_int(v));
        else put_trace_cell(mem.data(), layout, p, v), engine.written(layout.addr(p.area, p.index), probe_width(p, layout));
      }
    }
    std::memcpy(mem.data() + kSysDt, &dt, 4);
    mem.set_bit(Area::S, kBitFirstScan, k == 1);
    std::memset(mem.data() + kSysFault, 0, 4);
    engine.scan(mem.bytes);
    if (auto f = read_scan_fault(mem.data())) {
      f->scan = k;
      faults.push_back(*f);
      if (!opt.continue_after_fault) return faults;
    }
    uint32_t n = uint32_t(k);
    std::memcpy(mem.data() + kSysScan, &n, 4);
    out += std::to_string(k);
    for (const Probe& p : opt.watch) out += "," + format_probe(mem, p);
    out += "\n";
  }
  return faults;
}

}  // namespace ldc
