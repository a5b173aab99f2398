// ir/iltext.cpp -- the IL text form (--emit=il) and its reader.
//
//   program   = { line } ;
//   line      = ".rung" "line" INT [ STRING ] | ".label" NAME | ".edges" INT
//             | ".alias" NAME DEVICE | ".retain" DEVICE
//             | ".end" | MNEMONIC { operand } ;          (";" starts a comment)
#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <charconv>
#include <cstdlib>
#include <deque>
#include <iterator>
#include <set>
#include <unordered_map>

#include "ir/ir.h"

namespace ldc {

static std::string quote(const std::string& s) {
  std::string q = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') q += '\\';
    q += c;
  }
  return q + "\"";
}

std::string print_il_text(const Program& p) {
  std::string out = "; ldc IL of " + p.source + "\n";
  if (p.edge_slots) out += ".edges " + std::to_string(p.edge_slots) + "\n";
  for (const Alias& a : p.aliases)
    out += ".alias " + a.name + " " + dev_name(a.dev.dev) + std::to_string(a.dev.index) +
           (a.ty == Ty::None ? "" : std::string(" ") + ty_info(a.ty).name) + "\n";
  for (const DeviceRef& d : p.retain) out += ".retain " + std::string(dev_name(d.dev)) + std::to_string(d.index) + "\n";
  for (const Rung& r : p.rungs) {
    for (const auto& l : r.labels) out += ".label " + l + "\n";
    out += ".rung line " + std::to_string(r.line);
    if (!r.title.empty()) out += " " + quote(r.title);
    out += "\n";
    for (const Instr& in : r.code) {
      std::string m = op_spelling(in);
      out += "    " + m;
      if (in.nopd()) out += std::string(m.size() < 8 ? 8 - m.size() : 1, ' ');
      for (int i = 0; i < in.nopd(); i++) out += (i ? " " : "") + operand_text(in, i);
      out += "\n";
    }
  }
  for (const auto& l : p.end_labels) out += ".label " + l + "\n";
  out += ".end\n";
  return out;
}

namespace {

// A token of one line: a view into the text, or for a quoted string into
// `Line::unquoted` (escapes removed).
struct Tok {
  std::string_view text;
  int col;  // 1-based
  bool quoted = false;
};

struct Line {
  std::vector<Tok> toks;
  std::deque<std::string> unquoted;  // stable addresses for the quoted tokens' views
};

bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f' || c == '\n'; }
// A token's end: a blank or ';' (by table, for the loop over a token's characters).
const std::array<bool, 256> kEndsToken = [] {
  std::array<bool, 256> t{};
  for (int c = 0; c < 256; c++) t[size_t(c)] = is_blank(char(c)) || c == ';';
  return t;
}();

void split(std::string_view line, int lineno, Line& out) {
  out.toks.clear();
  if (!out.unquoted.empty()) out.unquoted.clear();
  size_t i = 0;
  while (i < line.size()) {
    char c = line[i];
    if (kEndsToken[uint8_t(c)]) {  // a blank, or ';' and the comment to the end of the line
      if (c == ';') break;
      i++;
      continue;
    }
    Tok tok;
    tok.col = int(i) + 1;
    if (c == '"') {
      tok.quoted = true;
      std::string& text = out.unquoted.emplace_back();
      i++;
      while (i < line.size() && line[i] != '"') {
        if (line[i] == '\\' && i + 1 < line.size()) i++;
        text += line[i++];
      }
      if (i >= line.size()) throw CompileError(lineno, tok.col, "unterminated string");
      i++;
      tok.text = text;
    } else {
      const size_t from = i;
      while (++i < line.size() && !kEndsToken[uint8_t(line[i])]) {}  // line[from] does not end it
      tok.text = std::string_view(line.data() + from, i - from);
    }
    out.toks.push_back(tok);
  }
}

bool is_name(std::string_view s) {
  if (s.empty() || !(std::isalpha((unsigned char)s[0]) || s[0] == '_')) return false;
  for (char c : s)
    if (!std::isalnum((unsigned char)c) && c != '_') return false;
  return true;
}

// The common case of parse_number, in one pass: an optional '-' and 1 to 9
// decimal digits (never outside INT32).  False for anything else, which the
// general path then reads.
bool plain_int(std::string_view s, Operand& o) {
  const bool neg = s[0] == '-';
  const size_t from = neg ? 1 : 0;
  if (s.size() == from || s.size() - from > 9) return false;
  int32_t v = 0;
  for (size_t i = from; i < s.size(); i++) {
    if (s[i] < '0' || s[i] > '9') return false;
    v = v * 10 + (s[i] - '0');
  }
  o.kind = OpdKind::ConstInt;
  o.ival = neg ? -v : v;
  return true;
}

// Numeric constant: INT32 or REAL (a '.', an exponent, inf or nan makes it REAL).
// What strtoll (base 10) and strtof accept, whole.
bool parse_number(std::string_view s, Operand& o) {
  if (s.empty()) return false;
  if (plain_int(s, o)) return true;
  char first = s[0];
  if (!(std::isdigit((unsigned char)first) || first == '-' || first == '+' || first == '.')) return false;
  bool real = s.find_first_of(".eEnN") != std::string_view::npos;
  if (real) {
    std::string z(s);
    errno = 0;
    char* end = nullptr;
    float f = std::strtof(z.c_str(), &end);
    if (*end || errno == ERANGE) return false;
    o.kind = OpdKind::ConstReal;
    o.fval = f;
    return true;
  }
  std::string_view digits = s;
  if (first == '+') digits.remove_prefix(1);  // strtoll takes one sign, '+' included
  if (digits.empty() || digits[0] == '+' || (digits[0] == '-' && first == '+')) return false;
  int64_t v = 0;
  auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), v);
  if (ec != std::errc() || end != digits.data() + digits.size() || v < INT32_MIN || v > INT32_MAX) return false;
  o.kind = OpdKind::ConstInt;
  o.ival = int32_t(v);
  return true;
}

