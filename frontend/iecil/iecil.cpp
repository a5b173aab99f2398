// frontend/iecil/iecil.cpp -- IEC 61131-3 Instruction List (docs/iec-il.md):
// the lexer, the reader of the classic subset, which turns a program into
// ldc's untyped IL directly (a program with typed declarations goes to
// typed.cpp), and the writer of
// `ldc --emit=iec-il`, which prints any ldc IL program as IEC IL that the
// reader reads back to the same behaviour.
//
//   program    = [ "PROGRAM" NAME ] { var_block } { line } [ "END_PROGRAM" ] ;
//   var_block  = ( "VAR" | "VAR_INPUT" | "VAR_OUTPUT" | "VAR_GLOBAL" ) { decl } "END_VAR" ;
//   decl       = NAME { "," NAME } [ "AT" location ] ":" TYPE [ ":=" literal ] ";" ;
//   line       = [ NAME ":" ] [ instruction ] EOL ;
//   instruction= operator [ operand ] | operator "(" [ operand ] | ")"
//              | "CAL" NAME "(" [ param { "," param } ] ")" ;
//   param      = NAME ":=" operand ;
// The current result (CR) of IL is the top of ldc's bit stack while it is
// BOOL; an INT or REAL result is a value operand plus, when computed, a hidden
// accumulator word.  Each LD outside parentheses starts an ldc rung.
#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <map>
#include <set>

#include "frontend/diag.h"
#include "frontend/frontend.h"
#include "frontend/iecil/iecil.h"

namespace ldc {
namespace iecil {


std::string upper(std::string_view s) {
  std::string u(s);
  for (char& c : u) c = char(std::toupper((unsigned char)c));
  return u;
}

// ---------------------------------------------------------------- lexer


// A direct address: %IX0.4, %QW2, %MD1 ...; without the size letter (%I0.4,
// %Q0.0, %M1.2) it is a bit, as IEC 61131-3 (2.4.1.1) has it: %IX0.4.
std::optional<DeviceRef> iec_address(const std::string& text, std::string& why) {
  std::string a = text;
  char region = a.size() >= 3 ? char(std::toupper((unsigned char)a[1])) : 0;
  if ((region == 'I' || region == 'Q' || region == 'M') && std::isdigit((unsigned char)a[2])) a.insert(2, "X");
  return parse_iec_address(a, why);
}

bool date_literal_head(std::string_view head) {
  size_t hash = head.find('#');
  if (hash == std::string_view::npos) return false;
  std::string p = upper(head.substr(0, hash));
  return p == "D" || p == "DATE" || p == "DT" || p == "DATE_AND_TIME" || p == "TOD" || p == "TIME_OF_DAY" ||
         p == "LDATE" || p == "LDT" || p == "LTOD";
}

static bool word_start(char c) { return std::isalnum((unsigned char)c) || c == '_' || c == '%'; }
static bool word_char(char c) { return std::isalnum((unsigned char)c) || c == '_' || c == '%' || c == '#' || c == '.'; }

std::vector<Tok> lex(std::string_view s) {
  std::vector<Tok> out;
  int line = 1;
  size_t bol = 0, i = 0;
  auto col = [&](size_t at) { return int(at - bol) + 1; };
  while (i < s.size()) {
    char c = s[i];
    if (c == '\n') {
      out.push_back({Tok::Eol, "", line, col(i)});
      line++, bol = ++i;
      continue;
    }
    if (c == ' ' || c == '\t' || c == '\r') { i++; continue; }
    if (c == '(' && i + 1 < s.size() && s[i + 1] == '*') {
      int l0 = line, c0 = col(i);
      i += 2;
      while (i < s.size() && !(s[i] == '*' && i + 1 < s.size() && s[i + 1] == ')')) {
        if (s[i] == '\n') line++, bol = i + 1;
        i++;
      }
      if (i >= s.size()) throw CompileError(l0, c0, "unterminated comment (* ... *)");
      i += 2;
      continue;
    }
    if (c == '/' && i + 1 < s.size() && s[i + 1] == '/') {
      while (i < s.size() && s[i] != '\n') i++;
      continue;
    }
    if (c == '\'') {  // a string literal, $-escapes kept for parse_literal (ir/model.h)
      size_t j = i + 1;
      while (j < s.size() && s[j] != '\'' && s[j] != '\n') j += s[j] == '$' && j + 1 < s.size() && s[j + 1] != '\n' ? 2 : 1;
      if (j >= s.size() || s[j] != '\'') throw CompileError(line, col(i), "unterminated string literal (a quote inside one is $')");
      out.push_back({Tok::Word, std::string(s.substr(i, j + 1 - i)), line, col(i)});
      i = j + 1;
      continue;
    }
    size_t st = i;
    bool sign = (c == '-' || c == '+') && i + 1 < s.size() && (std::isdigit((unsigned char)s[i + 1]) || s[i + 1] == '.');
    // a member after an index: a[2].x
    bool member = c == '.' && i + 1 < s.size() && (std::isalpha((unsigned char)s[i + 1]) || s[i + 1] == '_');
    if (word_start(c) || sign || member) {
      i++;
      bool numeric = sign || std::isdigit((unsigned char)c);
      // a sign inside a word: 1.0E-3, LREAL#1e-9, T#-2ms; '..' ends it (1..10)
      auto sign_inside = [&] {
        if (s[i] != '-' && s[i] != '+') return false;
        char before = s[i - 1];
        bool typed = s.substr(st, i - st).find('#') != std::string_view::npos;
        return before == '#' || ((numeric || typed) && (before == 'e' || before == 'E'));
      };
      // a date's '-' and a time of day's ':' before a digit: DATE#2024-01-31, TOD#12:30:00, DT#2024-01-31-12:30:00
      auto date_inside = [&] {
        if ((s[i] != '-' && s[i] != ':') || i + 1 >= s.size() || !std::isdigit((unsigned char)s[i + 1])) return false;
        return date_literal_head(s.substr(st, i - st));
      };
      while (i < s.size() && ((word_char(s[i]) && !(s[i] == '.' && i + 1 < s.size() && s[i + 1] == '.')) || sign_inside() || date_inside())) i++;
      out.push_back({Tok::Word, std::string(s.substr(st, i - st)), line, col(st)});
      continue;
    }
    if ((c == ':' || c == '=') && i + 1 < s.size() && (s[i + 1] == '=' || s[i + 1] == '>')) {
      out.push_back({Tok::Punct, std::string(s.substr(i, 2)), line, col(i)});
      i += 2;
      continue;
    }
    if (c == '.' && i + 1 < s.size() && s[i + 1] == '.') {
      out.push_back({Tok::Punct, "..", line, col(i)});
      i += 2;
      continue;
    }
    if (c == '(' || c == ')' || c == ':' || c == ',' || c == ';' || c == '[' || c == ']') {
      out.push_back({Tok::Punct, std::string(1, c), line, col(i)});
      i++;
      continue;
    }
    std::string shown = (unsigned char)c < 32 || (unsigned char)c >= 127 ? "byte " + std::to_string((unsigned char)c)
                                                                        : "'" + std::string(1, c) + "'";
    throw CompileError(line, col(i), "unexpected " + shown);
  }
  out.push_back({Tok::Eol, "", line, col(i)});
  out.push_back({Tok::End, "", line, col(i)});
  return out;
}

}  // namespace iecil

namespace {
using iecil::Tok;
using iecil::lex;
using iecil::upper;

constexpr uint32_t kVirtual = 0x40000000u;  // hidden devices before allocation
constexpr int kMaxParens = 16;

// ---------------------------------------------------------------- values

enum class Ty { None, Bool, Int, Real };

// An operand as written: a bit, a value, a literal, or a function block instance.
struct Val {
  enum Kind { Bit, Word, BoolLit, Inst } kind = Bit;
  Operand o;       // Bit: OpdKind::Bit; Word: Int/Real/ConstInt/ConstReal
  bool flag = false;  // BoolLit value
  int inst = -1;   // Inst: index into instances
  bool real() const { return o.is_real(); }
};

struct Instance {
  std::string name, type;  // TON TOF TP CTU CTD R_TRIG F_TRIG
  uint32_t index;          // T or C number, or the M of a trigger's Q (maybe virtual)
  bool timer() const { return type[0] == 'T'; }
  bool trig() const { return type[1] == '_'; }
  Dev dev() const { return trig() ? Dev::M : timer() ? Dev::T : Dev::C; }
};

struct Var {
  std::string name;
  Ty ty;
  Operand o;  // the device
};

// Literal: TRUE FALSE, 42 -7 16#FF 2#1010 8#17 1_000, 1.5 1e3, INT#5 REAL#2.5, T#1s500ms TIME#2m.
bool parse_literal(const std::string& w, Val& v, std::string& why) {
  std::string u = upper(w);
  if (u == "TRUE" || u == "FALSE" || u == "BOOL#1" || u == "BOOL#0" || u == "BOOL#TRUE" || u == "BOOL#FALSE") {
    v.kind = Val::BoolLit;
    v.flag = u == "TRUE" || u == "BOOL#1" || u == "BOOL#TRUE";
    return true;
  }
  size_t hash = u.find('#');
  std::string type = hash == std::string::npos ? "" : u.substr(0, hash);
  std::string body = hash == std::string::npos ? u : u.substr(hash + 1);
  auto make_int = [&](long long x) {
    if (x < INT32_MIN || x > INT32_MAX) { why = "constant out of the INT32 range: " + w; return false; }
    v.kind = Val::Word;
    v.o = Operand{OpdKind::ConstInt};
    v.o.ival = int32_t(x);
    return true;
  };
  if (type == "T" || type == "TIME") {
    // T#1d2h3m4s5ms, parts in decreasing order, each an integer
    if (body.empty()) { why = "empty duration " + w; return false; }
    long long ms = 0;
    size_t i = 0;
    bool neg = body[0] == '-';
    if (neg) i++;
    if (i >= body.size()) { why = "bad duration " + w; return false; }
    while (i < body.size()) {
      if (body[i] == '_') { i++; continue; }
      size_t st = i;
      while (i < body.size() && std::isdigit((unsigned char)body[i])) i++;
      if (st == i || i - st > 9) { why = "bad duration " + w + " (e.g. T#1s500ms)"; return false; }
      long long n = std::stoll(body.substr(st, i - st));
      size_t us = i;
      while (i < body.size() && std::isalpha((unsigned char)body[i])) i++;
      std::string unit = body.substr(us, i - us);
      long long mul = unit == "D" ? 86400000 : unit == "H" ? 3600000 : unit == "M" ? 60000 : unit == "S" ? 1000 : unit == "MS" ? 1 : 0;
      if (!mul) { why = "bad duration unit in " + w + " (d h m s ms)"; return false; }
      ms += n * mul;
      if (ms > INT32_MAX) { why = "duration above 2^31 ms: " + w; return false; }
    }
    return make_int(neg ? -ms : ms);
  }
  bool want_real = type == "REAL" || type == "LREAL";
  if (!type.empty() && !want_real && type != "INT" && type != "DINT" && type != "SINT" && type != "UINT" &&
      type != "UDINT" && type != "USINT" && type != "WORD" && type != "DWORD" && type != "BYTE" && type != "2" &&
      type != "8" && type != "16") {
    why = "unknown typed literal " + w;
    return false;
  }
  if (body.empty()) return false;
  int base = type == "2" ? 2 : type == "8" ? 8 : type == "16" ? 16 : 10;
  std::string digits;
  for (char c : body)
    if (c != '_') digits += c;
  if (digits.empty()) return false;
  if (base == 10 && !std::isdigit((unsigned char)digits[0]) && digits[0] != '-' && digits[0] != '+' && digits[0] != '.')
    return false;
  // a typed literal's body may be based too: INT#16#FF
  size_t h2 = digits.find('#');
  if (h2 != std::string::npos && base == 10) {
    std::string b = digits.substr(0, h2);
    base = b == "2" ? 2 : b == "8" ? 8 : b == "16" ? 16 : 0;
    if (!base) { why = "bad base in " + w; return false; }
    digits = digits.substr(h2 + 1);
    if (digits.empty()) { why = "bad number " + w; return false; }
  }
  errno = 0;
  char* end = nullptr;
  bool real = base == 10 && (want_real || digits.find_first_of(".E") != std::string::npos);
  if (real) {
    float f = std::strtof(digits.c_str(), &end);
    if (*end || errno == ERANGE || !std::isfinite(f)) { why = "bad REAL constant " + w; return false; }
    v.kind = Val::Word;
    v.o = Operand{OpdKind::ConstReal};
    v.o.fval = f;
    return true;
  }
  if (base != 10 && (digits[0] == '-' || digits[0] == '+')) { why = "bad number " + w; return false; }
  long long x = std::strtoll(digits.c_str(), &end, base);
  if (*end || errno == ERANGE) { why = "bad number " + w; return false; }
  if (base != 10 && x > INT32_MAX && x <= UINT32_MAX) x -= 0x100000000LL;  // 16#FFFFFFFF is -1
  return make_int(x);
}

// ---------------------------------------------------------------- reader

struct Reader {
  std::vector<Tok> t;
  size_t pos = 0;
  Program p;
  // Error recovery (docs/diagnostics.md): each declaration and line on its
  // own; names whose declaration was refused, and unknown names reported,
  // say nothing more (upper-case).
  iecil::Recovery* rec = nullptr;
  std::set<std::string> refused, unknown;

