// frontend/parse.cpp -- the .ld reader: source lines, rung grids, elements.
//
// A rung grid becomes a graph: every column boundary of every row is a point;
// wires and junctions join points into nodes, vertical links join rows, input
// elements are edges from the node on their left to the node on their right,
// and outputs hang on the node on their left.  Series/parallel reduction of that
// graph gives the rung tree of paper 003 (Fig. 5); what does not reduce is a
// bridge and is refused.
//
// The reader copies nothing it does not keep: lines and words are views into
// the source text; a rung's cells, points, nodes and adjacency lists live in
// flat arrays that every rung reuses; the reduction works on a small forest of
// indices (Forest) and builds each TreeNode once, at the end
// (docs/architecture.md, "The .ld reader").
#include <algorithm>
#include <cstring>
#include <functional>
#include <map>
#include <numeric>
#include <set>

#include "frontend/diag.h"
#include "frontend/frontend.h"
#include "frontend/operands.h"

namespace ldc {

std::string format_error(const std::string& file, std::string_view text, int line, int col, const std::string& msg) {
  return format_diagnostic(file, text, line, col, Severity::Error, msg);
}

namespace {

using K = TreeNode::Kind;

[[noreturn]] void fail(int line, int col, const std::string& msg) { throw CompileError(line, col, msg); }

std::string str(std::string_view s) { return std::string(s); }

// Element keywords are read by position (the first word of a multi-word
// element), so an alias may be called `start`, `reset` or `S`.  Only `END`,
// a one-word output of its own, would be ambiguous.
bool is_keyword(std::string_view s) { return iequals(s, "END"); }

struct Word {
  std::string_view text;  // a view into the source
  int col;                // 1-based column in the source line
};

// The blank-separated words of s into w (its storage reused).
void split_words(std::string_view s, int col0, std::vector<Word>& w) {
  w.clear();
  size_t i = 0;
  while (i < s.size()) {
    if (s[i] == ' ') { i++; continue; }
    size_t st = i;
    while (i < s.size() && s[i] != ' ') i++;
    w.push_back({s.substr(st, i - st), col0 + int(st)});
  }
}

bool is_blank(char c) { return c == ' ' || c == '\t'; }

std::string_view trim(std::string_view s) {
  while (!s.empty() && is_blank(s.front())) s.remove_prefix(1);
  while (!s.empty() && is_blank(s.back())) s.remove_suffix(1);
  return s;
}

// The column (0-based) of the first character that is not a blank, -1 for none.
int indent(std::string_view s) {
  size_t i = 0;
  while (i < s.size() && is_blank(s[i])) i++;
  return i == s.size() ? -1 : int(i);
}

bool is_comment(std::string_view s) {
  std::string_view t = trim(s);
  return t.starts_with("#") || t.starts_with("//");
}

// A `rung "title"` line (read with its rung): its first word is "rung".
bool is_title(std::string_view t) { return t.size() >= 4 && iequals(t.substr(0, 4), "RUNG") && (t.size() == 4 || t[4] == ' '); }

// ------------------------------------------------------------------ cells

enum class Cell : uint8_t { Blank, Wire, Junction, Vert, Elem, Out };

struct Token {
  int row, c0, c1;  // columns (0-based) of the brackets
  bool output;
};

// One rung's cells, row-major in flat arrays that the next rung reuses.  A
// border of blank cells around the grid lets every neighbour look-up (one
// row or column off the grid) go without a bounds check.
struct Grid {
  int rail = 0;       // column of the left rail
  int width = 0;      // columns, rail included
  int rows = 0;
  std::vector<Cell> cell;    // (rows + 2) * (width + 2), the border included
  std::vector<int> tok;      // token index at Elem/Out cells, else -1
  std::vector<Token> tokens;
  std::vector<char> joined;  // row joined to the left rail
  std::vector<std::string_view> text;  // the rows, trailing comment and blanks cut
  std::vector<int> right_rails;

  int stride = 0;     // width + 2
  int verts = 0;      // '|' cells drawn
  // (r, c) for -1 <= r <= rows, -1 <= c <= width
  size_t idx(int r, int c) const { return size_t(r * stride + c + stride + 1); }
  size_t cells() const { return size_t(rows + 2) * size_t(stride); }
  Cell at(int r, int c) const { return cell[idx(r, c)]; }
  const Token& token(int r, int c) const { return tokens[size_t(tok[idx(r, c)])]; }
  bool token_starts(int r, int c) const { return (at(r, c) == Cell::Elem || at(r, c) == Cell::Out) && token(r, c).c0 == c; }
  bool token_ends(int r, int c) const { return (at(r, c) == Cell::Elem || at(r, c) == Cell::Out) && token(r, c).c1 == c; }
  bool elem_ends(int r, int c) const { return at(r, c) == Cell::Elem && token(r, c).c1 == c; }
  bool out_ends(int r, int c) const { return at(r, c) == Cell::Out && token(r, c).c1 == c; }
  bool vertical(int r, int c) const { return at(r, c) == Cell::Junction || at(r, c) == Cell::Vert; }
};

struct UnionFind {
  std::vector<int> p;
  void reset(size_t n) {
    p.resize(n);
    std::iota(p.begin(), p.end(), 0);
  }
  int find(int x) {
    while (p[x] != x) x = p[x] = p[p[x]];
    return x;
  }
  void join(int a, int b) { p[find(a)] = find(b); }
};

// ------------------------------------------------------------------ the forest
// The rung's tree while the graph is reduced.  A leaf stands for a parsed
// element (an index into Parser::elems_); a node's kids are a list through
// `next`, so flattening a node into its parent and merging two sorted lists of
// branches splice indices.  `loc` is the location of the node's first element
// (the key branches are sorted by, top to bottom).

struct PNode {
  K kind;
  int elem = -1;                      // Leaf / Output: the element
  int first = -1, last = -1, next = -1;
  SrcLoc loc;
};

bool before(SrcLoc x, SrcLoc y) { return x.line != y.line ? x.line < y.line : x.col < y.col; }

struct Forest {
  std::vector<PNode> nodes;

