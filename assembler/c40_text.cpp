// C40 target: names, one-line parser, printer, GNU as source, listings.
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <set>

#include "assembler/c40_forms.h"

namespace ldc::as::c40 {
using namespace detail;
namespace {

constexpr std::string_view kRegNames[kNumRegs] = {
    "R0",  "R1",  "R2",  "R3",  "R4",  "R5",  "R6",  "R7",  "AR0", "AR1", "AR2",
    "AR3", "AR4", "AR5", "AR6", "AR7", "DP",  "IR0", "IR1", "BK",  "SP",  "ST",
    "DIE", "IIE", "IIF", "RS",  "RE",  "RC",  "R8",  "R9",  "R10", "R11"};

struct CondName {
  std::string_view name;
  Cond cond;
};
// Canonical names first (the printer uses the first entry of a code), then
// the aliases GNU as accepts.
constexpr CondName kConds[] = {
    {"U", Cond::U},     {"LO", Cond::LO},   {"LS", Cond::LS},     {"HI", Cond::HI},
    {"HS", Cond::HS},   {"EQ", Cond::EQ},   {"NE", Cond::NE},     {"LT", Cond::LT},
    {"LE", Cond::LE},   {"GT", Cond::GT},   {"GE", Cond::GE},     {"NV", Cond::NV},
    {"V", Cond::V},     {"NUF", Cond::NUF}, {"UF", Cond::UF},     {"NLV", Cond::NLV},
    {"LV", Cond::LV},   {"NLUF", Cond::NLUF}, {"LUF", Cond::LUF}, {"ZUF", Cond::ZUF},
    {"C", Cond::LO},    {"NC", Cond::HS},   {"Z", Cond::EQ},      {"NZ", Cond::NE},
    {"N", Cond::LT},    {"L", Cond::LT},    {"P", Cond::GT},      {"NN", Cond::GE},
};

std::string upper(std::string_view s) {
  std::string r(s);
  for (char& c : r) c = char(std::toupper(static_cast<unsigned char>(c)));
  return r;
}

std::string trim(std::string_view s) {
  size_t a = 0, b = s.size();
  while (a < b && std::isspace(static_cast<unsigned char>(s[a]))) ++a;
  while (b > a && std::isspace(static_cast<unsigned char>(s[b - 1]))) --b;
  return std::string(s.substr(a, b - a));
}

std::optional<Cond> cond_by_name(std::string_view s) {
  for (const CondName& c : kConds)
    if (c.name == s) return c.cond;
  return std::nullopt;
}

std::optional<Reg> reg_by_name(std::string_view s) {
  std::string u = upper(s);
  for (unsigned i = 0; i < kNumRegs; ++i)
    if (kRegNames[i] == u) return Reg(i);
  if (u.size() >= 2 && u[0] == 'F') {  // F0-F11: GNU as aliases of R0-R11
    std::string n = u.substr(1);
    if (n == "0" || n == "1" || n == "2" || n == "3" || n == "4" || n == "5" || n == "6" ||
        n == "7" || n == "8" || n == "9" || n == "10" || n == "11")
      return rx(unsigned(std::stoi(n)));
  }
  return std::nullopt;
}

bool is_ident_start(char c) { return std::isalpha(static_cast<unsigned char>(c)) || c == '_' || c == '.'; }
bool is_ident_char(char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '.'; }

bool is_label_name(std::string_view s) {
  if (s.empty() || !is_ident_start(s[0])) return false;
  for (char c : s)
    if (!is_ident_char(c)) return false;
  return !reg_by_name(s);
}

struct Number {
  bool is_float = false;
  int64_t i = 0;
  double f = 0;
};

bool all_hex(std::string_view s) {
  if (s.empty()) return false;
  for (char c : s)
    if (!std::isxdigit(static_cast<unsigned char>(c))) return false;
  return true;
}

// Decimal, 0x hex, TI hex (`0FFFh`), or a decimal float.
std::optional<Number> parse_number(std::string_view text) {
  std::string s = trim(text);
  bool neg = false;
  size_t p = 0;
  if (p < s.size() && (s[p] == '+' || s[p] == '-')) neg = s[p++] == '-';
  std::string body = s.substr(p);
  if (body.empty() || !(std::isdigit(static_cast<unsigned char>(body[0])) || body[0] == '.'))
    return std::nullopt;
  Number n;
  auto finish_int = [&](uint64_t v) -> std::optional<Number> {
    if (v > (uint64_t(1) << 40)) return std::nullopt;
    n.i = neg ? -int64_t(v) : int64_t(v);
    n.f = double(n.i);
    return n;
  };
  if (body.size() > 2 && body[0] == '0' && (body[1] == 'x' || body[1] == 'X')) {
    if (!all_hex(body.substr(2)) || body.size() > 12) return std::nullopt;
    return finish_int(std::stoull(body.substr(2), nullptr, 16));
  }
  if (body.size() > 1 && (body.back() == 'h' || body.back() == 'H')) {
    std::string h = body.substr(0, body.size() - 1);
    if (!all_hex(h) || h.size() > 10) return std::nullopt;
    return finish_int(std::stoull(h, nullptr, 16));
  }
  bool digits = true;
  for (char c : body) digits = digits && std::isdigit(static_cast<unsigned char>(c));
  if (digits) {
    if (body.size() > 13) return std::nullopt;
    return finish_int(std::stoull(body));
  }
  for (char c : body)
    if (!(std::isdigit(static_cast<unsigned char>(c)) || c == '.' || c == 'e' || c == 'E' ||
          c == '+' || c == '-'))
      return std::nullopt;
  char* end = nullptr;
  double v = std::strtod(body.c_str(), &end);
  if (end != body.c_str() + body.size() || !std::isfinite(v)) return std::nullopt;
  n.is_float = true;
  n.f = neg ? -v : v;
  return n;
}

// What an operand looks like before the instruction form gives it meaning.
struct RawOp {
  enum Kind { Reg, Num, Direct, Ind, Name } kind = Name;
  c40::Reg reg = c40::Reg::R0;
  Number num;
  c40::Ind ind;
  std::string name;
  std::string text;
};

[[noreturn]] void fail(const std::string& msg) { throw AsmError(msg); }

Ind parse_ind(const std::string& t) {
  // t starts with '*' and has no spaces.
  std::string u = upper(t);
  size_t p = 1;
  int pre = 0;  // 1 "+", 2 "-", 3 "++", 4 "--"
  if (u.compare(p, 2, "++") == 0) { pre = 3; p += 2; }
  else if (u.compare(p, 2, "--") == 0) { pre = 4; p += 2; }
  else if (u.compare(p, 1, "+") == 0) { pre = 1; p += 1; }
  else if (u.compare(p, 1, "-") == 0) { pre = 2; p += 1; }
  if (u.compare(p, 2, "AR") != 0 || p + 2 >= u.size() || u[p + 2] < '0' || u[p + 2] > '7')
    fail("bad indirect operand '" + t + "'");
  Ind ind;
  ind.ar = uint8_t(u[p + 2] - '0');
  p += 3;
  int post = 0;  // 1 "++", 2 "--"
  if (!pre) {
    if (u.compare(p, 2, "++") == 0) { post = 1; p += 2; }
    else if (u.compare(p, 2, "--") == 0) { post = 2; p += 2; }
  }
  bool has_idx = false;
  int idx = 0;  // 0 displacement, 1 IR0, 2 IR1
  int64_t disp = 1;
  if (p < u.size() && u[p] == '(') {
    size_t close = u.find(')', p);
    if (close == std::string::npos) fail("bad indirect operand '" + t + "'");
    std::string in = u.substr(p + 1, close - p - 1);
    if (in == "IR0") idx = 1;
    else if (in == "IR1") idx = 2;
    else {
      auto n = parse_number(in);
      if (!n || n->is_float || n->i < 0 || n->i > 255)
        fail("bad displacement in '" + t + "' (0-255, IR0 or IR1)");
      disp = n->i;
    }
    has_idx = true;
    p = close + 1;
  }
  bool circ = false, bitrev = false;
  if (p < u.size() && u[p] == '%') { circ = true; ++p; }
  else if (p < u.size() && u[p] == 'B') { bitrev = true; ++p; }
  if (p != u.size()) fail("bad indirect operand '" + t + "'");
  if (!pre && !post) {
    if (has_idx || circ || bitrev) fail("bad indirect operand '" + t + "'");
    ind.mod = kPlain;
    return ind;
  }
  if (bitrev) {
    if (post != 1 || idx != 1) fail("bit-reversed addressing is *ARn++(IR0)B");
    ind.mod = kBitRev;
    return ind;
  }
  if (circ && !post) fail("circular addressing needs a post-modification");
  int base = pre == 1 ? kPreAdd : pre == 2 ? kPreSub : pre == 3 ? kPreAddMod : pre == 4 ? kPreSubMod
           : post == 1 ? (circ ? kPostAddCirc : kPostAdd) : (circ ? kPostSubCirc : kPostSub);
  if (idx) {
    ind.mod = uint8_t(base + (idx == 1 ? kIr0 : kIr1));
    return ind;
  }
  if (disp == 0) {  // as GNU as: a zero displacement is *ARn
    ind.mod = kPlain;
    return ind;
  }
  ind.mod = uint8_t(base);
  ind.disp = uint8_t(disp);
  return ind;
}

RawOp parse_raw(std::string_view text) {
  std::string t;
  for (char c : text)
    if (!std::isspace(static_cast<unsigned char>(c))) t += c;
  RawOp r;
  r.text = t;
  if (t.empty()) fail("empty operand");
  if (t[0] == '@') {
    auto n = parse_number(t.substr(1));
    if (!n || n->is_float || n->i < 0 || n->i > 0xFFFF)
      fail("bad direct address '" + t + "' (@0-0xFFFF, the offset from DP)");
    r.kind = RawOp::Direct;
    r.num = *n;
    return r;
  }
  if (t[0] == '*') {
    r.kind = RawOp::Ind;
    r.ind = parse_ind(t);
    return r;
  }
  if (auto reg = reg_by_name(t)) {
    r.kind = RawOp::Reg;
    r.reg = *reg;
    return r;
  }
  if (auto n = parse_number(t)) {
    r.kind = RawOp::Num;
    r.num = *n;
    return r;
  }
  if (!is_label_name(t)) fail("bad operand '" + t + "'");
  r.kind = RawOp::Name;
  r.name = t;
  return r;
}

std::optional<std::pair<Mnemonic, Cond>> mnemonic_by_name(std::string_view name) {
  std::string u = upper(name);
  for (size_t i = 0; i < size_t(Mnemonic::Count_); ++i) {
    Mnemonic m = Mnemonic(i);
    if (has_cond(m)) continue;
    if (upper(spec(m).name) == u) return std::pair{m, Cond::U};
  }
  struct Pre {
    std::string_view pre;
    Mnemonic m, delayed;
  };
  constexpr Pre pres[] = {{"LDI", Mnemonic::Ldic, Mnemonic::Ldic},
                          {"LDF", Mnemonic::Ldfc, Mnemonic::Ldfc},
                          {"CALL", Mnemonic::Callc, Mnemonic::Callc},
                          {"RETS", Mnemonic::Retsc, Mnemonic::Retsc},
                          {"DB", Mnemonic::Dbc, Mnemonic::Dbcd},
                          {"B", Mnemonic::Bc, Mnemonic::Bcd}};
  for (const Pre& p : pres) {
    if (u.compare(0, p.pre.size(), p.pre) != 0) continue;
    std::string rest = u.substr(p.pre.size());
    if (rest.empty()) {
      if (p.m == Mnemonic::Ldic || p.m == Mnemonic::Ldfc) continue;
      return std::pair{p.m, Cond::U};
    }
    if (auto c = cond_by_name(rest)) return std::pair{p.m, *c};
    if (p.delayed != p.m && rest.back() == 'D') {
      std::string c2 = rest.substr(0, rest.size() - 1);
      if (c2.empty()) return std::pair{p.delayed, Cond::U};
      if (auto c = cond_by_name(c2)) return std::pair{p.delayed, *c};
    }
  }
  return std::nullopt;
}

// Gives a raw operand its meaning in operand position `pos` of mnemonic m.
Operand finish(const RawOp& r, Mnemonic m, unsigned pos) {
  const Spec& s = spec(m);
  switch (r.kind) {
    case RawOp::Reg: return Operand::r(r.reg);
    case RawOp::Direct: return Operand::d(uint16_t(r.num.i));
    case RawOp::Ind: return Operand::m(r.ind);
    case RawOp::Name: return Operand::l(r.name);
    case RawOp::Num: break;
  }
  const Number& n = r.num;
  bool branch = s.cls == Cls::I || s.cls == Cls::J || s.cls == Cls::JS || (s.cls == Cls::D && pos == 1);
  if (branch) {
    if (n.is_float) fail("bad branch target '" + r.text + "'");
    return Operand::a(n.i);
  }
  if (s.cls == Cls::Word) {
    if (n.is_float || n.i < -(int64_t(1) << 31) || n.i > 0xFFFFFFFFll)
      fail("bad .word value '" + r.text + "'");
    return Operand::i(n.i);
  }
  bool three = s.cls == Cls::T || s.cls == Cls::T2 || s.cls == Cls::S || s.cls == Cls::S2;
  if (three) {
    if (n.is_float || n.i < -128 || n.i > 127) fail("bad immediate '" + r.text + "' (-128..127)");
    return Operand::i(n.i);
  }
  switch (imm_kind(s.cls)) {
    case ImmKind::F16: {
      auto bits = short_float_from_double(n.f);
      if (!bits) fail("'" + r.text + "' is not a 16-bit short float (4-bit exponent, 12-bit mantissa)");
      return Operand::f(*bits);
    }
    case ImmKind::S16:
      if (n.is_float || n.i < -32768 || n.i > 0xFFFF) fail("bad immediate '" + r.text + "' (16 bits)");
      return Operand::i(n.i > 32767 ? n.i - 65536 : n.i);
    case ImmKind::U16:
      if (n.is_float || n.i < 0 || n.i > 0xFFFF) fail("bad immediate '" + r.text + "' (0..0xFFFF)");
      return Operand::i(n.i);
    case ImmKind::None: break;
  }
  fail("unexpected number '" + r.text + "'");
}

std::string hex(uint64_t v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "0x%llx", static_cast<unsigned long long>(v));
  return buf;
}

std::string float_text(uint16_t bits) {
  double v = short_float_to_double(bits);
  char buf[64];
  for (int prec = 1; prec <= 17; ++prec) {
    std::snprintf(buf, sizeof buf, "%.*g", prec, v);
    if (std::strtod(buf, nullptr) == v) break;
  }
  std::string s = buf;
  if (s.find_first_of(".e") == std::string::npos) s += ".0";
  return s;
}

// GNU as 2.40 converts some exact short-float decimals one unit in the last
// place toward zero; a quarter unit more magnitude makes it land on the
// intended bits. Powers of two (fraction 0) convert exactly as they are.
std::string gas_float_text(uint16_t bits) {
  if ((bits & 0x7FF) == 0 || (bits >> 12) == 8) return float_text(bits);
  int e = int(bits >> 12 & 0xF);
  if (e >= 8) e -= 16;
  double v = short_float_to_double(bits);
  double nudged = v + std::copysign(std::ldexp(1.0, e - 13), v);
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.17g", nudged);
  std::string s = buf;
  if (s.find_first_of(".e") == std::string::npos) s += ".0";
  return s;
}

std::string operand_text(const Operand& o, const Instruction& in, std::string_view base,
                        bool for_gas = false) {
  const Spec& s = spec(in.mnemonic);
  switch (o.kind) {
    case OperandKind::None: return "";
    case OperandKind::Reg: return std::string(reg_name(o.reg));
    case OperandKind::Imm:
      if (imm_kind(s.cls) == ImmKind::U16) return hex(uint64_t(o.imm));
      return std::to_string(o.imm);
    case OperandKind::Float: return for_gas ? gas_float_text(uint16_t(o.imm)) : float_text(uint16_t(o.imm));
    case OperandKind::Direct: return "@" + hex(uint64_t(o.imm));
    case OperandKind::Ind: return ind_text(o.ind);
    case OperandKind::Label: return o.label;
    case OperandKind::Address:
      if (!base.empty())
        return std::string(base) + (o.imm < 0 ? "-" : "+") + std::to_string(o.imm < 0 ? -o.imm : o.imm);
      return o.imm < 0 ? "-" + hex(uint64_t(-o.imm)) : hex(uint64_t(o.imm));
  }
  return "";
}

std::vector<std::string> split_operands(std::string_view s) {
  std::vector<std::string> out;
  std::string cur;
  int depth = 0;
  for (char c : s) {
    if (c == '(') ++depth;
    if (c == ')') --depth;
    if (c == ',' && depth == 0) {
      out.push_back(trim(cur));
      cur.clear();
    } else {
      cur += c;
    }
  }
  if (!trim(cur).empty() || !out.empty()) out.push_back(trim(cur));
  return out;
}

Instruction parse_instruction(std::string_view text) {
  std::string t = trim(text);
  if (t.empty()) fail("empty instruction");
  if (t.find("||") != std::string::npos) fail("parallel instructions are not in the subset");
  size_t sp = 0;
  while (sp < t.size() && !std::isspace(static_cast<unsigned char>(t[sp]))) ++sp;
  std::string name = t.substr(0, sp);
  auto mc = mnemonic_by_name(name);
  if (!mc) fail("unknown mnemonic '" + name + "'");
  Instruction in;
  in.mnemonic = mc->first;
  in.cond = mc->second;
  std::vector<std::string> ops = split_operands(std::string_view(t).substr(sp));
  if (ops.size() > 3) fail("too many operands");
  for (size_t i = 0; i < ops.size(); ++i) {
    if (ops[i].empty()) fail("empty operand");
    in.ops[i] = finish(parse_raw(ops[i]), in.mnemonic, unsigned(i));
  }
  in.num_operands = uint8_t(ops.size());
  return in;
}

std::pair<std::string, std::string> split_comment(std::string_view line) {
  size_t c = line.find(';');
  if (c == std::string_view::npos) return {std::string(line), ""};
  return {std::string(line.substr(0, c)), trim(line.substr(c + 1))};
}

}  // namespace