  // Runs `read` (a declaration or a line); with recovery, its error is
  // reported and false returned (the caller skips what it covers).
  template <class F>
  bool recover(F read) {
    if (!rec) {
      read();
      return true;
    }
    try {
      read();
      return true;
    } catch (const CompileError& e) {
      rec->report(e);
    }
    return false;
  }
  std::vector<Var> vars;
  std::vector<Instance> insts;
  std::map<std::string, size_t> var_of, inst_of;  // upper-case name -> index
  std::set<uint32_t> used[int(Dev::F) + 1];       // explicit device indices, per Dev
  std::vector<Dev> virt;                          // hidden devices, allocated at the end
  std::vector<std::pair<Operand, Operand>> inits; // (device, literal) initial values

  // generation state
  Rung* rung = nullptr;
  int depth = 0;      // bit-stack entries in this rung
  Ty cr = Ty::None;   // the current result's type
  Operand cur;        // the value of an INT/REAL current result
  bool cur_is_acc = false;
  struct Paren { std::string op; Ty outer; Operand cur; bool cur_is_acc; SrcLoc loc; };
  std::vector<Paren> parens;
  std::vector<std::string> labels_seen, pending_labels;
  struct Jump { std::string label; SrcLoc loc; size_t rung; };
  std::vector<Jump> jumps;
  uint32_t hbit[2] = {}, acc_int = 0, acc_real = 0;  // virtual hidden devices
  bool have_h[2] = {}, have_acc_int = false, have_acc_real = false;

  const Tok& peek() const { return t[pos]; }
  const Tok& next() { return t[pos < t.size() - 1 ? pos++ : pos]; }
  [[noreturn]] void fail(const Tok& k, const std::string& m) { throw CompileError(k.line, k.col, m); }
  [[noreturn]] void fail(SrcLoc l, const std::string& m) { throw CompileError(l.line, l.col, m); }
  bool is_kw(const Tok& k, const char* w) const { return k.kind == Tok::Word && upper(k.text) == w; }
  bool is_punct(const Tok& k, const char* p) const { return k.kind == Tok::Punct && k.text == p; }
  void skip_eols() {
    while (peek().kind == Tok::Eol) next();
  }
  const Tok& expect_punct(const char* p) {
    if (!is_punct(peek(), p)) fail(peek(), std::string("expected '") + p + "'" + found(peek()));
    return next();
  }
  static std::string found(const Tok& k) {
    if (k.kind == Tok::Eol) return " at the end of the line";
    if (k.kind == Tok::End) return " at the end of the file";
    return ", found '" + k.text + "'";
  }

  uint32_t new_virtual(Dev d) {
    virt.push_back(d);
    return kVirtual + uint32_t(virt.size() - 1);
  }
  void note_used(Dev d, uint32_t i) {
    if (int(d) <= int(Dev::F)) used[int(d)].insert(i);
  }

  // ---- declarations

  static bool is_ident(const std::string& s) {
    if (s.empty() || !(std::isalpha((unsigned char)s[0]) || s[0] == '_')) return false;
    for (char c : s)
      if (!std::isalnum((unsigned char)c) && c != '_') return false;
    return true;
  }

  // program = [ "PROGRAM" NAME ] { var_block } { line } [ "END_PROGRAM" ]
  void program() {
    skip_eols();
    if (is_kw(peek(), "PROGRAM")) {
      next();
      if (peek().kind != Tok::Word || !is_ident(peek().text)) fail(peek(), "expected the program's name" + found(peek()));
      next();
      end_line();
    }
    skip_eols();
    while (is_kw(peek(), "VAR") || is_kw(peek(), "VAR_INPUT") || is_kw(peek(), "VAR_OUTPUT") || is_kw(peek(), "VAR_GLOBAL")) {
      var_block();
      skip_eols();
    }
    for (size_t i = 0; i < insts.size(); i++) alias_of(insts[i].name, DeviceRef{insts[i].dev(), insts[i].index});
    initial_values();
    bool ended = false, skipping = false;
    while (peek().kind != Tok::End) {
      if (peek().kind == Tok::Eol) { next(); continue; }
      if (ended) fail(peek(), "text after END_PROGRAM");
      if (is_kw(peek(), "END_PROGRAM")) {
        next();
        if (!recover([&] { end_line(); })) skip_line();
        ended = true;
        continue;
      }
      if (!rec) { line(); continue; }
      size_t start = pos;
      if (skipping && !sync_line()) { skip_line(); continue; }
      skipping = false;
      if (recover([&] { line(); })) continue;
      // the line refused: the ones after it that go on with its value are
      // skipped too, up to the next that starts anew
      pos = start;
      skip_line();
      rung = nullptr;
      cr = Ty::None;
      parens.clear();
      skipping = true;
    }
    if (rec) rec->check();  // the labels of lines refused: their jumps would be reported again
    finish();
  }
  void skip_line() {
    while (peek().kind != Tok::Eol && peek().kind != Tok::End) next();
  }
  // Does the line at pos start anew, not going on with the value of the line
  // before it: a label, or a line that loads a value, calls a block, or jumps
  // or returns unconditionally.
  bool sync_line() const {
    if (peek().kind != Tok::Word) return false;
    if (pos + 1 < t.size() && is_punct(t[pos + 1], ":")) return true;
    std::string u = upper(peek().text);
    return u == "LD" || u == "LDN" || u == "CAL" || u == "JMP" || u == "RET";
  }