  int leaf(K k, int elem, SrcLoc loc) {
    nodes.push_back({k, elem, -1, -1, -1, loc});
    return int(nodes.size()) - 1;
  }
  int add(K k, int first, int last) {
    nodes.push_back({k, -1, first, last, -1, nodes[size_t(first)].loc});
    return int(nodes.size()) - 1;
  }
  // x's kids if it is of kind k (flattening), else x alone
  void list(K k, int x, int& first, int& last) {
    PNode& n = nodes[size_t(x)];
    if (n.kind == k) { first = n.first, last = n.last; }
    else { first = last = x, n.next = -1; }
  }
  // Combine terms into a node of kind k, flattening nested nodes of the same
  // kind; `sort`: branches by their first element (a stable merge: both lists
  // are sorted already).
  int combine(K k, int a, int b, bool sort) {
    int fa, la, fb, lb;
    list(k, a, fa, la);
    list(k, b, fb, lb);
    if (!sort) {
      nodes[size_t(la)].next = fb;
      return add(k, fa, lb);
    }
    int head = -1, tail = -1;
    auto append = [&](int x) {
      if (tail < 0) head = x;
      else nodes[size_t(tail)].next = x;
      tail = x;
    };
    while (fa >= 0 && fb >= 0) {
      int& from = before(nodes[size_t(fb)].loc, nodes[size_t(fa)].loc) ? fb : fa;
      int x = from;
      from = nodes[size_t(x)].next;
      append(x);
    }
    if (fa >= 0) append(fa), tail = la;
    else if (fb >= 0) append(fb), tail = lb;
    return add(k, head, tail);
  }
  int then(int cond, int action) {
    nodes[size_t(cond)].next = action;
    nodes[size_t(action)].next = -1;
    return add(K::Then, cond, action);
  }
};

struct Edge {
  int from, to;
  int term;  // a node of the forest
  bool action;
  bool alive = true;
};

// ------------------------------------------------------------------ parser

class Parser {
 public:
  // With `diag`, an error is reported there and the reader goes on with the
  // next declaration or rung (the program then ends with ErrorsReported);
  // without, the first error is thrown as it is.
  Parser(std::string_view text, std::string file, Diagnostics* diag = nullptr)
      : text_(text), file_(std::move(file)), diag_(diag) {}
  // names the file may use without declaring them (not listed in its aliases)
  void predefine(const std::vector<Alias>& names) {
    for (const Alias& a : names) aliases_[upper(a.name)] = AliasEntry{a.dev, a.name, 0, 0, true};
  }
  // The program; each rung's tree goes to `sink` as it is read (the returned
  // program then has no rungs), or, without a sink, into the program.
  TreeProgram program(const std::function<void(TreeRung&&)>& sink = nullptr);

 private:
  struct LabelDef {
    std::string name;
    int line, col = 1;
    bool used = false;
  };
  struct AliasEntry {
    DeviceRef dev;
    std::string name;   // as declared
    int line, col;      // of its declaration (0: predefined)
    bool used = false;  // for -Wunused
  };

  std::string_view text_;
  std::string file_;
  Diagnostics* diag_;
  bool quiet_ = false;  // the error at hand follows from one reported already: not reported
  std::set<std::string> poisoned_;            // aliases whose declaration had an error (upper case)
  std::vector<std::string_view> lines_;       // line n is lines_[n - 1]
  std::map<std::string, AliasEntry> aliases_;  // key: upper-case name
  std::vector<LabelDef> labels_;
  std::vector<Alias> alias_list_;  // in source order
  std::vector<DeviceRef> retain_;  // `retain Dn` lines, in source order
  size_t rung_count_ = 0;          // rungs in the file (seen by declarations)

  // per-rung working storage, reused by the next rung
  Grid g_;
  UnionFind uf_;
  std::vector<int> node_of_;  // point -> node
  int nodes_ = 0;
  int rail_point_ = 0;
  std::vector<Edge> edges_;
  std::vector<TreeNode> elems_;              // the parsed elements
  Forest forest_;
  std::vector<std::vector<int>> out_, in_;   // edges leaving / entering each node
  std::vector<char> from_rail_, to_out_;
  std::vector<int> stack_;
  std::vector<Word> words_, words2_;
  std::string key_;

  void read_lines();
  void declarations();
  void declaration(int no);
  void alias_declaration(int no, int col0);
  size_t rung_end(size_t i, int rail, int& misplaced);
  TreeRung rung(size_t first, size_t last, int rail);
  void grid(size_t first, size_t last, int rail);
  void grid_rows(size_t first, int rail);
  void grid_cells(size_t first, int rail);
  void grid_right_rails(size_t first);
  void check_cells(const Grid& g, int line0);
  TreeNode reduce(const Grid& g, int line0);
  void join_points(const Grid& g);
  int node(int pt);
  void element_edges(const Grid& g, int line0);
  void check_paths();
  void reach(int start, bool forward, std::vector<char>& seen);
  void series_parallel(int rail, int sink);
  [[noreturn]] void refuse_bridge(int rail);
  void build(int term, TreeNode& out);

  TreeNode input_element(std::string_view inner, int line, int col);
  TreeNode output_element(std::string_view inner, int line, int col, int rung_line);