std::string_view reg_name(Reg r) { return unsigned(r) < kNumRegs ? kRegNames[unsigned(r)] : "?"; }

std::string_view cond_name(Cond c) {
  for (const CondName& n : kConds)
    if (n.cond == c) return n.name;
  return "?";
}

std::string mnemonic_name(Mnemonic m, Cond c) {
  if (size_t(m) >= size_t(Mnemonic::Count_)) return "?";
  std::string n(spec(m).name);
  if (!has_cond(m)) return n;
  n += cond_name(c);
  if (m == Mnemonic::Bcd || m == Mnemonic::Dbcd) n += "D";
  return n;
}

std::string ind_text(const Ind& i) {
  std::string a = "AR" + std::to_string(i.ar);
  if (i.mod == kPlain) return "*" + a;
  if (i.mod == kBitRev) return "*" + a + "++(IR0)B";
  if (i.mod > kBitRev) return "*?";
  std::string x = i.mod >= kIr1 ? "IR1" : i.mod >= kIr0 ? "IR0" : std::to_string(i.disp);
  switch (i.mod & 7) {
    case kPreAdd: return "*+" + a + "(" + x + ")";
    case kPreSub: return "*-" + a + "(" + x + ")";
    case kPreAddMod: return "*++" + a + "(" + x + ")";
    case kPreSubMod: return "*--" + a + "(" + x + ")";
    case kPostAdd: return "*" + a + "++(" + x + ")";
    case kPostSub: return "*" + a + "--(" + x + ")";
    case kPostAddCirc: return "*" + a + "++(" + x + ")%";
    default: return "*" + a + "--(" + x + ")%";
  }
}

