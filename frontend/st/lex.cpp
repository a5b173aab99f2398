// frontend/st/lex.cpp -- the lexer of Structured Text (docs/st.md, "Lexical").
// Words follow the IEC IL lexer's conventions (frontend/iecil/iecil.cpp) so
// that declarations reach the typed reader as it reads them; a sign is an
// operator here, not part of a number, except inside a literal (1.0E-3,
// INT#-5, T#-2s, DATE#2024-01-31).
#include <cctype>

#include "frontend/st/st.h"

namespace ldc::st {

using iecil::Tok;

namespace {

bool word_start(char c) { return std::isalnum((unsigned char)c) || c == '_' || c == '%'; }
bool word_char(char c) { return std::isalnum((unsigned char)c) || c == '_' || c == '%' || c == '#' || c == '.'; }

struct Lexer {
  std::string_view s;
  size_t i = 0, bol = 0;
  int line = 1;
  std::vector<Tok> out;

  int col(size_t at) const { return int(at - bol) + 1; }
  [[noreturn]] void fail(size_t at, const std::string& m) const { throw CompileError(line, col(at), m); }
  char at(size_t k) const { return k < s.size() ? s[k] : '\0'; }
  void newline() { line++, bol = i + 1; }

  // (* ... *), nested as IEC 61131-3 3rd edition allows
  void comment() {
    int l0 = line, c0 = col(i), depth = 0;
    do {
      if (at(i) == '(' && at(i + 1) == '*') depth++, i += 2;
      else if (at(i) == '*' && at(i + 1) == ')') depth--, i += 2;
      else if (i >= s.size()) throw CompileError(l0, c0, "unterminated comment (* ... *)");
      else {
        if (s[i] == '\n') newline();
        i++;
      }
    } while (depth > 0);
  }
  // {pragma}: one "{" token (st.cpp's pragmas() decides what it means)
  void pragma() {
    int l0 = line, c0 = col(i);
    out.push_back({Tok::Punct, "{", l0, c0});
    while (i < s.size() && s[i] != '}') {
      if (s[i] == '\n') newline();
      i++;
    }
    if (i >= s.size()) throw CompileError(l0, c0, "unterminated pragma { ... }");
    i++;
  }
  void string_lit() {
    size_t j = i + 1;
    while (j < s.size() && s[j] != '\'' && s[j] != '\n') j += s[j] == '$' && j + 1 < s.size() && s[j + 1] != '\n' ? 2 : 1;
    if (j >= s.size() || s[j] != '\'') fail(i, "unterminated string literal (a quote inside one is $')");
    out.push_back({Tok::Word, std::string(s.substr(i, j + 1 - i)), line, col(i)});
    i = j + 1;
  }
  void word() {
    size_t st = i++;
    if (s[st] == '_' && at(st + 1) == '_')  // IEC 61131-3 forbids it, and ldc's ST temporaries are named so
      fail(st, "a name may not begin with two underscores (IEC 61131-3; ldc names its own temporaries so)");
    bool numeric = std::isdigit((unsigned char)s[st]);
    auto typed = [&] { return s.substr(st, i - st).find('#') != std::string_view::npos; };
    auto sign_inside = [&] {  // 1.0E-3, LREAL#1e-9, INT#-5, T#-2ms
      if (s[i] != '-' && s[i] != '+') return false;
      char before = s[i - 1];
      return before == '#' || ((numeric || typed()) && (before == 'e' || before == 'E') && std::isdigit((unsigned char)at(i + 1)));
    };
    auto date_inside = [&] {  // DATE#2024-01-31, TOD#12:30:00, DT#2024-01-31-12:30:00
      if ((s[i] != '-' && s[i] != ':') || !std::isdigit((unsigned char)at(i + 1))) return false;
      return iecil::date_literal_head(s.substr(st, i - st));
    };
    while (i < s.size() && ((word_char(s[i]) && !(s[i] == '.' && at(i + 1) == '.')) || sign_inside() || date_inside())) i++;
    std::string text(s.substr(st, i - st));
    // "T# 30000ms": blanks after a literal's '#', as OpenPLC Editor writes a
    // duration, are dropped (MatIEC reads them so)
    if (text.back() == '#' && text.size() > 1 && (at(i) == ' ' || at(i) == '\t')) {
      size_t j = i;
      while (at(j) == ' ' || at(j) == '\t') j++;
      if (std::isalnum((unsigned char)at(j)) || at(j) == '-') {
        i = j;
        size_t rest = i;
        if (at(i) == '-') i++;
        while (i < s.size() && ((word_char(s[i]) && !(s[i] == '.' && at(i + 1) == '.')) || sign_inside() || date_inside())) i++;
        text += std::string(s.substr(rest, i - rest));
      }
    }
    out.push_back({Tok::Word, text, line, col(st)});
  }
  void punct(size_t n) {
    out.push_back({Tok::Punct, std::string(s.substr(i, n)), line, col(i)});
    i += n;
  }

  void run() {
    static const char* two[] = {":=", "=>", "<=", ">=", "<>", "**", ".."};
    while (i < s.size()) {
      char c = s[i];
      if (c == '\n') { newline(); i++; continue; }
      if (c == ' ' || c == '\t' || c == '\r' || c == '\f') { i++; continue; }
      if (c == '(' && at(i + 1) == '*') { comment(); continue; }
      if (c == '/' && at(i + 1) == '/') {
        while (i < s.size() && s[i] != '\n') i++;
        continue;
      }
      if (c == '{') { pragma(); continue; }
      if (c == '\'') { string_lit(); continue; }
      if (c == '"') fail(i, "a WSTRING literal: ldc has no WSTRING (docs/st.md)");
      // a member after an index or a call: a[2].x
      if (word_start(c) || (c == '.' && (std::isalpha((unsigned char)at(i + 1)) || at(i + 1) == '_'))) { word(); continue; }
      bool done = false;
      for (const char* t : two)
        if (c == t[0] && at(i + 1) == t[1]) { punct(2); done = true; break; }
      if (done) continue;
      if (std::string_view("()[],;:+-*/<>=&").find(c) != std::string_view::npos) { punct(1); continue; }
      std::string shown = (unsigned char)c < 32 || (unsigned char)c >= 127 ? "byte " + std::to_string((unsigned char)c)
                                                                          : "'" + std::string(1, c) + "'";
      fail(i, "unexpected " + shown);
    }
    out.push_back({Tok::End, "", line, col(i)});
  }
};

}  // namespace

std::vector<Tok> lex(std::string_view s) {
  Lexer l{s};
  l.run();
  return std::move(l.out);
}

}  // namespace ldc::st