  void end_line() {
    if (peek().kind != Tok::Eol && peek().kind != Tok::End) fail(peek(), "unexpected '" + peek().text + "' at the end of the line");
    if (peek().kind == Tok::Eol) next();
  }

  // var_block = VAR { decl } END_VAR
  void var_block() {
    const Tok& head = next();
    if (is_kw(peek(), "RETAIN") || is_kw(peek(), "CONSTANT")) fail(peek(), "'" + peek().text + "' variables are not supported (docs/iec-il.md)");
    for (;;) {
      skip_eols();
      if (is_kw(peek(), "END_VAR")) { next(); end_line(); return; }
      if (peek().kind == Tok::End) fail(head, "'" + head.text + "' block without END_VAR");
      size_t start = pos;
      if (!recover([&] { decl(); })) skip_decl(start);
    }
  }
  // After a refused declaration: the names it declares that are not declared
  // (what comes before its ':' or AT) are remembered, so that their uses say
  // nothing; the reader goes on after its ';' (or at the END_VAR of one
  // without it).
  void skip_decl(size_t start) {
    pos = start;
    bool naming = true;
    while (peek().kind != Tok::End && !is_kw(peek(), "END_VAR")) {
      const Tok& k = next();
      if (is_punct(k, ":") || is_kw(k, "AT")) naming = false;
      if (naming && k.kind == Tok::Word && !var_of.count(upper(k.text)) && !inst_of.count(upper(k.text))) refused.insert(upper(k.text));
      if (is_punct(k, ";")) break;
    }
    if (pos == start) next();
  }

  // decl = NAME { "," NAME } [ "AT" location ] ":" TYPE [ ":=" literal ] ";"
  void decl() {
    std::vector<Tok> names;
    for (;;) {
      const Tok& n = next();
      if (n.kind != Tok::Word || !is_ident(n.text)) fail(n, "expected a variable name" + found(n));
      std::string u = upper(n.text);
      if (var_of.count(u) || inst_of.count(u)) fail(n, "second declaration of '" + n.text + "'");
      for (const Tok& o : names)
        if (upper(o.text) == u) fail(n, "second declaration of '" + n.text + "'");
      names.push_back(n);
      skip_eols();
      if (!is_punct(peek(), ",")) break;
      next();
      skip_eols();
    }
    std::optional<DeviceRef> at;
    Tok at_tok;
    if (is_kw(peek(), "AT")) {
      next();
      at_tok = next();
      if (names.size() > 1) fail(at_tok, "one variable per AT location");
      std::string why;
      if (at_tok.kind == Tok::Word) at = at_tok.text[0] == '%' ? iecil::iec_address(at_tok.text, why) : parse_device(at_tok.text);
      if (!at) fail(at_tok, why.empty() ? "expected a location (%IX0.0, %QW2, %MD1 ... or an ldc device)" + found(at_tok) : why);
      if (at->index >= device_count(at->dev)) fail(at_tok, "location " + at_tok.text + " is outside ldc's devices");
    }
    skip_eols();
    expect_punct(":");
    skip_eols();
    const Tok& ty = next();
    if (ty.kind != Tok::Word) fail(ty, "expected a type" + found(ty));
    std::string T = upper(ty.text);
    Ty vty = T == "BOOL" ? Ty::Bool
             : T == "REAL" ? Ty::Real
             : (T == "INT" || T == "DINT" || T == "SINT" || T == "UINT" || T == "UDINT" || T == "USINT" || T == "WORD" ||
                T == "DWORD" || T == "BYTE" || T == "TIME") ? Ty::Int : Ty::None;
    bool trig = T == "R_TRIG" || T == "F_TRIG";
    bool inst = T == "TON" || T == "TOF" || T == "TP" || T == "CTU" || T == "CTD" || trig;
    if (vty == Ty::None && !inst)
      fail(ty, "unsupported type '" + ty.text + "' (BOOL, INT/DINT/WORD/TIME..., REAL, TON, TOF, TP, CTU, CTD, R_TRIG, F_TRIG)");
    bool timer_type = T == "TON" || T == "TOF" || T == "TP";
    if (at && trig) fail(at_tok, "an " + T + " instance has no location");
    if (at && inst && at->dev != (timer_type ? Dev::T : Dev::C))
      fail(at_tok, std::string("a ") + T + " instance is located at a " + (timer_type ? "timer (AT T3)" : "counter (AT C3)") + " or nowhere");
    if (at && !inst && (at->dev == Dev::T || at->dev == Dev::C))
      fail(at_tok, "timers and counters are declared as instances (t1 AT T1 : TON;)");
    skip_eols();
    Val init;
    bool has_init = false;
    Tok init_tok;
    if (is_punct(peek(), ":=")) {
      next();
      init_tok = next();
      std::string why;
      if (inst) fail(init_tok, "a function block instance has no initial value");
      if (init_tok.kind != Tok::Word || !parse_literal(init_tok.text, init, why))
        fail(init_tok, why.empty() ? "expected a literal initial value" + found(init_tok) : why);
      if ((vty == Ty::Bool) != (init.kind == Val::BoolLit) || (vty == Ty::Int && init.o.kind == OpdKind::ConstReal))
        fail(init_tok, "initial value " + init_tok.text + " does not fit type " + ty.text);
      has_init = true;
      skip_eols();
    }
    expect_punct(";");
    for (const Tok& n : names) {
      std::string u = upper(n.text);
      if (inst) {
        Instance in{n.text, T, 0};
        bool timer = in.timer();
        auto d = at ? at : parse_device(n.text);  // an instance at T3 or named T3 is that device
        if (in.trig()) {
          in.index = new_virtual(Dev::M);  // its Q
        } else if (d && d->dev == (timer ? Dev::T : Dev::C) && d->index < device_count(d->dev)) {
          in.index = d->index;
          for (const Instance& o : insts)
            if (!o.trig() && o.timer() == timer && o.index == in.index) fail(n, "'" + n.text + "' is already the device of '" + o.name + "'");
          note_used(d->dev, d->index);
        } else {
          in.index = new_virtual(timer ? Dev::T : Dev::C);
        }
        inst_of[u] = insts.size();
        insts.push_back(in);
        continue;
      }
      Var v{n.text, vty, {}};
      Dev d;
      uint32_t idx;
      if (at) {
        d = at->dev, idx = at->index;
        bool bit = bit_area(d) != Area::Count, word = word_area(d) != Area::Count;
        if (vty == Ty::Bool ? !bit : (!word || (d == Dev::F) != (vty == Ty::Real)))
          fail(at_tok, "location " + at_tok.text + " does not fit type " + ty.text);
        note_used(d, idx);
      } else {
        d = vty == Ty::Bool ? Dev::M : vty == Ty::Real ? Dev::F : Dev::D;
        idx = new_virtual(d);
      }
      Area a = vty == Ty::Bool ? bit_area(d) : word_area(d);
      v.o = Operand{vty == Ty::Bool ? OpdKind::Bit : vty == Ty::Real ? OpdKind::Real : OpdKind::Int, a, idx};
      var_of[u] = vars.size();
      vars.push_back(v);
      alias_of(n.text, DeviceRef{d, idx});
      if (has_init) {
        if (a == Area::X || a == Area::WX) fail(init_tok, "an input (" + n.text + ") has no initial value: the I/O writes it");
        inits.emplace_back(v.o, init.kind == Val::BoolLit ? [&] { Operand c{OpdKind::ConstInt}; c.ival = init.flag; return c; }() : init.o);
      }
    }
  }

  void alias_of(const std::string& name, DeviceRef d) {
    if (parse_device(name) || upper(name) == "DT") return;  // names that spell a device get no alias
    p.aliases.push_back({name, d});
  }

  // Initial values: written on the first scan, before anything else (S1).
  void initial_values() {
    if (inits.empty()) return;
    here = SrcLoc{1, 1};
    start_rung(here);
    emit(Op::LOAD, Operand{OpdKind::Bit, Area::S, kBitFirstScan});
    for (auto& [dev, lit] : inits) {
      if (dev.kind == OpdKind::Bit) emit(lit.ival ? Op::SET : Op::RST, dev);
      else emit(Op::MOV, lit, dev);
    }
    rung = nullptr;
  }

  // ---- operands