std::optional<uint16_t> short_float_from_double(double v) {
  if (v == 0) return uint16_t(0x8000);
  if (!std::isfinite(v)) return std::nullopt;
  int x = 0;
  double m = std::frexp(std::fabs(v), &x);  // |v| = m * 2^x, m in [0.5, 1)
  double mant = 2 * m;                      // [1, 2)
  int e = x - 1;
  int s = 0;
  double f;
  if (v > 0) {
    f = (mant - 1) * 2048;
  } else if (mant == 1) {  // -2^e = -2 * 2^(e-1)
    e -= 1;
    s = 1;
    f = 0;
  } else {
    s = 1;
    f = (2 - mant) * 2048;
  }
  if (e < -7 || e > 7 || f != std::floor(f) || f < 0 || f > 2047) return std::nullopt;
  return uint16_t((unsigned(e) & 0xF) << 12 | unsigned(s) << 11 | unsigned(f));
}

double short_float_to_double(uint16_t bits) {
  int e = int(bits >> 12 & 0xF);
  if (e >= 8) e -= 16;
  if (e == -8) return 0;
  int f = bits & 0x7FF;
  double mant = (bits & 0x800) ? -2.0 + f / 2048.0 : 1.0 + f / 2048.0;
  return std::ldexp(mant, e);
}

