// frontend/ldmicro_format.h -- the text of LDmicro's STRING element
// (docs/ldmicro.md, "Strings"): how LDmicro's file reader turns the saved
// text into characters, and the one printf conversion the element may hold.
// Facts of LDmicro's file format and of C's printf; no code of either.
#pragma once
#include <string>
#include <string_view>

namespace ldc::ldmicro_format {

// The saved text as LDmicro's reader makes it: "(none)" is empty; \x20 and
// \\x20 are a space; \' \" \? \\ \a \b \e \f \n \r \t \v are their characters;
// a backslash before anything else stays; then every newline is deleted.
inline std::string load_text(std::string_view s) {
  if (s == "(none)") return "";
  static const std::string_view from = "'\"?\\abefnrtv", to = "'\"?\\\a\b\x1b\f\n\r\t\v";
  std::string r;
  for (size_t i = 0; i < s.size(); i++) {
    if (s[i] != '\\') { r += s[i]; continue; }
    if (s.substr(i + 1, 3) == "x20") { r += ' '; i += 3; continue; }
    if (s.substr(i + 1, 4) == "\\x20") { r += ' '; i += 4; continue; }
    size_t k = i + 1 < s.size() ? from.find(s[i + 1]) : std::string_view::npos;
    if (k == std::string_view::npos) { r += '\\'; continue; }
    r += to[k];
    i++;
  }
  std::string out;
  for (char c : r)
    if (c != '\n') out += c;
  return out;
}

// One conversion: %[flags][width][.precision][length]conv, conv one of
// d i u x X o c; length h (16 bits), hh (8 bits) or l (32 bits, as int).
struct Spec {
  char conv = 0;
  bool minus = false, plus = false, space = false, alt = false, zero = false;
  int width = 0;
  int prec = -1;  // none
  int bits = 32;  // h: 16, hh: 8
};

// text = before [spec after]; %% is a '%' in before or after.
struct Format {
  std::string before, after;
  bool has_spec = false;
  Spec spec;
};

constexpr int kMaxField = 255;  // the largest width or precision ldc takes

// Splits `text` as sprintf(dest, text, value) reads it.  Returns "" or the
// reason the text is refused.
inline std::string parse(const std::string& text, Format& f) {
  auto number = [&](size_t& i, int& v) {
    v = 0;
    while (i < text.size() && text[i] >= '0' && text[i] <= '9') {
      v = v * 10 + (text[i++] - '0');
      if (v > kMaxField) return false;
    }
    return true;
  };
  for (size_t i = 0; i < text.size(); i++) {
    std::string& out = f.has_spec ? f.after : f.before;
    if (text[i] != '%') { out += text[i]; continue; }
    if (++i >= text.size()) return "a '%' ends the text";
    if (text[i] == '%') { out += '%'; continue; }
    if (f.has_spec) return "more than one conversion: STRING passes one value, so a second one reads past it";
    Spec s;
    for (;; i++) {
      if (i >= text.size()) return "an unfinished conversion ends the text";
      char c = text[i];
      if (c == '-') s.minus = true;
      else if (c == '+') s.plus = true;
      else if (c == ' ') s.space = true;
      else if (c == '#') s.alt = true;
      else if (c == '0') s.zero = true;
      else break;
    }
    if (text[i] == '*') return "a '*' width or precision reads a second value, and STRING passes one";
    if (!number(i, s.width)) return "a field width over " + std::to_string(kMaxField) + " is not supported";
    if (i < text.size() && text[i] == '.') {
      i++;
      if (i < text.size() && text[i] == '*') return "a '*' width or precision reads a second value, and STRING passes one";
      if (!number(i, s.prec)) return "a precision over " + std::to_string(kMaxField) + " is not supported";
    }
    if (i < text.size() && text[i] == 'h') {
      s.bits = 16;
      if (++i < text.size() && text[i] == 'h') s.bits = 8, i++;
    } else if (i < text.size() && text[i] == 'l') {
      i++;
      if (i < text.size() && text[i] == 'l') return "the length 'll' (a 64-bit value) does not match the integer STRING passes";
    }
    if (i >= text.size()) return "an unfinished conversion ends the text";
    char c = text[i];
    if (c == 'c') {
      if (s.plus || s.space || s.alt || s.zero || s.prec >= 0 || s.bits != 32)
        return "%c takes only the flag '-' and a width (anything else is undefined in C)";
    } else if (std::string_view("diuxXo").find(c) == std::string_view::npos) {
      return std::string("the conversion '%") + c + "' does not print an integer; STRING passes an integer (d i u x X o c)";
    }
    s.conv = c == 'i' ? 'd' : c;
    f.spec = s;
    f.has_spec = true;
  }
  return "";
}

}  // namespace ldc::ldmicro_format