Operand parse_operand(char sig, const Tok& t, int lineno, uint32_t edges) {
  Operand o;
  auto fail = [&](const std::string& m) -> Operand { throw CompileError(lineno, t.col, m); };
  if (sig == 'l') {
    if (!is_name(t.text)) fail("expected a label name, found '" + std::string(t.text) + "'");
    o.kind = OpdKind::Label;
    o.label = std::string(t.text);
    return o;
  }
  if (sig == 'e') {
    if (t.text.size() < 2 || std::toupper((unsigned char)t.text[0]) != 'E') fail("expected an edge slot E<n>");
    Operand n;
    if (!parse_number(t.text.substr(1), n) || n.kind != OpdKind::ConstInt || n.ival < 0) fail("bad edge slot '" + std::string(t.text) + "'");
    if (uint32_t(n.ival) >= edges) fail("edge slot " + std::string(t.text) + " outside the .edges count");
    o.kind = OpdKind::Edge;
    o.index = uint32_t(n.ival);
    return o;
  }
  if ((sig == 'v' || sig == 'i') && parse_number(t.text, o)) {
    if (sig == 'i' && o.kind == OpdKind::ConstReal) fail("REAL constant where INT32 is required");
    return o;
  }
  auto d = parse_device(t.text);
  if (!d) fail("expected a device, found '" + std::string(t.text) + "'");
  if (d->index >= device_count(d->dev)) fail("device index out of range: " + std::string(t.text));
  if (sig == 't' || sig == 'c') {
    if (d->dev != (sig == 't' ? Dev::T : Dev::C)) fail(std::string("expected a ") + (sig == 't' ? "timer" : "counter"));
    o.kind = sig == 't' ? OpdKind::Timer : OpdKind::Counter;
    o.index = d->index;
    return o;
  }
  bool bitctx = sig == 'b' || sig == 'w';
  Area a = bitctx ? bit_area(d->dev) : word_area(d->dev);
  if (a == Area::Count || !operand_area_ok(sig, a, d->index)) fail("device " + std::string(t.text) + " is not allowed here");
  o.area = a;
  o.index = d->index;
  o.kind = bitctx ? OpdKind::Bit : (area_is_real(a) ? OpdKind::Real : OpdKind::Int);
  return o;
}