  // operand = literal | %address | NAME | NAME "." output | ldc device
  Val operand(const Tok& k) {
    if (k.kind != Tok::Word) fail(k, "expected an operand" + found(k));
    Val v;
    std::string why;
    if (parse_literal(k.text, v, why)) return v;
    if (!why.empty()) fail(k, why);
    std::string u = upper(k.text);
    if (k.text[0] == '%') {
      auto d = iecil::iec_address(k.text, why);
      if (!d) fail(k, why.empty() ? "bad IEC address " + k.text : why);
      return device(k, *d);
    }
    size_t dot = u.find('.');
    if (dot != std::string::npos) {
      std::string base = u.substr(0, dot), field = u.substr(dot + 1);
      auto it = inst_of.find(base);
      if (it == inst_of.end() && rec && (refused.count(base) || !unknown.insert(base).second))
        throw iecil::Quiet(k.line, k.col, "unknown instance again");
      if (it == inst_of.end()) fail(k, "'" + k.text.substr(0, dot) + "' is not a declared timer or counter");
      const Instance& in = insts[it->second];
      if (field == "Q" && in.trig()) v.o = Operand{OpdKind::Bit, Area::M, in.index};
      else if (field == "Q") v.o = Operand{OpdKind::Bit, in.timer() ? Area::TQ : Area::CQ, in.index};
      else if ((field == "ET" && in.timer()) || (field == "CV" && !in.timer())) {
        v.kind = Val::Word;
        v.o = Operand{OpdKind::Int, in.timer() ? Area::TW : Area::CW, in.index};
      } else {
        fail(k, in.type + " instance '" + in.name + "' has no output '" + k.text.substr(dot + 1) + "' (" +
                    (in.trig() ? "Q" : in.timer() ? "Q, ET" : "Q, CV") + ")");
      }
      return v;
    }
    if (auto it = var_of.find(u); it != var_of.end()) {
      const Var& var = vars[it->second];
      v.kind = var.ty == Ty::Bool ? Val::Bit : Val::Word;
      v.o = var.o;
      return v;
    }
    if (auto it = inst_of.find(u); it != inst_of.end()) {
      v.kind = Val::Inst;
      v.inst = int(it->second);
      return v;
    }
    if (rec && refused.count(u)) throw iecil::Quiet(k.line, k.col, "refused");  // even where its name spells a device (F1)
    if (auto d = parse_device(k.text)) {
      if (d->dev == Dev::T || d->dev == Dev::C)
        fail(k, "declare timer/counter '" + k.text + "' as an instance (" + k.text + " : " + (d->dev == Dev::T ? "TON" : "CTU") +
                    ";) and use " + k.text + ".Q, " + k.text + (d->dev == Dev::T ? ".ET" : ".CV"));
      return device(k, *d);
    }
    if (rec && (refused.count(u) || !unknown.insert(u).second)) throw iecil::Quiet(k.line, k.col, "unknown variable again");
    fail(k, "unknown variable '" + k.text + "'");
  }

  Val device(const Tok& k, DeviceRef d) {
    if (d.index >= device_count(d.dev)) fail(k, "device index out of range: " + k.text);
    note_used(d.dev, d.index);
    Val v;
    Area b = bit_area(d.dev);
    if (b != Area::Count) {
      v.o = Operand{OpdKind::Bit, b, d.index};
    } else {
      v.kind = Val::Word;
      Area w = word_area(d.dev);
      v.o = Operand{area_is_real(w) ? OpdKind::Real : OpdKind::Int, w, d.index};
    }
    return v;
  }

  Operand bit_of(const Val& v, const Tok& k, const char* what) {
    if (v.kind != Val::Bit) fail(k, std::string(what) + " needs a BOOL operand, '" + k.text + "' is not one");
    return v.o;
  }
  Operand writable_bit(const Val& v, const Tok& k, const char* what) {
    Operand o = bit_of(v, k, what);
    if (!operand_area_ok('w', o.area, o.index)) fail(k, "'" + k.text + "' cannot be written (an input, a timer/counter output or a read-only system bit)");
    return o;
  }
  Operand value_of(const Val& v, const Tok& k, const char* what) {
    if (v.kind != Val::Word) fail(k, std::string(what) + " needs an INT or REAL operand, '" + k.text + "' is not one");
    return v.o;
  }

  // ---- code

  void start_rung(SrcLoc loc) {
    Rung r;
    r.line = loc.line;
    r.labels = std::move(pending_labels);
    pending_labels.clear();
    if (p.rungs.size() >= kMaxRungs) fail(loc, "more than " + std::to_string(kMaxRungs) + " rungs");
    p.rungs.push_back(std::move(r));
    rung = &p.rungs.back();
    depth = 0;
  }
  SrcLoc here;
  void emit_at(Op op, SrcLoc at, Operand a = {}, Operand b = {}, Operand c = {}) {
    Instr in;
    in.op = op;
    in.a[0] = a, in.a[1] = b, in.a[2] = c;
    for (int i = 0; i < in.nopd(); i++)
      if (op_info(op).operands[i] == 'e') in.a[i] = Operand{OpdKind::Edge, Area::Sys, p.edge_slots++};
    in.loc = at.line ? at : here;
    depth += op_info(op).push - op_info(op).pop;
    if (depth > kMaxStackDepth) fail(in.loc, "expression too deeply nested: it needs more than " + std::to_string(kMaxStackDepth) + " bit-stack entries");
    rung->code.push_back(in);
  }
  void emit(Op op, Operand a = {}, Operand b = {}, Operand c = {}) { emit_at(op, SrcLoc{}, a, b, c); }

  Operand hidden_bit(int k) {
    if (!have_h[k]) hbit[k] = new_virtual(Dev::M), have_h[k] = true;
    return Operand{OpdKind::Bit, Area::M, hbit[k]};
  }
  Operand acc(bool real) {
    if (real) {
      if (!have_acc_real) acc_real = new_virtual(Dev::F), have_acc_real = true;
      return Operand{OpdKind::Real, Area::F, acc_real};
    }
    if (!have_acc_int) acc_int = new_virtual(Dev::D), have_acc_int = true;
    return Operand{OpdKind::Int, Area::D, acc_int};
  }

  // the top of the bit stack becomes `b`
  void replace_top(Operand b) {
    if (depth <= 1 && parens.empty()) {
      start_rung(here);
    } else {
      emit(Op::MPP);
    }
    emit(Op::LOAD, b);
  }
  void negate_top() {
    Operand h = hidden_bit(0);
    emit(Op::OUTN, h);
    replace_top(h);
  }
  // top = top XOR b (XORN: XOR NOT b)
  void xor_top(Operand b, bool n) {
    Operand h = hidden_bit(1);
    emit(Op::OUT, h);
    emit(n ? Op::AND : Op::ANDN, b);
    emit(Op::LOADN, h);
    emit(n ? Op::ANDN : Op::AND, b);
    emit(Op::ORBLK);
  }

  void need_cr(const Tok& k, Ty want) {
    if (cr == Ty::None)
      fail(k, "'" + k.text + "' needs a current result: after a label, a jump, a call or at the start, begin with LD");
    if (want == Ty::Bool && cr != Ty::Bool) fail(k, "'" + k.text + "' needs a BOOL current result, this one is " + (cr == Ty::Real ? "REAL" : "INT"));
    if (want == Ty::Int && cr == Ty::Bool) fail(k, "'" + k.text + "' needs an INT or REAL current result, this one is BOOL");
  }

  // line = [ NAME ":" ] [ instruction ] EOL
  void line() {
    if (peek().kind == Tok::Eol) { next(); return; }
    const Tok& first = peek();
    if (first.kind == Tok::Word && is_punct(t[pos + 1], ":")) {
      label(first);
      pos += 2;
      if (peek().kind == Tok::Eol || peek().kind == Tok::End) { end_line(); return; }
    }
    const Tok& op = next();
    if (op.kind == Tok::Punct && op.text == ")") {
      here = {op.line, op.col};
      close_paren(op);
      end_line();
      return;
    }
    if (op.kind != Tok::Word) fail(op, "expected an IL operator" + found(op));
    here = {op.line, op.col};
    instruction(op);
    end_line();
  }

  void label(const Tok& k) {
    if (!is_ident(k.text)) fail(k, "bad label name '" + k.text + "'");
    if (!parens.empty()) fail(k, "a label inside parentheses");
    for (auto& l : labels_seen)
      if (l == k.text) fail(k, "duplicate label '" + k.text + "'");
    labels_seen.push_back(k.text);
    pending_labels.push_back(k.text);
    rung = nullptr;
    cr = Ty::None;  // the current result is undefined at a label
  }

