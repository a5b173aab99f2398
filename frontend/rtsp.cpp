// frontend/rtsp.cpp -- the RTSP language of paper 000 (docs/rtsp.md): a C-like
// preprocessor (#define, #undef, #ifdef, #ifndef, #if, #elif, #else, #endif,
// C comments), then
//
//   program    = { "init" action | if_stmt | action } ;
//   if_stmt    = ( "if" | "ifbecome" ) condition "then" { stmt } [ "else" { stmt } ] "fi" ;
//   stmt       = if_stmt | action ;
//   condition  = COND_FUNC "(" item { "," data } ")" ;
//   action     = ACTION_FUNC "(" item { "," data } ")" ";" ;
//   data       = item | expr ;                 (an expression of constants)
//   expr       = xor { "|" xor } ;   xor = and { "^" and } ;   and = sum { "&" sum } ;
//   sum        = term { ("+" | "-") term } ;   term = unary { ("*" | "/") unary } ;
//   unary      = ("-" | "~" | "+") unary | NUMBER | "bit0".."bit31" | "(" expr ")" ;
//
// Each statement becomes rung trees over ldc devices; an if's condition is
// kept in a hidden M bit, so its branches see the value it had at the if.
#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <cstdlib>
#include <functional>
#include <map>
#include <set>

#include "frontend/diag.h"
#include "frontend/frontend.h"
#include "frontend/treebuild.h"