  const DeviceRef* alias(std::string_view name);
  [[noreturn]] void unknown_name(const Word& w);
  bool recover(const std::function<void()>& read);
  void report(int line, int col, const std::string& msg);
  void warn_unused();
  DeviceRef device(const Word& w);
  Operand bit(const Word& w, char sig);
  Operand value(const Word& w, char sig);
  Operand timer_or_counter(const Word& w, char sig);
};

void Parser::read_lines() { lines_ = source_line_views(text_); }

// declarations: alias = "alias" NAME "=" device ;  label = "label" NAME ;
// Read first, so aliases and labels may be used anywhere in the file.
void Parser::declarations() {
  bool in_rung = false;
  for (size_t i = 0; i < lines_.size(); i++) {
    std::string_view t = trim(lines_[i]);
    bool row = !t.empty() && t[0] == '|';
    rung_count_ += row && !in_rung;
    in_rung = row;
    if (t.empty() || is_comment(t) || row || is_title(t)) continue;
    recover([&] { declaration(int(i) + 1); });
  }
}

void Parser::declaration(int no) {
  std::string_view text = lines_[size_t(no - 1)];
  int col0 = indent(text) + 1;
  split_words(text.substr(col0 - 1), col0, words_);
  const std::vector<Word>& w = words_;
  if (iequals(w[0].text, "ALIAS")) {
    alias_declaration(no, col0);
  } else if (iequals(w[0].text, "LABEL")) {
    if (w.size() != 2 || !is_identifier(w[1].text)) fail(no, col0, "expected: label NAME");
    for (auto& d : labels_)
      if (iequals(d.name, w[1].text))
        throw NotedError(no, w[1].col, "duplicate label '" + str(w[1].text) + "'", {{d.line, d.col, "first defined here"}});
    labels_.push_back({str(w[1].text), no, w[1].col});
  } else if (iequals(w[0].text, "RETAIN")) {
    // retain = "retain" D-word : the word keeps its value across restarts (docs/il.md, .retain)
    if (w.size() != 2) fail(no, col0, "expected: retain Dn");
    DeviceRef d = device(w[1]);
    if (d.dev != Dev::D) fail(no, w[1].col, "retain needs a D word (D0..D" + std::to_string(device_count(Dev::D) - 1) + ")");
    if (std::find(retain_.begin(), retain_.end(), d) == retain_.end()) retain_.push_back(d);
  } else if (!iequals(w[0].text, "RUNG")) {
    fail(no, col0, "expected a rung row starting with '|', 'alias', 'label', 'retain', 'rung \"title\"' or a comment");
  }
}

// alias = "alias" NAME "=" device [":" TYPE]   ("alias a=X1", "alias a = X1", "alias n = D0 : LINT")
void Parser::alias_declaration(int no, int col0) {
  std::string_view text = lines_[size_t(no - 1)];
  // the name as far as it can be read: should the declaration be refused, its uses say nothing more
  if (words_.size() > 1) {
    std::string_view first = words_[1].text.substr(0, words_[1].text.find('='));
    if (is_identifier(first) && !aliases_.count(upper(first))) poisoned_.insert(upper(first));
  }
  std::string rest = str(trim(text.substr(col0 - 1 + 5)));
  size_t eq = rest.find('=');
  int rest_col = int(text.find(rest, col0 - 1 + 5)) + 1;
  if (eq == std::string::npos) fail(no, col0, "expected: alias NAME = DEVICE");
  std::string name = str(trim(std::string_view(rest).substr(0, eq)));
  std::string_view target = trim(std::string_view(rest).substr(eq + 1));
  if (!is_identifier(name)) fail(no, rest_col, "alias name '" + name + "' must be letters, digits and _");
  std::string why;
  if (parse_device(name) || parse_iec_address(name, why) || is_keyword(name))
    fail(no, rest_col, "'" + name + "' cannot be an alias name: it is a device or a keyword");
  std::string key = upper(name);
  if (auto it = aliases_.find(key); it != aliases_.end())
    throw NotedError(no, rest_col, "alias '" + name + "' is already defined",
                     it->second.line ? std::vector<DiagNote>{{it->second.line, it->second.col, "first defined here"}}
                                     : std::vector<DiagNote>{});
  poisoned_.insert(key);  // until the declaration is read: its uses then say nothing more
  if (target.empty()) fail(no, rest_col + int(eq) + 1, "expected a device after '='");
  int tcol = int(text.rfind(target)) + 1;
  Ty ty = Ty::None;  // "= D0 : LINT": the variable's type (docs/format.md)
  if (size_t colon = target.find(':'); colon != std::string_view::npos) {
    std::string_view tname = trim(target.substr(colon + 1));
    int ncol = int(text.rfind(tname)) + 1;
    auto t = ty_from_name(tname);
    if (!t) fail(no, ncol, "unknown type '" + str(tname) + "' (an IEC elementary type: INT, LINT, UDINT, LREAL, TIME ...)");
    ty = *t;
    target = trim(target.substr(0, colon));
    if (target.empty()) fail(no, tcol, "expected a device before ':'");
  }
  DeviceRef dev;
  try {
    dev = device(Word{target, tcol});
  } catch (CompileError& e) {
    e.line = no;
    throw;
  }
  Alias a{name, dev, ty};
  if (std::string why = alias_type_problem(a); !why.empty()) fail(no, tcol, why);
  aliases_[key] = AliasEntry{dev, name, no, rest_col};
  poisoned_.erase(key);
  alias_list_.push_back(std::move(a));
}

const DeviceRef* Parser::alias(std::string_view name) {
  if (aliases_.empty()) return nullptr;
  key_.assign(name);
  for (char& c : key_) c = upper_ascii(c);
  auto it = aliases_.find(key_);
  if (it == aliases_.end()) return nullptr;
  it->second.used = true;
  return &it->second.dev;
}

std::string spell(DeviceRef d) { return std::string(dev_name(d.dev)) + std::to_string(d.index); }

// "; did you mean '%IX0.1' (X1)?" for `I0.1`: the IEC direct address a
// name written without its '%' (or without the X of a bit) looks like; `Q7`
// (another PLC's output 7) is ldc's Y7.
std::string iec_hint(std::string_view text) {
  std::vector<std::string> tries = {"%" + str(text)};
  char c0 = text.empty() ? 0 : upper_ascii(text[0]);
  if ((c0 == 'I' || c0 == 'Q' || c0 == 'M') && text.size() > 1 && text[1] >= '0' && text[1] <= '9' &&
      text.find('.') != std::string_view::npos)
    tries.push_back("%" + std::string(1, c0) + "X" + str(text.substr(1)));
  for (const std::string& t : tries) {
    std::string why;
    auto d = parse_iec_address(t, why);
    if (d && d->index < device_count(d->dev)) return "; did you mean '" + upper(t) + "' (" + spell(*d) + ")?";
  }
  // I5 and Q5 in other PLCs' spelling are ldc's X5 and Y5
  if ((c0 == 'I' || c0 == 'Q') && text.size() > 1 && text.find_first_not_of("0123456789", 1) == std::string_view::npos) {
    auto d = parse_device(std::string(c0 == 'I' ? "X" : "Y") + str(text.substr(1)));
    if (d && d->index < device_count(d->dev))
      return "; did you mean '" + spell(*d) + "' (" + (c0 == 'I' ? "inputs" : "outputs") + " are " + dev_name(d->dev) + " devices)?";
  }
  return "";
}

// An unknown name: the alias it is a typo of (within an edit distance of
// 2), or the IEC address it looks like.  A name whose alias declaration had
// an error says nothing more (the error is reported already).
void Parser::unknown_name(const Word& w) {
  std::string msg = "unknown device or alias '" + str(w.text) + "'";
  if (poisoned_.count(upper(w.text))) {
    quiet_ = true;
    fail(0, w.col, msg);
  }
  std::vector<std::string> names;
  for (const auto& [key, a] : aliases_) names.push_back(a.name);
  if (std::string near = closest_name(w.text, names); !near.empty()) {
    const AliasEntry& a = aliases_.at(upper(near));
    std::vector<DiagNote> notes;
    if (a.line) notes.push_back({a.line, a.col, "'" + a.name + "' declared here"});
    throw NotedError(0, w.col, msg + "; did you mean '" + near + "'?", notes);
  }
  fail(0, w.col, msg + iec_hint(w.text));
}

DeviceRef Parser::device(const Word& w) {
  if (const DeviceRef* d = alias(w.text)) return *d;
  try {
    return resolve_device_spelling(w.text, w.col, "device or alias");
  } catch (CompileError& e) {
    if (std::string_view(e.what()).starts_with("unknown device or alias")) unknown_name(w);
    throw;
  }
}

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
  const DeviceRef* al = alias(w.text);
  std::optional<DeviceRef> spelled = al ? std::nullopt : parse_device(w.text);
  bool named = al || spelled || w.text[0] == '%';
  if (!named) {
    auto c = parse_constant(w.text, why);
    if (!c && why.empty()) unknown_name(w);
    if (!c) fail(0, w.col, why);
    if (sig == 'd') fail(0, w.col, "a constant cannot be a destination");
    if (sig == 'i' && c->kind == OpdKind::ConstReal) fail(0, w.col, "INT32 needed here, not the REAL constant " + str(w.text));
    return *c;
  }
  DeviceRef d = al ? *al : spelled ? device_in_range(*spelled, w.text, w.col) : device(w);
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
  size_t n = 0;
  for (auto& x : w) n += x.text.size() + 1;
  std::string s;
  s.reserve(n);
  for (auto& x : w) {
    if (!s.empty()) s += ' ';
    s += x.text;
  }
  return s;
}

// contact = ["/"] bit | ("P" | "N") bit | value cmp value | "TRUE"
// cmp     = "==" | "=" | "!=" | "<>" | "<" | "<=" | ">" | ">="
TreeNode Parser::input_element(std::string_view inner, int line, int col) {
  TreeNode n;
  n.kind = K::Leaf;
  n.elem.loc = {line, col};
  int icol = col + 1;  // column of inner[0]
  size_t opos = inner.find_first_of("=!<>");
  if (opos != std::string_view::npos) {
    static const std::pair<const char*, Op> cmps[] = {{"==", Op::LDEQ}, {"!=", Op::LDNE}, {"<>", Op::LDNE},
                                                      {"<=", Op::LDLE}, {">=", Op::LDGE}, {"<", Op::LDLT},
                                                      {">", Op::LDGT},  {"=", Op::LDEQ}};
    Op op = Op::LDEQ;
    size_t len = 0;
    for (auto& [s, o] : cmps)
      if (inner.compare(opos, std::strlen(s), s) == 0) { op = o; len = std::strlen(s); break; }
    if (!len) fail(line, icol + int(opos), "unknown compare operator; use == != <> < <= > >=");
    std::vector<Word>& lhs = words_;
    std::vector<Word>& rhs = words2_;
    split_words(inner.substr(0, opos), icol, lhs);
    split_words(inner.substr(opos + len), icol + int(opos + len), rhs);
    if (lhs.size() != 1) fail(line, lhs.empty() ? icol + int(opos) : lhs[1].col, "a compare needs one operand on each side");
    if (rhs.size() != 1) fail(line, rhs.empty() ? icol + int(opos) : rhs[1].col, "a compare needs one operand on each side");
    n.elem.op = op;
    try {
      n.elem.a[0] = value(lhs[0], 'v');
      n.elem.a[1] = value(rhs[0], 'v');
    } catch (CompileError& e) {
      e.line = line;
      throw;
    }
    n.text.reserve(lhs[0].text.size() + len + rhs[0].text.size() + 2);
    n.text.append(lhs[0].text).append(" ").append(inner.substr(opos, len)).append(" ").append(rhs[0].text);
    return n;
  }
  std::vector<Word>& w = words_;
  split_words(inner, icol, w);
  if (w.empty()) fail(line, col, "empty contact []");
  try {
    if (w[0].text[0] == '/') {
      if (w[0].text.size() > 1) w[0] = {w[0].text.substr(1), w[0].col + 1};
      else w.erase(w.begin());
      if (w.size() != 1) fail(0, col, "expected a normally-closed contact like [/X1]");
      n.elem.op = Op::LOADN;
      n.elem.a[0] = bit(w[0], 'b');
      n.text.append("/").append(w[0].text);
    } else if (w.size() == 2 && (iequals(w[0].text, "P") || iequals(w[0].text, "N"))) {
      n.elem.op = iequals(w[0].text, "P") ? Op::LOADP : Op::LOADF;
      n.elem.a[0] = bit(w[1], 'b');
      n.text.append(upper(w[0].text)).append(" ").append(w[1].text);
    } else if (w.size() == 1 && iequals(w[0].text, "TRUE") && !aliases_.count("TRUE")) {
      n.elem.op = Op::TRUE;  // always closed (IL TRUE); an alias named TRUE keeps its meaning
      n.text = "TRUE";
    } else if (w.size() == 1) {
      n.elem.op = Op::LOAD;
      n.elem.a[0] = bit(w[0], 'b');
      n.text = w[0].text;
    } else {
      fail(0, col, "cannot read contact [" + str(inner) + "]; expected [X1], [/X1], [P X1], [N X1] or a compare like [D0 > 100]");
    }
  } catch (CompileError& e) {
    e.line = line;
    throw;
  }
  return n;
}

struct NamedOp {
  std::string_view name;
  Op op;
};
// word arithmetic and logic: a b destination
constexpr NamedOp kArith[] = {{"ADD", Op::ADD}, {"SUB", Op::SUB}, {"MUL", Op::MUL},   {"DIV", Op::DIV},
                              {"MOD", Op::MOD}, {"AND", Op::WAND}, {"OR", Op::WOR},   {"XOR", Op::WXOR},
                              {"SHL", Op::SHL}, {"SHR", Op::SHR}};
// a destination
constexpr NamedOp kUnary[] = {{"NOT", Op::WNOT}, {"SIN", Op::SIN}, {"COS", Op::COS}, {"TAN", Op::TAN}, {"SQRT", Op::SQRT},
                              {"EXP", Op::EXP},  {"LN", Op::LN},   {"ABS", Op::ABS}, {"MOV", Op::MOV}};

constexpr NamedOp kTimers[] = {{"TON", Op::TON},   {"TOF", Op::TOF},   {"TP", Op::TP},
                               {"MTON", Op::MTON}, {"MTOF", Op::MTOF}, {"MTP", Op::MTP}};

// `word` upper-case in buf when it is short enough to be a keyword, else ""
// (which is no keyword).
std::string_view keyword(std::string_view word, char (&buf)[8]) {
  if (word.size() >= sizeof buf) return {};
  for (size_t i = 0; i < word.size(); i++) buf[i] = upper_ascii(word[i]);
  return {buf, word.size()};
}

template <size_t N>
const NamedOp* find_op(const NamedOp (&table)[N], std::string_view kw) {
  for (const NamedOp& o : table)
    if (kw == o.name) return &o;
  return nullptr;
}

// output = bit | "/" bit | ("S"|"R") bit | "RST" (bit|timer|counter)
//        | ("TON"|"TOF"|"TP"|"MTON"|"MTOF"|"MTP") timer preset | ("CTU"|"CTD") counter preset
//        | "MOV" value dst | ("ADD"|"SUB"|"MUL"|"DIV"|"MOD"|"AND"|"OR"|"XOR"|"SHL"|"SHR") value value dst
//        | ("NOT"|"SIN"|"COS"|"TAN"|"SQRT"|"EXP"|"LN"|"ABS") value dst | "JMP" label | "END"
TreeNode Parser::output_element(std::string_view inner, int line, int col, int rung_line) {
  TreeNode n;
  n.kind = K::Output;
  n.elem.loc = {line, col};
  std::vector<Word>& w = words_;
  split_words(inner, col + 1, w);
  if (w.empty()) fail(line, col, "empty output ()");
  n.text = joined_words(w);
  char kwbuf[8];  // the first word upper-case (keywords are short)
  std::string_view kw = keyword(w[0].text, kwbuf);
  auto want = [&](size_t count, const char* form) {
    if (w.size() != count) fail(line, col, "expected (" + std::string(form) + ")");
  };
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
      LabelDef* def = nullptr;
      for (auto& d : labels_)
        if (iequals(d.name, w[1].text)) def = &d;
      if (!def) {
        std::vector<std::string> names;
        for (auto& d : labels_) names.push_back(d.name);
        std::string near = closest_name(w[1].text, names);
        std::vector<DiagNote> notes;
        for (auto& d : labels_)
          if (d.name == near) notes.push_back({d.line, d.col, "'" + near + "' defined here"});
        throw NotedError(0, w[1].col, "undefined label '" + str(w[1].text) + "'" + (near.empty() ? "" : "; did you mean '" + near + "'?"), notes);
      }
      def->used = true;
      if (def->line < rung_line) fail(0, w[1].col, "backward jump to label '" + str(w[1].text) + "' (line " + std::to_string(def->line) + "); jumps go forward only");
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
    } else if (const NamedOp* tm = find_op(kTimers, kw)) {
      want(3, (str(kw) + " Tn preset").c_str());
      operands(tm->op);
      if (in.a[1].kind == OpdKind::ConstInt && in.a[1].ival < 0) fail(0, w[2].col, "a timer preset cannot be negative");
    } else if (kw == "CTU" || kw == "CTD") {
      want(3, (str(kw) + " Cn preset").c_str());
      operands(kw == "CTU" ? Op::CTU : Op::CTD);
    } else if (const NamedOp* ar = find_op(kArith, kw)) {
      want(4, (str(kw) + " a b destination").c_str());
      operands(ar->op);
    } else if (const NamedOp* un = find_op(kUnary, kw)) {
      want(3, (str(kw) + " a destination").c_str());
      operands(un->op);
    } else if (w.size() == 1 || (w.size() == 2 && w[0].text == "/")) {
      bool neg = w[0].text[0] == '/';
      Word target = w.size() == 2 ? w[1] : neg ? Word{w[0].text.substr(1), w[0].col + 1} : w[0];
      in.op = neg ? Op::OUTN : Op::OUT;
      in.a[0] = bit(target, 'w');
    } else {
      fail(0, col, "unknown output element (" + str(inner) + ")");
    }
  } catch (CompileError& e) {
    e.line = line;
    throw;
  }
  return n;
}