  void instruction(const Tok& op) {
    std::string u = upper(op.text);
    bool paren = false;
    if (is_punct(peek(), "(") && u != "CAL") {
      paren = true;
      next();
    }
    static const std::set<std::string> needs_operand = {"LD", "LDN", "ST", "STN", "S", "R", "AND", "ANDN", "OR", "ORN", "XOR",
                                                        "XORN", "ADD", "SUB", "MUL", "DIV", "MOD", "GT", "GE", "EQ", "NE",
                                                        "LT", "LE", "JMP", "JMPC", "JMPCN", "SHL", "SHR", "CAL"};
    static const std::set<std::string> no_operand = {"NOT", "RET", "RETC", "RETCN", "SIN", "COS", "TAN", "SQRT", "EXP",
                                                     "LN", "ABS", "MOVE"};
    if (!needs_operand.count(u) && !no_operand.count(u)) {
      static const std::set<std::string> ldc_ops = {"LOAD", "LOADN", "OUT", "OUTN", "SET", "RST", "ANDBLK", "ORBLK", "MPS", "MRD", "MPP"};
      fail(op, "unknown IL operator '" + op.text + "'" +
                   (ldc_ops.count(u) ? std::string(" (this file is read as IEC IL; ldc's own IL starts with a '.rung' line)") : ""));
    }
    if (paren) {
      if (u != "AND" && u != "ANDN" && u != "OR" && u != "ORN" && u != "XOR" && u != "XORN")
        fail(op, "'" + op.text + "(' is not supported: only AND( ANDN( OR( ORN( XOR( XORN( open parentheses");
      open_paren(op, u);
      return;
    }
    if (no_operand.count(u)) {
      if (peek().kind == Tok::Word) fail(peek(), "'" + op.text + "' takes no operand");
      return simple(op, u);
    }
    if (peek().kind != Tok::Word) fail(peek(), "'" + op.text + "' needs an operand" + found(peek()));
    const Tok& k = next();
    if (u == "CAL") return call(op, k);
    if (u == "JMP" || u == "JMPC" || u == "JMPCN") return jump(op, u, k);
    Val v = operand(k);
    if (u == "LD" || u == "LDN") return load(op, u == "LDN", v, k);
    if (u == "ST" || u == "STN") return store(op, u == "STN", v, k);
    if (u == "S" || u == "R") return set_reset(op, u == "S", v, k);
    need_cr(op, Ty::None);
    if (cr == Ty::Bool) {
      if (u == "AND" || u == "ANDN" || u == "OR" || u == "ORN") {
        Operand b = bit_of(v, k, op.text.c_str());
        return emit(u == "AND" ? Op::AND : u == "ANDN" ? Op::ANDN : u == "OR" ? Op::OR : Op::ORN, b);
      }
      if (u == "XOR" || u == "XORN") return xor_top(bit_of(v, k, op.text.c_str()), u == "XORN");
      fail(op, "'" + op.text + "' needs an INT or REAL current result, this one is BOOL");
    }
    word_op(op, u, value_of(v, k, op.text.c_str()), k);
  }

  // LD / LDN: a new rung (or the start of a parenthesised expression)
  void load(const Tok& op, bool neg, const Val& v, const Tok& k) {
    if (parens.empty() || cr != Ty::None) {
      if (!parens.empty()) fail(op, "LD inside parentheses: write it after the opening operator (AND( x)");
      start_rung(here);
    }
    push_value(op, neg, v, k);
  }
  void push_value(const Tok& op, bool neg, const Val& v, const Tok& k) {
    if (v.kind == Val::BoolLit) {
      if (v.flag != neg) emit(Op::TRUE);
      else emit(Op::LDNE, Operand{OpdKind::ConstInt}, Operand{OpdKind::ConstInt});  // FALSE: 0 <> 0
      cr = Ty::Bool;
    } else if (v.kind == Val::Bit) {
      emit(neg ? Op::LOADN : Op::LOAD, v.o);
      cr = Ty::Bool;
    } else if (v.kind == Val::Word) {
      if (neg) fail(op, "LDN needs a BOOL operand; for a bitwise NOT write LD " + k.text + " then NOT");
      emit(Op::TRUE);  // the gate of the word instructions that follow
      cr = v.real() ? Ty::Real : Ty::Int;
      cur = v.o;
      cur_is_acc = false;
    } else {
      fail(k, "'" + k.text + "' is a function block instance: load one of its outputs (" + k.text + ".Q)");
    }
  }

  void store(const Tok& op, bool neg, const Val& v, const Tok& k) {
    need_cr(op, Ty::None);
    if (cr == Ty::Bool) return emit(neg ? Op::OUTN : Op::OUT, writable_bit(v, k, op.text.c_str()));
    if (neg) fail(op, "STN needs a BOOL current result");
    Operand d = value_of(v, k, "ST");
    if (d.kind == OpdKind::ConstInt || d.kind == OpdKind::ConstReal || !operand_area_ok('d', d.area, d.index))
      fail(k, "'" + k.text + "' cannot be written (an input or a constant)");
    Instr& last = rung->code.back();
    if (cur_is_acc && last.nopd() && last.a[last.nopd() - 1] == cur) {
      last.a[last.nopd() - 1] = d;  // the operation writes the variable directly
    } else {
      emit(Op::MOV, cur, d);
    }
    cur = d;
    cur_is_acc = false;
    cr = d.is_real() ? Ty::Real : Ty::Int;
  }

  void set_reset(const Tok& op, bool set, const Val& v, const Tok& k) {
    need_cr(op, Ty::Bool);
    if (v.kind == Val::Inst) {
      if (set) fail(k, "S on a function block instance: only R (reset) is supported");
      const Instance& in = insts[v.inst];
      if (in.trig()) fail(k, "R on an " + in.type + " instance: only timers and counters are reset");
      return emit(in.timer() ? Op::RSTT : Op::RSTC, in.timer() ? Operand{OpdKind::Timer, Area::Sys, in.index}
                                                               : Operand{OpdKind::Counter, Area::Sys, in.index});
    }
    emit(set ? Op::SET : Op::RST, writable_bit(v, k, op.text.c_str()));
  }

  void word_op(const Tok& op, const std::string& u, Operand b, const Tok& k) {
    static const std::map<std::string, Op> arith = {{"ADD", Op::ADD}, {"SUB", Op::SUB}, {"MUL", Op::MUL}, {"DIV", Op::DIV},
                                                    {"MOD", Op::MOD}, {"AND", Op::WAND}, {"OR", Op::WOR}, {"XOR", Op::WXOR},
                                                    {"SHL", Op::SHL}, {"SHR", Op::SHR}};
    static const std::map<std::string, Op> cmp = {{"GT", Op::LDGT}, {"GE", Op::LDGE}, {"EQ", Op::LDEQ},
                                                  {"NE", Op::LDNE}, {"LT", Op::LDLT}, {"LE", Op::LDLE}};
    if (auto c = cmp.find(u); c != cmp.end()) {
      emit(c->second, cur, b);
      emit(Op::ANDBLK);  // the compare replaces the gate below it
      cr = Ty::Bool;
      return;
    }
    auto a = arith.find(u);
    if (a == arith.end()) fail(op, "'" + op.text + "' needs a BOOL current result, this one is " + (cr == Ty::Real ? "REAL" : "INT"));
    const char* sig = op_info(a->second).operands;
    bool real = cur.is_real() || b.is_real();
    if (sig[0] == 'i' && real) fail(k, "'" + op.text + "' works on INT values only");
    Operand d = acc(real);
    emit(a->second, cur, b, d);
    cur = d;
    cur_is_acc = true;
    cr = real ? Ty::Real : Ty::Int;
  }

  void simple(const Tok& op, const std::string& u) {
    if (u == "RET") {
      start_rung(here);
      emit(Op::TRUE);
      emit(Op::END);
      rung = nullptr;
      cr = Ty::None;
      return;
    }
    need_cr(op, u == "NOT" || u == "MOVE" ? Ty::None : u.rfind("RET", 0) == 0 ? Ty::Bool : Ty::Int);
    if (u == "RETC") return emit(Op::END);
    if (u == "RETCN") {
      Operand h = hidden_bit(0);
      emit(Op::OUTN, h);
      emit(Op::LOAD, h);
      emit(Op::END);
      return emit(Op::MPP);
    }
    if (u == "MOVE") return;
    if (u == "NOT" && cr == Ty::Bool) return negate_top();
    Op f = u == "NOT" ? Op::WNOT : u == "SIN" ? Op::SIN : u == "COS" ? Op::COS : u == "TAN" ? Op::TAN : u == "SQRT" ? Op::SQRT
         : u == "EXP" ? Op::EXP : u == "LN" ? Op::LN : Op::ABS;
    bool real = f == Op::ABS ? cur.is_real() : f != Op::WNOT;
    if (f == Op::WNOT && cur.is_real()) fail(op, "NOT works on BOOL or INT values only");
    Operand d = acc(real);
    emit(f, cur, d);
    cur = d;
    cur_is_acc = true;
    cr = real ? Ty::Real : Ty::Int;
  }

  void open_paren(const Tok& op, const std::string& u) {
    need_cr(op, Ty::Bool);
    if (int(parens.size()) >= kMaxParens) fail(op, "parentheses nested deeper than " + std::to_string(kMaxParens));
    parens.push_back({u, cr, cur, cur_is_acc, here});
    cr = Ty::None;
    if (peek().kind == Tok::Word) {
      const Tok& k = next();
      push_value(op, false, operand(k), k);
    } else {
      // "AND(" alone: the next line is LD x or LDN x
      end_line();
      while (peek().kind == Tok::Eol) next();
      const Tok& ld = next();
      if (!is_kw(ld, "LD") && !is_kw(ld, "LDN")) fail(ld, "after '" + op.text + "(' comes its first operand, or LD/LDN on the next line");
      here = {ld.line, ld.col};
      if (peek().kind != Tok::Word) fail(peek(), "'" + ld.text + "' needs an operand" + found(peek()));
      const Tok& k = next();
      push_value(ld, is_kw(ld, "LDN"), operand(k), k);
    }
  }

