// frontend/parse.cpp -- the .ld reader: source lines, rung grids, elements.
//
// A rung grid becomes a graph: every column boundary of every row is a point;
// wires and junctions join points into nodes, vertical links join rows, input
// elements are edges from the node on their left to the node on their right,
// and outputs hang on the node on their left.  Series/parallel reduction of that
// graph gives the rung tree of paper 003 (Fig. 5); what does not reduce is a
// bridge and is refused.
#include <algorithm>
#include <cstring>
#include <map>
#include <numeric>

#include "frontend/frontend.h"
#include "frontend/operands.h"

namespace ldc {

std::string format_error(const std::string& file, std::string_view text, int line, int col, const std::string& msg) {
  std::string out = file + ":" + std::to_string(line) + ":" + std::to_string(col) + ": error: " + msg + "\n";
  // find the line
  size_t pos = 0;
  for (int l = 1; l < line && pos != std::string_view::npos; l++) {
    pos = text.find('\n', pos);
    if (pos != std::string_view::npos) pos++;
  }
  if (pos == std::string_view::npos || pos > text.size()) return out;
  size_t end = text.find('\n', pos);
  std::string src(text.substr(pos, end == std::string_view::npos ? std::string_view::npos : end - pos));
  if (!src.empty() && src.back() == '\r') src.pop_back();
  out += src + "\n";
  std::string caret;
  for (int i = 0; i + 1 < col && i < int(src.size()); i++) caret += src[i] == '\t' ? '\t' : ' ';
  out += caret + "^\n";
  return out;
}

namespace {

using K = TreeNode::Kind;

[[noreturn]] void fail(int line, int col, const std::string& msg) { throw CompileError(line, col, msg); }

// Element keywords are read by position (the first word of a multi-word
// element), so an alias may be called `start`, `reset` or `S`.  Only `END`,
// a one-word output of its own, would be ambiguous.
bool is_keyword(std::string_view s) { return upper(s) == "END"; }

struct Word {
  std::string text;
  int col;  // 1-based column in the source line
};

std::vector<Word> split_words(std::string_view s, int col0) {
  std::vector<Word> w;
  size_t i = 0;
  while (i < s.size()) {
    if (s[i] == ' ') { i++; continue; }
    size_t st = i;
    while (i < s.size() && s[i] != ' ') i++;
    w.push_back({std::string(s.substr(st, i - st)), col0 + int(st)});
  }
  return w;
}

std::string trim(std::string_view s) {
  size_t a = s.find_first_not_of(" \t"), b = s.find_last_not_of(" \t");
  return a == std::string_view::npos ? std::string() : std::string(s.substr(a, b - a + 1));
}

// ------------------------------------------------------------------ cells

enum class Cell : uint8_t { Blank, Wire, Junction, Vert, Elem, Out };

struct Token {
  int row, c0, c1;  // columns (0-based) of the brackets
  bool output;
};

struct Grid {
  int rail = 0;       // column of the left rail
  int width = 0;      // columns, rail included
  std::vector<std::vector<Cell>> cell;
  std::vector<std::vector<int>> tok;  // token index at Elem/Out cells, else -1
  std::vector<Token> tokens;
  std::vector<bool> joined;  // row joined to the left rail
  Cell at(int r, int c) const {
    if (r < 0 || r >= int(cell.size()) || c < 0 || c >= width) return Cell::Blank;
    return cell[r][c];
  }
  bool token_starts(int r, int c) const { return (at(r, c) == Cell::Elem || at(r, c) == Cell::Out) && tokens[tok[r][c]].c0 == c; }
  bool token_ends(int r, int c) const { return (at(r, c) == Cell::Elem || at(r, c) == Cell::Out) && tokens[tok[r][c]].c1 == c; }
  bool elem_ends(int r, int c) const { return at(r, c) == Cell::Elem && tokens[tok[r][c]].c1 == c; }
  bool out_ends(int r, int c) const { return at(r, c) == Cell::Out && tokens[tok[r][c]].c1 == c; }
  bool vertical(int r, int c) const { return at(r, c) == Cell::Junction || at(r, c) == Cell::Vert; }
};

struct UnionFind {
  std::vector<int> p;
  explicit UnionFind(size_t n) : p(n) { std::iota(p.begin(), p.end(), 0); }
  int find(int x) {
    while (p[x] != x) x = p[x] = p[p[x]];
    return x;
  }
  void join(int a, int b) { p[find(a)] = find(b); }
};

// ------------------------------------------------------------------ parser

class Parser {
 public:
  Parser(std::string_view text, std::string file) : text_(text), file_(std::move(file)) {}
  // names the file may use without declaring them (not listed in its aliases)
  void predefine(const std::vector<Alias>& names) {
    for (const Alias& a : names) aliases_[upper(a.name)] = a.dev;
  }
  TreeProgram program();