// ------------------------------------------------------------------ grids

// A rung row without its trailing "# comment" (a '#' outside any element).
std::string_view cut_comment(std::string_view s) {
  if (s.find('#') == std::string_view::npos) return s;
  int depth = 0;
  for (size_t i = 0; i < s.size(); i++) {
    char c = s[i];
    if (c == '[' || c == '(') depth++;
    else if ((c == ']' || c == ')') && depth > 0) depth--;
    else if (c == '#' && depth == 0) return s.substr(0, i);
  }
  return s;
}

// The rung's rows into g_: views of the source lines, cut before a trailing
// "# comment" and trailing blanks; the widest row sets the grid's width.
void Parser::grid(size_t first, size_t last, int rail) {
  Grid& g = g_;
  g.rail = rail;
  g.rows = int(last - first);
  g.width = 0;
  if (g.rows > kMaxRungRows) fail(int(first) + 1, rail + 1, "rung too tall (at most " + std::to_string(kMaxRungRows) + " rows)");
  grid_rows(first, rail);
  grid_cells(first, rail);
  grid_right_rails(first);
  g.joined.assign(size_t(g.rows), 0);
  for (int r = 0; r < g.rows; r++) {
    Cell k = g.at(r, rail + 1);
    g.joined[size_t(r)] = k == Cell::Wire || k == Cell::Elem || k == Cell::Out;
  }
}