  void close_paren(const Tok& k) {
    if (parens.empty()) fail(k, "')' without '('");
    need_cr(k, Ty::Bool);
    Paren pr = parens.back();
    parens.pop_back();
    if (pr.op == "AND") emit(Op::ANDBLK);
    else if (pr.op == "OR") emit(Op::ORBLK);
    else {
      Operand h = hidden_bit(0);
      bool n = pr.op == "ANDN" || pr.op == "ORN";
      emit(n ? Op::OUTN : Op::OUT, h);
      emit(Op::MPP);
      if (pr.op == "ANDN") emit(Op::AND, h);
      else if (pr.op == "ORN") emit(Op::OR, h);
      else xor_top(h, pr.op == "XORN");
    }
    cr = Ty::Bool;
    cur = pr.cur, cur_is_acc = pr.cur_is_acc;
  }

  void jump(const Tok& op, const std::string& u, const Tok& k) {
    if (!is_ident(k.text)) fail(k, "expected a label name, found '" + k.text + "'");
    if (!parens.empty()) fail(op, "a jump inside parentheses");
    auto target = [&] { Operand l{OpdKind::Label}; l.label = k.text; return l; };
    // to a label already seen: a loop, the IL's LOOP (docs/il.md "Loops": each
    // back edge counts against the scan's budget)
    const bool back = std::find(labels_seen.begin(), labels_seen.end(), k.text) != labels_seen.end();
    const Op jop = back ? Op::LOOP : Op::JMP;
    jumps.push_back({k.text, here, 0});
    if (u == "JMP") {
      start_rung(here);
      emit(Op::TRUE);
      emit(jop, target());
      rung = nullptr;
      cr = Ty::None;  // undefined after an unconditional jump
    } else {
      need_cr(op, Ty::Bool);
      if (u == "JMPC") {
        emit(jop, target());
      } else {
        Operand h = hidden_bit(0);
        emit(Op::OUTN, h);
        emit(Op::LOAD, h);
        emit(jop, target());
        emit(Op::MPP);
      }
    }
    jumps.back().rung = p.rungs.size() - 1;
    if (back) jumps.pop_back();  // checked: its label comes before it
  }

  // CAL inst(IN := x, PT := y)  /  CAL inst(CU := x, R := y, PV := z)  /  CAL inst(CD := x, LD := y, PV := z)
  void call(const Tok& op, const Tok& k) {
    if (!parens.empty()) fail(op, "CAL inside parentheses");
    auto it = inst_of.find(upper(k.text));
    if (it == inst_of.end() && rec && (refused.count(upper(k.text)) || !unknown.insert(upper(k.text)).second))
      throw iecil::Quiet(k.line, k.col, "unknown instance again");
    if (it == inst_of.end()) fail(k, "'" + k.text + "' is not a declared TON, TOF, TP, CTU, CTD, R_TRIG or F_TRIG instance");
    const Instance in = insts[it->second];
    std::map<std::string, std::pair<Val, Tok>> args;
    if (!is_punct(peek(), "(")) fail(peek(), "expected '(' and the parameters of " + in.type + found(peek()));
    next();
    while (!is_punct(peek(), ")")) {
      const Tok& name = next();
      std::string pn = upper(name.text);
      bool ok = in.trig() ? pn == "CLK"
                : in.timer() ? (pn == "IN" || pn == "PT")
                             : (pn == "PV" || (in.type == "CTU" ? (pn == "CU" || pn == "R") : (pn == "CD" || pn == "LD")));
      if (name.kind != Tok::Word || !ok)
        fail(name, in.type + " has no input '" + name.text + "' (" +
                       (in.trig() ? "CLK" : in.timer() ? "IN, PT" : in.type == "CTU" ? "CU, R, PV" : "CD, LD, PV") + ")");
      if (args.count(pn)) fail(name, "second value for " + pn);
      expect_punct(":=");
      const Tok& vt = next();
      Val v = operand(vt);
      args.emplace(pn, std::make_pair(v, vt));
      if (is_punct(peek(), ",")) next();
      else if (!is_punct(peek(), ")")) fail(peek(), "expected ',' or ')'" + found(peek()));
    }
    next();
    // the current result survives the call: its rungs push and pop their own
    bool keep = cr != Ty::None;
    auto bit_arg = [&](const std::string& n) -> std::optional<Val> {
      auto a = args.find(n);
      if (a == args.end()) return std::nullopt;
      if (a->second.first.kind != Val::Bit && a->second.first.kind != Val::BoolLit)
        fail(a->second.second, n + " needs a BOOL value, '" + a->second.second.text + "' is not one");
      return a->second.first;
    };
    auto int_arg = [&](const std::string& n) -> Operand {
      auto a = args.find(n);
      if (a == args.end()) fail(k, "CAL of " + in.type + " '" + in.name + "' needs " + n + " :=");
      if (a->second.first.kind != Val::Word || a->second.first.real())
        fail(a->second.second, n + " needs an INT or TIME value, '" + a->second.second.text + "' is not one");
      return a->second.first.o;
    };
    auto push_bit = [&](const Val& v) {
      if (!keep) start_rung(here);
      if (v.kind == Val::BoolLit) {
        if (v.flag) emit(Op::TRUE);
        else emit(Op::LDNE, Operand{OpdKind::ConstInt}, Operand{OpdKind::ConstInt});
      } else {
        emit(Op::LOAD, v.o);
      }
    };
    auto done = [&] {
      if (keep) emit(Op::MPP);
      else rung = nullptr;
    };
    // R_TRIG: Q := CLK AND NOT M, M := CLK (M FALSE at first): LOADP CLK.
    // F_TRIG: Q := NOT CLK AND NOT M, M := NOT CLK with M TRUE at first, as
    // the library OpenPLC ships has it (no pulse on the first scan): LOADF
    // CLK, whose memory holds CLK (NOT M), FALSE at first.
    if (in.trig()) {
      auto clk = bit_arg("CLK");
      if (!clk) fail(k, "CAL of " + in.type + " '" + in.name + "' needs CLK :=");
      if (clk->kind == Val::BoolLit) fail(args["CLK"].second, "CLK needs a BOOL variable");
      if (!keep) start_rung(here);
      Operand q{OpdKind::Bit, Area::M, in.index};
      emit(in.type == "F_TRIG" ? Op::LOADF : Op::LOADP, clk->o, Operand{OpdKind::Edge});
      emit(Op::OUT, q);
      done();
      return;
    }
    if (in.timer()) {
      auto inb = bit_arg("IN");
      if (!inb) fail(k, "CAL of " + in.type + " '" + in.name + "' needs IN :=");
      Operand pt = int_arg("PT");
      push_bit(*inb);
      emit(in.type == "TON" ? Op::TON : in.type == "TOF" ? Op::TOF : Op::TP, Operand{OpdKind::Timer, Area::Sys, in.index}, pt);
      done();
      return;
    }
    Operand c{OpdKind::Counter, Area::Sys, in.index};
    bool up = in.type == "CTU";
    auto cnt = bit_arg(up ? "CU" : "CD");
    auto rst = bit_arg(up ? "R" : "LD");
    if (rst) {  // R resets (LD loads PV) before counting, as IEC's CTU/CTD
      push_bit(*rst);
      if (up) emit(Op::RSTC, c);
      else emit(Op::MOV, int_arg("PV"), Operand{OpdKind::Int, Area::CW, in.index});
      done();
    }
    if (cnt) {
      Operand pv = int_arg("PV");
      if (rst) {  // count a rising edge of CU while R is off
        if (!keep) start_rung(here);
        if (cnt->kind == Val::BoolLit) fail(args[up ? "CU" : "CD"].second, "a counter input needs a BOOL variable");
        emit(Op::LOADP, cnt->o, Operand{OpdKind::Edge});
        if (rst->kind == Val::BoolLit) {
          if (rst->flag) emit(Op::AND, cnt->o), emit(Op::ANDN, cnt->o);  // R := TRUE: never counts
        } else {
          emit(Op::ANDN, rst->o);
        }
      } else {
        push_bit(*cnt);
      }
      emit(up ? Op::CTU : Op::CTD, c, pv, Operand{OpdKind::Edge});
      done();
    }
    if (!cnt && !rst) fail(k, "CAL of " + in.type + " '" + in.name + "' needs " + (up ? "CU or R" : "CD or LD"));
  }

  // ---- the end: labels, jumps, hidden devices

