// tools/md2man -- turns a manual page written in docs/man/NAME.1.md into
// roff for man(1).  The build runs it on every page; `cmake --install`
// installs the results under share/man/man1.
//
// The markdown it reads (docs/man/README.md shows the form):
//   # NAME(1) -- one-line description      the title, first line
//   ## HEADING                              a section (.SH)
//   * TERM                                  a tagged paragraph (.TP): the term,
//     indented lines                        then its description
//       four-space indented lines           verbatim (.nf ... .fi)
//   blank line                              a new paragraph (.PP)
//   `code`                                  bold; everything else is text
//
//   md2man IN.md OUT.1
// Exit status 1 with `IN:LINE: error: ...` on anything else.
#include <cctype>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace {

struct Failure {
  std::string message;
};

// Text for roff: backslashes escaped, minus signs as \-, `code` in bold.
std::string inline_text(const std::string& s, const std::string& where) {
  std::string out;
  bool code = false;
  for (char c : s) {
    if (c == '`') {
      out += code ? "\\fR" : "\\fB";
      code = !code;
    } else if (c == '\\') {
      out += "\\e";
    } else if (c == '-') {
      out += "\\-";
    } else {
      out += c;
    }
  }
  if (code) throw Failure{where + ": error: unclosed `"};
  return out;
}

// A line must not start with . or ' (roff requests).
std::string line_out(const std::string& s) { return !s.empty() && (s[0] == '.' || s[0] == '\'') ? "\\&" + s : s; }

std::string convert(const std::vector<std::string>& lines, const std::string& file) {
  auto where = [&](size_t i) { return file + ":" + std::to_string(i + 1); };
  if (lines.empty() || lines[0].rfind("# ", 0) != 0) throw Failure{where(0) + ": error: the first line is '# NAME(1) -- description'"};
  const std::string& t = lines[0];
  size_t open = t.find('('), close = t.find(')'), dash = t.find(" -- ");
  if (open == std::string::npos || close == std::string::npos || dash == std::string::npos || open > close || close > dash)
    throw Failure{where(0) + ": error: the first line is '# NAME(1) -- description'"};
  std::string name = t.substr(2, open - 2), section = t.substr(open + 1, close - open - 1);
  std::string upper = name;
  for (char& c : upper) c = char(std::toupper(static_cast<unsigned char>(c)));
  std::ostringstream o;
  o << ".TH " << upper << " " << section << " \"\" \"ldc\" \"ldc manual\"\n";
  o << ".SH NAME\n" << name << " \\- " << inline_text(t.substr(dash + 4), where(0)) << "\n";
  bool verbatim = false;
  for (size_t i = 1; i < lines.size(); i++) {
    const std::string& l = lines[i];
    bool indented4 = l.rfind("    ", 0) == 0;
    if (verbatim && !indented4) o << ".fi\n", verbatim = false;
    if (l.empty()) {
      o << ".PP\n";
    } else if (l.rfind("## ", 0) == 0) {
      o << ".SH " << inline_text(l.substr(3), where(i)) << "\n";
    } else if (l.rfind("* ", 0) == 0) {
      o << ".TP\n" << line_out(inline_text(l.substr(2), where(i))) << "\n";
    } else if (indented4) {
      if (!verbatim) o << ".nf\n", verbatim = true;
      o << line_out(inline_text(l.substr(4), where(i))) << "\n";
    } else if (l.rfind("  ", 0) == 0) {
      o << line_out(inline_text(l.substr(2), where(i))) << "\n";
    } else if (l[0] == '#' || l[0] == ' ') {
      throw Failure{where(i) + ": error: a heading is '## HEADING'; indent by 2 (a term's text) or 4 (verbatim)"};
    } else {
      o << line_out(inline_text(l, where(i))) << "\n";
    }
  }
  if (verbatim) o << ".fi\n";
  return o.str();
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: md2man IN.md OUT.1\n");
    return 2;
  }
  std::ifstream in(argv[1]);
  if (!in) {
    std::fprintf(stderr, "md2man: error: cannot read %s\n", argv[1]);
    return 1;
  }
  std::vector<std::string> lines;
  for (std::string l; std::getline(in, l);) lines.push_back(l);
  try {
    std::string roff = convert(lines, argv[1]);
    std::string tmp = std::string(argv[2]) + ".tmp";
    std::ofstream out(tmp);
    out << roff;
    out.close();
    if (!out || std::rename(tmp.c_str(), argv[2]) != 0) {
      std::remove(tmp.c_str());
      std::fprintf(stderr, "md2man: error: cannot write %s\n", argv[2]);
      return 1;
    }
  } catch (const Failure& f) {
    std::fprintf(stderr, "%s\n", f.message.c_str());
    return 1;
  }
  return 0;
}