void Parser::grid_rows(size_t first, int /*rail*/) {
  Grid& g = g_;
  g.text.resize(size_t(g.rows));
  for (int r = 0; r < g.rows; r++) {
    int no = int(first) + r + 1;
    std::string_view s = cut_comment(lines_[first + size_t(r)]);
    while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
    if (s.size() > size_t(kMaxRowWidth)) fail(no, kMaxRowWidth, "rung row too wide (at most " + std::to_string(kMaxRowWidth) + " columns)");
    size_t tab = s.find('\t');
    if (tab != std::string_view::npos) fail(no, int(tab) + 1, "tab in a rung row; use spaces so the grid lines up");
    g.text[size_t(r)] = s;
    g.width = std::max(g.width, int(s.size()) + 1);
  }
}

// cell = "-" | "+" | "|" | " " | "[" ... "]" | "(" ... ")"
void Parser::grid_cells(size_t first, int rail) {
  Grid& g = g_;
  g.stride = g.width + 2;
  g.cell.assign(g.cells(), Cell::Blank);
  g.tok.assign(g.cells(), -1);
  g.tokens.clear();
  g.verts = 0;
  for (int r = 0; r < g.rows; r++) {
    std::string_view s = g.text[size_t(r)];
    int no = int(first) + r + 1;
    for (int c = rail + 1; c < int(s.size()); c++) {
      char ch = s[c];
      if (ch == '[' || ch == '(') {
        char close = ch == '[' ? ']' : ')';
        size_t e = size_t(c) + 1;
        while (e < s.size() && s[e] != '[' && s[e] != ']' && s[e] != '(' && s[e] != ')') e++;
        if (e == s.size() || s[e] != close)
          fail(no, c + 1, std::string("'") + ch + "' without a closing '" + close + "'");
        g.tokens.push_back({r, c, int(e), ch == '('});
        for (int k = c; k <= int(e); k++) {
          g.cell[g.idx(r, k)] = ch == '(' ? Cell::Out : Cell::Elem;
          g.tok[g.idx(r, k)] = int(g.tokens.size()) - 1;
        }
        c = int(e);
      } else if (ch == ']' || ch == ')') {
        fail(no, c + 1, std::string("unmatched '") + ch + "'");
      } else if (ch == '-') g.cell[g.idx(r, c)] = Cell::Wire;
      else if (ch == '+') g.cell[g.idx(r, c)] = Cell::Junction;
      else if (ch == '|') g.cell[g.idx(r, c)] = Cell::Vert, g.verts++;
      else if (ch != ' ')
        fail(no, c + 1, std::string("unexpected '") + ch + "' in a rung; elements are written [..] and (..)");
    }
  }
}