  void finish() {
    if (!parens.empty()) fail(parens.back().loc, "'(' is never closed");
    p.end_labels = std::move(pending_labels);
    std::map<std::string, size_t> where;  // label -> index of the rung it precedes
    for (size_t r = 0; r < p.rungs.size(); r++)
      for (auto& l : p.rungs[r].labels) where[l] = r;
    for (auto& l : p.end_labels) where[l] = p.rungs.size();
    for (const Jump& j : jumps) {
      auto w = where.find(j.label);
      if (w == where.end()) fail(j.loc, "undefined label '" + j.label + "'");
      if (w->second <= j.rung)  // cannot be: a jump to a label seen before it is a LOOP
        fail(j.loc, "backward jump to '" + j.label + "'");
    }
    if (p.rungs.empty()) {
      const Tok* last = &t.front();
      for (const Tok& k : t)
        if (k.kind == Tok::Word) last = &k;
      fail(*last, "the program has no instructions");
    }
    // hidden and unlocated devices: the lowest indices no explicit operand uses
    std::vector<uint32_t> real(virt.size());
    uint32_t next[int(Dev::F) + 1] = {};
    for (size_t i = 0; i < virt.size(); i++) {
      int d = int(virt[i]);
      while (used[d].count(next[d])) next[d]++;
      if (next[d] >= device_count(virt[i]))
        throw CompileError(1, 1, std::string("no free ") + dev_name(virt[i]) + " device left for the program's variables");
      real[i] = next[d]++;
    }
    auto fix = [&](uint32_t& idx) {
      if (idx >= kVirtual) idx = real[idx - kVirtual];
    };
    for (Rung& r : p.rungs)
      for (Instr& in : r.code)
        for (int i = 0; i < in.nopd(); i++)
          if (in.a[i].kind != OpdKind::ConstInt && in.a[i].kind != OpdKind::Edge && in.a[i].kind != OpdKind::Label) fix(in.a[i].index);
    for (Alias& a : p.aliases) fix(a.dev.index);
  }
};

}  // namespace

bool looks_like_ldc_il(std::string_view text) {
  size_t i = 0;
  while (i < text.size()) {
    char c = text[i];
    if (c == ' ' || c == '\t' || c == '\r' || c == '\n') { i++; continue; }
    if (c == ';') {  // an ldc IL comment line
      while (i < text.size() && text[i] != '\n') i++;
      continue;
    }
    return c == '.';
  }
  return false;
}

Program parse_iec_il(std::string_view text, const std::string& filename) {
  if (text.size() > kMaxSourceBytes) throw CompileError(1, 1, "source larger than " + std::to_string(kMaxSourceBytes >> 20) + " MiB");
  std::vector<Tok> toks = lex(text);
  if (iecil::needs_typed_reader(toks)) return iecil::parse_typed_il(toks, filename);
  Reader r;
  r.p.source = filename;
  r.t = std::move(toks);
  r.program();
  return std::move(r.p);
}

Program parse_iec_il(std::string_view text, const std::string& filename, Diagnostics& diag) {
  if (text.size() > kMaxSourceBytes) throw CompileError(1, 1, "source larger than " + std::to_string(kMaxSourceBytes >> 20) + " MiB");
  diag.source(filename, text);
  iecil::Recovery rec(diag, filename);
  std::vector<Tok> toks = lex(text);
  if (iecil::needs_typed_reader(toks)) return iecil::parse_typed_il(toks, filename, false, rec);
  Reader r;
  r.p.source = filename;
  r.t = std::move(toks);
  r.rec = &rec;
  try {
    r.program();
  } catch (const CompileError& e) {  // the file's structure: the reader stops
    if (!rec.failed()) throw;
    rec.report(e);  // after errors reported: it is one more of them
  }
  rec.check();
  return std::move(r.p);
}

// ---------------------------------------------------------------- writer

namespace {

struct Writer {
  const Program& p;
  std::string body;
  std::map<std::pair<int, uint32_t>, std::string> names;  // (area, index) -> alias used in operands
  std::map<uint32_t, std::string> timer_type, counter_type;
  std::set<std::string> temps;  // hidden BOOL variables
  int labels = 0;
  const Rung* rung = nullptr;
  const Instr* instr = nullptr;

  explicit Writer(const Program& prog) : p(prog) {}

  [[noreturn]] void fail(const std::string& m) const {
    std::string at = "rung line " + std::to_string(rung ? rung->line : 0);
    if (instr) at += ", instruction '" + instr_text(*instr) + "'";
    throw std::runtime_error(p.source + ": " + at + ": " + m);
  }

  void line(const std::string& s) {
    std::string l = "    " + s + "\n";
    if (s.rfind("ST ", 0) == 0 && body.size() >= l.size() && body.compare(body.size() - l.size(), l.size(), l) == 0) return;
    body += l;  // (a store repeated at once is dropped)
  }
  std::string temp(const char* kind, uint32_t n) {
    std::string t = std::string("_ldc_") + kind + std::to_string(n);
    temps.insert(t);
    return t;
  }
  std::string s(int pos) { return temp("s", uint32_t(pos)); }

  std::string opd(const Operand& o) {
    switch (o.kind) {
      case OpdKind::ConstInt: return std::to_string(o.ival);
      case OpdKind::ConstReal:
        if (!std::isfinite(o.fval)) fail("a non-finite REAL constant has no IEC IL spelling");
        return real_text(o.fval);
      case OpdKind::Timer: note_timer(o.index, nullptr); return inst_name('T', o.index);
      case OpdKind::Counter: note_counter(o.index, nullptr); return inst_name('C', o.index);
      case OpdKind::Bit: case OpdKind::Int: case OpdKind::Real: break;
      default: fail("operand '" + operand_text(o) + "' has no IEC IL spelling");
    }
    if (auto it = names.find({int(o.area), o.index}); it != names.end()) return it->second;
    std::string n = std::to_string(o.index);
    auto bit = [&](const char* r) { return std::string("%") + r + "X" + std::to_string(o.index / 8) + "." + std::to_string(o.index % 8); };
    switch (o.area) {
      case Area::X: return bit("I");
      case Area::Y: return bit("Q");
      case Area::M: return bit("M");
      case Area::K: return "K" + n;
      case Area::S: return "S" + n;
      case Area::WX: return "%IW" + n;
      case Area::WY: return "%QW" + n;
      case Area::D: return "%MW" + n;
      case Area::F: return "%MD" + n;
      case Area::TQ: note_timer(o.index, nullptr); return inst_name('T', o.index) + ".Q";
      case Area::TW: note_timer(o.index, nullptr); return inst_name('T', o.index) + ".ET";
      case Area::CQ: note_counter(o.index, nullptr); return inst_name('C', o.index) + ".Q";
      case Area::CW: note_counter(o.index, nullptr); return inst_name('C', o.index) + ".CV";
      default: fail("operand '" + operand_text(o) + "' has no IEC IL spelling");
    }
  }
  std::map<std::pair<char, uint32_t>, std::string> inst_alias;  // a timer's or counter's first alias
  std::string inst_name(char kind, uint32_t i) {
    auto it = inst_alias.find({kind, i});
    return it != inst_alias.end() ? it->second : kind + std::to_string(i);
  }
  std::set<std::pair<char, uint32_t>> typed;  // instances whose type a call fixed
  void note(std::map<uint32_t, std::string>& m, char kind, uint32_t i, const char* type, const char* dflt) {
    if (!type) {
      m.emplace(i, dflt);
      return;
    }
    if (typed.count({kind, i}) && m[i] != type)
      fail(std::string(kind == 'T' ? "timer T" : "counter C") + std::to_string(i) + " is used both as " + m[i] +
           " and as " + type + ": an IEC instance has one type");
    m[i] = type;
    typed.insert({kind, i});
  }
  void note_timer(uint32_t i, const char* type) { note(timer_type, 'T', i, type, "TON"); }
  void note_counter(uint32_t i, const char* type) { note(counter_type, 'C', i, type, "CTU"); }

  // Does the push at code[i] (depth d >= 1) start a group of pure bit logic that a
  // later ANDBLK/ORBLK closes?  Returns the index of that BLK, or 0.
  size_t pure_group(size_t i) const {
    int rel = 0, max_rel = 0;
    for (size_t j = i; j < rung->code.size(); j++) {
      Op op = rung->code[j].op;
      if (op == Op::LOAD || op == Op::LOADN) rel++;
      else if (op == Op::ANDBLK || op == Op::ORBLK) rel--;
      else if (op != Op::AND && op != Op::ANDN && op != Op::OR && op != Op::ORN) return 0;
      max_rel = std::max(max_rel, rel);
      if (rel == 0) return max_rel <= kMaxParens ? j : 0;
    }
    return 0;
  }
  void group(size_t i, size_t end) {
    const Instr& first = rung->code[i];
    const char* opener = rung->code[end].op == Op::ANDBLK ? "AND(" : "OR(";
    if (first.op == Op::LOAD) line(std::string(opener) + " " + opd(first.a[0]));
    else line(opener), line("LDN " + opd(first.a[0]));
    for (size_t k = i + 1; k < end; k++) {
      const Instr& in = rung->code[k];
      if (in.op == Op::LOAD || in.op == Op::LOADN) {
        size_t m = pure_group(k);
        group(k, m);
        k = m;
      } else {
        line(std::string(op_info(in.op).name) + " " + opd(in.a[0]));
      }
    }
    line(")");
  }

