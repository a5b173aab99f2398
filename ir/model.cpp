// ir/model.cpp -- the typed program model (ir/model.h): types and their
// sizes, POUs, access paths, the layout of the variable area, initial values
// and IEC literals with MatIEC's meaning.
#include "ir/model.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "ir/typed.h"

namespace ldc::model {
namespace {

std::string upper(std::string_view s) {
  std::string u(s);
  for (char& c : u) c = char(std::toupper((unsigned char)c));
  return u;
}
[[noreturn]] void fail(SrcLoc at, const std::string& m) { throw ModelError{at, m}; }

constexpr uint32_t kAreaBits = 8192, kAreaCells = 8192;  // M and D (device_count)

}  // namespace

const char* var_class_name(VarClass c) {
  switch (c) {
    case VarClass::Input: return "VAR_INPUT";
    case VarClass::Output: return "VAR_OUTPUT";
    case VarClass::InOut: return "VAR_IN_OUT";
    case VarClass::Local: return "VAR";
    case VarClass::Temp: return "VAR_TEMP";
    case VarClass::External: return "VAR_EXTERNAL";
    case VarClass::Global: return "VAR_GLOBAL";
  }
  return "VAR";
}

// ---------------------------------------------------------------- types

Model::Model() {
  for (int i = 0; i < kTyCount; i++) {
    Type t;
    t.kind = TypeKind::Elem;
    t.name = kTys[i].name;
    t.elem = Ty(i);
    t.size = Ty(i) == Ty::BOOL ? Size{1, 0} : Size{0, uint32_t(kTys[i].cells)};
    types.push_back(t);
    by_name_[t.name] = TypeId(i);
  }
  for (const char* alias : {"TIME_OF_DAY", "DATE_AND_TIME", "LTOD", "LTIME_OF_DAY", "LDT", "LDATE_AND_TIME", "LDATE"})
    by_name_[alias] = TypeId(*ty_from_name(alias));
}

TypeId Model::find_type(std::string_view name) const {
  auto it = by_name_.find(upper(name));
  return it == by_name_.end() ? kNoType : it->second;
}

Ty Model::scalar_ty(TypeId id) const {
  const Type& t = type(id);
  return t.scalar() ? t.elem : Ty::None;
}

bool Model::same_type(TypeId a, TypeId b) const {
  if (a == b) return true;
  Ty x = scalar_ty(a), y = scalar_ty(b);
  return x != Ty::None && x == y && type(a).kind != TypeKind::Enum && type(b).kind != TypeKind::Enum;
}

std::string Model::type_name(TypeId id) const {
  const Type& t = type(id);
  if (!t.name.empty()) return t.name;
  switch (t.kind) {
    case TypeKind::Array: {
      std::string s = "ARRAY[";
      for (size_t i = 0; i < t.dims.size(); i++)
        s += (i ? ", " : "") + std::to_string(t.dims[i].lo) + ".." + std::to_string(t.dims[i].hi);
      return s + "] OF " + type_name(t.of);
    }
    case TypeKind::Struct: return "STRUCT";
    case TypeKind::Subrange: return std::string(ty_info(t.elem).name) + "(" + std::to_string(t.lo) + ".." + std::to_string(t.hi) + ")";
    case TypeKind::Enum: return "(enumeration)";
    default: return ty_info(t.elem).name;
  }
}

void Model::finish_type(Type& t, SrcLoc loc) {
  switch (t.kind) {
    case TypeKind::Elem: t.size = t.elem == Ty::BOOL ? Size{1, 0} : Size{0, uint32_t(ty_info(t.elem).cells)}; return;
    case TypeKind::Enum: t.elem = Ty::DINT; t.size = {0, 1}; return;
    case TypeKind::Subrange:
      if (t.lo > t.hi) fail(loc, "empty subrange " + std::to_string(t.lo) + ".." + std::to_string(t.hi));
      t.size = t.elem == Ty::BOOL ? Size{1, 0} : Size{0, uint32_t(ty_info(t.elem).cells)};
      return;
    case TypeKind::Array: {
      if (t.dims.empty()) fail(loc, "an array without dimensions");
      uint64_t n = 1;
      for (const Dim& d : t.dims) {
        if (d.lo > d.hi) fail(loc, "empty array dimension " + std::to_string(d.lo) + ".." + std::to_string(d.hi));
        n *= d.count();
        if (n > kAreaBits + kAreaCells) fail(loc, "array of " + std::to_string(n) + "+ elements: more than the devices hold");
      }
      Size e = type(t.of).size;
      uint64_t bits = uint64_t(e.bits) * n, cells = uint64_t(e.cells) * n;
      if (bits > kAreaBits || cells > kAreaCells)
        fail(loc, "array " + type_name(t.of) + " x " + std::to_string(n) + " needs more than the " +
                      std::to_string(kAreaBits) + " M bits / " + std::to_string(kAreaCells) + " D cells of the devices");
      t.size = {uint32_t(bits), uint32_t(cells)};
      return;
    }
    case TypeKind::Struct: case TypeKind::Block: {
      Size at;
      for (size_t i = 0; i < t.members.size(); i++) {
        for (size_t j = 0; j < i; j++)
          if (upper(t.members[j].name) == upper(t.members[i].name)) fail(loc, "member '" + t.members[i].name + "' declared twice");
        t.members[i].offset = at;
        at = at + type(t.members[i].type).size;
        if (at.bits > kAreaBits || at.cells > kAreaCells) fail(loc, "'" + t.name + "' needs more room than the devices hold");
      }
      t.size = at;
      return;
    }
  }
}

TypeId Model::add_type(Type t, SrcLoc loc) {
  if (!t.name.empty() && by_name_.count(upper(t.name))) fail(loc, "a second type named '" + t.name + "'");
  finish_type(t, loc);
  TypeId id = TypeId(types.size());
  if (!t.name.empty()) by_name_[upper(t.name)] = id;
  types.push_back(std::move(t));
  return id;
}

// ---------------------------------------------------------------- POUs

int Model::add_pou(Pou p) {
  std::string u = upper(p.name);
  if (find_pou(p.name) >= 0 || by_name_.count(u)) fail(p.loc, "a second POU or type named '" + p.name + "'");
  Type b;
  b.kind = TypeKind::Block;
  b.pou = int(pous.size());
  for (const Var& v : p.vars) {
    for (const Member& m : b.members)
      if (upper(m.name) == upper(v.name)) fail(v.loc, "'" + v.name + "' declared twice in " + p.name);
    // located, external and in-out variables take no room of the instance
    // (they are the device, the global, the caller's variable)
    bool room = !v.at && v.cls != VarClass::External && v.cls != VarClass::InOut;
    b.members.push_back({v.name, room ? v.type : kNoType, {}, v.init});
  }
  if (p.kind == PouKind::Function && p.result != kNoType) {
    if (find_member_index(b, p.name) >= 0) fail(p.loc, "a variable named like its FUNCTION '" + p.name + "'");
    b.members.push_back({p.name, p.result, {}, {}});
  }
  // the Block's size counts only the members with room
  Size at;
  for (Member& m : b.members) {
    m.offset = at;
    if (m.type != kNoType) at = at + type(m.type).size;
    if (at.bits > kAreaBits || at.cells > kAreaCells) fail(p.loc, "'" + p.name + "' needs more room than the devices hold");
  }
  b.size = at;
  if (p.kind == PouKind::FunctionBlock) b.name = p.name;
  p.block = TypeId(types.size());
  types.push_back(std::move(b));
  if (p.kind == PouKind::FunctionBlock) by_name_[u] = p.block;
  pous.push_back(std::move(p));
  return int(pous.size() - 1);
}

int Model::find_member_index(const Type& t, std::string_view name) {
  std::string u = upper(name);
  for (size_t i = 0; i < t.members.size(); i++)
    if (upper(t.members[i].name) == u) return int(i);
  return -1;
}

int Model::find_pou(std::string_view name) const {
  std::string u = upper(name);
  for (size_t i = 0; i < pous.size(); i++)
    if (upper(pous[i].name) == u) return int(i);
  return -1;
}

void Model::expand_guard(const Model& m, const std::vector<int>& stack, int callee, SrcLoc at) {
  auto it = std::find(stack.begin(), stack.end(), callee);
  if (it == stack.end()) return;
  std::string cycle;
  for (; it != stack.end(); ++it) cycle += m.pous[size_t(*it)].name + " -> ";
  fail(at, "recursion: " + cycle + m.pous[size_t(callee)].name +
               " (POUs are expanded inline at each call, so a POU cannot call itself, directly or through others)");
}

// ---------------------------------------------------------------- access

const Member* Model::member(TypeId t, std::string_view name) const {
  const Type& ty = type(t);
  int i = find_member_index(ty, name);
  return i < 0 ? nullptr : &ty.members[size_t(i)];
}

Ref Model::select_member(const Ref& r, std::string_view name, SrcLoc at) const {
  const Type& t = type(r.type);
  if (t.kind != TypeKind::Struct && t.kind != TypeKind::Block)
    fail(at, "'" + std::string(name) + "': a " + type_name(r.type) + " has no members");
  const Member* m = member(r.type, name);
  if (!m || m->type == kNoType) {
    std::string known;
    for (const Member& k : t.members)
      if (k.type != kNoType) known += (known.empty() ? "" : ", ") + k.name;
    fail(at, type_name(r.type) + " has no member '" + std::string(name) + "'" + (known.empty() ? "" : " (" + known + ")"));
  }
  Ref out = r;
  out.type = m->type;
  out.at = r.at + m->offset;
  return out;
}

Ref Model::select_element(const Ref& r, const std::vector<std::pair<Operand, Ty>>& idx, SrcLoc at) const {
  const Type& t = type(r.type);
  if (t.kind != TypeKind::Array) fail(at, "'" + type_name(r.type) + "' is not an array: it has no elements");
  if (idx.size() != t.dims.size())
    fail(at, type_name(r.type) + " takes " + std::to_string(t.dims.size()) + " index(es), not " + std::to_string(idx.size()));
  Ref out = r;
  out.type = t.of;
  // the stride of dimension k: the element's size times the counts of the dimensions after it
  std::vector<Size> stride(t.dims.size());
  Size s = type(t.of).size;
  for (size_t k = t.dims.size(); k-- > 0;) {
    stride[k] = s;
    s = s * t.dims[k].count();
  }
  for (size_t k = 0; k < idx.size(); k++) {
    const auto& [o, ty] = idx[k];
    TyKind kind = ty == Ty::None ? TyKind::Bool : ty_info(ty).kind;
    if (!(kind == TyKind::Signed || kind == TyKind::Unsigned))  // ANY_INT, what IDX takes
      fail(at, std::string("an array index must be an integer (SINT .. ULINT), this one is ") + (ty == Ty::None ? "untyped" : ty_info(ty).name));
    if (o.kind == OpdKind::ConstT) {
      uint64_t v = o.bits();
      if (!typed::index_ok(ty, v, t.dims[k].lo, t.dims[k].hi))
        fail(at, "index " + (typed::is_signed(ty) ? std::to_string(int64_t(v)) : std::to_string(v)) + " outside " +
                     std::to_string(t.dims[k].lo) + ".." + std::to_string(t.dims[k].hi));
      out.at = out.at + stride[k] * uint32_t(int64_t(v) - t.dims[k].lo);
    } else {
      out.steps.push_back({o, ty, t.dims[k], stride[k]});
    }
  }
  return out;
}

// ---------------------------------------------------------------- layout

void Model::set_area(uint32_t bit_base, uint32_t cell_base) {
  base_ = next_ = {bit_base, cell_base};
}

Place Model::place(Size s, SrcLoc at) {
  Place p = next_;
  if (uint64_t(next_.bit) + s.bits > kAreaBits || uint64_t(next_.cell) + s.cells > kAreaCells)
    fail(at, "the program's variables need more than the " + std::to_string(kAreaBits) + " M bits and " +
                 std::to_string(kAreaCells) + " D cells of the devices");
  next_ = next_ + s;
  return p;
}

// ---------------------------------------------------------------- initial values

void Model::initial_stores(TypeId id, Place p, const Init* init, std::vector<Store>& out, bool zeros) const {
  const Type& t = type(id);
  if (!init || init->kind == Init::None) init = t.init.kind == Init::None ? nullptr : &t.init;
  SrcLoc loc = init ? init->loc : SrcLoc{};
  if (t.scalar() && t.elem == Ty::STRING) {  // its cells: the length and the bytes (DINT and DWORD stores)
    std::string bytes;
    if (init) {
      if (init->kind != Init::Value) fail(loc, "a STRING takes one string literal, not a list or structure");
      std::string why;
      if (!literal_as(init->value, Ty::STRING, why)) fail(loc, why);
      bytes = init->value.str;
    }
    std::vector<uint32_t> cells = string_cells(bytes);
    for (uint32_t k = 0; k < cells.size(); k++)
      if (cells[k] != 0 || zeros) out.push_back({k == 0 ? Ty::DINT : Ty::DWORD, p + Size{0, k}, cells[k]});
    return;
  }
  if (t.scalar()) {
    if (!init) {
      if (zeros) out.push_back({t.elem, p, 0});
      return;
    }
    if (init->kind != Init::Value) fail(loc, "a " + type_name(id) + " takes one value, not a list or structure");
    std::string why;
    auto v = literal_as(init->value, t.elem, why);
    if (!v) fail(loc, why);
    if (t.kind == TypeKind::Subrange) {
      int64_t x = typed::is_signed(t.elem) ? int64_t(v->bits) : int64_t(v->bits);
      if (x < t.lo || x > t.hi) fail(loc, "initial value " + std::to_string(x) + " outside " + type_name(id));
    }
    if (v->bits != 0 || zeros) out.push_back({t.elem, p, v->bits});
    return;
  }
  if (t.kind == TypeKind::Array) {
    uint32_t n = 1;
    for (const Dim& d : t.dims) n *= d.count();
    Size e = type(t.of).size;
    if (init && init->kind != Init::List) fail(loc, "an array's initial value is a list [a, b, n(c)]");
    uint32_t k = 0;
    if (init)
      for (const auto& [count, v] : init->list)
        for (uint32_t c = 0; c < count; c++, k++) {
          if (k >= n) fail(v.loc, "more initial values than the " + std::to_string(n) + " elements of " + type_name(id));
          initial_stores(t.of, p + e * k, &v, out, zeros);
        }
    for (; k < n; k++) initial_stores(t.of, p + e * k, nullptr, out, zeros);
    return;
  }
  // a structure or an instance: the members' own values, replaced by the given ones
  if (init && init->kind != Init::Fields) fail(loc, "a " + type_name(id) + "'s initial value is (member := value, ...)");
  if (init)
    for (const auto& [name, v] : init->fields) {
      const Member* m = member(id, name);
      if (!m || m->type == kNoType) fail(v.loc, type_name(id) + " has no member '" + name + "'");
    }
  for (const Member& m : t.members) {
    if (m.type == kNoType) continue;
    const Init* given = nullptr;
    if (init)
      for (const auto& [name, v] : init->fields)
        if (upper(name) == upper(m.name)) given = &v;
    initial_stores(m.type, p + m.offset, given ? given : (m.init.kind == Init::None ? nullptr : &m.init), out, zeros);
  }
}

// ---------------------------------------------------------------- lowering helpers

Operand operand_at(Ty t, Place p, Area bits, Area cells) {
  Operand o;
  if (t == Ty::BOOL) {
    o.kind = OpdKind::Bit, o.area = bits, o.index = p.bit;
  } else {
    o.kind = area_is_real(cells) ? OpdKind::Real : OpdKind::Int, o.area = cells, o.index = p.cell;
  }
  return o;
}
Operand operand_of(const Model& m, const Ref& r) { return operand_at(m.scalar_ty(r.type), r.at, r.bits, r.cells); }

int32_t stride_of(Ty t, Size s) { return int32_t(t == Ty::BOOL ? s.bits : s.cells); }

// ---------------------------------------------------------------- literals

namespace {

// digits (with '_') in `base` into v; false if empty, a bad digit or above 2^64.
bool digits_value(std::string_view s, int base, uint64_t& v) {
  v = 0;
  bool any = false;
  for (char c : s) {
    if (c == '_') continue;
    int d = std::isdigit((unsigned char)c) ? c - '0' : std::isalpha((unsigned char)c) ? std::toupper((unsigned char)c) - 'A' + 10 : 99;
    if (d >= base) return false;
    if (v > (UINT64_MAX - uint64_t(d)) / uint64_t(base)) return false;
    v = v * uint64_t(base) + uint64_t(d);
    any = true;
  }
  return any;
}

// A duration's body: [-] { number unit } with units d h m s ms us ns, each
// number may have a fraction (MatIEC's T#1h2m3.5s).  Exact in integers: the
// fraction's digits times the unit, truncated to the nanosecond.
bool duration_ns(std::string_view b, int64_t& ns, std::string& why) {
  bool neg = !b.empty() && b[0] == '-';
  if (neg || (!b.empty() && b[0] == '+')) b.remove_prefix(1);
  if (b.empty()) return why = "empty duration", false;
  __int128 total = 0;
  size_t i = 0;
  while (i < b.size()) {
    if (b[i] == '_') { i++; continue; }
    size_t st = i;
    while (i < b.size() && (std::isdigit((unsigned char)b[i]) || b[i] == '_')) i++;
    std::string_view whole = b.substr(st, i - st), frac;
    if (i < b.size() && b[i] == '.') {
      size_t f = ++i;
      while (i < b.size() && (std::isdigit((unsigned char)b[i]) || b[i] == '_')) i++;
      frac = b.substr(f, i - f);
    }
    size_t us = i;
    while (i < b.size() && std::isalpha((unsigned char)b[i])) i++;
    std::string unit = upper(b.substr(us, i - us));
    int64_t mul = unit == "D" ? 86400000000000LL : unit == "H" ? 3600000000000LL : unit == "M" ? 60000000000LL
                : unit == "S" ? 1000000000LL : unit == "MS" ? 1000000LL : unit == "US" ? 1000LL : unit == "NS" ? 1LL : 0;
    uint64_t w = 0;
    if (!mul || !digits_value(whole, 10, w) || w > (uint64_t(1) << 62)) return why = "bad duration part (d h m s ms us ns)", false;
    total += __int128(w) * mul;
    __int128 scale = 1, fv = 0;
    for (char c : frac) {
      if (c == '_') continue;
      if (scale < __int128(1000000000000000000LL)) fv = fv * 10 + (c - '0'), scale *= 10;
    }
    total += fv * mul / scale;
    if (total > __int128(INT64_MAX) + neg) return why = "duration beyond the range of TIME (about 292 years)", false;  // -2^63 is one
  }
  ns = int64_t(neg ? -total : total);
  return true;
}

// days from 1970-01-01 of a proleptic Gregorian date (H. Hinnant's days_from_civil)
int64_t days_from_civil(int64_t y, unsigned m, unsigned d) {
  y -= m <= 2;
  const int64_t era = (y >= 0 ? y : y - 399) / 400;
  const unsigned yoe = unsigned(y - era * 400);
  const unsigned doy = (153 * (m + (m > 2 ? -3 : 9)) + 2) / 5 + d - 1;
  const unsigned doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
  return era * 146097 + int64_t(doe) - 719468;
}
bool date_ns(std::string_view s, int64_t& ns) {  // YYYY-MM-DD
  int y = 0;
  unsigned m = 0, d = 0;
  if (std::sscanf(std::string(s).c_str(), "%d-%u-%u", &y, &m, &d) != 3 || m < 1 || m > 12 || d < 1 || d > 31) return false;
  int64_t days = days_from_civil(y, m, d);
  if (days > INT64_MAX / typed::kNsPerDay || days < INT64_MIN / typed::kNsPerDay) return false;  // beyond DATE's ns (years 1678..2262)
  ns = days * typed::kNsPerDay;
  return true;
}
bool tod_ns(std::string_view s, int64_t& ns) {  // HH:MM:SS[.frac]
  unsigned h = 0, m = 0;
  size_t c1 = s.find(':'), c2 = s.find(':', c1 == std::string_view::npos ? 0 : c1 + 1);
  if (c1 == std::string_view::npos || c2 == std::string_view::npos) return false;
  uint64_t hv = 0, mv = 0;
  if (!digits_value(s.substr(0, c1), 10, hv) || !digits_value(s.substr(c1 + 1, c2 - c1 - 1), 10, mv) || hv > 23 || mv > 59) return false;
  h = unsigned(hv), m = unsigned(mv);
  std::string why;
  int64_t sec = 0;
  if (!duration_ns(std::string(s.substr(c2 + 1)) + "s", sec, why) || sec >= 60000000000LL) return false;
  ns = int64_t(h) * 3600000000000LL + int64_t(m) * 60000000000LL + sec;
  return true;
}

}  // namespace

std::optional<std::string> string_literal_bytes(std::string_view text, std::string& why) {
  why.clear();
  if (text.size() < 2 || text.front() != '\'' || text.back() != '\'') return why = "a string literal is written 'text'", std::nullopt;
  std::string out;
  auto hex = [](char c) { return c >= '0' && c <= '9' ? c - '0' : c >= 'a' && c <= 'f' ? c - 'a' + 10 : c >= 'A' && c <= 'F' ? c - 'A' + 10 : -1; };
  for (size_t i = 1; i + 1 < text.size(); i++) {
    char c = text[i];
    if (c == '\'') return why = "a quote inside a string literal is written $'", std::nullopt;
    if (c != '$') { out += c; continue; }
    if (i + 2 >= text.size()) return why = "a '$' at the end of a string literal (write $$)", std::nullopt;
    char e = text[++i];
    switch (e) {  // MatIEC's generate_c_base.cc: $L and $N are both LF
      case '$': case '\'': out += e; continue;
      case 'L': case 'l': case 'N': case 'n': out += '\n'; continue;
      case 'P': case 'p': out += '\f'; continue;
      case 'R': case 'r': out += '\r'; continue;
      case 'T': case 't': out += '\t'; continue;
      default: break;
    }
    if (hex(e) < 0 || i + 2 >= text.size() || hex(text[i + 1]) < 0)
      return why = std::string("unknown escape '$") + e + "' in a string literal ($$ $' $L $N $P $R $T $hh)", std::nullopt;
    out += char(hex(e) * 16 + hex(text[++i]));
  }
  if (out.size() > typed::kStrMax)
    return why = "a string literal of " + std::to_string(out.size()) + " bytes: a STRING holds 126 (MatIEC's STR_MAX_LEN)", std::nullopt;
  return out;
}

std::vector<uint32_t> string_cells(const std::string& bytes) {
  std::vector<uint32_t> c(typed::kStrBytes / 4, 0);
  c[0] = uint32_t(bytes.size());
  for (size_t i = 0; i < bytes.size() && i < typed::kStrMax; i++) c[1 + i / 4] |= uint32_t(uint8_t(bytes[i])) << (8 * (i % 4));
  return c;
}

std::optional<ParsedLit> parse_literal(std::string_view text, std::string& why) {
  why.clear();
  if (text.empty()) return std::nullopt;
  if (text[0] == '\'' || (text.size() > 8 && upper(text.substr(0, 8)) == "STRING#'")) {
    auto b = string_literal_bytes(text[0] == '\'' ? text : text.substr(7), why);
    if (!b) return why += ": " + std::string(text), std::nullopt;
    ParsedLit p;
    p.lit = {Ty::STRING, 0};
    p.str = *b;
    return p;
  }
  std::string u = upper(text);
  ParsedLit p;
  if (u == "TRUE" || u == "FALSE") {
    p.lit = {Ty::BOOL, u == "TRUE" ? 1u : 0u};
    return p;
  }
  size_t hash = u.find('#');
  std::string type = hash == std::string::npos ? "" : u.substr(0, hash);
  std::string body = hash == std::string::npos ? u : u.substr(hash + 1);
  auto bad = [&](const std::string& m) -> std::optional<ParsedLit> { why = m + ": " + std::string(text); return std::nullopt; };
  // durations and dates
  if (type == "T" || type == "TIME" || type == "LT" || type == "LTIME") {
    int64_t ns = 0;
    if (!duration_ns(body, ns, why)) return bad(why.empty() ? "bad duration" : why);
    p.lit = {type[0] == 'L' ? Ty::LTIME : Ty::TIME, uint64_t(ns)};
    return p;
  }
  if (type == "D" || type == "DATE" || type == "LDATE" || type == "LD") {
    int64_t ns = 0;
    if (!date_ns(body, ns)) return bad("bad date (DATE#2024-01-31, years 1678..2262)");
    p.lit = {Ty::DATE, uint64_t(ns)};
    return p;
  }
  if (type == "TOD" || type == "TIME_OF_DAY" || type == "LTOD") {
    int64_t ns = 0;
    if (!tod_ns(body, ns)) return bad("bad time of day (TOD#12:30:00.5)");
    p.lit = {Ty::TOD, uint64_t(ns)};
    return p;
  }
  if (type == "DT" || type == "DATE_AND_TIME" || type == "LDT") {
    int64_t d = 0, t = 0;
    size_t dash = body.size() > 10 ? 10 : std::string::npos;  // YYYY-MM-DD-HH:MM:SS
    if (dash == std::string::npos || body[dash] != '-' || !date_ns(body.substr(0, dash), d) || !tod_ns(body.substr(dash + 1), t))
      return bad("bad date and time (DT#2024-01-31-12:30:00)");
    if (d > INT64_MAX - t) return bad("date and time beyond the range of DT (years 1678..2262)");
    p.lit = {Ty::DT, uint64_t(d + t)};
    return p;
  }
  // a typed number: TYPE#number, the number maybe based (INT#16#FF)
  std::optional<Ty> ty;
  if (!type.empty() && type != "2" && type != "8" && type != "16") {
    ty = ty_from_name(type);
    if (!ty) {
      if (!std::isdigit((unsigned char)text[0])) return std::nullopt;  // a name with '#' is not ours to judge (an enum Color#Red)
      return bad("unknown literal type");
    }
    if (*ty == Ty::BOOL && (body == "TRUE" || body == "FALSE")) body = body == "TRUE" ? "1" : "0";
  } else {
    body = u;
  }
  int base = 10;
  size_t h2 = body.find('#');
  if (h2 != std::string::npos) {
    std::string b = body.substr(0, h2);
    base = b == "2" ? 2 : b == "8" ? 8 : b == "16" ? 16 : 0;
    if (!base) return bad("bad base (2#, 8#, 16#)");
    body = body.substr(h2 + 1);
  }
  if (body.empty()) return bad("bad number");
  bool neg = body[0] == '-';
  std::string_view digits = body;
  if (neg || body[0] == '+') digits.remove_prefix(1);
  if (digits.empty() || !(std::isxdigit((unsigned char)digits[0]) || (base == 10 && digits[0] == '.')) ||
      (base == 10 && !std::isdigit((unsigned char)digits[0]) && digits[0] != '.')) {
    if (!ty && hash == std::string::npos) return std::nullopt;  // a name, not a number
    return bad("bad number");
  }
  bool real = base == 10 && digits.find_first_of(".E") != std::string_view::npos;
  if (real) {
    std::string clean;
    for (char c : body)
      if (c != '_') clean += c;
    char* end = nullptr;
    double d = std::strtod(clean.c_str(), &end);
    if (*end || !std::isfinite(d)) return bad("bad real number");
    if (ty) {
      if (!typed::is_real(*ty)) return bad(std::string("a real number is not a ") + ty_info(*ty).name);
      p.lit = {*ty, typed::real_bits(*ty, d)};
    } else {
      p.untyped_real = true, p.rval = d;
    }
    return p;
  }
  if (base != 10 && neg) return bad("a based number has no sign");
  uint64_t mag = 0;
  if (!digits_value(digits, base, mag)) {
    if (!ty && base == 10 && hash == std::string::npos && !std::isdigit((unsigned char)text[0]) && text[0] != '-' && text[0] != '+')
      return std::nullopt;
    return bad("bad number");
  }
  if (neg && mag > (uint64_t(1) << 63)) return bad("number outside LINT");
  if (!ty) {
    if (!neg && mag > uint64_t(INT64_MAX)) {  // 16#FFFFFFFFFFFFFFFF: an unsigned 64-bit value
      p.untyped_int = true, p.ival = int64_t(mag);
      p.lit = {Ty::ULINT, mag};
      return p;
    }
    p.untyped_int = true, p.ival = neg ? int64_t(0 - mag) : int64_t(mag);
    return p;
  }
  ParsedLit q;
  q.untyped_int = true, q.ival = neg ? int64_t(0 - mag) : int64_t(mag);
  if (!neg && mag > uint64_t(INT64_MAX)) q.lit = {Ty::ULINT, mag};
  auto v = literal_as(q, *ty, why);
  if (!v) return bad(why);
  p.lit = *v;
  return p;
}

std::optional<Lit> literal_as(const ParsedLit& p, Ty t, std::string& why) {
  const char* tn = ty_info(t).name;
  if ((p.lit.ty == Ty::STRING) != (t == Ty::STRING))  // a STRING's bytes are p.str: its cells come from string_cells
    return why = p.lit.ty == Ty::STRING ? std::string("a string literal is not a ") + tn : "a STRING takes a string literal 'text'",
           std::nullopt;
  if (t == Ty::STRING) return Lit{t, 0};
  if (p.untyped_real) {
    if (!typed::is_real(t)) return why = std::string("a real number is not a ") + tn, std::nullopt;
    return Lit{t, typed::real_bits(t, p.rval)};
  }
  if (p.untyped_int) {
    TyKind k = ty_info(t).kind;
    if (k == TyKind::Real) return Lit{t, typed::real_bits(t, p.lit.ty == Ty::ULINT ? double(p.lit.bits) : double(p.ival))};
    if (k == TyKind::Time || k == TyKind::Date)
      return why = std::string("a number is not a ") + tn + " (write T#5s, DATE#2024-01-31 ...)", std::nullopt;
    bool big = p.lit.ty == Ty::ULINT;  // above INT64_MAX
    uint64_t v = big ? p.lit.bits : uint64_t(p.ival);
    bool fits;
    if (k == TyKind::Bool) fits = !big && (p.ival == 0 || p.ival == 1);
    else if (typed::is_signed(t)) fits = !big && typed::norm(t, v) == v;
    else fits = (big || p.ival >= 0) && typed::norm(t, v) == v;
    if (!fits) return why = (big ? std::to_string(v) : std::to_string(p.ival)) + " is outside the range of " + tn, std::nullopt;
    return Lit{t, v};
  }
  if (p.lit.ty == t) return p.lit;
  return why = std::string("a ") + ty_info(p.lit.ty).name + " literal where a " + tn + " is wanted", std::nullopt;
}

}  // namespace ldc::model