// A typed instruction's mnemonic: SPELLING.T or SPELLING.T.U (ADD.INT,
// CONV.DINT.REAL), its types checked against the op's types column.
std::optional<Op> typed_op(const Tok& head, int lineno, Ty& ty, Ty& src) {
  std::string_view m = head.text;
  size_t d1 = m.find('.'), d2 = m.find('.', d1 + 1);
  auto op = typed_op_from_name(m.substr(0, d1));
  if (!op) throw CompileError(lineno, head.col, "unknown mnemonic '" + std::string(m) + "'");
  auto t = ty_from_name(m.substr(d1 + 1, d2 == std::string_view::npos ? std::string_view::npos : d2 - d1 - 1));
  std::optional<Ty> u;
  if (d2 != std::string_view::npos) u = ty_from_name(m.substr(d2 + 1));
  if (!t || (d2 != std::string_view::npos && !u)) throw CompileError(lineno, head.col, "unknown type in '" + std::string(m) + "'");
  ty = *t, src = u ? *u : Ty::None;
  if (op_info(*op).typed == 2 && !u) throw CompileError(lineno, head.col, std::string(m) + " needs a source type too (" + std::string(m) + ".TYPE)");
  if (!op_takes(*op, ty, src)) throw CompileError(lineno, head.col, std::string(m.substr(0, d1)) + " does not take these types");
  return op;
}

// An operand of a typed instruction, of type t: a constant of t (written as
// a number), a device that can hold a t, or an INT32 constant (k).
Operand parse_typed_operand(char sig, Ty t, const Tok& tok, int lineno) {
  auto fail = [&](const std::string& m) -> Operand { throw CompileError(lineno, tok.col, m); };
  Operand o;
  if (sig == 'k') {
    if (!parse_number(tok.text, o) || o.kind != OpdKind::ConstInt) fail("expected an INT32 constant, found '" + std::string(tok.text) + "'");
    return o;
  }
  if (auto d = parse_device(tok.text)) {
    if (d->index >= device_count(d->dev)) fail("device index out of range: " + std::string(tok.text));
    Area a = t == Ty::BOOL ? bit_area(d->dev) : word_area(d->dev);
    static const Layout kStandard = Layout::standard(0);
    if (a == Area::Count || !typed_area_ok(sig, t, a, d->index, kStandard))
      fail("device " + std::string(tok.text) + " cannot hold this " + ty_info(t).name + " operand");
    o.area = a;
    o.index = d->index;
    o.kind = area_is_bit(a) ? OpdKind::Bit : area_is_real(a) ? OpdKind::Real : OpdKind::Int;
    return o;
  }
  if (sig != 's' && sig != 'x') fail("expected a device, found '" + std::string(tok.text) + "'");
  std::string why;
  auto v = parse_typed_const(t, tok.text, why);
  if (!v) fail(why);
  return Operand::typed_const(*v);
}

}  // namespace

// An alias: a name, or an instance's or structure's member INSTANCE.MEMBER of
// names, and array elements NAME[3] (the PLCopen importer's aliases, docs/plcopen.md).
bool is_alias_name(std::string_view s) {
  for (size_t a = 0;;) {
    size_t d = s.find('.', a);
    std::string_view seg = s.substr(a, d == std::string_view::npos ? std::string_view::npos : d - a);
    size_t lb = seg.find('[');  // an array's element a[3], a[1,-2]
    if (lb != std::string_view::npos) {
      if (seg.back() != ']' || seg.find_first_not_of("0123456789,-", lb + 1) != seg.size() - 1) return false;
      seg = seg.substr(0, lb);
    }
    if (!is_name(seg)) return false;
    if (d == std::string_view::npos) return true;
    a = d + 1;
  }
}