  void write_rung(const Rung& r) {
    rung = &r;
    instr = nullptr;
    for (const auto& l : r.labels) body += l + ":\n";
    body += "(* rung line " + std::to_string(r.line) + (r.title.empty() ? "" : " \"" + sanitize(r.title) + "\"") + " *)\n";
    int d = 0;
    auto need = [&](int n) {
      if (d < n) fail("the bit stack holds " + std::to_string(d) + " entries, this instruction needs " + std::to_string(n));
    };
    for (size_t i = 0; i < r.code.size(); i++) {
      const Instr& in = r.code[i];
      instr = &in;
      const OpInfo& oi = op_info(in.op);
      if (oi.push) {
        if (d >= 1) {
          if (in.op == Op::LOAD || in.op == Op::LOADN) {
            if (size_t end = pure_group(i)) {
              group(i, end);
              i = end;
              continue;
            }
          }
          line("ST " + s(d - 1));
        }
        push(in, d);
        d++;
        continue;
      }
      switch (in.op) {
        case Op::AND: case Op::ANDN: case Op::OR: case Op::ORN:
          need(1);
          line(std::string(oi.name) + " " + opd(in.a[0]));
          break;
        case Op::ANDBLK: case Op::ORBLK:
          need(2);
          line(std::string(in.op == Op::ANDBLK ? "AND " : "OR ") + s(d - 2));
          d--;
          break;
        case Op::MRD: need(2); line("LD " + s(d - 2)); break;
        case Op::MPP: need(2); line("LD " + s(d - 2)); d--; break;
        case Op::OUT: need(1); line("ST " + opd(in.a[0])); break;
        case Op::OUTN: need(1); line("STN " + opd(in.a[0])); break;
        case Op::SET: need(1); line("S " + opd(in.a[0])); break;
        case Op::RST: need(1); line("R " + opd(in.a[0])); break;
        case Op::RSTT: case Op::RSTC: need(1); line("R " + opd(in.a[0])); break;
        case Op::JMP: case Op::LOOP: need(1); line("JMPC " + in.a[0].label.str()); break;  // back to a label before: a LOOP again
        case Op::END: need(1); line("RETC"); break;
        case Op::TON: case Op::TOF: case Op::TP: {
          need(1);
          note_timer(in.a[0].index, oi.name);
          line("ST " + s(d - 1));
          line("CAL " + opd(in.a[0]) + "(IN := " + s(d - 1) + ", PT := " + opd(in.a[1]) + ")");
          break;
        }
        case Op::CTU: case Op::CTD: {
          need(1);
          note_counter(in.a[0].index, oi.name);
          line("ST " + s(d - 1));
          line("CAL " + opd(in.a[0]) + "(" + (in.op == Op::CTU ? "CU" : "CD") + " := " + s(d - 1) + ", PV := " + opd(in.a[1]) + ")");
          break;
        }
        default: {  // an application instruction: skipped unless the top is on
          need(1);
          std::string skip = "_ldc_L" + std::to_string(labels++);
          line("ST " + s(d - 1));
          line("JMPCN " + skip);
          line("LD " + opd(in.a[0]));
          static const std::map<Op, const char*> fn = {
              {Op::ADD, "ADD"}, {Op::SUB, "SUB"}, {Op::MUL, "MUL"}, {Op::DIV, "DIV"}, {Op::MOD, "MOD"},
              {Op::WAND, "AND"}, {Op::WOR, "OR"}, {Op::WXOR, "XOR"}, {Op::SHL, "SHL"}, {Op::SHR, "SHR"},
              {Op::WNOT, "NOT"}, {Op::SIN, "SIN"}, {Op::COS, "COS"}, {Op::TAN, "TAN"}, {Op::SQRT, "SQRT"},
              {Op::EXP, "EXP"}, {Op::LN, "LN"}, {Op::ABS, "ABS"}};
          if (in.op != Op::MOV) {
            auto f = fn.find(in.op);
            if (f == fn.end()) fail("no IEC IL equivalent");
            line(in.nopd() == 3 ? std::string(f->second) + " " + opd(in.a[1]) : std::string(f->second));
          }
          line("ST " + opd(in.a[in.nopd() - 1]));
          body += skip + ":\n";
          line("LD " + s(d - 1));
          break;
        }
      }
    }
  }

  // a push at depth d (the entries below are saved in temporaries)
  void push(const Instr& in, int d) {
    switch (in.op) {
      case Op::LOAD: return line("LD " + opd(in.a[0]));
      case Op::LOADN: return line("LDN " + opd(in.a[0]));
      case Op::TRUE: return line("LD TRUE");
      case Op::LOADP: case Op::LOADF: {  // the previous value in a BOOL of its own, FALSE at first
        std::string e = temp("e", in.a[1].index), b = opd(in.a[0]);
        line((in.op == Op::LOADP ? "LD " : "LDN ") + b);
        line((in.op == Op::LOADP ? "ANDN " : "AND ") + e);
        line("ST " + s(d));
        line("LD " + b);
        line("ST " + e);
        return line("LD " + s(d));
      }
      case Op::MPS: return line("ST " + s(d - 1));  // the copy is the current result
      default: break;
    }
    static const std::map<Op, const char*> cmp = {{Op::LDEQ, "EQ"}, {Op::LDNE, "NE"}, {Op::LDLT, "LT"},
                                                  {Op::LDLE, "LE"}, {Op::LDGT, "GT"}, {Op::LDGE, "GE"}};
    auto c = cmp.find(in.op);
    if (c == cmp.end()) fail("no IEC IL equivalent");
    line("LD " + opd(in.a[0]));
    line(std::string(c->second) + " " + opd(in.a[1]));
  }

  static std::string sanitize(const std::string& t) {
    std::string o;
    for (size_t i = 0; i < t.size(); i++) {
      if (t[i] == '\n' || t[i] == '\r') o += ' ';
      else if (t[i] == '*' && i + 1 < t.size() && t[i + 1] == ')') o += "* ";
      else if (t[i] == '(' && i + 1 < t.size() && t[i + 1] == '*') o += "( ";
      else o += t[i];
    }
    return o;
  }

  std::string run() {
    // aliases: variables at their devices (the first name of a device names its operands)
    std::string vars;
    std::set<std::string> taken;
    for (const Alias& a : p.aliases) {
      std::string u = upper(a.name);
      if ((a.dev.dev == Dev::T || a.dev.dev == Dev::C) && !taken.count(u) && a.dev.index < device_count(a.dev.dev) &&
          inst_alias.emplace(std::make_pair(dev_name(a.dev.dev)[0], a.dev.index), a.name).second) {
        taken.insert(u);  // the instance is declared with this name, located at its device
        continue;
      }
      // a member's or an element's alias (p.x, v[2], of the typed reader) is no IEC name
      bool ident = std::all_of(a.name.begin(), a.name.end(), [](char c) { return std::isalnum((unsigned char)c) || c == '_'; });
      if (!ident || taken.count(u) || a.dev.dev == Dev::T || a.dev.dev == Dev::C || a.dev.index >= device_count(a.dev.dev)) {
        vars += "    (* " + a.name + " = " + dev_name(a.dev.dev) + std::to_string(a.dev.index) + ": no IEC declaration *)\n";
        continue;
      }
      taken.insert(u);
      Area bit = bit_area(a.dev.dev), word = word_area(a.dev.dev);
      Operand o{bit != Area::Count ? OpdKind::Bit : OpdKind::Int, bit != Area::Count ? bit : word, a.dev.index};
      std::string loc = opd(o);
      if (loc[0] != '%') loc = std::string(dev_name(a.dev.dev)) + std::to_string(a.dev.index);
      const char* type = bit != Area::Count ? "BOOL" : word == Area::F ? "REAL" : "DINT";
      vars += "    " + a.name + " AT " + loc + " : " + type + ";\n";
      names.emplace(std::make_pair(int(o.area), o.index), a.name);
    }
    for (const Rung& r : p.rungs) write_rung(r);
    rung = nullptr, instr = nullptr;
    for (const auto& l : p.end_labels) body += l + ":\n";
    auto instance = [&](char kind, uint32_t i, const std::string& ty) {
      std::string n = inst_name(kind, i), dev = kind + std::to_string(i);
      vars += "    " + n + (n == dev ? "" : " AT " + dev) + " : " + ty + ";\n";
    };
    for (const auto& [i, ty] : timer_type) instance('T', i, ty);
    for (const auto& [i, ty] : counter_type) instance('C', i, ty);
    for (const auto& t : temps)
      if (taken.count(upper(t))) fail("the name " + t + " is needed for a temporary");
    for (const auto& t : temps) vars += "    " + t + " : BOOL;\n";
    std::string out = "(* IEC 61131-3 IL written by ldc from " + sanitize(p.source) + " *)\nPROGRAM main\n";
    if (!vars.empty()) out += "VAR\n" + vars + "END_VAR\n";
    return out + body + "END_PROGRAM\n";
  }
};

}  // namespace

std::string print_iec_il(const Program& p) { return Writer(p).run(); }

}  // namespace ldc