std::string print(const Instruction& in, std::string_view address_base) {
  std::string out = mnemonic_name(in.mnemonic, in.cond);
  for (unsigned i = 0; i < in.num_operands && i < 3; ++i)
    out += (i ? ", " : " ") + operand_text(in.ops[i], in, address_base);
  return out;
}

std::string print_gnu_as(const Instruction& in, std::string_view address_base) {
  std::string out = mnemonic_name(in.mnemonic, in.cond);
  for (unsigned i = 0; i < in.num_operands && i < 3; ++i)
    out += (i ? ", " : " ") + operand_text(in.ops[i], in, address_base, true);
  return out;
}

Instruction parse(std::string_view line) {
  auto [code, comment] = split_comment(line);
  std::string t = trim(code);
  size_t colon = t.find(':');
  if (colon != std::string::npos && colon > 0 && is_label_name(trim(t.substr(0, colon))))
    fail("labels are not instructions (use parse_line)");
  return parse_instruction(t);
}

Line parse_line(std::string_view text) {
  Line l;
  auto [code, comment] = split_comment(text);
  l.comment = comment;
  std::string t = trim(code);
  size_t colon = t.find(':');
  if (colon != std::string::npos) {
    std::string name = trim(t.substr(0, colon));
    if (!is_label_name(name)) fail("bad label '" + name + "'");
    l.label = name;
    t = trim(t.substr(colon + 1));
  }
  if (!t.empty()) l.inst = parse_instruction(t);
  return l;
}

std::string to_gnu_as(const C40Program& p) {
  return gnu_as_text(p, "\t.text\n.Lcode:\n", ";",
                   [](const Instruction& in, bool) { return print_gnu_as(in, ".Lcode"); });
}

std::string listing(const C40Program& p, const Result& r) {
  auto item_head = [&](const ItemLayout& lay) {
    std::string word = "          ";
    if (lay.size == 4 && lay.offset + 4 <= r.code.size())
      word = listing_field("%08x  ", uint32_t(r.code[lay.offset]) | uint32_t(r.code[lay.offset + 1]) << 8 |
                                        uint32_t(r.code[lay.offset + 2]) << 16 | uint32_t(r.code[lay.offset + 3]) << 24);
    return listing_field("%06x  ", lay.offset / 4) + word;
  };
  return listing_text(
      p, r, ";", [&](uint32_t off) { return listing_field("%06x", off / 4) + "            "; }, item_head,
      [](const Instruction& in, const ItemLayout&) { return print(in); });
}

}  // namespace ldc::as::c40