namespace ldc {
namespace {

using namespace treebuild;

constexpr int kMaxNesting = 64;           // if statements, #if groups, expression depth, macro depth
constexpr size_t kMaxTokens = 1u << 22;   // tokens after macro expansion

// ---- where the data groups live (docs/rtsp.md)
constexpr uint32_t kGroupSize[] = {256, 256, 2048, 4096, 1024, 256};  // D A B I F T
constexpr const char kGroups[] = "DABIFT";
constexpr uint32_t kBBase = 4096, kABase = 6144, kTimeoutBase = 6400, kScratch = 6656;
constexpr uint32_t kAnalogIo = 256;  // An is WX(256+n) / WY(256+n)

// ---------------------------------------------------------------- tokens

struct Tok {
  // Bad: where a line refused by the preprocessor was (error recovery); the
  // statement it falls in is refused without a word
  enum Kind { Ident, Int, Real, Punct, End, Bad } kind = End;
  std::string text;
  int line = 0, col = 0;
  uint64_t ival = 0;
  double rval = 0;
};

[[noreturn]] void fail(const Tok& t, const std::string& m) { throw CompileError(t.line, t.col, m); }

// ---------------------------------------------------------------- error recovery

[[noreturn]] void stop(const Tok& t, const std::string& m) { throw Stop(t.line, t.col, m); }

// With `diag`, a unit (a line, a directive, a statement, an argument) that
// fails is reported and the reader goes on; without, the first error is thrown.
struct Recovery {
  Diagnostics* diag = nullptr;
  std::string file;
  // false: the unit was refused (its error reported, or a Cascade)
  bool unit(const std::function<void()>& read) const { return recover_unit(diag, file, read); }
  // an error that does not stop the unit (it is reported, and the unit goes on)
  void report(const Tok& t, const std::string& m) const {
    unit([&] { fail(t, m); });
  }
};

// Tokens of one line (comments already blanked); `col0` is the column of line[0].
std::vector<Tok> tokenize(std::string_view line, int lineno) {
  std::vector<Tok> out;
  size_t i = 0;
  while (i < line.size()) {
    char c = line[i];
    if (c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v') { i++; continue; }
    Tok t;
    t.line = lineno, t.col = int(i) + 1;
    size_t st = i;
    if (std::isalpha((unsigned char)c) || c == '_') {
      while (i < line.size() && (std::isalnum((unsigned char)line[i]) || line[i] == '_')) i++;
      t.kind = Tok::Ident;
    } else if (std::isdigit((unsigned char)c) || (c == '.' && i + 1 < line.size() && std::isdigit((unsigned char)line[i + 1]))) {
      bool hex = c == '0' && i + 1 < line.size() && (line[i + 1] == 'x' || line[i + 1] == 'X');
      if (hex) i += 2;
      while (i < line.size() && (std::isalnum((unsigned char)line[i]) || line[i] == '.' ||
                                 ((line[i] == '+' || line[i] == '-') && !hex && (line[i - 1] == 'e' || line[i - 1] == 'E'))))
        i++;
      std::string s(line.substr(st, i - st));
      char* end = nullptr;
      errno = 0;
      if (!hex && s.find_first_of(".eE") != std::string::npos) {
        t.kind = Tok::Real;
        t.rval = std::strtod(s.c_str(), &end);
        if (*end || errno == ERANGE || !std::isfinite(t.rval)) fail(t, "bad number '" + s + "'");
      } else {
        t.kind = Tok::Int;
        t.ival = std::strtoull(hex ? s.c_str() + 2 : s.c_str(), &end, hex ? 16 : 10);
        if (*end || (hex && s.size() == 2)) fail(t, "bad number '" + s + "'");
        if (errno == ERANGE || t.ival > 0xFFFFFFFFull) fail(t, "constant '" + s + "' does not fit in 32 bits");
      }
    } else {
      static const char* two[] = {"&&", "||", "==", "!=", "<=", ">=", "<<", ">>"};
      t.kind = Tok::Punct;
      for (const char* p : two)
        if (line.substr(i, 2) == p) i += 2;
      if (i == st) {
        if (!std::strchr("(),;&|^~+-*/%!<>#", c) || c == 0) {
          std::string shown = (unsigned char)c < 32 || (unsigned char)c >= 127 ? "byte " + std::to_string((unsigned char)c)
                                                                              : "'" + std::string(1, c) + "'";
          fail(t, "unexpected " + shown);
        }
        i++;
      }
    }
    t.text = std::string(line.substr(st, i - st));
    out.push_back(t);
  }
  return out;
}

// ---------------------------------------------------------------- preprocessor

struct Preprocessor {
  std::map<std::string, std::vector<Tok>> macros;
  std::vector<Tok> out;
  Recovery rec;
  std::set<std::string> refused_macros;  // names of refused #define lines: their uses say nothing
  int refused_groups = 0;                // #if groups whose directive was refused, open

  // Expands object-like macros in `in` into `dst`; `at` is the use site.
  void expand(const std::vector<Tok>& in, std::vector<Tok>& dst, std::vector<std::string>& active, const Tok* at) {
    for (const Tok& t : in) {
      auto m = t.kind == Tok::Ident ? macros.find(t.text) : macros.end();
      const Tok& site = at ? *at : t;
      if (m != macros.end() && std::find(active.begin(), active.end(), t.text) == active.end()) {
        if (int(active.size()) >= kMaxNesting) fail(site, "macros nested deeper than " + std::to_string(kMaxNesting));
        active.push_back(t.text);
        expand(m->second, dst, active, &site);
        active.pop_back();
        continue;
      }
      if (dst.size() >= kMaxTokens) stop(site, "the program is too large after macro expansion");
      Tok c = t;
      c.line = site.line, c.col = site.col;
      dst.push_back(c);
    }
  }

  struct Group {
    bool parent_active, taken, active, seen_else;
    Tok at;
    bool refused = false;  // its #if was refused: the group is skipped, its #else too
  };

  void run(std::string_view text) {
    std::string clean = strip_comments(text);
    std::vector<Group> groups;
    auto active = [&] { return groups.empty() || groups.back().active; };
    int lineno = 0;
    size_t pos = 0;
    while (pos <= clean.size()) {
      size_t nl = clean.find('\n', pos);
      std::string_view line = std::string_view(clean).substr(pos, nl == std::string::npos ? std::string::npos : nl - pos);
      pos = nl == std::string::npos ? clean.size() + 1 : nl + 1;
      lineno++;
      size_t first = line.find_first_not_of(" \t\r\f\v");
      if (first == std::string_view::npos) continue;
      if (line[first] != '#') {
        if (!active()) continue;
        std::vector<std::string> stack;
        size_t at = out.size();
        if (!rec.unit([&] { expand(tokenize(line, lineno), out, stack, nullptr); })) {
          out.resize(at);  // the refused line: a Bad token in its place
          Tok bad;
          bad.kind = Tok::Bad, bad.line = lineno, bad.col = int(first) + 1;
          out.push_back(bad);
        }
        continue;
      }
      // a directive
      std::string_view rest = line.substr(first + 1);
      size_t ws = rest.find_first_not_of(" \t");
      if (ws == std::string_view::npos) continue;  // the null directive
      size_t we = ws;
      while (we < rest.size() && (std::isalnum((unsigned char)rest[we]) || rest[we] == '_')) we++;
      std::string name(rest.substr(ws, we - ws));
      Tok dir;
      dir.line = lineno, dir.col = int(first + 1 + ws) + 1, dir.text = name;
      std::string_view args = rest.substr(we);
      int args_col = int(first + 1 + we);  // column offset of args[0] minus one
      directive(name, dir, args, args_col, lineno, groups);
    }
    if (!groups.empty() && !groups.back().refused) rec.report(groups.back().at, "#" + groups.back().at.text + " without #endif");
  }

  // One directive.  With recovery, a refused one is reported and its meaning
  // kept where it is plain (#else and #endif with text after them), a refused
  // #if opens a group that is skipped whole, and the name of a refused #define
  // (or of an unknown directive) is remembered: its uses say nothing.
  void directive(const std::string& name, const Tok& dir, std::string_view args, int args_col, int lineno,
                 std::vector<Group>& groups) {
    auto active = [&] { return groups.empty() || groups.back().active; };
    auto arg_tokens = [&] {
      std::vector<Tok> a = tokenize(args, lineno);
      for (Tok& t : a) t.col += args_col;
      return a;
    };
    // tokens that a directive does not take: reported, the directive done
    auto nothing_after = [&] {
      rec.unit([&] {
        std::vector<Tok> a = arg_tokens();
        if (!a.empty()) fail(a[0], "unexpected text after #" + name);
      });
    };
    if (name == "if" || name == "ifdef" || name == "ifndef") {
      bool parent = active(), v = false;
      bool read = rec.unit([&] {
        if (int(groups.size()) >= kMaxNesting && !refused_groups)
          fail(dir, "#if groups nested deeper than " + std::to_string(kMaxNesting));
        v = parent && (name == "if" ? eval_if(arg_tokens(), dir) : defined_arg(arg_tokens(), dir) == (name == "ifdef"));
      });
      groups.push_back({parent, v || !read, v && read, false, dir, !read});
      refused_groups += !read;
    } else if (name == "elif" || name == "else") {
      if (groups.empty()) {  // a lost #if: a refused group, skipped to its #endif
        if (rec.diag) groups.push_back({active(), true, false, name == "else", dir, true}), refused_groups++;
        return rec.report(dir, "#" + name + " without #if");
      }
      Group& g = groups.back();
      if (g.seen_else) return rec.report(dir, "#" + name + " after #else");
      if (name == "else") {
        nothing_after();
        g.seen_else = true;
        g.active = g.parent_active && !g.taken;
      } else {
        bool v = false;
        if (!rec.unit([&] { v = g.parent_active && !g.taken && eval_if(arg_tokens(), dir); })) g.taken = true;  // skipped
        g.active = v;
      }
      g.taken |= g.active;
    } else if (name == "endif") {
      if (groups.empty()) return rec.report(dir, "#endif without #if");
      nothing_after();
      refused_groups -= groups.back().refused;
      groups.pop_back();
    } else if (!active()) {
      return;  // other directives in a skipped group are not read
    } else if (name == "define") {
      std::vector<Tok> a;
      rec.unit([&] {
        a = arg_tokens();
        if (a.empty() || a[0].kind != Tok::Ident) fail(a.empty() ? dir : a[0], "#define needs a macro name");
        size_t after = size_t(a[0].col - 1 - args_col) + a[0].text.size();
        if (after < args.size() && args[after] == '(') {
          refused_macros.insert(a[0].text);
          fail(a[0], "function-like macros are not supported (docs/rtsp.md): #define " + a[0].text + " has a '(' right after its name");
        }
        macros[a[0].text] = std::vector<Tok>(a.begin() + 1, a.end());
        refused_macros.erase(a[0].text);
      });
    } else if (name == "undef") {
      rec.unit([&] {
        std::vector<Tok> a = arg_tokens();
        if (a.size() != 1 || a[0].kind != Tok::Ident) fail(a.empty() ? dir : a[0], "#undef needs one macro name");
        macros.erase(a[0].text);
      });
    } else {
      try {  // `#defin X 1`: X's uses are quiet
        std::vector<Tok> a = arg_tokens();
        if (!a.empty() && a[0].kind == Tok::Ident) refused_macros.insert(a[0].text);
      } catch (const CompileError&) {  // the directive's own error is the one said
      }
      rec.report(dir, "unknown directive '#" + name + "' (#define #undef #ifdef #ifndef #if #elif #else #endif)");
    }
  }

  // Comments become blanks (newlines kept), so columns stay those of the file.
  static std::string strip_comments(std::string_view s) {
    std::string o(s);
    size_t i = 0;
    int line = 1;
    size_t bol = 0;
    while (i < o.size()) {
      if (o[i] == '\n') { line++, bol = i + 1, i++; continue; }
      if (o[i] == '/' && i + 1 < o.size() && o[i + 1] == '/') {
        while (i < o.size() && o[i] != '\n') o[i++] = ' ';
        continue;
      }
      if (o[i] == '/' && i + 1 < o.size() && o[i + 1] == '*') {
        int l0 = line, c0 = int(i - bol) + 1;
        o[i] = o[i + 1] = ' ';
        i += 2;
        while (i < o.size() && !(o[i] == '*' && i + 1 < o.size() && o[i + 1] == '/')) {
          if (o[i] == '\n') line++, bol = i + 1;
          else o[i] = ' ';
          i++;
        }
        if (i >= o.size()) throw CompileError(l0, c0, "unterminated comment /* ... */");
        o[i] = o[i + 1] = ' ';
        i += 2;
        continue;
      }
      i++;
    }
    return o;
  }

  bool defined_arg(const std::vector<Tok>& a, const Tok& dir) {
    if (a.size() != 1 || a[0].kind != Tok::Ident) fail(a.empty() ? dir : a[0], "#" + dir.text + " needs one macro name");
    return macros.count(a[0].text) > 0;
  }

  // #if: `defined NAME` / `defined(NAME)` first, then macros, then C's integer
  // constant expression with names left over as 0.
  bool eval_if(const std::vector<Tok>& a, const Tok& dir) {
    std::vector<Tok> d;
    for (size_t i = 0; i < a.size(); i++) {
      if (a[i].kind == Tok::Ident && a[i].text == "defined") {
        bool paren = i + 1 < a.size() && a[i + 1].text == "(";
        size_t n = i + (paren ? 2 : 1);
        if (n >= a.size() || a[n].kind != Tok::Ident || (paren && (n + 1 >= a.size() || a[n + 1].text != ")")))
          fail(a[i], "'defined' needs a macro name");
        Tok v = a[i];
        v.kind = Tok::Int, v.ival = macros.count(a[n].text) ? 1 : 0, v.text = std::to_string(v.ival);
        d.push_back(v);
        i = n + (paren ? 1 : 0);
        continue;
      }
      d.push_back(a[i]);
    }
    std::vector<Tok> e;
    std::vector<std::string> stack;
    expand(d, e, stack, nullptr);
    if (e.empty()) fail(dir, "#" + dir.text + " needs an expression");
    Tok end = e.back();
    end.kind = Tok::End, end.col += int(end.text.size()), end.text = "";
    e.push_back(end);
    size_t p = 0;
    int64_t v = cexpr(e, p, 0, 0);
    if (e[p].kind != Tok::End) fail(e[p], "unexpected '" + e[p].text + "' in #" + dir.text);
    return v != 0;
  }

  // precedence climbing over C's binary operators (level 0 = ||)
  int64_t cexpr(const std::vector<Tok>& e, size_t& p, int level, int depth) {
    static const std::vector<std::vector<std::string>> ops = {
        {"||"}, {"&&"}, {"|"}, {"^"}, {"&"}, {"==", "!="}, {"<", ">", "<=", ">="}, {"<<", ">>"}, {"+", "-"}, {"*", "/", "%"}};
    if (depth > kMaxNesting) fail(e[p], "#if expression nested too deeply");
    if (level == int(ops.size())) return cunary(e, p, depth);
    int64_t v = cexpr(e, p, level + 1, depth + 1);
    for (;;) {
      const Tok& o = e[p];
      if (o.kind != Tok::Punct || std::find(ops[level].begin(), ops[level].end(), o.text) == ops[level].end()) return v;
      p++;
      int64_t r = cexpr(e, p, level + 1, depth + 1);
      uint64_t a = uint64_t(v), b = uint64_t(r);
      const std::string& s = o.text;
      if ((s == "/" || s == "%") && r == 0) fail(o, "division by zero in #if");
      if ((s == "<<" || s == ">>") && (r < 0 || r > 63)) fail(o, "shift count out of range in #if");
      v = s == "||" ? (v || r) : s == "&&" ? (v && r) : s == "|" ? int64_t(a | b) : s == "^" ? int64_t(a ^ b)
        : s == "&" ? int64_t(a & b) : s == "==" ? v == r : s == "!=" ? v != r : s == "<" ? v < r : s == ">" ? v > r
        : s == "<=" ? v <= r : s == ">=" ? v >= r : s == "<<" ? int64_t(a << r) : s == ">>" ? (v >> r)
        : s == "+" ? int64_t(a + b) : s == "-" ? int64_t(a - b) : s == "*" ? int64_t(a * b)
        : (v == INT64_MIN && r == -1) ? (s == "/" ? v : 0) : s == "/" ? v / r : v % r;
    }
  }
  int64_t cunary(const std::vector<Tok>& e, size_t& p, int depth) {
    const Tok& t = e[p];
    if (depth > kMaxNesting) fail(t, "#if expression nested too deeply");
    if (t.kind == Tok::Punct && (t.text == "!" || t.text == "~" || t.text == "-" || t.text == "+")) {
      p++;
      int64_t v = cunary(e, p, depth + 1);
      return t.text == "!" ? !v : t.text == "~" ? ~v : t.text == "-" ? int64_t(0 - uint64_t(v)) : v;
    }
    if (t.kind == Tok::Punct && t.text == "(") {
      p++;
      int64_t v = cexpr(e, p, 0, depth + 1);
      if (e[p].text != ")" || e[p].kind != Tok::Punct) fail(e[p], "expected ')' in #if");
      p++;
      return v;
    }
    if (t.kind == Tok::Int) return p++, int64_t(t.ival);
    if (t.kind == Tok::Ident) return p++, 0;  // C: a name left after expansion is 0
    if (t.kind == Tok::Real) fail(t, "a REAL constant in #if");
    fail(t, t.kind == Tok::End ? "#if expression ends too early" : "unexpected '" + t.text + "' in #if");
  }
};

// ---------------------------------------------------------------- the program

struct Item {
  char g = 0;  // D A B I F T
  uint32_t n = 0;
  Tok at;
  bool real() const { return g == 'F'; }
};
struct Data {
  bool is_item = false;
  Item item;
  bool real = false;
  uint32_t ival = 0;  // 32 bits, two's complement
  double rval = 0;
  Tok at;
};
struct Call {
  std::string name;  // canonical spelling
  Item item;
  std::vector<Data> args;
  Tok at;
};
struct Stmt {
  enum Kind { Action, If, Init } kind = Action;
  bool become = false;
  Call call;
  std::vector<Stmt> then_, else_;
  Tok at;
};

struct FuncInfo {
  const char* name;
  bool cond;
  int nargs;  // after the item
};
const FuncInfo kFuncs[] = {
    {"IsBitOn", true, 1},  {"IsBitAnyOn", true, 1}, {"IsBitOff", true, 1}, {"IsBitAnyOff", true, 1},
    {"IsBitEq", true, 2},  {"IsBitNe", true, 2},    {"IsLt", true, 1},     {"IsLe", true, 1},
    {"IsEq", true, 1},     {"IsNe", true, 1},       {"IsGe", true, 1},     {"IsGt", true, 1},
    {"SetBitOn", false, 1}, {"SetBitOff", false, 1}, {"SetBitEq", false, 2}, {"Set", false, 1},
    {"Add", false, 1},     {"Sub", false, 1},       {"Mul", false, 1},     {"Div", false, 1},
    {"BitAnd", false, 2},  {"BitOr", false, 2},     {"BitXor", false, 2},  {"BitNeg", false, 1},
    {"BitShl", false, 1},  {"BitShr", false, 1},    {"TimerOn", false, 1}, {"TimerReset", false, 0},
    {"AioAdc", false, 0},  {"AioDac", false, 0},
};
const FuncInfo* find_func(const std::string& s) {
  for (const FuncInfo& f : kFuncs) {
    std::string a = f.name, b = s;
    if (a.size() != b.size()) continue;
    bool eq = true;
    for (size_t i = 0; i < a.size(); i++) eq &= std::tolower((unsigned char)a[i]) == std::tolower((unsigned char)b[i]);
    if (eq) return &f;
  }
  return nullptr;
}
bool is_kw(const Tok& t, const char* kw) {
  if (t.kind != Tok::Ident || t.text.size() != std::strlen(kw)) return false;
  for (size_t i = 0; i < t.text.size(); i++)
    if (std::tolower((unsigned char)t.text[i]) != kw[i]) return false;
  return true;
}

struct Parser {
  std::vector<Tok> t;
  size_t p = 0;
  // Error recovery: a statement (and an argument of a call) is the unit; a
  // refused one is skipped to its end (sync).  Said nothing more: an error in a
  // statement holding a line the preprocessor refused (a Bad token), the uses of
  // a refused macro, and the 'fi' (or 'else') of an if whose header was refused.
  Recovery rec;
  std::set<std::string> refused_macros;
  int refused_ifs = 0;  // ifs refused before their body: their 'fi' is still to come
  int refused = 0;      // statements refused so far
  std::set<std::string> unknown_names;  // reported once (as gcc does), later uses quiet

  // An unknown name: said at its first use only.
  [[noreturn]] void unknown(const Tok& k, const std::string& m) {
    if (refused_macros.count(k.text) || (rec.diag && !unknown_names.insert(k.text).second)) throw Cascade();
    fail(k, m);
  }

  bool bad_in(size_t from, size_t to) const {
    for (size_t i = from; i <= to && i < t.size(); i++)
      if (t[i].kind == Tok::Bad) return true;
    return false;
  }
  // Reads a unit starting at token p; false if it was refused (reported unless
  // it holds a Bad token).
  bool attempt(const std::function<void()>& read) {
    size_t start = p;
    return recover_unit(rec.diag, rec.file, read, [&] { return bad_in(start, p); });
  }
  static bool starts_statement(const Tok& k) {
    return is_kw(k, "if") || is_kw(k, "ifbecome") || is_kw(k, "else") || is_kw(k, "fi") || is_kw(k, "init");
  }
  // After a refused statement that began at `start`: on past its ';' (or the
  // 'then' of an if's header), stopping before what begins another statement.
  // An if, or what looks like a misspelled one (an unknown word before a condition).
  bool if_header(size_t start) const {
    if (is_kw(t[start], "if") || is_kw(t[start], "ifbecome")) return true;
    const FuncInfo* f = start + 1 < t.size() && t[start + 1].kind == Tok::Ident ? find_func(t[start + 1].text) : nullptr;
    return t[start].kind == Tok::Ident && !find_func(t[start].text) && f && f->cond;
  }
  void sync(size_t start) {
    int depth = 0;  // parentheses open since the statement's start
    for (size_t i = start; i < p; i++)
      if (t[i].kind == Tok::Punct) depth += t[i].text == "(" ? 1 : t[i].text == ")" ? -1 : 0;
    if (p == start) next();
    bool header = if_header(start);
    while (peek().kind != Tok::End) {
      const Tok& k = peek();
      if (k.kind == Tok::Punct) depth += k.text == "(" ? 1 : k.text == ")" ? -1 : 0;
      if ((k.kind == Tok::Punct && k.text == ";" && depth <= 0) || is_kw(k, "then")) return void(next());
      bool call = k.kind == Tok::Ident && find_func(k.text) && p + 1 < t.size() && t[p + 1].text == "(";
      if (starts_statement(k) || (call && !(header && p == start + 1))) return;  // (an if's own condition is not)
      next();
    }
  }
  // One statement into `out`; with recovery a refused one is skipped.
  void one(std::vector<Stmt>& out, const std::function<Stmt()>& read) {
    size_t start = p;
    if (attempt([&] { out.push_back(read()); })) return;
    refused++;
    if (if_header(start)) refused_ifs++;
    sync(start);
  }

  const Tok& peek() const { return t[p]; }
  const Tok& next() { return t[p < t.size() - 1 ? p++ : p]; }
  static std::string shown(const Tok& k) { return k.kind == Tok::End ? "the end of the program" : "'" + k.text + "'"; }
  void expect(const char* s) {
    if (peek().kind != Tok::Punct || peek().text != s) fail(peek(), std::string("expected '") + s + "', found " + shown(peek()));
    next();
  }

  // program = { "init" action | if_stmt | action }
  std::vector<Stmt> program() {
    std::vector<Stmt> out;
    while (peek().kind != Tok::End) {
      one(out, [&] {
        if (!is_kw(peek(), "init")) return stmt(0);
        Stmt s;
        s.kind = Stmt::Init;
        s.at = next();
        s.call = call(false);
        return s;
      });
    }
    return out;
  }

  // stmt = if_stmt | action
  Stmt stmt(int depth) {
    Stmt s;
    s.at = peek();
    if (is_kw(peek(), "if") || is_kw(peek(), "ifbecome")) {
      if (depth >= kMaxNesting) fail(peek(), "if statements nested deeper than " + std::to_string(kMaxNesting));
      s.kind = Stmt::If;
      s.become = is_kw(next(), "ifbecome");
      s.call = call(true);
      if (!is_kw(peek(), "then")) fail(peek(), "expected 'then' after the condition, found " + shown(peek()));
      next();
      std::vector<Stmt>* branch = &s.then_;
      int refused0 = refused;
      for (;;) {
        if (is_kw(peek(), "fi")) { next(); break; }
        if (is_kw(peek(), "else")) {
          // a second else: reported (unless a refused if's else), and read as this one's
          if (branch == &s.else_ && !refused_ifs && refused == refused0) {
            refused_ifs++;  // a lost if's else, most likely: its 'fi' says nothing
            rec.report(peek(), "second 'else' of one if");
          }
          next();
          branch = &s.else_;
          continue;
        }
        if (peek().kind == Tok::End) {
          if (refused_ifs) refused_ifs--, throw Cascade();  // a refused if's body took this one's 'fi'
          if (refused > refused0) throw Cascade();  // the refused statement may have been the 'fi'
          fail(s.at, "'" + s.at.text + "' without 'fi'");
        }
        if (is_kw(peek(), "init")) {  // reported, and its action read as a statement of the if
          rec.report(peek(), "'init' only at the top of the program, not inside an if");
          next();
          continue;
        }
        one(*branch, [&] { return stmt(depth + 1); });
      }
      return s;
    }
    if (is_kw(peek(), "then") || is_kw(peek(), "else") || is_kw(peek(), "fi")) {
      if (refused_ifs) {  // the 'fi' (or 'then', 'else') of an if whose header was refused
        if (is_kw(next(), "fi")) refused_ifs--;
        throw Cascade();
      }
      if (!is_kw(peek(), "fi")) refused_ifs++;  // a lost if header: its 'else' and 'fi' say nothing
      fail(peek(), "'" + peek().text + "' without 'if'");
    }
    s.call = call(false);
    return s;
  }

  // condition / action = FUNC "(" item { "," data } ")" [ ";" ]
  Call call(bool cond) {
    Call c;
    c.at = next();
    if (c.at.kind != Tok::Ident) fail(c.at, std::string("expected ") + (cond ? "a condition" : "an action") + ", found " + shown(c.at));
    const FuncInfo* f = find_func(c.at.text);
    if (!f) {
      if (c.at.text.size() > 4 && c.at.text.compare(0, 4, "Func") == 0)
        unknown(c.at, "user functions (" + c.at.text + ") are not supported: ldc has no FuncN table");
      unknown(c.at, "unknown function '" + c.at.text + "'" + (peek().text == "(" ? "" : " (a macro not defined?)"));
    }
    if (f->cond != cond)
      fail(c.at, std::string("'") + f->name + "' is " + (f->cond ? "a condition: use it after if or ifbecome" : "an action, not a condition"));
    c.name = f->name;
    expect("(");
    // each argument is a unit: a wrong one is reported and the next one read
    bool refused = !attempt([&] { c.item = item(next()); });
    for (int i = 0; i < f->nargs; i++) {
      if (peek().text != "," || peek().kind != Tok::Punct) {
        if (refused) throw Cascade();  // the refused argument's end was not found
        fail(peek(), std::string(f->name) + " takes " + std::to_string(f->nargs + 1) + " arguments");
      }
      next();
      size_t from = p;
      if (!attempt([&] { c.args.push_back(data()); })) refused = true, skip_argument(from);
    }
    if (refused) throw Cascade();  // the statement is refused, its arguments' errors said
    if (peek().text == ",") fail(peek(), std::string(f->name) + " takes " + std::to_string(f->nargs + 1) + " arguments");
    expect(")");
    if (!cond) {
      if (peek().kind != Tok::Punct || peek().text != ";") fail(peek(), "expected ';' after the action, found " + shown(peek()));
      next();
    }
    return c;
  }
  // After a refused argument that began at token `from`: to the ',' or ')'
  // that ends it (back to the call's ')' if the error took it).
  void skip_argument(size_t from) {
    int depth = 0;
    for (size_t i = from; i < p; i++) {
      if (t[i].kind != Tok::Punct) continue;
      if (t[i].text == "(") depth++;
      else if (t[i].text == ")" && depth-- == 0) return void(p = i);
    }
    for (; peek().kind != Tok::End && !starts_statement(peek()) && !is_kw(peek(), "then"); next()) {
      const Tok& k = peek();
      if (k.kind != Tok::Punct) continue;
      if (k.text == "(") depth++;
      else if (k.text == ")" && depth-- == 0) return;
      else if ((k.text == "," && depth == 0) || k.text == ";") return;
    }
  }

  static bool item_text(const Tok& k, Item& it) {
    if (k.kind != Tok::Ident || k.text.size() < 2) return false;
    const char* g = std::strchr(kGroups, std::toupper((unsigned char)k.text[0]));
    if (!g || !*g) return false;
    for (size_t i = 1; i < k.text.size(); i++)
      if (!std::isdigit((unsigned char)k.text[i])) return false;
    if (k.text.size() > 9) return false;
    it.g = *g;
    it.n = uint32_t(std::stoul(k.text.substr(1)));
    it.at = k;
    return true;
  }
  Item item(const Tok& k) {
    Item it;
    if (!item_text(k, it)) {
      std::string m = "expected a group item (D0, A1, B2, I3, F4, T5), found " + shown(k);
      if (k.kind == Tok::Ident) unknown(k, m);
      fail(k, m);
    }
    uint32_t max = kGroupSize[std::strchr(kGroups, it.g) - kGroups];
    if (it.n >= max) fail(k, "group item " + k.text + " out of range (" + std::string(1, it.g) + "0.." + std::string(1, it.g) + std::to_string(max - 1) + ")");
    return it;
  }

  // data = item | expr
  Data data() {
    Data d;
    d.at = peek();
    Item it;
    if (item_text(peek(), it)) {
      d.is_item = true;
      d.item = item(next());
      if (peek().kind == Tok::Punct && std::strchr("+-*/&|^", peek().text[0]))
        fail(d.at, "group item " + d.at.text + " inside an expression: an argument is one item or constants only");
      return d;
    }
    Value v = expr(0);
    if (v.real && !std::isfinite(float(v.r))) fail(d.at, "REAL constant out of range");
    d.real = v.real;
    d.rval = v.r;
    d.ival = uint32_t(uint64_t(v.i));
    return d;
  }

  struct Value {
    bool real = false;
    int64_t i = 0;
    double r = 0;
    double as_real() const { return real ? r : double(int32_t(uint32_t(uint64_t(i)))); }
  };
  Value binary(const Tok& o, Value a, Value b) {
    const std::string& s = o.text;
    bool bitop = s == "&" || s == "|" || s == "^";
    if (bitop && (a.real || b.real)) fail(o, "'" + s + "' needs integer operands");
    if (a.real || b.real) {
      double x = a.as_real(), y = b.as_real();
      if (s == "/" && y == 0) fail(o, "division by zero");
      Value v;
      v.real = true;
      v.r = s == "+" ? x + y : s == "-" ? x - y : s == "*" ? x * y : x / y;
      if (!std::isfinite(v.r)) fail(o, "REAL constant out of range");
      return v;
    }
    // 32-bit arithmetic (the values are C's 32-bit integers)
    int32_t x = int32_t(uint32_t(uint64_t(a.i))), y = int32_t(uint32_t(uint64_t(b.i)));
    uint32_t ux = uint32_t(x), uy = uint32_t(y);
    Value v;
    if (s == "/" && y == 0) fail(o, "division by zero");
    v.i = s == "&" ? (ux & uy) : s == "|" ? (ux | uy) : s == "^" ? (ux ^ uy) : s == "+" ? uint32_t(ux + uy)
        : s == "-" ? uint32_t(ux - uy) : s == "*" ? uint32_t(ux * uy) : (x == INT32_MIN && y == -1) ? uint32_t(x) : uint32_t(x / y);
    return v;
  }
  Value expr(int depth) {  // expr = xor { "|" xor }
    return level(depth, 0);
  }
  Value level(int depth, int lv) {
    static const char* ops[][2] = {{"|", nullptr}, {"^", nullptr}, {"&", nullptr}, {"+", "-"}, {"*", "/"}};
    if (depth > kMaxNesting) fail(peek(), "expression nested deeper than " + std::to_string(kMaxNesting));
    if (lv == 5) return unary(depth);
    Value v = level(depth + 1, lv + 1);
    while (peek().kind == Tok::Punct && (peek().text == ops[lv][0] || (ops[lv][1] && peek().text == ops[lv][1]))) {
      const Tok& o = next();
      v = binary(o, v, level(depth + 1, lv + 1));
    }
    return v;
  }
  Value unary(int depth) {
    const Tok& k = next();
    if (depth > kMaxNesting) fail(k, "expression nested deeper than " + std::to_string(kMaxNesting));
    Value v;
    if (k.kind == Tok::Punct && (k.text == "-" || k.text == "~" || k.text == "+")) {
      v = unary(depth + 1);
      if (k.text == "~") {
        if (v.real) fail(k, "'~' needs an integer operand");
        v.i = ~uint32_t(uint64_t(v.i));
      } else if (k.text == "-") {
        if (v.real) v.r = -v.r;
        else v.i = uint32_t(0u - uint32_t(uint64_t(v.i)));
      }
      return v;
    }
    if (k.kind == Tok::Punct && k.text == "(") {
      v = level(depth + 1, 0);
      expect(")");
      return v;
    }
    if (k.kind == Tok::Int) return v.i = int64_t(k.ival), v;
    if (k.kind == Tok::Real) return v.real = true, v.r = k.rval, v;
    if (k.kind == Tok::Ident && k.text.size() > 3 && (k.text.compare(0, 3, "bit") == 0 || k.text.compare(0, 3, "BIT") == 0) &&
        k.text.find_first_not_of("0123456789", 3) == std::string::npos) {
      unsigned n = k.text.size() > 5 ? 99 : unsigned(std::stoul(k.text.substr(3)));
      if (n > 31) fail(k, "bit number of " + k.text + " out of range (bit0..bit31)");
      return v.i = int64_t(1u << n), v;
    }
    Item it;
    if (item_text(k, it)) fail(k, "group item " + k.text + " inside an expression: an argument is one item or constants only");
    if (k.kind == Tok::Ident) unknown(k, "unknown name '" + k.text + "' (not a macro, item or bitN)");
    fail(k, "expected a value, found " + shown(k));
  }
};

// ---------------------------------------------------------------- code

struct Gen {
  Recovery rec;  // a statement is the unit: a refused one makes no rungs, its branches are still read
  TreeProgram tp;
  std::set<uint32_t> written_d, timers;
  std::set<std::pair<char, uint32_t>> used;  // items for aliases
  std::map<uint32_t, Operand> run_bit;       // timer -> hidden M
  uint32_t next_m = 0;
  int line = 0;

  Operand new_bit() {
    if (next_m >= device_count(Dev::M)) throw Stop(line, 1, "too many if statements and timers (no hidden M bit left)");
    return bit_opd(Area::M, next_m++);
  }
  static Operand scratch(int k) { return int_opd(Area::D, kScratch + uint32_t(k)); }

  void scan(const std::vector<Stmt>& ss) {  // which DIO channels are written; which timers exist
    for (const Stmt& s : ss) {
      const Call& c = s.call;
      used.insert({c.item.g, c.item.n});
      for (const Data& d : c.args)
        if (d.is_item) used.insert({d.item.g, d.item.n});
      if (s.kind != Stmt::If && c.item.g == 'D') written_d.insert(c.item.n);
      for (const Data& d : c.args)
        if (d.is_item && d.item.g == 'T') timers.insert(d.item.n);
      if (c.item.g == 'T') timers.insert(c.item.n);
      scan(s.then_);
      scan(s.else_);
    }
  }

  Operand read(const Item& it) const {
    switch (it.g) {
      case 'D': return int_opd(written_d.count(it.n) ? Area::WY : Area::WX, it.n);
      case 'A': return int_opd(Area::D, kABase + it.n);
      case 'B': return int_opd(Area::D, kBBase + it.n);
      case 'I': return int_opd(Area::D, it.n);
      case 'F': return Operand{OpdKind::Real, Area::F, it.n};
      default: return int_opd(Area::TW, it.n);
    }
  }
  Operand value(const Data& d) const {
    if (d.is_item) return read(d.item);
    if (d.real) {
      Operand o{OpdKind::ConstReal};
      o.fval = float(d.rval);
      return o;
    }
    return const_opd(int32_t(d.ival));
  }

  static TreeNode node(TreeNode::Kind k, Op op, SrcLoc loc, Operand a = {}, Operand b = {}, Operand c = {}) {
    TreeNode n;
    n.kind = k;
    n.elem.op = op;
    n.elem.a[0] = a, n.elem.a[1] = b, n.elem.a[2] = c;
    n.elem.loc = loc;
    if (op == Op::LOAD || op == Op::LOADN) n.text = (op == Op::LOADN ? "/" : "") + operand_text(a);
    else n.text = instr_text(n.elem);
    return n;
  }
  static TreeNode out(Op op, SrcLoc loc, Operand a = {}, Operand b = {}, Operand c = {}) {
    return node(TreeNode::Kind::Output, op, loc, a, b, c);
  }
  static TreeNode leaf(Op op, SrcLoc loc, Operand a = {}, Operand b = {}) { return node(TreeNode::Kind::Leaf, op, loc, a, b); }
  static SrcLoc loc(const Tok& t) { return SrcLoc{t.line, t.col}; }

  void rung(const Cond& path, std::vector<TreeNode> actions, const Tok& at) {
    if (actions.empty() || path.k == Cond::False) return;
    if (tp.rungs.size() >= kMaxRungs) stop(at, "the program needs more than " + std::to_string(kMaxRungs) + " rungs");
    TreeRung r;
    r.line = at.line;
    TreeNode act = fork_of(std::move(actions));
    if (path.k == Cond::True) {
      r.root = std::move(act);
    } else {
      r.root.kind = TreeNode::Kind::Then;
      r.root.kids.push_back(path.n);
      r.root.kids.push_back(std::move(act));
    }
    tp.rungs.push_back(std::move(r));
  }

  // `d` as the item's type: a REAL constant for an integer item is truncated
  // now (C's conversion), an F item goes through a scratch word.
  Operand as_type_of(const Item& it, const Data& d, std::vector<TreeNode>& pre, int k) const {
    if (it.real() || !(d.is_item ? d.item.real() : d.real)) return value(d);
    if (!d.is_item) return const_opd(real_to_int(float(d.rval)));
    pre.push_back(out(Op::MOV, loc(d.at), value(d), scratch(k)));
    return scratch(k);
  }
  Operand int_value(const Data& d, const char* fn) const {
    if (d.is_item ? d.item.real() : d.real) fail(d.at, std::string(fn) + " takes integer bit patterns, not REAL values");
    return value(d);
  }
  void int_item(const Call& c) const {
    if (c.item.real()) fail(c.item.at, c.name + " works on the bits of D, A, B, I or T items, " + c.item.at.text + " is a float");
  }

  // condition: the rungs computing its inputs (gated by path), then the leaf
  TreeNode condition(const Call& c, const Cond& path) {
    std::vector<TreeNode> pre;
    SrcLoc at = loc(c.at);
    Operand item = read(c.item);
    const std::string& f = c.name;
    TreeNode lf;
    if (f.rfind("IsBit", 0) == 0) {
      int_item(c);
      Operand m = int_value(c.args[0], f.c_str());
      pre.push_back(out(Op::WAND, at, item, m, scratch(0)));
      if (f == "IsBitEq" || f == "IsBitNe") {
        Operand dv = int_value(c.args[1], f.c_str());
        Operand rhs;
        if (m.kind == OpdKind::ConstInt && dv.kind == OpdKind::ConstInt) rhs = const_opd(m.ival & dv.ival);
        else pre.push_back(out(Op::WAND, at, dv, m, scratch(1))), rhs = scratch(1);
        lf = leaf(f == "IsBitEq" ? Op::LDEQ : Op::LDNE, at, scratch(0), rhs);
      } else {
        Op op = f == "IsBitOn" || f == "IsBitOff" ? Op::LDEQ : Op::LDNE;
        Operand rhs = f == "IsBitOn" || f == "IsBitAnyOff" ? m : const_opd(0);
        lf = leaf(op, at, scratch(0), rhs);
      }
    } else {
      static const std::map<std::string, Op> cmp = {{"IsLt", Op::LDLT}, {"IsLe", Op::LDLE}, {"IsEq", Op::LDEQ},
                                                    {"IsNe", Op::LDNE}, {"IsGe", Op::LDGE}, {"IsGt", Op::LDGT}};
      Operand rhs = as_type_of(c.item, c.args[0], pre, 2);
      lf = leaf(cmp.at(f), at, item, rhs);
    }
    rung(path, std::move(pre), c.at);
    return lf;
  }

  std::vector<TreeNode> action(const Call& c) {
    std::vector<TreeNode> o;
    SrcLoc at = loc(c.at);
    const std::string& f = c.name;
    const Item& it = c.item;
    bool timer_fn = f == "TimerOn" || f == "TimerReset", aio = f == "AioAdc" || f == "AioDac";
    if (timer_fn != (it.g == 'T'))
      fail(it.at, timer_fn ? f + " works on a timer item (T0..T255), not " + it.at.text
                           : it.at.text + " is a timer: only TimerOn and TimerReset act on it");
    if (aio && it.g != 'A') fail(it.at, f + " works on an analog item (A0..A255), not " + it.at.text);
    Operand dst = it.g == 'D' ? int_opd(Area::WY, it.n) : read(it);
    auto arg = [&](size_t i) { return int_value(c.args[i], f.c_str()); };
    auto fold_or = [&](Operand a, auto fn, int k, Op op, Operand b) {  // fn(a,b) when constant, else op a b scratch(k)
      if (a.kind == OpdKind::ConstInt && b.kind == OpdKind::ConstInt) return const_opd(fn(a.ival, b.ival));
      o.push_back(out(op, at, a, b, scratch(k)));
      return scratch(k);
    };
    auto bitnot = [&](Operand a, int k) {
      if (a.kind == OpdKind::ConstInt) return const_opd(~a.ival);
      o.push_back(out(Op::WNOT, at, a, scratch(k)));
      return scratch(k);
    };
    auto band = [](int32_t a, int32_t b) { return a & b; };
    auto bor = [](int32_t a, int32_t b) { return a | b; };
    if (f == "SetBitOn") int_item(c), o.push_back(out(Op::WOR, at, dst, arg(0), dst));
    else if (f == "SetBitOff") int_item(c), o.push_back(out(Op::WAND, at, dst, bitnot(arg(0), 0), dst));
    else if (f == "SetBitEq") {  // (item & ~mask) | (data & mask)
      int_item(c);
      Operand keep = fold_or(dst, band, 0, Op::WAND, bitnot(arg(0), 1));
      Operand put = fold_or(arg(1), band, 2, Op::WAND, arg(0));
      o.push_back(out(Op::WOR, at, keep, put, dst));
    } else if (f == "BitAnd") {  // item & (~mask | data)
      int_item(c);
      o.push_back(out(Op::WAND, at, dst, fold_or(bitnot(arg(0), 0), bor, 0, Op::WOR, arg(1)), dst));
    } else if (f == "BitOr" || f == "BitXor") {  // item | (data & mask), item ^ (data & mask)
      int_item(c);
      o.push_back(out(f == "BitOr" ? Op::WOR : Op::WXOR, at, dst, fold_or(arg(1), band, 0, Op::WAND, arg(0)), dst));
    } else if (f == "BitNeg") int_item(c), o.push_back(out(Op::WXOR, at, dst, arg(0), dst));
    else if (f == "BitShl" || f == "BitShr") int_item(c), o.push_back(out(f == "BitShl" ? Op::SHL : Op::SHR, at, dst, arg(0), dst));
    else if (f == "Set") o.push_back(out(Op::MOV, at, as_type_of(it, c.args[0], o, 2), dst));
    else if (f == "Add" || f == "Sub" || f == "Mul" || f == "Div") {
      Op op = f == "Add" ? Op::ADD : f == "Sub" ? Op::SUB : f == "Mul" ? Op::MUL : Op::DIV;
      Operand v = as_type_of(it, c.args[0], o, 2);
      o.push_back(out(op, at, dst, v, dst));
    } else if (f == "TimerOn") {
      Data d = c.args[0];
      Operand timeout = as_type_of(Item{'I', 0, {}}, d, o, 2);
      o.push_back(out(Op::SET, at, run(it.n)));
      o.push_back(out(Op::MOV, at, timeout, int_opd(Area::D, kTimeoutBase + it.n)));
      o.push_back(out(Op::MOV, at, const_opd(0), int_opd(Area::TW, it.n)));
    } else if (f == "TimerReset") {
      o.push_back(out(Op::RST, at, run(it.n)));
      o.push_back(out(Op::MOV, at, const_opd(-1), int_opd(Area::TW, it.n)));
    } else if (f == "AioAdc") {
      o.push_back(out(Op::MOV, at, int_opd(Area::WX, kAnalogIo + it.n), read(it)));
    } else {  // AioDac
      o.push_back(out(Op::MOV, at, read(it), int_opd(Area::WY, kAnalogIo + it.n)));
    }
    return o;
  }
  Operand run(uint32_t timer) {
    auto r = run_bit.find(timer);
    if (r == run_bit.end()) r = run_bit.emplace(timer, new_bit()).first;
    return r->second;
  }

  void stmts(const std::vector<Stmt>& ss, const Cond& path) {
    for (const Stmt& s : ss) {
      line = s.at.line;
      Operand t;  // an if's hidden bit
      bool made = rec.unit([&] { t = statement(s, path); });
      refused |= !made;
      if (s.kind != Stmt::If) continue;
      SrcLoc at = loc(s.at);
      // a refused condition: its branches are still checked, under no condition
      stmts(s.then_, made ? Cond::of(leaf(Op::LOAD, at, t)) : Cond::yes());
      stmts(s.else_, made ? c_and(path, Cond::of(leaf(Op::LOADN, at, t))) : Cond::yes());
    }
  }
  // The rungs of one statement (an if's: its condition into the hidden bit it returns).
  Operand statement(const Stmt& s, const Cond& path) {
    if (s.kind == Stmt::Init) {
      rung(Cond::of(leaf(Op::LOAD, loc(s.at), bit_opd(Area::S, kBitFirstScan))), action(s.call), s.at);
      return {};
    }
    if (s.kind == Stmt::Action) {
      rung(path, action(s.call), s.at);
      return {};
    }
    SrcLoc at = loc(s.at);
    TreeNode lf = condition(s.call, path);
    Operand t = new_bit();
    if (!s.become) {
      rung(c_and(path, Cond::of(lf)), {out(Op::OUT, at, t)}, s.at);
      return t;
    }
    // fires when the condition is true and was false when this if last ran
    Operand now = new_bit(), before = new_bit();
    rung(c_and(path, Cond::of(lf)), {out(Op::OUT, at, now)}, s.at);
    rung(c_and(Cond::of(leaf(Op::LOAD, at, now)), Cond::of(leaf(Op::LOADN, at, before))), {out(Op::OUT, at, t)}, s.at);
    if (path.k == Cond::True) {
      rung(Cond::of(leaf(Op::LOAD, at, now)), {out(Op::OUT, at, before)}, s.at);
    } else {
      TreeNode set_b, rst_b;
      set_b.kind = rst_b.kind = TreeNode::Kind::Then;
      set_b.kids = {leaf(Op::LOAD, at, now), out(Op::SET, at, before)};
      rst_b.kids = {leaf(Op::LOADN, at, now), out(Op::RST, at, before)};
      rung(path, {set_b, rst_b}, s.at);
    }
    return t;
  }

  void program(const std::vector<Stmt>& ss, const Tok& first) {
    scan(ss);
    // the timers advance before the program runs (paper 000, Fig. 4): a TON
    // always on, its elapsed time forced to -1 while the timer is stopped
    for (uint32_t n : timers) {
      SrcLoc at = loc(first);
      rung(Cond::yes(), {out(Op::TON, at, timer_opd(n), int_opd(Area::D, kTimeoutBase + n))}, first);
      rung(Cond::of(leaf(Op::LOADN, at, run(n))), {out(Op::MOV, at, const_opd(-1), int_opd(Area::TW, n))}, first);
    }
    stmts(ss, Cond::yes());
    for (auto [g, n] : used) {
      std::string name = std::string(1, g) + std::to_string(n);
      switch (g) {
        case 'D': tp.aliases.push_back({std::string(written_d.count(n) ? "DO" : "DI") + std::to_string(n), {written_d.count(n) ? Dev::WY : Dev::WX, n}}); break;
        case 'A': tp.aliases.push_back({name, {Dev::D, kABase + n}}); break;
        case 'B': tp.aliases.push_back({name, {Dev::D, kBBase + n}}); break;
        case 'I': tp.aliases.push_back({name, {Dev::D, n}}); break;
        default: break;  // Fn and Tn are ldc's own Fn and Tn
      }
    }
    if (tp.rungs.empty() && !refused) fail(first, "the program has no statements");
  }
  bool refused = false;  // a line or statement was refused: "no statements" is not said
};


// Reads a program; with `diag`, every error is reported there (a Stop ends the
// reading) and a program with errors ends with ErrorsReported.
TreeProgram read_rtsp(std::string_view text, const std::string& filename, Diagnostics* diag) {
  if (text.size() > kMaxSourceBytes)
    throw CompileError(1, 1, "source file too large (at most " + std::to_string(kMaxSourceBytes >> 20) + " MiB)");
  Recovery rec{diag, filename};
  int errors0 = diag ? diag->errors() : 0;
  Preprocessor pp;
  pp.rec = rec;
  pp.run(text);
  Parser ps;
  ps.rec = rec;
  ps.refused_macros = std::move(pp.refused_macros);
  ps.t = std::move(pp.out);
  Tok end;  // just after the last token
  if (!ps.t.empty()) end.line = ps.t.back().line, end.col = ps.t.back().col + int(ps.t.back().text.size());
  else end.line = end.col = 1;
  end.kind = Tok::End;
  ps.t.push_back(end);
  Tok first = ps.t.front();
  std::vector<Stmt> prog = ps.program();
  Gen g;
  g.rec = rec;
  g.tp.source = filename;
  g.refused = diag && diag->errors() > errors0;
  g.program(prog, first);
  if (diag && diag->errors() > errors0) throw ErrorsReported();
  return std::move(g.tp);
}

}  // namespace

TreeProgram parse_rtsp(std::string_view text, const std::string& filename) { return read_rtsp(text, filename, nullptr); }

TreeProgram parse_rtsp(std::string_view text, const std::string& filename, Diagnostics& diag) {
  try {
    return read_rtsp(text, filename, &diag);
  } catch (const ErrorsReported&) {
    throw;
  } catch (const CompileError& e) {  // a Stop (a limit of the whole program), or the file too large
    diag.error(filename, e);
    throw ErrorsReported();
  }
}

}  // namespace ldc