// Room for the rungs up front (each `.rung` counted, a few in comments or
// titles too many): the rungs are not moved each time their vector doubles.
static size_t rungs_in(std::string_view text) {
  size_t n = 0;
  for (size_t at = text.find(".rung"); at != std::string_view::npos; at = text.find(".rung", at + 5)) n++;
  return n;
}

Program parse_il_text(std::string_view text, const std::string& filename) { return parse_il_text(text, filename, nullptr); }

Program parse_il_text(std::string_view text, const std::string& filename, const std::function<void(const CompileError&)>& report) {
  Program p;
  p.source = filename;
  p.rungs.reserve(rungs_in(text));
  std::vector<std::string> pending_labels;
  std::unordered_map<std::string, size_t> label_rung;  // label -> index of the rung it precedes
  Rung* cur = nullptr;
  // cur's instructions, gathered here and moved into it when it ends: one
  // allocation a rung, not one each time its code doubles
  std::vector<Instr> code;
  code.reserve(256);
  auto end_rung = [&] {
    if (cur) cur->code.assign(std::make_move_iterator(code.begin()), std::make_move_iterator(code.end()));
    code.clear();
    cur = nullptr;
  };
  Line ln;
  bool ended = false, skip_after_end = false, in_refused_rung = false;
  int lineno = 0;
  size_t pos = 0;
  while (pos <= text.size()) {
    size_t nl = text.find('\n', pos);
    std::string_view line = text.substr(pos, nl == std::string_view::npos ? std::string_view::npos : nl - pos);
    pos = nl == std::string_view::npos ? text.size() + 1 : nl + 1;
    lineno++;
    // With `report`, a line's error is reported and the reader goes on with
    // the next line; the instructions after a refused .rung line are skipped
    // (they would be outside a rung, or in the one before).
    bool refused = false;
    auto line_of = [&](auto&& f) {
      if (!report) return f();
      try {
        f();
      } catch (const CompileError& e) {
        report(e);
        refused = true;
      }
    };
    line_of([&] { split(line, lineno, ln); });
    if (refused) continue;
    const std::vector<Tok>& toks = ln.toks;
    if (toks.empty()) continue;
    const Tok& head = toks[0];
    auto instruction = [&] {  // built in place at the end of the rung's code
      Ty ty = Ty::None, src = Ty::None;
      auto op = head.text.find('.') == std::string_view::npos ? op_from_name(head.text) : typed_op(head, lineno, ty, src);
      if (!op || op_info(*op).typed != (ty != Ty::None) + (src != Ty::None))
        throw CompileError(lineno, head.col, "unknown mnemonic '" + std::string(head.text) + "'");
      if (!cur) throw CompileError(lineno, head.col, "instruction outside a .rung");
      const char* sig = op_info(*op).operands;
      const int n = kOps[int(*op)].nopd;
      if (int(toks.size()) - 1 != n)
        throw CompileError(lineno, head.col, std::string(op_info(*op).name) + " takes " + std::to_string(n) + " operand(s)");
      Instr& in = code.emplace_back();
      in.op = *op;
      in.ty = ty, in.src = src;
      in.loc = {lineno, head.col};
      for (int i = 0; i < n; i++)
        in.a[i] = op_info(*op).typed ? parse_typed_operand(sig[i], operand_type(in, i), toks[i + 1], lineno)
                                     : parse_operand(sig[i], toks[i + 1], lineno, p.edge_slots);
    };
    if (ended && skip_after_end) continue;
    if (in_refused_rung && !head.text.starts_with('.')) continue;
    line_of([&] {
      if (ended) throw CompileError(lineno, head.col, "text after .end");
      if (!head.text.starts_with('.')) {  // every directive starts with '.', no mnemonic does
        instruction();
      } else if (head.text == ".end") {
        if (toks.size() > 1) throw CompileError(lineno, toks[1].col, "unexpected text after .end");
        end_rung();
        ended = true;
      } else if (head.text == ".edges") {
        Operand n;
        if (toks.size() != 2 || !parse_number(toks[1].text, n) || n.kind != OpdKind::ConstInt || n.ival < 0)
          throw CompileError(lineno, head.col, ".edges needs a count");
        p.edge_slots = uint32_t(n.ival);
      } else if (head.text == ".alias") {
        std::optional<DeviceRef> d;
        if (toks.size() < 3 || toks.size() > 4 || !is_alias_name(toks[1].text) || !(d = parse_device(toks[2].text)) ||
            d->index >= device_count(d->dev))
          throw CompileError(lineno, head.col, ".alias needs a name, a device and optionally a type");
        Alias a{std::string(toks[1].text), *d};
        if (toks.size() == 4) {
          auto t = ty_from_name(toks[3].text);
          if (!t) throw CompileError(lineno, toks[3].col, "unknown type '" + std::string(toks[3].text) + "'");
          a.ty = *t;
          if (std::string why = alias_type_problem(a); !why.empty()) throw CompileError(lineno, toks[3].col, why);
        }
        p.aliases.push_back(std::move(a));
      } else if (head.text == ".retain") {
        std::optional<DeviceRef> d;
        if (toks.size() != 2 || !(d = parse_device(toks[1].text)) || d->dev != Dev::D || d->index >= device_count(Dev::D))
          throw CompileError(lineno, head.col, ".retain needs a D word (D0..D" + std::to_string(device_count(Dev::D) - 1) + ")");
        if (std::find(p.retain.begin(), p.retain.end(), *d) == p.retain.end()) p.retain.push_back(*d);
      } else if (head.text == ".label") {
        if (toks.size() != 2 || !is_name(toks[1].text)) throw CompileError(lineno, head.col, ".label needs a name");
        std::string name(toks[1].text);
        if (!label_rung.emplace(name, p.rungs.size()).second)
          throw CompileError(lineno, toks[1].col, "duplicate label '" + name + "'");
        pending_labels.push_back(std::move(name));
        end_rung();
      } else if (head.text == ".rung") {
        Operand n;
        if (toks.size() < 3 || toks[1].text != "line" || !parse_number(toks[2].text, n) || n.kind != OpdKind::ConstInt)
          throw CompileError(lineno, head.col, "expected .rung line N [\"title\"]");
        Rung r;
        r.line = n.ival;
        r.labels = std::move(pending_labels);
        pending_labels.clear();
        if (toks.size() >= 4) {
          if (!toks[3].quoted || toks.size() > 4) throw CompileError(lineno, toks[3].col, "expected a quoted rung title");
          r.title = std::string(toks[3].text);
        }
        end_rung();
        p.rungs.push_back(std::move(r));
        cur = &p.rungs.back();
      } else {
        instruction();
      }
    });
    if (refused && !ended && head.text == ".end") ended = true;  // a .end with text after it ends the program all the same
    if (refused && ended) skip_after_end = true;                 // "text after .end": once
    if (head.text == ".rung") in_refused_rung = refused;
    else if (head.text == ".label" || head.text == ".end") in_refused_rung = false;
  }
  auto fail = [&](const CompileError& e) {
    if (!report) throw e;
    report(e);
  };
  if (!ended) fail(CompileError(lineno, 1, "missing .end"));
  p.end_labels = std::move(pending_labels);
  // Every jump goes forward to a defined label; a LOOP back to one.
  std::set<std::string> undefined;  // each said once
  for (size_t r = 0; r < p.rungs.size(); r++)
    for (const Instr& in : p.rungs[r].code)
      for (int i = 0; i < in.nopd(); i++)
        if (in.a[i].kind == OpdKind::Label) {
          const std::string& name = in.a[i].label;
          auto it = label_rung.find(name);
          if (it == label_rung.end()) {
            if (undefined.insert(name).second) fail(CompileError(in.loc.line, in.loc.col, "undefined label '" + name + "'"));
          } else if (in.op == Op::LOOP && it->second > r) {
            fail(CompileError(in.loc.line, in.loc.col, "LOOP to '" + name + "', which does not come before it"));
          } else if (in.op != Op::LOOP && it->second <= r) {
            fail(CompileError(in.loc.line, in.loc.col, "backward jump to '" + name + "' (only a LOOP goes back)"));
          }
        }
  return p;
}

}  // namespace ldc