 private:
  struct Line {
    std::string text;
    int no;
  };
  struct LabelDef {
    std::string name;
    int line;
  };

  std::string_view text_;
  std::string file_;
  std::vector<Line> lines_;
  std::map<std::string, DeviceRef> aliases_;  // key: upper-case name
  std::vector<LabelDef> labels_;
  std::vector<Alias> alias_list_;  // in source order
  std::vector<DeviceRef> retain_;  // `retain Dn` lines, in source order

  void read_lines();
  void declarations();
  TreeRung rung(size_t first, size_t last, int rail);
  Grid grid(size_t first, size_t last, int rail);
  void check_cells(const Grid& g, int line0);
  TreeNode reduce(const Grid& g, int line0);

  TreeNode input_element(const std::string& inner, int line, int col);
  TreeNode output_element(const std::string& inner, int line, int col, int rung_line);

  DeviceRef device(const Word& w);
  Operand bit(const Word& w, char sig);
  Operand value(const Word& w, char sig);
  Operand timer_or_counter(const Word& w, char sig);
};

void Parser::read_lines() {
  int no = 0;
  for (std::string& l : source_lines(text_)) lines_.push_back({std::move(l), ++no});
}

bool is_comment(const std::string& s) {
  std::string t = trim(s);
  return t.rfind("#", 0) == 0 || t.rfind("//", 0) == 0;
}

// declarations: alias = "alias" NAME "=" device ;  label = "label" NAME ;
// Read first, so aliases and labels may be used anywhere in the file.
void Parser::declarations() {
  for (const Line& l : lines_) {
    std::string t = trim(l.text);
    if (t.empty() || is_comment(t) || t[0] == '|') continue;
    int col0 = int(l.text.find_first_not_of(" \t")) + 1;
    auto w = split_words(l.text.substr(col0 - 1), col0);
    std::string kw = upper(w[0].text);
    if (kw == "ALIAS") {
      // allow "alias a=X1" and "alias a = X1"
      std::string rest = trim(l.text.substr(col0 - 1 + 5));
      size_t eq = rest.find('=');
      int rest_col = int(l.text.find(rest, col0 - 1 + 5)) + 1;
      if (eq == std::string::npos) fail(l.no, col0, "expected: alias NAME = DEVICE");
      std::string name = trim(rest.substr(0, eq)), target = trim(rest.substr(eq + 1));
      if (!is_identifier(name)) fail(l.no, rest_col, "alias name '" + name + "' must be letters, digits and _");
      std::string why;
      if (parse_device(name) || parse_iec_address(name, why) || is_keyword(name))
        fail(l.no, rest_col, "'" + name + "' cannot be an alias name: it is a device or a keyword");
      std::string key = upper(name);
      if (aliases_.count(key)) fail(l.no, rest_col, "alias '" + name + "' is already defined");
      if (target.empty()) fail(l.no, rest_col + int(eq) + 1, "expected a device after '='");
      int tcol = int(l.text.rfind(target)) + 1;
      try {
        aliases_[key] = device(Word{target, tcol});
      } catch (CompileError& e) { fail(l.no, e.col, e.what()); }
      alias_list_.push_back({name, aliases_[key]});
    } else if (kw == "LABEL") {
      if (w.size() != 2 || !is_identifier(w[1].text)) fail(l.no, col0, "expected: label NAME");
      for (auto& d : labels_)
        if (upper(d.name) == upper(w[1].text))
          fail(l.no, w[1].col, "duplicate label '" + w[1].text + "' (first defined on line " + std::to_string(d.line) + ")");
      labels_.push_back({w[1].text, l.no});
    } else if (kw == "RETAIN") {
      // retain = "retain" D-word : the word keeps its value across restarts (docs/il.md, .retain)
      if (w.size() != 2) fail(l.no, col0, "expected: retain Dn");
      DeviceRef d = device(w[1]);
      if (d.dev != Dev::D) fail(l.no, w[1].col, "retain needs a D word (D0..D" + std::to_string(device_count(Dev::D) - 1) + ")");
      if (std::find(retain_.begin(), retain_.end(), d) == retain_.end()) retain_.push_back(d);
    } else if (kw != "RUNG") {
      fail(l.no, col0, "expected a rung row starting with '|', 'alias', 'label', 'retain', 'rung \"title\"' or a comment");
    }
  }
}

DeviceRef Parser::device(const Word& w) { return resolve_device(w.text, w.col, aliases_, "device or alias"); }

std::string spell(DeviceRef d) { return std::string(dev_name(d.dev)) + std::to_string(d.index); }

// A bit operand: 'b' readable, 'w' writable.
Operand Parser::bit(const Word& w, char sig) {
  DeviceRef d = device(w);
  Area a = bit_area(d.dev);
  if (a == Area::Count)
    fail(0, w.col, spell(d) + " is a word; a bit device is needed here (compare words, e.g. [" + spell(d) + " <> 0])");
  if (sig == 'w') {
    if (d.dev == Dev::X) fail(0, w.col, spell(d) + " is an input; coils drive Y, M or K devices");
    if (d.dev == Dev::T || d.dev == Dev::C)
      fail(0, w.col, "the done bit of " + spell(d) + " is driven by its " + (d.dev == Dev::T ? "timer" : "counter") +
                         "; reset it with (RST " + spell(d) + ")");
    if (d.dev == Dev::S && d.index != kBitError) fail(0, w.col, spell(d) + " is a read-only system bit");
  }
  Operand o{OpdKind::Bit, a, d.index};
  return o;
}

// A word or constant: 'v' any, 'i' INT32 only, 'd' writable destination.
Operand Parser::value(const Word& w, char sig) {
  std::string why;
  bool named = aliases_.count(upper(w.text)) || parse_device(w.text) || w.text[0] == '%';
  if (!named) {
    auto c = parse_constant(w.text, why);
    if (!c) fail(0, w.col, why.empty() ? "unknown device or alias '" + w.text + "'" : why);
    if (sig == 'd') fail(0, w.col, "a constant cannot be a destination");
    if (sig == 'i' && c->kind == OpdKind::ConstReal) fail(0, w.col, "INT32 needed here, not the REAL constant " + w.text);
    return *c;
  }
  DeviceRef d = device(w);
  Area a = word_area(d.dev);
  if (a == Area::Count) fail(0, w.col, spell(d) + " is a bit; a word or a constant is needed here");
  if (sig == 'i' && a == Area::F) fail(0, w.col, "INT32 needed here; " + spell(d) + " is REAL");
  if (sig == 'd' && a == Area::WX) fail(0, w.col, spell(d) + " is an input word and cannot be written");
  Operand o{area_is_real(a) ? OpdKind::Real : OpdKind::Int, a, d.index};
  return o;
}

Operand Parser::timer_or_counter(const Word& w, char sig) {
  DeviceRef d = device(w);
  Dev want = sig == 't' ? Dev::T : Dev::C;
  if (d.dev != want) fail(0, w.col, spell(d) + " is not a " + (sig == 't' ? "timer (T0..T255)" : "counter (C0..C255)"));
  Operand o{sig == 't' ? OpdKind::Timer : OpdKind::Counter};
  o.index = d.index;
  return o;
}

std::string joined_words(const std::vector<Word>& w) {
  std::string s;
  for (auto& x : w) s += (s.empty() ? "" : " ") + x.text;
  return s;
}

// contact = ["/"] bit | ("P" | "N") bit | value cmp value | "TRUE"
// cmp     = "==" | "=" | "!=" | "<>" | "<" | "<=" | ">" | ">="
TreeNode Parser::input_element(const std::string& inner, int line, int col) {
  TreeNode n;
  n.kind = K::Leaf;
  n.elem.loc = {line, col};
  int icol = col + 1;  // column of inner[0]
  size_t opos = inner.find_first_of("=!<>");
  if (opos != std::string::npos) {
    static const std::pair<const char*, Op> cmps[] = {{"==", Op::LDEQ}, {"!=", Op::LDNE}, {"<>", Op::LDNE},
                                                      {"<=", Op::LDLE}, {">=", Op::LDGE}, {"<", Op::LDLT},
                                                      {">", Op::LDGT},  {"=", Op::LDEQ}};
    Op op = Op::LDEQ;
    size_t len = 0;
    for (auto& [s, o] : cmps)
      if (inner.compare(opos, std::strlen(s), s) == 0) { op = o; len = std::strlen(s); break; }
    if (!len) fail(line, icol + int(opos), "unknown compare operator; use == != <> < <= > >=");
    auto lhs = split_words(inner.substr(0, opos), icol), rhs = split_words(inner.substr(opos + len), icol + int(opos + len));
    if (lhs.size() != 1) fail(line, lhs.empty() ? icol + int(opos) : lhs[1].col, "a compare needs one operand on each side");
    if (rhs.size() != 1) fail(line, rhs.empty() ? icol + int(opos) : rhs[1].col, "a compare needs one operand on each side");
    n.elem.op = op;
    try {
      n.elem.a[0] = value(lhs[0], 'v');
      n.elem.a[1] = value(rhs[0], 'v');
    } catch (CompileError& e) { fail(line, e.col, e.what()); }
    n.text = lhs[0].text + " " + inner.substr(opos, len) + " " + rhs[0].text;
    return n;
  }
  auto w = split_words(inner, icol);
  if (w.empty()) fail(line, col, "empty contact []");
  try {
    if (w[0].text[0] == '/') {
      if (w[0].text.size() > 1) w[0] = {w[0].text.substr(1), w[0].col + 1};
      else w.erase(w.begin());
      if (w.size() != 1) fail(0, col, "expected a normally-closed contact like [/X1]");
      n.elem.op = Op::LOADN;
      n.elem.a[0] = bit(w[0], 'b');
      n.text = "/" + w[0].text;
    } else if (w.size() == 2 && (upper(w[0].text) == "P" || upper(w[0].text) == "N")) {
      n.elem.op = upper(w[0].text) == "P" ? Op::LOADP : Op::LOADF;
      n.elem.a[0] = bit(w[1], 'b');
      n.text = upper(w[0].text) + " " + w[1].text;
    } else if (w.size() == 1 && upper(w[0].text) == "TRUE" && !aliases_.count("TRUE")) {
      n.elem.op = Op::TRUE;  // always closed (IL TRUE); an alias named TRUE keeps its meaning
      n.text = "TRUE";
    } else if (w.size() == 1) {
      n.elem.op = Op::LOAD;
      n.elem.a[0] = bit(w[0], 'b');
      n.text = w[0].text;
    } else {
      fail(0, col, "cannot read contact [" + inner + "]; expected [X1], [/X1], [P X1], [N X1] or a compare like [D0 > 100]");
    }
  } catch (CompileError& e) { fail(line, e.col, e.what()); }
  return n;
}

// output = bit | "/" bit | ("S"|"R") bit | "RST" (bit|timer|counter)
//        | ("TON"|"TOF"|"TP"|"MTON"|"MTOF"|"MTP") timer preset | ("CTU"|"CTD") counter preset
//        | "MOV" value dst | ("ADD"|"SUB"|"MUL"|"DIV"|"MOD"|"AND"|"OR"|"XOR"|"SHL"|"SHR") value value dst
//        | ("NOT"|"SIN"|"COS"|"TAN"|"SQRT"|"EXP"|"LN"|"ABS") value dst | "JMP" label | "END"
TreeNode Parser::output_element(const std::string& inner, int line, int col, int rung_line) {
  TreeNode n;
  n.kind = K::Output;
  n.elem.loc = {line, col};
  auto w = split_words(inner, col + 1);
  if (w.empty()) fail(line, col, "empty output ()");
  n.text = joined_words(w);
  std::string kw = upper(w[0].text);
  auto want = [&](size_t count, const char* form) {
    if (w.size() != count) fail(line, col, "expected (" + std::string(form) + ")");
  };
  static const std::map<std::string, Op> arith = {
      {"ADD", Op::ADD}, {"SUB", Op::SUB}, {"MUL", Op::MUL}, {"DIV", Op::DIV}, {"MOD", Op::MOD}, {"AND", Op::WAND},
      {"OR", Op::WOR},  {"XOR", Op::WXOR}, {"SHL", Op::SHL}, {"SHR", Op::SHR}};
  static const std::map<std::string, Op> unary = {{"NOT", Op::WNOT}, {"SIN", Op::SIN}, {"COS", Op::COS},
                                                  {"TAN", Op::TAN},  {"SQRT", Op::SQRT}, {"EXP", Op::EXP},
                                                  {"LN", Op::LN},    {"ABS", Op::ABS},  {"MOV", Op::MOV}};
  try {
    Instr& in = n.elem;
    auto operands = [&](Op op) {
      in.op = op;
      const char* sig = op_info(op).operands;
      for (int i = 0; sig[i] && sig[i] != 'e'; i++) {
        const Word& x = w[i + 1];
        in.a[i] = (sig[i] == 't' || sig[i] == 'c') ? timer_or_counter(x, sig[i]) : value(x, sig[i]);
      }
    };
    if (kw == "END") {
      want(1, "END");
      in.op = Op::END;
    } else if (kw == "JMP") {
      want(2, "JMP label");
      in.op = Op::JMP;
      const LabelDef* def = nullptr;
      for (auto& d : labels_)
        if (upper(d.name) == upper(w[1].text)) def = &d;
      if (!def) fail(0, w[1].col, "undefined label '" + w[1].text + "'");
      if (def->line < rung_line) fail(0, w[1].col, "backward jump to label '" + w[1].text + "' (line " + std::to_string(def->line) + "); jumps go forward only");
      in.a[0].kind = OpdKind::Label;
      in.a[0].label = def->name;
    } else if ((kw == "S" || kw == "SET" || kw == "R" || kw == "RESET") && w.size() == 2) {
      in.op = (kw[0] == 'S') ? Op::SET : Op::RST;
      in.a[0] = bit(w[1], 'w');
    } else if (kw == "RST") {
      want(2, "RST device");
      DeviceRef d = device(w[1]);
      if (d.dev == Dev::T) { in.op = Op::RSTT; in.a[0] = timer_or_counter(w[1], 't'); }
      else if (d.dev == Dev::C) { in.op = Op::RSTC; in.a[0] = timer_or_counter(w[1], 'c'); }
      else { in.op = Op::RST; in.a[0] = bit(w[1], 'w'); }
    } else if (kw == "TON" || kw == "TOF" || kw == "TP" || kw == "MTON" || kw == "MTOF" || kw == "MTP") {
      want(3, (kw + " Tn preset").c_str());
      operands(*op_from_name(kw));
      if (in.a[1].kind == OpdKind::ConstInt && in.a[1].ival < 0) fail(0, w[2].col, "a timer preset cannot be negative");
    } else if (kw == "CTU" || kw == "CTD") {
      want(3, (kw + " Cn preset").c_str());
      operands(kw == "CTU" ? Op::CTU : Op::CTD);
    } else if (arith.count(kw)) {
      want(4, (kw + " a b destination").c_str());
      operands(arith.at(kw));
    } else if (unary.count(kw)) {
      want(3, (kw + " a destination").c_str());
      operands(unary.at(kw));
    } else if (w.size() == 1 || (w.size() == 2 && w[0].text == "/")) {
      bool neg = w[0].text[0] == '/';
      Word target = w.size() == 2 ? w[1] : neg ? Word{w[0].text.substr(1), w[0].col + 1} : w[0];
      in.op = neg ? Op::OUTN : Op::OUT;
      in.a[0] = bit(target, 'w');
    } else {
      fail(0, col, "unknown output element (" + inner + ")");
    }
  } catch (CompileError& e) { fail(line, e.col, e.what()); }
  return n;
}

// ------------------------------------------------------------------ grids

Grid Parser::grid(size_t first, size_t last, int rail) {
  Grid g;
  g.rail = rail;
  int rows = int(last - first);
  if (rows > kMaxRungRows) fail(lines_[first].no, rail + 1, "rung too tall (at most " + std::to_string(kMaxRungRows) + " rows)");
  std::vector<std::string> text(rows);
  for (int r = 0; r < rows; r++) {
    const Line& l = lines_[first + r];
    // cut a trailing "# comment" (a '#' outside any element)
    std::string s = l.text;
    int depth = 0;
    for (size_t i = 0; i < s.size(); i++) {
      char c = s[i];
      if (c == '[' || c == '(') depth++;
      else if ((c == ']' || c == ')') && depth > 0) depth--;
      else if (c == '#' && depth == 0) { s.resize(i); break; }
    }
    while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.pop_back();
    if (s.size() > size_t(kMaxRowWidth)) fail(l.no, kMaxRowWidth, "rung row too wide (at most " + std::to_string(kMaxRowWidth) + " columns)");
    size_t tab = s.find('\t');
    if (tab != std::string::npos) fail(l.no, int(tab) + 1, "tab in a rung row; use spaces so the grid lines up");
    text[r] = s;
    g.width = std::max(g.width, int(s.size()) + 1);
  }
  g.cell.assign(rows, std::vector<Cell>(g.width, Cell::Blank));
  g.tok.assign(rows, std::vector<int>(g.width, -1));
  for (int r = 0; r < rows; r++) {
    const std::string& s = text[r];
    int no = lines_[first + r].no;
    for (int c = rail + 1; c < int(s.size()); c++) {
      char ch = s[c];
      if (ch == '[' || ch == '(') {
        char close = ch == '[' ? ']' : ')';
        size_t e = s.find_first_of("[]()", c + 1);
        if (e == std::string::npos || s[e] != close)
          fail(no, c + 1, std::string("'") + ch + "' without a closing '" + close + "'");
        g.tokens.push_back({r, c, int(e), ch == '('});
        for (int k = c; k <= int(e); k++) {
          g.cell[r][k] = ch == '(' ? Cell::Out : Cell::Elem;
          g.tok[r][k] = int(g.tokens.size()) - 1;
        }
        c = int(e);
      } else if (ch == ']' || ch == ')') {
        fail(no, c + 1, std::string("unmatched '") + ch + "'");
      } else if (ch == '-') g.cell[r][c] = Cell::Wire;
      else if (ch == '+') g.cell[r][c] = Cell::Junction;
      else if (ch == '|') g.cell[r][c] = Cell::Vert;
      else if (ch != ' ')
        fail(no, c + 1, std::string("unexpected '") + ch + "' in a rung; elements are written [..] and (..)");
    }
  }
  // What may follow an output: wire, blanks and the right rail.
  std::vector<int> right_rails;
  for (const Token& t : g.tokens) {
    if (!t.output) continue;
    int no = lines_[first + t.row].no;
    int last_nb = -1;
    for (int c = t.c1 + 1; c < g.width; c++)
      if (g.at(t.row, c) != Cell::Blank) last_nb = c;
    for (int c = t.c1 + 1; c <= last_nb; c++) {
      Cell k = g.at(t.row, c);
      if (k == Cell::Out) fail(no, c + 1, "outputs cannot be in series; draw parallel outputs on rows of their own");
      if (k == Cell::Elem) fail(no, c + 1, "an element cannot follow an output; the output must end its row");
      if (k == Cell::Junction) fail(no, c + 1, "a branch cannot start after an output; the output must end its row");
      if (k == Cell::Vert && c != last_nb) fail(no, c + 1, "unexpected '|' after an output");
      if (k == Cell::Vert) right_rails.push_back(c);
    }
  }
  // The right rail, where drawn, is not part of the network.
  for (int r = 0; r < rows; r++) {
    int last_nb = -1;
    for (int c = 0; c < g.width; c++)
      if (g.cell[r][c] != Cell::Blank) last_nb = c;
    if (last_nb >= 0 && g.cell[r][last_nb] == Cell::Vert &&
        std::find(right_rails.begin(), right_rails.end(), last_nb) != right_rails.end())
      g.cell[r][last_nb] = Cell::Blank;
  }
  g.joined.resize(rows);
  for (int r = 0; r < rows; r++) {
    Cell k = g.at(r, rail + 1);
    g.joined[r] = k == Cell::Wire || k == Cell::Elem || k == Cell::Out;
  }
  return g;
}

// Every wire end, junction and vertical link must connect to something.
void Parser::check_cells(const Grid& g, int line0) {
  int rows = int(g.cell.size());
  auto left_ok = [&](int r, int c) {  // something on the left of column c feeds it
    if (c == g.rail + 1) return bool(g.joined[r]);
    Cell k = g.at(r, c - 1);
    return k == Cell::Wire || k == Cell::Junction || g.token_ends(r, c - 1);
  };
  auto right_ok = [&](int r, int c) {  // something on the right of column c takes it
    Cell k = g.at(r, c + 1);
    return k == Cell::Wire || k == Cell::Junction || g.token_starts(r, c + 1);
  };
  for (int r = 0; r < rows; r++) {
    int no = line0 + r;
    bool tail = false;  // this run of wire is drawn after an output (found once per run: linear in the width)
    for (int c = g.rail + 1; c < g.width; c++) {
      Cell k = g.cell[r][c];
      if (k == Cell::Wire) {
        if (!left_ok(r, c)) fail(no, c + 1, "dangling wire: nothing connects to its left end");
        if (g.at(r, c - 1) != Cell::Wire) tail = g.out_ends(r, c - 1);
        if (!tail && !right_ok(r, c)) fail(no, c + 1, "dangling wire: it leads nowhere");
      } else if (k == Cell::Junction) {
        int links = (c > g.rail + 1 && left_ok(r, c)) + right_ok(r, c) + g.vertical(r - 1, c) + g.vertical(r + 1, c);
        if (g.out_ends(r, c - 1)) fail(no, c + 1, "a branch cannot start after an output");
        if (links < 2) fail(no, c + 1, "dangling junction: '+' must join at least two wires");
      } else if (k == Cell::Vert) {
        if (!g.vertical(r - 1, c) || !g.vertical(r + 1, c))
          fail(no, c + 1, "dangling vertical link: '|' must connect '+' or '|' above and below");
      } else if (g.token_starts(r, c)) {
        const Token& t = g.tokens[g.tok[r][c]];
        if (g.out_ends(r, c - 1)) fail(no, c + 1, t.output ? "outputs cannot be in series" : "an element cannot follow an output");
        if (!left_ok(r, c))
          fail(no, c + 1, c == g.rail + 1 ? "not connected to the left rail" : "element not connected on its left");
        if (!t.output && !right_ok(r, t.c1))
          fail(no, c + 1, "element reaches no output: nothing connects on its right");
      }
    }
  }
}

// ------------------------------------------------------------------ reduction

struct Edge {
  int from, to;
  TreeNode term;
  bool action;
  bool alive = true;
};

SrcLoc first_loc(const TreeNode& n) {
  const TreeNode* p = &n;
  while (!p->kids.empty()) p = &p->kids[0];
  return p->elem.loc;
}
bool before(const TreeNode& a, const TreeNode& b) {
  SrcLoc x = first_loc(a), y = first_loc(b);
  return x.line != y.line ? x.line < y.line : x.col < y.col;
}

// Combine terms into a node of kind k, flattening nested nodes of the same kind.
TreeNode combine(K k, TreeNode a, TreeNode b, bool sort) {
  TreeNode n;
  n.kind = k;
  for (TreeNode* x : {&a, &b}) {
    if (x->kind == k) for (auto& kid : x->kids) n.kids.push_back(std::move(kid));
    else n.kids.push_back(std::move(*x));
  }
  if (sort) std::stable_sort(n.kids.begin(), n.kids.end(), before);
  return n;
}

TreeNode Parser::reduce(const Grid& g, int line0) {
  int rows = int(g.cell.size()), W = g.width + 1;
  // points: boundary (r, c) = r * W + c; vertical link cell (r, c) = rows * W + r * W + c
  int npts = 2 * rows * W + 2;
  const int RAIL = npts - 2;
  UnionFind uf(npts);
  auto B = [&](int r, int c) { return r * W + c; };
  auto V = [&](int r, int c) { return g.at(r, c) == Cell::Junction ? B(r, c) : rows * W + r * W + c; };
  for (int r = 0; r < rows; r++) {
    if (g.joined[r]) uf.join(B(r, g.rail + 1), RAIL);
    for (int c = g.rail + 1; c < g.width; c++) {
      Cell k = g.cell[r][c];
      if (k == Cell::Wire || k == Cell::Junction) uf.join(B(r, c), B(r, c + 1));
      if (g.vertical(r, c) && g.vertical(r + 1, c)) uf.join(V(r, c), V(r + 1, c));
    }
  }
  // nodes and edges
  std::vector<int> node_of(size_t(npts), -1);
  int nodes = 0;
  auto node = [&](int pt) {
    int& id = node_of[size_t(uf.find(pt))];
    if (id < 0) id = nodes++;
    return id;
  };
  int rail = node(RAIL);
  std::vector<Edge> edges;
  std::vector<int> outputs_at;
  int rung_line = line0;
  for (const Token& t : g.tokens) {
    int no = line0 + t.row;
    const std::string& src = lines_[size_t(no - 1)].text;
    std::string raw = src.substr(t.c0 + 1, t.c1 - t.c0 - 1);
    Edge e;
    e.from = node(B(t.row, t.c0));
    if (t.output) {
      e.term = output_element(raw, no, t.c0 + 1, rung_line);
      e.to = -1;  // the sink, set below
      e.action = true;
      outputs_at.push_back(e.from);
    } else {
      e.term = input_element(raw, no, t.c0 + 1);
      e.to = node(B(t.row, t.c1 + 1));
      e.action = false;
      if (e.from == e.to) fail(no, t.c0 + 1, "element is short-circuited: a wire joins its two ends");
    }
    edges.push_back(std::move(e));
  }
  if (outputs_at.empty()) fail(line0, g.rail + 1, "rung has no output");
  const int SINK = nodes;
  int nn = SINK + 1;
  for (auto& e : edges)
    if (e.action) e.to = SINK;
  // every element must lie on a path from the rail to an output
  std::vector<std::vector<int>> fwd(nn), bwd(nn);
  for (size_t i = 0; i < edges.size(); i++) {
    fwd[edges[i].from].push_back(int(i));
    bwd[edges[i].to].push_back(int(i));
  }
  auto reach = [&](int start, bool forward) {
    std::vector<char> seen(nn, 0);
    std::vector<int> st{start};
    seen[start] = 1;
    while (!st.empty()) {
      int v = st.back();
      st.pop_back();
      for (int ei : (forward ? fwd[v] : bwd[v])) {
        int u = forward ? edges[ei].to : edges[ei].from;
        if (!seen[u]) { seen[u] = 1; st.push_back(u); }
      }
    }
    return seen;
  };
  auto from_rail = reach(rail, true), to_out = reach(SINK, false);
  for (auto& e : edges) {
    SrcLoc l = e.term.elem.loc;
    if (!from_rail[e.from]) fail(l.line, l.col, "not connected to the left power rail");
    if (!to_out[e.to]) fail(l.line, l.col, "element reaches no output");
  }
  // series/parallel reduction, keeping the adjacency lists up to date
  std::vector<std::vector<int>> out(nn), in(nn);
  for (size_t i = 0; i < edges.size(); i++) {
    out[edges[i].from].push_back(int(i));
    in[edges[i].to].push_back(int(i));
  }
  auto unlink = [](std::vector<int>& v, int e) { v.erase(std::find(v.begin(), v.end(), e)); };
  for (bool changed = true; changed;) {
    changed = false;
    for (int u = 0; u < nn; u++) {
      // parallel: edges from u with the same far end become one
      auto& o = out[u];
      for (size_t a = 0; a < o.size(); a++) {
        for (size_t b = a + 1; b < o.size();) {
          Edge& ea = edges[o[a]];
          Edge& eb = edges[o[b]];
          if (eb.to != ea.to) { b++; continue; }
          ea.term = combine(ea.action ? K::Fork : K::Parallel, std::move(ea.term), std::move(eb.term), true);
          eb.alive = false;
          unlink(in[eb.to], o[b]);
          o.erase(o.begin() + long(b));
          changed = true;
        }
      }
      // series: u with one edge in and one edge out joins them
      if (u == rail || u == SINK || in[u].size() != 1 || out[u].size() != 1 || in[u][0] == out[u][0]) continue;
      int i1 = in[u][0], i2 = out[u][0];
      Edge& e1 = edges[i1];
      Edge& e2 = edges[i2];
      if (e2.action) {
        TreeNode t;
        t.kind = K::Then;
        t.kids.push_back(std::move(e1.term));
        t.kids.push_back(std::move(e2.term));
        e1.term = std::move(t);
        e1.action = true;
      } else {
        e1.term = combine(K::Series, std::move(e1.term), std::move(e2.term), false);
      }
      unlink(in[e2.to], i2);
      in[e2.to].push_back(i1);
      e1.to = e2.to;
      e2.alive = false;
      in[u].clear();
      out[u].clear();
      changed = true;
    }
  }
  std::vector<Edge*> left;
  for (auto& e : edges)
    if (e.alive) left.push_back(&e);
  if (left.size() == 1 && left[0]->from == rail && left[0]->to == SINK) return std::move(left[0]->term);
  // Not series-parallel: point at a bridging element if there is one.
  std::vector<int> indeg(nn), outdeg(nn);
  for (Edge* e : left) { outdeg[e->from]++; indeg[e->to]++; }
  Edge* culprit = left[0];
  for (Edge* e : left)
    if (!e->action && outdeg[e->from] >= 2 && indeg[e->to] >= 2 && e->from != rail) { culprit = e; break; }
  SrcLoc l = first_loc(culprit->term);
  fail(l.line, l.col, "network is not series-parallel (a bridge); redraw it as series and parallel blocks");
}

TreeRung Parser::rung(size_t first, size_t last, int rail) {
  Grid g = grid(first, last, rail);
  int line0 = lines_[first].no;
  check_cells(g, line0);
  TreeRung r;
  r.line = line0;
  r.root = reduce(g, line0);
  return r;
}

// program = { blank | comment | alias | label | title | rung }
// title   = "rung" STRING         (directly above its rung)
// rung    = row { row }           (first non-blank character '|', all in one column)
TreeProgram Parser::program() {
  read_lines();
  declarations();
  TreeProgram p;
  p.source = file_;
  p.aliases = alias_list_;
  p.retain = retain_;
  std::vector<std::string> labels;
  std::string title;
  int title_line = 0;
  for (size_t i = 0; i < lines_.size();) {
    const Line& l = lines_[i];
    std::string t = trim(l.text);
    int col0 = int(l.text.find_first_not_of(" \t")) + 1;
    if (title_line && (t.empty() || t[0] != '|'))
      fail(title_line, 1, "a rung title must be directly above its rung");
    if (t.empty() || is_comment(t)) { i++; continue; }
    if (t[0] == '|') {
      int rail = col0 - 1;
      size_t j = i;
      while (j < lines_.size()) {
        std::string u = trim(lines_[j].text);
        if (u.empty() || u[0] != '|') break;
        int c = int(lines_[j].text.find_first_not_of(" \t"));
        if (c != rail) fail(lines_[j].no, c + 1, "left rail out of line: this rung's rail is in column " + std::to_string(rail + 1));
        j++;
      }
      if (p.rungs.size() >= kMaxRungs) fail(l.no, col0, "too many rungs (at most " + std::to_string(kMaxRungs) + ")");
      TreeRung r = rung(i, j, rail);
      r.labels = std::move(labels);
      labels.clear();
      r.title = title;
      title.clear();
      title_line = 0;
      p.rungs.push_back(std::move(r));
      i = j;
      continue;
    }
    auto w = split_words(t, col0);
    std::string kw = upper(w[0].text);
    if (kw == "LABEL") labels.push_back(w[1].text);
    else if (kw == "RUNG") {
      size_t q1 = l.text.find('"'), q2 = l.text.rfind('"');
      if (q1 == std::string::npos || q2 == q1 || trim(l.text.substr(q2 + 1)) != "" ||
          upper(trim(l.text.substr(0, q1))) != "RUNG")
        fail(l.no, col0, "expected: rung \"title\"");
      title = l.text.substr(q1 + 1, q2 - q1 - 1);
      title_line = l.no;
    }
    i++;
  }
  if (title_line) fail(title_line, 1, "a rung title must be directly above its rung");
  p.end_labels = std::move(labels);
  if (p.rungs.empty()) fail(std::max(1, int(lines_.size())), 1, "no rungs in this program");
  return p;
}

}  // namespace

TreeProgram parse_ld(std::string_view text, const std::string& filename) { return Parser(text, filename).program(); }

TreeProgram parse_ld(std::string_view text, const std::string& filename, const std::vector<Alias>& predefined) {
  Parser p(text, filename);
  p.predefine(predefined);
  return p.program();
}

}  // namespace ldc