// What may follow an output: wire, blanks and the right rail, which, where
// drawn, is not part of the network.
void Parser::grid_right_rails(size_t first) {
  Grid& g = g_;
  g.right_rails.clear();
  for (const Token& t : g.tokens) {
    if (!t.output) continue;
    int no = int(first) + t.row + 1;
    int last_nb = -1;
    for (int c = t.c1 + 1; c < g.width; c++)
      if (g.at(t.row, c) != Cell::Blank) last_nb = c;
    for (int c = t.c1 + 1; c <= last_nb; c++) {
      Cell k = g.at(t.row, c);
      if (k == Cell::Out) fail(no, c + 1, "outputs cannot be in series; draw parallel outputs on rows of their own");
      if (k == Cell::Elem) fail(no, c + 1, "an element cannot follow an output; the output must end its row");
      if (k == Cell::Junction) fail(no, c + 1, "a branch cannot start after an output; the output must end its row");
      if (k == Cell::Vert && c != last_nb) fail(no, c + 1, "unexpected '|' after an output");
      if (k == Cell::Vert) g.right_rails.push_back(c);
    }
  }
  if (g.right_rails.empty()) return;
  for (int r = 0; r < g.rows; r++) {
    int last_nb = -1;
    for (int c = 0; c < g.width; c++)
      if (g.cell[g.idx(r, c)] != Cell::Blank) last_nb = c;
    if (last_nb >= 0 && g.cell[g.idx(r, last_nb)] == Cell::Vert &&
        std::find(g.right_rails.begin(), g.right_rails.end(), last_nb) != g.right_rails.end())
      g.cell[g.idx(r, last_nb)] = Cell::Blank;
  }
}

// A dangling '+' or '|' at (r, c): most often the '+' or '|' it should join
// is drawn a column or two off in the row above or below; the note points at it.
[[noreturn]] void fail_near_link(const Grid& g, int line0, int r, int c, const std::string& msg) {
  for (int dr : {-1, 1})
    for (int dc : {-1, 1, -2, 2}) {
      int rr = r + dr, cc = c + dc;
      if (rr < 0 || rr >= g.rows || cc <= g.rail || !g.vertical(rr, cc) || g.vertical(r, cc)) continue;
      const char* what = g.at(rr, cc) == Cell::Junction ? "'+'" : "'|'";
      throw NotedError(line0 + r, c + 1, msg,
                       {{line0 + rr, cc + 1, std::string("the ") + what + (dr < 0 ? " above" : " below") + " is in column " +
                                                 std::to_string(cc + 1) + ", not " + std::to_string(c + 1) +
                                                 "; a vertical link joins '+' and '|' of the same column"}});
    }
  fail(line0 + r, c + 1, msg);
}

// Every wire end, junction and vertical link must connect to something.
void Parser::check_cells(const Grid& g, int line0) {
  auto left_ok = [&](int r, int c) {  // something on the left of column c feeds it
    if (c == g.rail + 1) return bool(g.joined[size_t(r)]);
    Cell k = g.at(r, c - 1);
    return k == Cell::Wire || k == Cell::Junction || g.token_ends(r, c - 1);
  };
  auto right_ok = [&](int r, int c) {  // something on the right of column c takes it
    Cell k = g.at(r, c + 1);
    return k == Cell::Wire || k == Cell::Junction || g.token_starts(r, c + 1);
  };
  for (int r = 0; r < g.rows; r++) {
    int no = line0 + r;
    bool tail = false;  // this run of wire is drawn after an output (found once per run: linear in the width)
    for (int c = g.rail + 1; c < g.width; c++) {
      Cell k = g.cell[g.idx(r, c)];
      if (k == Cell::Wire) {
        if (!left_ok(r, c)) fail(no, c + 1, "dangling wire: nothing connects to its left end");
        if (g.at(r, c - 1) != Cell::Wire) tail = g.out_ends(r, c - 1);
        if (!tail && !right_ok(r, c)) fail(no, c + 1, "dangling wire: it leads nowhere");
      } else if (k == Cell::Junction) {
        int links = (c > g.rail + 1 && left_ok(r, c)) + right_ok(r, c) + g.vertical(r - 1, c) + g.vertical(r + 1, c);
        if (g.out_ends(r, c - 1)) fail(no, c + 1, "a branch cannot start after an output");
        if (links < 2) fail_near_link(g, line0, r, c, "dangling junction: '+' must join at least two wires");
      } else if (k == Cell::Vert) {
        if (!g.vertical(r - 1, c) || !g.vertical(r + 1, c))
          fail_near_link(g, line0, r, c, "dangling vertical link: '|' must connect '+' or '|' above and below");
      } else if (g.token_starts(r, c)) {
        const Token& t = g.token(r, c);
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
// Points: boundary (r, c) = r * W + c; vertical link cell (r, c) =
// rows * W + r * W + c (only a grid with a '|' drawn has them); the rail is
// the point before the last.

void Parser::join_points(const Grid& g) {
  int rows = g.rows, W = g.width + 1;
  int npts = rows * W + (g.verts ? rows * W : 0) + 2;
  const int RAIL = rail_point_ = npts - 2;
  uf_.reset(size_t(npts));
  auto B = [&](int r, int c) { return r * W + c; };
  auto V = [&](int r, int c) { return g.at(r, c) == Cell::Junction ? B(r, c) : rows * W + r * W + c; };
  for (int r = 0; r < rows; r++) {
    if (g.joined[size_t(r)]) uf_.join(B(r, g.rail + 1), RAIL);
    for (int c = g.rail + 1; c < g.width; c++) {
      Cell k = g.cell[g.idx(r, c)];
      if (k == Cell::Wire || k == Cell::Junction) uf_.join(B(r, c), B(r, c + 1));
      if (g.vertical(r, c) && g.vertical(r + 1, c)) uf_.join(V(r, c), V(r + 1, c));
    }
  }
  node_of_.assign(size_t(npts), -1);
  nodes_ = 0;
}

int Parser::node(int pt) {
  int& id = node_of_[size_t(uf_.find(pt))];
  if (id < 0) id = nodes_++;
  return id;
}

// Every element an edge (outputs: to the sink, numbered once all nodes are).
void Parser::element_edges(const Grid& g, int line0) {
  int W = g.width + 1;
  edges_.clear();
  elems_.clear();
  forest_.nodes.clear();
  int rung_line = line0;
  for (const Token& t : g.tokens) {
    int no = line0 + t.row;
    std::string_view raw = lines_[size_t(no - 1)].substr(size_t(t.c0) + 1, size_t(t.c1 - t.c0 - 1));
    Edge e;
    e.from = node(t.row * W + t.c0);
    e.action = t.output;
    e.to = -1;  // an output's sink, set by the caller
    if (t.output) {
      elems_.push_back(output_element(raw, no, t.c0 + 1, rung_line));
    } else {
      elems_.push_back(input_element(raw, no, t.c0 + 1));
      e.to = node(t.row * W + t.c1 + 1);
      if (e.from == e.to) fail(no, t.c0 + 1, "element is short-circuited: a wire joins its two ends");
    }
    const TreeNode& n = elems_.back();
    e.term = forest_.leaf(n.kind, int(elems_.size()) - 1, n.elem.loc);
    edges_.push_back(e);
  }
}

void Parser::reach(int start, bool forward, std::vector<char>& seen) {
  seen.assign(size_t(nodes_) + 1, 0);
  stack_.assign(1, start);
  seen[size_t(start)] = 1;
  while (!stack_.empty()) {
    int v = stack_.back();
    stack_.pop_back();
    for (int ei : (forward ? out_[size_t(v)] : in_[size_t(v)])) {
      int u = forward ? edges_[size_t(ei)].to : edges_[size_t(ei)].from;
      if (!seen[size_t(u)]) { seen[size_t(u)] = 1; stack_.push_back(u); }
    }
  }
}

// Every element must lie on a path from the rail (node 0) to an output (the
// sink); builds the adjacency lists the reduction keeps up to date.
void Parser::check_paths() {
  size_t nn = size_t(nodes_) + 1;
  if (out_.size() < nn) out_.resize(nn), in_.resize(nn);
  for (size_t u = 0; u < nn; u++) out_[u].clear(), in_[u].clear();
  for (size_t i = 0; i < edges_.size(); i++) {
    out_[size_t(edges_[i].from)].push_back(int(i));
    in_[size_t(edges_[i].to)].push_back(int(i));
  }
  reach(0, true, from_rail_);
  reach(nodes_, false, to_out_);
  for (const Edge& e : edges_) {
    SrcLoc l = forest_.nodes[size_t(e.term)].loc;
    if (!from_rail_[size_t(e.from)]) fail(l.line, l.col, "not connected to the left power rail");
    if (!to_out_[size_t(e.to)]) fail(l.line, l.col, "element reaches no output");
  }
}

// Series/parallel reduction, keeping the adjacency lists up to date.
void Parser::series_parallel(int rail, int sink) {
  auto unlink = [](std::vector<int>& v, int e) { v.erase(std::find(v.begin(), v.end(), e)); };
  for (bool changed = true; changed;) {
    changed = false;
    for (int u = 0; u <= sink; u++) {
      // parallel: edges from u with the same far end become one
      auto& o = out_[size_t(u)];
      for (size_t a = 0; a < o.size(); a++) {
        for (size_t b = a + 1; b < o.size();) {
          Edge& ea = edges_[size_t(o[a])];
          Edge& eb = edges_[size_t(o[b])];
          if (eb.to != ea.to) { b++; continue; }
          ea.term = forest_.combine(ea.action ? K::Fork : K::Parallel, ea.term, eb.term, true);
          eb.alive = false;
          unlink(in_[size_t(eb.to)], o[b]);
          o.erase(o.begin() + long(b));
          changed = true;
        }
      }
      // series: u with one edge in and one edge out joins them
      auto& i = in_[size_t(u)];
      if (u == rail || u == sink || i.size() != 1 || o.size() != 1 || i[0] == o[0]) continue;
      int i1 = i[0], i2 = o[0];
      Edge& e1 = edges_[size_t(i1)];
      Edge& e2 = edges_[size_t(i2)];
      if (e2.action) {
        e1.term = forest_.then(e1.term, e2.term);
        e1.action = true;
      } else {
        e1.term = forest_.combine(K::Series, e1.term, e2.term, false);
      }
      unlink(in_[size_t(e2.to)], i2);
      in_[size_t(e2.to)].push_back(i1);
      e1.to = e2.to;
      e2.alive = false;
      i.clear();
      o.clear();
      changed = true;
    }
  }
}

// Not series-parallel: point at a bridging element if there is one.
void Parser::refuse_bridge(int rail) {
  std::vector<Edge*> left;
  for (auto& e : edges_)
    if (e.alive) left.push_back(&e);
  std::vector<int> indeg(size_t(nodes_) + 1), outdeg(size_t(nodes_) + 1);
  for (Edge* e : left) { outdeg[size_t(e->from)]++; indeg[size_t(e->to)]++; }
  Edge* culprit = left[0];
  for (Edge* e : left)
    if (!e->action && outdeg[size_t(e->from)] >= 2 && indeg[size_t(e->to)] >= 2 && e->from != rail) { culprit = e; break; }
  SrcLoc l = forest_.nodes[size_t(culprit->term)].loc;
  fail(l.line, l.col, "network is not series-parallel (a bridge); redraw it as series and parallel blocks");
}

// The kids of the forest's inner node `term` into `out` (exactly as many
// as it has); each TreeNode is built once, elements are moved in.
void Parser::build(int term, TreeNode& out) {
  const PNode& p = forest_.nodes[size_t(term)];
  out.kind = p.kind;
  size_t n = 0;
  for (int k = p.first; k >= 0; k = forest_.nodes[size_t(k)].next) n++;
  out.kids.reserve(n);
  for (int k = p.first; k >= 0; k = forest_.nodes[size_t(k)].next) {
    const PNode& kid = forest_.nodes[size_t(k)];
    if (kid.elem >= 0) {
      out.kids.push_back(std::move(elems_[size_t(kid.elem)]));
    } else {
      out.kids.emplace_back();
      build(k, out.kids.back());
    }
  }
}

TreeNode Parser::reduce(const Grid& g, int line0) {
  join_points(g);
  int rail = node(rail_point_);  // node 0
  element_edges(g, line0);
  bool outputs = false;
  for (Edge& e : edges_) outputs |= e.action;
  if (!outputs) fail(line0, g.rail + 1, "rung has no output");
  const int SINK = nodes_;
  for (auto& e : edges_)
    if (e.action) e.to = SINK;
  check_paths();
  series_parallel(rail, SINK);
  const Edge* only = nullptr;
  size_t alive = 0;
  for (const Edge& e : edges_)
    if (e.alive && !alive++) only = &e;
  if (alive != 1 || only->from != rail || only->to != SINK) refuse_bridge(rail);
  const PNode& top = forest_.nodes[size_t(only->term)];
  if (top.elem >= 0) return std::move(elems_[size_t(top.elem)]);
  TreeNode root;
  build(only->term, root);
  return root;
}

TreeRung Parser::rung(size_t first, size_t last, int rail) {
  grid(first, last, rail);
  int line0 = int(first) + 1;
  check_cells(g_, line0);
  TreeRung r;
  r.line = line0;
  r.root = reduce(g_, line0);
  return r;
}

// The rows of the rung starting at line index i: up to the first line whose
// first non-blank character is not '|'.  Every row's rail must be in column
// `rail`: the first row whose rail is not is `misplaced` (-1: none), refused
// when the rung is read.
size_t Parser::rung_end(size_t i, int rail, int& misplaced) {
  size_t j = i;
  misplaced = -1;
  while (j < lines_.size()) {
    std::string_view u = trim(lines_[j]);
    if (u.empty() || u[0] != '|') break;
    if (indent(lines_[j]) != rail && misplaced < 0) misplaced = int(j);
    j++;
  }
  return j;
}

// program = { blank | comment | alias | label | title | rung }
// title   = "rung" STRING         (directly above its rung)
// rung    = row { row }           (first non-blank character '|', all in one column)
TreeProgram Parser::program(const std::function<void(TreeRung&&)>& sink) {
  int errors0 = diag_ ? diag_->errors() : 0;
  if (diag_) diag_->source(file_, text_);
  read_lines();
  declarations();
  TreeProgram p;
  p.source = file_;
  p.aliases = alias_list_;
  p.retain = retain_;
  if (!sink) p.rungs.reserve(std::min(rung_count_, kMaxRungs));
  size_t rungs = 0;
  std::vector<std::string> labels;
  std::string title;
  int title_line = 0;
  for (size_t i = 0; i < lines_.size();) {
    std::string_view text = lines_[i];
    int no = int(i) + 1;
    std::string_view t = trim(text);
    int col0 = indent(text) + 1;
    if (title_line && (t.empty() || t[0] != '|')) {
      report(title_line, 1, "a rung title must be directly above its rung");
      title_line = 0;
      title.clear();
    }
    if (t.empty() || is_comment(t)) { i++; continue; }
    if (t[0] == '|') {
      int misplaced;
      size_t j = rung_end(i, col0 - 1, misplaced);
      if (rungs >= kMaxRungs) fail(no, col0, "too many rungs (at most " + std::to_string(kMaxRungs) + ")");
      recover([&] {  // an error: on to the next rung
        if (misplaced >= 0)
          fail(misplaced + 1, indent(lines_[size_t(misplaced)]) + 1,
               "left rail out of line: this rung's rail is in column " + std::to_string(col0));
        TreeRung r = rung(i, j, col0 - 1);
        r.labels = std::move(labels);
        r.title = std::move(title);
        if (sink) sink(std::move(r));
        else p.rungs.push_back(std::move(r));
      });
      labels.clear();
      title.clear();
      title_line = 0;
      rungs++;
      i = j;
      continue;
    }
    split_words(t, col0, words_);
    if (iequals(words_[0].text, "LABEL")) {
      if (words_.size() == 2) labels.push_back(str(words_[1].text));  // else declarations() reported it
    }
    else if (iequals(words_[0].text, "RUNG")) {
      size_t q1 = text.find('"'), q2 = text.rfind('"');
      if (q1 == std::string_view::npos || q2 == q1 || !trim(text.substr(q2 + 1)).empty() ||
          !iequals(trim(text.substr(0, q1)), "RUNG")) {
        report(no, col0, "expected: rung \"title\"");
      } else {
        title = str(text.substr(q1 + 1, q2 - q1 - 1));
        title_line = no;
      }
    }
    i++;
  }
  if (title_line) report(title_line, 1, "a rung title must be directly above its rung");
  p.end_labels = std::move(labels);
  if (rungs == 0) report(std::max(1, int(lines_.size())), 1, "no rungs in this program");
  if (diag_ && diag_->errors() > errors0) throw ErrorsReported();
  warn_unused();
  return p;
}

// Reads one declaration or rung; an error is thrown (no diagnostics) or
// reported, and the caller goes on after what `read` covers.
bool Parser::recover(const std::function<void()>& read) {
  if (!diag_) {
    read();
    return true;
  }
  try {
    read();
    return true;
  } catch (CompileError& e) {
    if (!quiet_) diag_->error(file_, e);
    quiet_ = false;
    return false;
  }
}

void Parser::report(int line, int col, const std::string& msg) {
  recover([&] { fail(line, col, msg); });
}

// -Wunused, -Wunused-label: names the program declares and never uses.
void Parser::warn_unused() {
  if (!diag_) return;
  if (diag_->wants("unused"))
    for (const Alias& a : alias_list_) {
      const AliasEntry& e = aliases_.at(upper(a.name));
      if (!e.used) diag_->warning("unused", file_, e.line, e.col, "alias '" + e.name + "' is never used");
    }
  if (diag_->wants("unused-label"))
    for (const LabelDef& l : labels_)
      if (!l.used) diag_->warning("unused-label", file_, l.line, l.col, "label '" + l.name + "' is never jumped to");
}

}  // namespace

TreeProgram parse_ld(std::string_view text, const std::string& filename) { return Parser(text, filename).program(); }

TreeProgram parse_ld(std::string_view text, const std::string& filename, Diagnostics& diag) {
  return Parser(text, filename, &diag).program();
}

Program parse_ld_to_il(std::string_view text, const std::string& filename, Diagnostics& diag) {
  Program il;
  TreeProgram head = Parser(text, filename, &diag).program([&](TreeRung&& r) { lower_rung(r, il); });
  il.source = std::move(head.source);
  il.aliases = std::move(head.aliases);
  il.end_labels = std::move(head.end_labels);
  il.retain = std::move(head.retain);
  return il;
}

Program parse_ld_to_il(std::string_view text, const std::string& filename) {
  Program il;
  TreeProgram head = Parser(text, filename).program([&](TreeRung&& r) { lower_rung(r, il); });
  il.source = std::move(head.source);
  il.aliases = std::move(head.aliases);
  il.end_labels = std::move(head.end_labels);
  il.retain = std::move(head.retain);
  return il;
}

TreeProgram parse_ld(std::string_view text, const std::string& filename, const std::vector<Alias>& predefined) {
  Parser p(text, filename);
  p.predefine(predefined);
  return p.program();
}

}  // namespace ldc
