// frontend/st/st.cpp -- Structured Text bodies to the typed IEC IL reader
// (docs/st.md).  An ST file has the declarations of an IEC IL file (TYPE,
// FUNCTION_BLOCK, FUNCTION, PROGRAM, VAR blocks), which are passed on as they
// are; each POU body's statements are parsed into a syntax tree and written
// as IL instructions whose tokens carry the ST source's line and column, so
// the typed reader (frontend/iecil/typed.cpp) types, checks and lowers them
// and every message points into the ST file.
//
// An expression is written as IL evaluates it: the left operand loaded, each
// operator applied to the current result with its right operand, a right
// operand that is itself an expression in IL parentheses (ADD( b / MUL c / )).
// What IL cannot take as an operand -- an index or argument that is an
// expression, a call on the right of an operator -- is computed first into a
// temporary (__Tn), which the typed reader gives the type of the value stored.
#include <algorithm>
#include <cctype>
#include <map>
#include <optional>
#include <set>

#include "frontend/st/st.h"
#include "frontend/st/sfc_text.h"

#include "frontend/diag.h"
#include "frontend/frontend.h"
#include "ir/model.h"

namespace ldc::st {

using iecil::Tok;
using iecil::upper;

namespace {

constexpr int kMaxNesting = 200;          // expressions and statements: hostile input cannot exhaust the stack
constexpr int kMaxParenDepth = 12;        // the typed reader takes 16
constexpr int64_t kMaxUnrolled = 16;      // iterations of a FOR loop written out instead of looped

// One level of nesting of the parser or the writer, refused beyond
// kMaxNesting (hostile input cannot exhaust the stack).
struct Nest {
  int& d;
  Nest(int& depth, const Tok& at) : d(depth) {
    if (++d > kMaxNesting) throw CompileError(at.line, at.col, "nested deeper than " + std::to_string(kMaxNesting));
  }
  ~Nest() { d--; }
};

// An error after which the rest of the file cannot be read as ST (a chart
// written as text: its STEP ... END_STEP are no statements), even with error
// recovery: the reader stops there.
struct Unreadable : CompileError {
  using CompileError::CompileError;
};

// ---------------------------------------------------------------- syntax tree

struct Expr;
struct Sel {                   // [i, j] then .member (either may be absent)
  std::vector<Expr> index;
  Tok member;                  // a Word ".x.y", or kind End
};
struct Expr {
  enum Kind { Lit, Var, Unary, Binary, Call } kind = Lit;
  Tok tok;                     // the literal, the variable's first word, the operator, the called name
  std::string op;              // Unary/Binary: the IL operator (NOT NEG ADD GT ...)
  std::vector<Expr> kids;      // Unary 1, Binary 2, Call its arguments
  std::vector<Tok> names;      // Call: each argument's formal name (kind End: positional)
  std::vector<bool> outs;      // Call: NAME => variable
  std::vector<Sel> sels;       // Var
};

struct Stmt {
  enum Kind { Assign, CallFb, CallFn, If, Case, For, While, Repeat, Exit, Continue, Return } kind = Assign;
  Tok tok;
  Expr target, value;                    // Assign; CallFb/CallFn: value
  std::vector<Expr> conds;               // If (one per branch); While/Repeat: 1
  std::vector<std::vector<Stmt>> blocks; // If/Case: one per branch, then the ELSE block if any
  bool has_else = false;
  std::vector<std::vector<std::pair<Expr, std::optional<Expr>>>> labels;  // Case: per branch, values and ranges
  Expr from, to, by;                     // For (by: kind Lit with an End tok when absent)
  bool has_by = false;
};

// ---------------------------------------------------------------- the parser

class Parser {
 public:
  Parser(const std::vector<Tok>& t, size_t pos, std::set<std::string> functions, iecil::Recovery* rec = nullptr)
      : t_(t), pos_(pos), functions_(std::move(functions)), rec_(rec) {}
  size_t pos() const { return pos_; }

  // statement_list = { statement } up to one of the words `ends`
  // `to_eof`: the end of the file ends the list too (a POU's body, as CODESYS
  // exports it without its END_ line)
  std::vector<Stmt> statement_list(std::initializer_list<const char*> ends, bool to_eof = false) {
    std::vector<Stmt> out;
    for (;;) {
      const Tok& k = peek();
      if (k.kind == Tok::End && to_eof) return out;
      if (k.kind == Tok::End) fail(k, std::string("expected ") + *ends.begin() + " at the end of the file");
      for (const char* e : ends)
        if (kw(k, e)) return out;
      if (punct(k, ";")) { next(); continue; }
      std::string u = upper(k.text);
      if (k.kind == Tok::Word && (u.rfind("END_", 0) == 0 || u == "ELSE" || u == "ELSIF" || u == "UNTIL" || u == "THEN" || u == "DO")) {
        // with recovery: the end of the POU ends this list's block too (its
        // statement is refused, in the list around it); another END_ word
        // ends a block's list as if it were the right one (END_REPEAT closing
        // a WHILE); a word out of place elsewhere is reported and passed over
        std::string why = std::string("expected ") + *ends.begin() + found(k);
        if (!rec_ || pou_end(k)) fail(k, why);
        rec_->report(CompileError(k.line, k.col, why));
        if (!to_eof && u.rfind("END_", 0) == 0 && std::string(*ends.begin()).rfind("END_", 0) == 0) return out;
        next();
        continue;
      }
      recover_statement(out);
    }
  }

 private:
  const std::vector<Tok>& t_;
  size_t pos_;
  std::set<std::string> functions_;
  iecil::Recovery* rec_;
  int depth_ = 0;

  static bool pou_end(const Tok& k) {
    return k.kind == Tok::End || kw(k, "END_PROGRAM") || kw(k, "END_FUNCTION_BLOCK") || kw(k, "END_FUNCTION");
  }
  // One statement into `out`; with recovery, a refused one is reported and
  // passed over (skip_statement).
  void recover_statement(std::vector<Stmt>& out) {
    if (!rec_) {
      out.push_back(statement());
      return;
    }
    size_t start = pos_;
    try {
      out.push_back(statement());
    } catch (const Unreadable&) {
      throw;
    } catch (const CompileError& e) {
      rec_->report(e);
      skip_statement(start);
    }
  }
  // Passes over the statement that starts at `start`: up to its ';', or to
  // the END_IF ... that closes it when it opens a block (the blocks inside it
  // counted), or to the word that closes the block around it (ELSE, ELSIF,
  // UNTIL, END_..., left for that block).
  void skip_statement(size_t start) {
    pos_ = start;
    int depth = 0;
    for (;;) {
      const Tok& k = peek();
      std::string u = k.kind == Tok::Word ? upper(k.text) : "";
      if (pou_end(k)) break;
      if (u == "IF" || u == "CASE" || u == "FOR" || u == "WHILE" || u == "REPEAT") {
        depth++;
      } else if (u == "END_IF" || u == "END_CASE" || u == "END_FOR" || u == "END_WHILE" || u == "END_REPEAT") {
        if (depth == 0) break;
        if (--depth == 0) {
          next();
          if (punct(peek(), ";")) next();
          return;
        }
      } else if (depth == 0 && (u == "ELSE" || u == "ELSIF" || u == "UNTIL" || u.rfind("END_", 0) == 0)) {
        break;
      } else if (depth == 0 && punct(k, ";")) {
        next();
        return;
      }
      next();
    }
    if (pos_ == start && peek().kind != Tok::End && !pou_end(peek())) next();
  }

  const Tok& peek(size_t k = 0) const { return t_[std::min(pos_ + k, t_.size() - 1)]; }
  const Tok& next() { return t_[pos_ < t_.size() - 1 ? pos_++ : pos_]; }
  [[noreturn]] static void fail(const Tok& k, const std::string& m) { throw CompileError(k.line, k.col, m); }
  static bool kw(const Tok& k, const char* w) { return k.kind == Tok::Word && upper(k.text) == w; }
  static bool punct(const Tok& k, const char* p) { return k.kind == Tok::Punct && k.text == p; }
  static std::string found(const Tok& k) { return k.kind == Tok::End ? " at the end of the file" : ", found '" + k.text + "'"; }
  const Tok& expect(const char* p) {
    if (!punct(peek(), p)) fail(peek(), std::string("expected '") + p + "'" + found(peek()));
    return next();
  }
  const Tok& expect_kw(const char* w) {
    if (!kw(peek(), w)) fail(peek(), std::string("expected ") + w + found(peek()));
    return next();
  }
  void semicolon(const Tok& stmt) {
    if (!punct(peek(), ";")) fail(peek(), "expected ';' after the statement that starts at " + std::to_string(stmt.line) + ":" + std::to_string(stmt.col) + found(peek()));
    next();
  }
  // after END_IF, END_CASE, END_FOR, END_WHILE, END_REPEAT the ';' may be
  // left out, as CODESYS and RuSTy read it (nothing else can follow there)
  void end_semicolon() {
    if (punct(peek(), ";")) next();
  }
  static bool is_name(const Tok& k) {
    if (k.kind != Tok::Word || k.text.empty()) return false;
    return std::isalpha((unsigned char)k.text[0]) || k.text[0] == '_' || k.text[0] == '%';  // %QX0.0: a direct address
  }

  // statement = assignment | call | if | case | for | while | repeat | EXIT ";" | CONTINUE ";" | RETURN ";"
  Stmt statement() {
    const Tok& k = peek();
    Nest n(depth_, k);
    std::string u = upper(k.text);
    if (k.kind == Tok::Word) {
      if (u == "IF") return if_stmt();
      if (u == "CASE") return case_stmt();
      if (u == "FOR") return for_stmt();
      if (u == "WHILE" || u == "REPEAT") return loop_stmt(u);
      if ((u == "INITIAL_STEP" || u == "STEP" || u == "TRANSITION") && peek(1).kind == Tok::Word)
        throw Unreadable(k.line, k.col, "'" + k.text + "': an element of a chart among statements; a POU body is a chart written as text or statements, not both (docs/st.md)");
      if (u == "EXIT" || u == "CONTINUE" || u == "RETURN") {
        Stmt s;
        s.kind = u == "EXIT" ? Stmt::Exit : u == "CONTINUE" ? Stmt::Continue : Stmt::Return;
        s.tok = next();
        semicolon(s.tok);
        return s;
      }
    }
    if (!is_name(k)) fail(k, "expected a statement" + found(k));
    return assignment_or_call();
  }

  // assignment = variable ":=" expression ";"     call = NAME "(" [ args ] ")" ";"
  Stmt assignment_or_call() {
    Stmt s;
    s.tok = peek();
    if (punct(peek(1), "(")) {
      s.value = call(next());
      s.kind = functions_.count(upper(s.tok.text)) ? Stmt::CallFn : Stmt::CallFb;
      semicolon(s.tok);
      return s;
    }
    s.target = variable(next());
    if (punct(peek(), "(")) {  // an instance in an array: fbs[2](IN := x)
      s.value = call(s.target.tok);
      s.value.sels = s.target.sels;
      s.kind = Stmt::CallFb;
      semicolon(s.tok);
      return s;
    }
    if (punct(peek(), "=")) fail(peek(), "'=' compares; an assignment is ':='");
    expect(":=");
    s.value = expression();
    semicolon(s.tok);
    return s;
  }

  // if = IF expr THEN stmts { ELSIF expr THEN stmts } [ ELSE stmts ] END_IF ";"
  Stmt if_stmt() {
    Stmt s;
    s.kind = Stmt::If;
    s.tok = next();
    for (;;) {
      s.conds.push_back(expression());
      expect_kw("THEN");
      s.blocks.push_back(statement_list({"END_IF", "ELSIF", "ELSE"}));
      if (kw(peek(), "ELSIF")) { next(); continue; }
      break;
    }
    if (kw(peek(), "ELSE")) {
      next();
      s.blocks.push_back(statement_list({"END_IF"}));
      s.has_else = true;
    }
    expect_kw("END_IF");
    end_semicolon();
    return s;
  }

  // case = CASE expr OF { case_list ":" stmts } [ ELSE stmts ] END_CASE ";"
  // case_list = case_item { "," case_item }    case_item = expr [ ".." expr ]
  Stmt case_stmt() {
    Stmt s;
    s.kind = Stmt::Case;
    s.tok = next();
    s.value = expression();
    expect_kw("OF");
    // (any END_ word ends the branches: END_CASE is then expected)
    while (!kw(peek(), "ELSE") && !(peek().kind == Tok::Word && upper(peek().text).rfind("END_", 0) == 0)) {
      if (peek().kind == Tok::End) fail(s.tok, "CASE without END_CASE");
      std::vector<std::pair<Expr, std::optional<Expr>>> items;
      for (;;) {
        Expr lo = expression();
        std::optional<Expr> hi;
        if (punct(peek(), "..")) next(), hi = expression();
        items.push_back({std::move(lo), std::move(hi)});
        if (punct(peek(), ",")) { next(); continue; }
        break;
      }
      expect(":");
      s.labels.push_back(std::move(items));
      s.blocks.push_back(case_block());
    }
    if (kw(peek(), "ELSE")) {
      next();
      s.blocks.push_back(statement_list({"END_CASE"}));
      s.has_else = true;
    }
    expect_kw("END_CASE");
    end_semicolon();
    return s;
  }
  // the statements of one CASE branch: up to the next label (an expression then ':' or '..' or ',')
  std::vector<Stmt> case_block() {
    std::vector<Stmt> out;
    for (;;) {
      const Tok& k = peek();
      if (k.kind == Tok::End || kw(k, "ELSE") || (k.kind == Tok::Word && upper(k.text).rfind("END_", 0) == 0)) return out;
      if (punct(k, ";")) { next(); continue; }
      if (starts_case_label()) return out;
      recover_statement(out);
    }
  }
  bool starts_case_label() const {
    size_t i = pos_;
    if (punct(t_[i], "-")) i++;
    if (t_[i].kind != Tok::Word) return false;
    const Tok& n = t_[i + 1 < t_.size() ? i + 1 : i];
    return punct(n, ":") || punct(n, "..") || punct(n, ",");
  }

  // for = FOR NAME ":=" expr TO expr [ BY expr ] DO stmts END_FOR ";"
  Stmt for_stmt() {
    Stmt s;
    s.kind = Stmt::For;
    s.tok = next();
    const Tok& v = next();
    if (!is_name(v) || v.text.find('.') != std::string::npos) fail(v, "expected the FOR loop's control variable" + found(v));
    s.target = variable(v);
    expect(":=");
    s.from = expression();
    expect_kw("TO");
    s.to = expression();
    if (kw(peek(), "BY")) {
      next();
      s.by = expression();
      s.has_by = true;
    }
    expect_kw("DO");
    s.blocks.push_back(statement_list({"END_FOR"}));
    next();
    end_semicolon();
    return s;
  }
  // while = WHILE expr DO stmts END_WHILE ";"    repeat = REPEAT stmts UNTIL expr END_REPEAT ";"
  Stmt loop_stmt(const std::string& u) {
    Stmt s;
    s.kind = u == "WHILE" ? Stmt::While : Stmt::Repeat;
    s.tok = next();
    if (s.kind == Stmt::While) {
      s.conds.push_back(expression());
      expect_kw("DO");
      s.blocks.push_back(statement_list({"END_WHILE"}));
      next();
    } else {
      s.blocks.push_back(statement_list({"UNTIL"}));
      next();
      s.conds.push_back(expression());
      expect_kw("END_REPEAT");
    }
    end_semicolon();
    return s;
  }

  // ---- expressions, IEC 61131-3 precedence (lowest first): OR, XOR, AND &,
  // = <>, < > <= >=, + -, * / MOD, **, unary - NOT, primary.  As MatIEC's
  // grammar has it, a unary operator binds tighter than ** (-2**2 is 4).
  Expr expression() { return binary_level(0); }

  struct Level { std::vector<std::pair<const char*, const char*>> ops; };  // spelling, IL operator
  static const std::vector<Level>& levels() {
    static const std::vector<Level> k = {
        {{{"OR", "OR"}}},
        {{{"XOR", "XOR"}}},
        {{{"AND", "AND"}, {"&", "AND"}}},
        {{{"=", "EQ"}, {"<>", "NE"}}},
        {{{"<", "LT"}, {">", "GT"}, {"<=", "LE"}, {">=", "GE"}}},
        {{{"+", "ADD"}, {"-", "SUB"}}},
        {{{"*", "MUL"}, {"/", "DIV"}, {"MOD", "MOD"}}},
        {{{"**", "EXPT"}}},
    };
    return k;
  }
  const char* level_op(size_t lv, const Tok& k) const {
    for (auto [spell, il] : levels()[lv].ops) {
      bool word = std::isalpha((unsigned char)spell[0]);
      if (word ? kw(k, spell) : punct(k, spell)) return il;
    }
    return nullptr;
  }
  Expr binary_level(size_t lv) {
    if (lv == levels().size()) return unary();
    Nest n(depth_, peek());
    Expr l = binary_level(lv + 1);
    while (const char* op = level_op(lv, peek())) {
      Expr b;
      b.kind = Expr::Binary;
      b.tok = next();
      b.op = op;
      b.kids.push_back(std::move(l));
      b.kids.push_back(binary_level(lv + 1));
      l = std::move(b);
    }
    return l;
  }
  // unary = ( "-" | "+" | NOT ) unary | primary
  Expr unary() {
    Nest n(depth_, peek());
    if (punct(peek(), "+")) {
      next();
      return unary();
    }
    if (punct(peek(), "-") || kw(peek(), "NOT")) {
      Expr u;
      u.kind = Expr::Unary;
      u.tok = next();
      u.op = punct(u.tok, "-") ? "NEG" : "NOT";
      u.kids.push_back(unary());
      return u;
    }
    return primary();
  }
  // primary = "(" expr ")" | literal | NAME "(" args ")" | variable
  Expr primary() {
    const Tok& k = peek();
    if (punct(k, "(")) {
      next();
      Expr e = expression();
      expect(")");
      return e;
    }
    if (k.kind != Tok::Word) fail(k, "expected an operand" + found(k));
    next();
    if (!is_name(k) || k.text.find('#') != std::string::npos || kw(k, "TRUE") || kw(k, "FALSE")) {
      Expr e;
      e.kind = Expr::Lit;
      e.tok = k;
      return e;
    }
    if (punct(peek(), "(")) return call(k);
    return variable(k);
  }
  // variable = NAME { "[" expr { "," expr } "]" [ ".member" ] }
  Expr variable(const Tok& first) {
    Expr e;
    e.kind = Expr::Var;
    e.tok = first;
    while (punct(peek(), "[")) {
      next();
      Sel s;
      for (;;) {
        s.index.push_back(expression());
        if (punct(peek(), ",")) { next(); continue; }
        break;
      }
      expect("]");
      if (peek().kind == Tok::Word && peek().text[0] == '.') s.member = next();
      e.sels.push_back(std::move(s));
    }
    return e;
  }
  // call = NAME "(" [ arg { "," arg } ] ")"    arg = [ NAME ( ":=" | "=>" ) ] expr
  Expr call(const Tok& name) {
    Expr c;
    c.kind = Expr::Call;
    c.tok = name;
    expect("(");
    while (!punct(peek(), ")")) {
      Tok formal;
      bool out = false;
      if (is_name(peek()) && (punct(peek(1), ":=") || punct(peek(1), "=>"))) {
        formal = next();
        out = next().text == "=>";
      }
      c.names.push_back(formal);
      c.outs.push_back(out);
      c.kids.push_back(out ? variable(next()) : expression());
      if (punct(peek(), ",")) { next(); continue; }
      if (!punct(peek(), ")")) fail(peek(), "expected ',' or ')'" + found(peek()));
    }
    next();
    return c;
  }
};

// ---------------------------------------------------------------- the standard functions' inputs

// The formal input names of MatIEC's standard functions (lib/*.txt), in
// order, for a call written with them (LIMIT(MN := 0, IN := x, MX := 9)).
// Functions of one input take IN; the extensible ones IN1, IN2, ...
const std::vector<std::string>* std_inputs(const std::string& u) {
  static const std::map<std::string, std::vector<std::string>> k = {
      {"LIMIT", {"MN", "IN", "MX"}},       {"SEL", {"G", "IN0", "IN1"}},     {"SHL", {"IN", "N"}},
      {"SHR", {"IN", "N"}},                {"ROL", {"IN", "N"}},             {"ROR", {"IN", "N"}},
      {"LEFT", {"IN", "L"}},               {"RIGHT", {"IN", "L"}},           {"MID", {"IN", "L", "P"}},
      {"INSERT", {"IN1", "IN2", "P"}},     {"DELETE", {"IN", "L", "P"}},     {"REPLACE", {"IN1", "IN2", "L", "P"}},
      {"FIND", {"IN1", "IN2"}},            {"SUB", {"IN1", "IN2"}},          {"DIV", {"IN1", "IN2"}},
      {"MOD", {"IN1", "IN2"}},             {"EXPT", {"IN1", "IN2"}}};
  auto it = k.find(u);
  return it == k.end() ? nullptr : &it->second;
}
// Extensible functions: f(a, b, c) is ((a f b) f c).
bool extensible(const std::string& u) {
  static const std::set<std::string> k = {"ADD", "MUL", "AND", "OR", "XOR", "MAX", "MIN", "CONCAT"};
  return k.count(u) > 0;
}
// The comparison functions: GT(a, b) is a > b (two inputs here).
bool comparison(const std::string& u) {
  static const std::set<std::string> k = {"GT", "GE", "EQ", "LE", "LT", "NE"};
  return k.count(u) > 0;
}

// ---------------------------------------------------------------- writing IL

class Writer {
 public:
  Writer(std::vector<Tok>& out, const std::set<std::string>& functions, iecil::Recovery* rec = nullptr)
      : out_(out), functions_(functions), rec_(rec) {}

  // Each statement's lines start after an Eol marked `statement`:
  // with error recovery the typed reader goes on at the next statement after
  // a line it refused.  A statement refused here is reported and not written.
  void body(const std::vector<Stmt>& stmts) {
    for (const Stmt& s : stmts) {
      if (!out_.empty() && out_.back().kind == Tok::Eol) out_.back().statement = true;
      if (!rec_) {
        statement(s);
        continue;
      }
      size_t written = out_.size(), loops = loops_.size();
      try {
        statement(s);
      } catch (const CompileError& e) {
        rec_->report(e);
        out_.resize(written);
        loops_.resize(loops);
      }
    }
  }

 private:
  std::vector<Tok>& out_;
  const std::set<std::string>& functions_;  // the file's FUNCTIONs (upper-case); any other call is standard
  iecil::Recovery* rec_;
  int labels_ = 0, selectors_ = 0, temps_ = 0;
  std::map<const Expr*, std::string> temp_;  // hoisted values of the current statement
  struct Loop { std::string exit, next; };
  std::vector<Loop> loops_;
  int depth_ = 0;

  [[noreturn]] static void fail(const Tok& k, const std::string& m) { throw CompileError(k.line, k.col, m); }
  static Tok word(const Tok& at, std::string text) { return {Tok::Word, std::move(text), at.line, at.col}; }
  static Tok punct(const Tok& at, std::string text) { return {Tok::Punct, std::move(text), at.line, at.col}; }
  void eol(const Tok& at) { out_.push_back({Tok::Eol, "", at.line, at.col}); }
  // one IL line: op operand-tokens EOL
  void line(const Tok& at, const std::string& op, const std::vector<Tok>& operand = {}) {
    out_.push_back(word(at, op));
    out_.insert(out_.end(), operand.begin(), operand.end());
    eol(at);
  }
  std::string new_label() { return "__L" + std::to_string(++labels_); }
  void label(const Tok& at, const std::string& l) {
    out_.push_back(word(at, l));
    out_.push_back(punct(at, ":"));
    eol(at);
  }

  // ---- statements

  void statement(const Stmt& s) {
    temp_.clear();
    temps_ = 0;
    switch (s.kind) {
      case Stmt::Assign: return assign(s);
      case Stmt::CallFb: return call_fb(s);
      case Stmt::CallFn:
        prepare(s.value);
        return value(s.value);
      case Stmt::If: return if_stmt(s);
      case Stmt::Case: return case_stmt(s);
      case Stmt::For: return for_stmt(s);
      case Stmt::While: return while_stmt(s);
      case Stmt::Repeat: return repeat_stmt(s);
      case Stmt::Exit:
      case Stmt::Continue:
        if (loops_.empty()) fail(s.tok, s.tok.text + " outside a loop");
        return line(s.tok, "JMP", {word(s.tok, s.kind == Stmt::Exit ? loops_.back().exit : loops_.back().next)});
      case Stmt::Return: return line(s.tok, "RET");
    }
  }

  void assign(const Stmt& s) {
    if (s.value.kind == Expr::Call && std_en_eno(s.value)) return en_call(s.value, &s.target);
    prepare_var(s.target);
    prepare(s.value);
    value(s.value);
    line(s.tok, "ST", operand(s.target));
  }

  // inst(IN := x, PT := T#1s, Q => done): CAL inst(IN := ..., Q => done).
  // Non-formal, inst(x, T#1s, done): CAL inst(x, T#1s, done), each argument
  // a variable or a constant (an expression computed first), which the IL
  // reader binds to the block's parameters in order (outputs included).
  void call_fb(const Stmt& s) {
    const Expr& c = s.value;
    std::vector<Tok> args;
    for (size_t i = 0; i < c.kids.size(); i++) {
      if (!c.outs[i]) hoist_unless_simple(c.kids[i], true);
      else prepare_var(c.kids[i]);
    }
    for (size_t i = 0; i < c.kids.size(); i++) {
      if (i) args.push_back(punct(c.tok, ","));
      if (c.names[i].kind != Tok::End) {
        args.push_back(word(c.names[i], c.names[i].text));
        args.push_back(punct(c.names[i], c.outs[i] ? "=>" : ":="));
      }
      append(args, operand(c.kids[i]));
    }
    std::vector<Tok> opd = operand_var_name(c);
    opd.push_back(punct(c.tok, "("));
    append(opd, args);
    opd.push_back(punct(c.tok, ")"));
    line(s.tok, "CAL", opd);
  }
  // the instance of an FB call: a name, a member path, or an element (fbs[2])
  std::vector<Tok> operand_var_name(const Expr& c) {
    Expr inst;
    inst.kind = Expr::Var;
    inst.tok = c.tok;
    inst.sels = c.sels;
    prepare_var(inst);
    return operand(inst);
  }

  // IF: each condition jumps past its block when FALSE
  void if_stmt(const Stmt& s) {
    std::string end = new_label();
    for (size_t i = 0; i < s.conds.size(); i++) {
      std::string skip = new_label();
      temp_.clear();
      prepare(s.conds[i]);
      value(s.conds[i]);
      line(s.conds[i].tok, "JMPCN", {word(s.tok, skip)});
      body(s.blocks[i]);
      line(s.tok, "JMP", {word(s.tok, end)});
      label(s.tok, skip);
    }
    if (s.has_else) body(s.blocks.back());
    label(s.tok, end);
  }

  // CASE: the selector once into __Sn, each branch's labels an OR of compares
  void case_stmt(const Stmt& s) {
    std::string sel = "__S" + std::to_string(++selectors_), end = new_label();
    prepare(s.value);
    value(s.value);
    line(s.tok, "ST", {word(s.tok, sel)});
    Expr sv;
    sv.kind = Expr::Var;
    sv.tok = word(s.tok, sel);
    for (size_t b = 0; b < s.labels.size(); b++) {
      Expr cond = case_condition(sv, s.labels[b]);
      std::string skip = new_label();
      temp_.clear();
      temps_ = 0;
      prepare(cond);
      value(cond);
      line(s.labels[b][0].first.tok, "JMPCN", {word(s.tok, skip)});
      body(s.blocks[b]);
      line(s.tok, "JMP", {word(s.tok, end)});
      label(s.tok, skip);
    }
    if (s.has_else) body(s.blocks.back());
    label(s.tok, end);
  }
  static Expr binary(const Tok& at, const char* op, Expr l, Expr r) {
    Expr b;
    b.kind = Expr::Binary;
    b.tok = at;
    b.op = op;
    b.kids.push_back(std::move(l));
    b.kids.push_back(std::move(r));
    return b;
  }
  static Expr case_condition(const Expr& sel, const std::vector<std::pair<Expr, std::optional<Expr>>>& items) {
    std::optional<Expr> cond;
    for (const auto& [lo, hi] : items) {
      Expr one = hi ? binary(lo.tok, "AND", binary(lo.tok, "GE", sel, lo), binary(hi->tok, "LE", sel, *hi))
                    : binary(lo.tok, "EQ", sel, lo);
      cond = cond ? binary(lo.tok, "OR", std::move(*cond), std::move(one)) : std::move(one);
    }
    return *cond;
  }

  // The loops (docs/st.md, "Loops"): a head label, the body, the LOOP back to
  // the head (docs/il.md: each back edge counts against the scan's budget).
  // EXIT jumps to the end, CONTINUE to the LOOP (a JMP goes forward only).
  void loop_body(const Stmt& s, const Loop& l) {
    loops_.push_back(l);
    body(s.blocks[0]);
    loops_.pop_back();
    label(s.tok, l.next);
  }
  void back(const Tok& at, const std::string& head) { line(at, "LOOP", {word(at, head)}); }
  void condition(const Expr& c) {
    temp_.clear();
    temps_ = 0;
    prepare(c);
    value(c);
  }
  // WHILE c DO body END_WHILE: head: c; JMPCN end; body; next: LOOP head; end:
  void while_stmt(const Stmt& s) {
    std::string head = new_label();
    Loop l{new_label(), new_label()};
    label(s.tok, head);
    condition(s.conds[0]);
    line(s.conds[0].tok, "JMPCN", {word(s.tok, l.exit)});
    loop_body(s, l);
    back(s.tok, head);
    label(s.tok, l.exit);
  }
  // REPEAT body UNTIL c END_REPEAT: head: body; next: c; JMPC end; LOOP head; end:
  void repeat_stmt(const Stmt& s) {
    std::string head = new_label();
    Loop l{new_label(), new_label()};
    label(s.tok, head);
    loop_body(s, l);
    condition(s.conds[0]);
    line(s.conds[0].tok, "JMPC", {word(s.tok, l.exit)});
    back(s.tok, head);
    label(s.tok, l.exit);
  }
  static Expr literal(const Tok& at, int64_t v) {
    Expr e;
    e.kind = Expr::Lit;
    e.tok = word(at, std::to_string(v));
    return e;
  }
  // FOR i := a TO b BY c as MatIEC's C has it: for (i = a; c > 0 ? i <= b :
  // i >= b; i += c), b and c evaluated at every test.  A loop of constant
  // bounds and at most kMaxUnrolled iterations whose body does not write i is
  // unrolled instead.
  void for_stmt(const Stmt& s) {
    auto from = const_int(s.from), to = const_int(s.to), by = s.has_by ? const_int(s.by) : std::optional<int64_t>(1);
    if (by && *by == 0) fail(s.by.tok, "FOR ... BY 0 never ends");
    if (from && to && by) {
      int64_t n = *by > 0 ? (*to >= *from ? (*to - *from) / *by + 1 : 0) : (*to <= *from ? (*from - *to) / -*by + 1 : 0);
      if (n <= kMaxUnrolled && !writes(s.blocks[0], s.target.tok.text)) return unrolled_for(s, *from, *by, n);
    }
    temp_.clear();
    temps_ = 0;
    prepare(s.from);
    value(s.from);
    line(s.target.tok, "ST", operand(s.target));
    std::string head = new_label();
    Loop l{new_label(), new_label()};
    label(s.tok, head);
    Expr step = s.has_by ? s.by : literal(s.tok, 1);
    Expr up = binary(s.to.tok, "LE", s.target, s.to), down = binary(s.to.tok, "GE", s.target, s.to);
    Expr test = by ? (*by > 0 ? up : down)
                   : binary(s.tok, "OR", binary(s.tok, "AND", binary(s.by.tok, "GT", step, literal(s.tok, 0)), up),
                            binary(s.tok, "AND", binary(s.by.tok, "LE", step, literal(s.tok, 0)), down));
    condition(test);
    line(s.tok, "JMPCN", {word(s.tok, l.exit)});
    loop_body(s, l);
    Expr next = binary(s.tok, "ADD", s.target, step);
    condition(next);
    line(s.target.tok, "ST", operand(s.target));
    back(s.tok, head);
    label(s.tok, l.exit);
  }
  // i := v; body; ... then i := the value after the last step, as MatIEC's C
  // for loop leaves it; EXIT skips that.
  void unrolled_for(const Stmt& s, int64_t from, int64_t by, int64_t n) {
    Loop l{new_label(), ""};
    for (int64_t k = 0; k < n; k++) {
      l.next = new_label();
      store_const(s.target, from + k * by);
      loop_body(s, l);
    }
    store_const(s.target, from + n * by);
    label(s.tok, l.exit);
  }
  void store_const(const Expr& var, int64_t v) {
    line(var.tok, "LD", {word(var.tok, std::to_string(v))});
    line(var.tok, "ST", {word(var.tok, var.tok.text)});
  }
  static bool writes(const std::vector<Stmt>& b, const std::string& name) {
    for (const Stmt& s : b) {
      if (s.kind == Stmt::Assign && upper(s.target.tok.text) == upper(name)) return true;
      if (s.kind == Stmt::For && upper(s.target.tok.text) == upper(name)) return true;
      for (size_t i = 0; i < s.value.kids.size(); i++)
        if (s.kind == Stmt::CallFb && s.value.outs[i] && upper(s.value.kids[i].tok.text) == upper(name)) return true;
      for (const auto& blk : s.blocks)
        if (writes(blk, name)) return true;
    }
    return false;
  }
  // An integer constant expression: a decimal or based literal, -, +, *.
  static std::optional<int64_t> const_int(const Expr& e) {
    if (e.kind == Expr::Lit) return int_literal(e.tok.text);
    if (e.kind == Expr::Unary && e.op == "NEG") {
      auto v = const_int(e.kids[0]);
      return v ? std::optional<int64_t>(-*v) : std::nullopt;
    }
    if (e.kind == Expr::Binary && (e.op == "ADD" || e.op == "SUB" || e.op == "MUL")) {
      auto a = const_int(e.kids[0]), b = const_int(e.kids[1]);
      if (!a || !b || std::abs(*a) > (int64_t(1) << 30) || std::abs(*b) > (int64_t(1) << 30)) return std::nullopt;
      return e.op == "ADD" ? *a + *b : e.op == "SUB" ? *a - *b : *a * *b;
    }
    return std::nullopt;
  }
  // 42, 16#2A, 2#101, 8#7, 1_000, and those after an integer type's name (INT#5)
  static std::optional<int64_t> int_literal(std::string t) {
    size_t hash = t.find('#');
    if (hash != std::string::npos && !std::isdigit((unsigned char)t[0])) {
      static const std::set<std::string> ints = {"SINT", "INT", "DINT", "LINT", "USINT", "UINT", "UDINT", "ULINT"};
      if (!ints.count(upper(t.substr(0, hash)))) return std::nullopt;
      t = t.substr(hash + 1);
    }
    bool neg = !t.empty() && t[0] == '-';
    if (neg) t = t.substr(1);
    int base = 10;
    if (size_t h = t.find('#'); h != std::string::npos) {
      std::string b = t.substr(0, h);
      base = b == "16" ? 16 : b == "8" ? 8 : b == "2" ? 2 : 0;
      if (!base) return std::nullopt;
      t = t.substr(h + 1);
    }
    int64_t v = 0;
    bool any = false;
    for (char c : t) {
      if (c == '_') continue;
      int d = std::isdigit((unsigned char)c) ? c - '0' : std::isxdigit((unsigned char)c) ? std::toupper((unsigned char)c) - 'A' + 10 : 99;
      if (d >= base || v > (int64_t(1) << 40)) return std::nullopt;
      v = v * base + d, any = true;
    }
    if (!any) return std::nullopt;
    return neg ? -v : v;
  }

  // ---- expressions

  // Could computing e fault or do more than give a value: an element at a
  // computed index (an index fault), a call (a FUNCTION's VAR_IN_OUT and
  // externals, and its own elements)?
  bool may_fault(const Expr& e) const {
    if (e.kind == Expr::Call) return true;
    for (const Expr& k : e.kids)
      if (may_fault(k)) return true;
    for (const Sel& s : e.sels)
      for (const Expr& i : s.index)
        if (!(i.kind == Expr::Lit || foldable(i)) || may_fault(i)) return true;
    return false;
  }
  // l AND r, l OR r where r may fault: MatIEC writes BOOL's AND and OR as C's
  // && and ||, which compute r only when l does not decide (the guard of
  // `WHILE (i <= 5) AND (a[i] <> x)` keeps a[6] unread).  Into a temporary:
  //   <l>; ST __Tn; LD __Tn; __ANDTHEN skip (OR: __ORELSE); <r>; AND __Tn; ST __Tn; skip:
  // The typed reader's __ANDTHEN jumps when a BOOL CR is FALSE and does
  // nothing for a bit string (C's &, which computes both).
  void short_circuit(const Expr& e) {
    std::string skip = new_label(), t = "__T" + std::to_string(++temps_);
    prepare(e.kids[0]);
    value(e.kids[0]);
    line(e.tok, "ST", {word(e.tok, t)});
    line(e.tok, "LD", {word(e.tok, t)});
    line(e.tok, e.op == "AND" ? "__ANDTHEN" : "__ORELSE", {word(e.tok, skip)});
    prepare(e.kids[1]);
    value(e.kids[1]);
    line(e.tok, e.op, {word(e.tok, t)});
    line(e.tok, "ST", {word(e.tok, t)});
    label(e.tok, skip);
    temp_[&e] = t;
  }
  static bool has_call(const Expr& e) {
    if (e.kind == Expr::Call) return true;
    for (const Expr& k : e.kids)
      if (has_call(k)) return true;
    for (const Sel& s : e.sels)
      for (const Expr& k : s.index)
        if (has_call(k)) return true;
    return false;
  }
  static int height(const Expr& e) {
    int h = 0;
    for (const Expr& k : e.kids) h = std::max(h, height(k));
    return h + 1;
  }
  // An expression of untyped integer literals (-7 / 2, 3 * 4 + 1): folded
  // to one literal with C's division and remainder, as MatIEC folds constant
  // expressions, so that it takes the type of its use like a literal does.
  static std::optional<int64_t> folded(const Expr& e) {
    if (e.kind == Expr::Lit) {
      const std::string& t = e.tok.text;
      if (t.find('#') != std::string::npos || !std::isdigit((unsigned char)t[0])) return std::nullopt;
      return int_literal(t);
    }
    if (e.kind == Expr::Unary && e.op == "NEG") {
      auto v = folded(e.kids[0]);
      return v ? std::optional<int64_t>(-*v) : std::nullopt;
    }
    if (e.kind != Expr::Binary) return std::nullopt;
    auto a = folded(e.kids[0]), b = folded(e.kids[1]);
    constexpr int64_t lim = int64_t(1) << 31;
    if (!a || !b || *a > lim || *a < -lim || *b > lim || *b < -lim) return std::nullopt;
    if (e.op == "ADD") return *a + *b;
    if (e.op == "SUB") return *a - *b;
    if (e.op == "MUL") return *a * *b;
    if (e.op == "DIV" && *b != 0) return *a / *b;
    if (e.op == "MOD" && *b != 0) return *a % *b;
    return std::nullopt;
  }
  static bool foldable(const Expr& e) { return e.kind != Expr::Lit && folded(e).has_value(); }

  // An operand IL takes as it is: a literal (a negated one too), or a
  // variable whose indices are literals or plain variables.
  bool simple(const Expr& e) const {
    if (temp_.count(&e)) return true;
    if (e.kind == Expr::Lit || foldable(e)) return true;
    if (e.kind == Expr::Unary && e.op == "NEG" && e.kids[0].kind == Expr::Lit) return true;
    if (e.kind != Expr::Var) return false;
    for (const Sel& s : e.sels)
      for (const Expr& i : s.index)
        // a constant index expression (arr[(10 MOD 5) + 1]) is folded, not hoisted: operand() writes its value
        if (!(i.kind == Expr::Lit || foldable(i) || (i.kind == Expr::Var && i.sels.empty()) || temp_.count(&i))) return false;
    return true;
  }
  // Computes e into a temporary unless IL takes it as an operand.  `cut`:
  // its use cuts it to its type (a function's or block's input, an index),
  // so the typed reader stores it cut (__Un), where C's int is computed
  // with no more than the type's own arithmetic (Reader::narrow_back); an
  // operator's operand (__Tn) keeps C's int.
  void hoist_unless_simple(const Expr& e, bool cut = false) {
    if (e.kind == Expr::Var) prepare_var(e);
    if (simple(e)) return;
    prepare(e);
    value(e);
    std::string t = (cut ? "__U" : "__T") + std::to_string(++temps_);
    line(e.tok, "ST", {word(e.tok, t)});
    temp_[&e] = t;
  }
  void prepare_var(const Expr& v) {
    for (const Sel& s : v.sels)
      for (const Expr& i : s.index)
        if (!(i.kind == Expr::Lit || (i.kind == Expr::Var && i.sels.empty()))) hoist_unless_simple(i, true);
  }
  // What value(e) needs computed first.
  void prepare(const Expr& e) {
    Nest n(depth_, e.tok);
    switch (e.kind) {
      case Expr::Lit: return;
      case Expr::Var: return prepare_var(e);
      case Expr::Unary: return prepare(e.kids[0]);
      case Expr::Binary: {
        if ((e.op == "AND" || e.op == "OR") && may_fault(e.kids[1])) return short_circuit(e);
        prepare(e.kids[0]);
        const Expr& r = e.kids[1];
        if (simple(r) || r.kind == Expr::Var) return prepare_var(r);
        if (has_call(r) || height(r) > kMaxParenDepth) return hoist_unless_simple(r);
        return prepare(r);
      }
      case Expr::Call: {
        if (std_en_eno(e)) return en_call(e);
        std::vector<const Expr*> in = inputs(e);
        bool formal = formal_user_call(e);
        for (size_t i = 0; i < in.size(); i++) {
          if (i == 0 && !formal) prepare(*in[0]);
          else hoist_unless_simple(*in[i], true);
        }
        for (size_t i = 0; i < e.kids.size(); i++)
          if (e.outs[i]) prepare_var(e.kids[i]);
        return;
      }
    }
  }
  // A standard function called with EN or ENO (as Beremiz writes a block
  // whose EN is wired): MatIEC's generated C returns the type's initial value
  // and sets ENO FALSE when EN is FALSE, else computes and sets ENO TRUE.
  // The value goes to a temporary, computed only with EN:
  //   LD en; JMPCN skip; <f(inputs)>; ST __Tr; JMP end; skip: LD __ZERO; ST __Tr; end: LD en; ST eno
  bool std_en_eno(const Expr& c) const {
    if (formal_user_call(c) || c.names.empty() || c.names[0].kind == Tok::End) return false;
    for (const Tok& n : c.names)
      if (upper(n.text) == "EN" || upper(n.text) == "ENO") return true;
    return false;
  }
  // `to`: the assignment's target, written directly (so that a literal
  // input, MOVE(EN := c, IN := 1), takes the target's type)
  void en_call(const Expr& c, const Expr* to = nullptr) {
    Expr plain = c;
    plain.kids.clear(), plain.names.clear(), plain.outs.clear();
    const Expr *en = nullptr, *eno = nullptr;
    for (size_t i = 0; i < c.kids.size(); i++) {
      std::string u = upper(c.names[i].text);
      if (u == "EN" && !c.outs[i]) en = &c.kids[i];
      else if (u == "ENO" && c.outs[i]) eno = &c.kids[i];
      else plain.kids.push_back(c.kids[i]), plain.names.push_back(c.names[i]), plain.outs.push_back(c.outs[i]);
    }
    std::string end = new_label(), skip = new_label(), r = "__T" + std::to_string(++temps_);
    if (to) prepare_var(*to);
    std::vector<Tok> dest = to ? operand(*to) : std::vector<Tok>{word(c.tok, r)};
    if (en) hoist_unless_simple(*en);
    std::vector<Tok> en_opd = en ? operand(*en) : std::vector<Tok>{word(c.tok, "TRUE")};
    if (en) {
      line(c.tok, "LD", en_opd);
      line(c.tok, "JMPCN", {word(c.tok, skip)});
    }
    prepare(plain);
    value(plain);
    line(c.tok, "ST", dest);
    if (en) {
      line(c.tok, "JMP", {word(c.tok, end)});
      label(c.tok, skip);
      line(c.tok, "LD", {word(c.tok, "__ZERO")});
      line(c.tok, "ST", dest);
      label(c.tok, end);
    }
    if (eno) {
      prepare_var(*eno);
      line(c.tok, "LD", en_opd);
      line(c.tok, "ST", operand(*eno));
    }
    if (!to) temp_[&c] = r;
  }

  // A call of a function that is not standard, with formal arguments: passed
  // to the typed reader as F(A := x, B := y), which binds them by name.
  bool formal_user_call(const Expr& c) const {
    bool named = !c.names.empty() && c.names[0].kind != Tok::End;
    return (named || c.kids.empty()) && functions_.count(upper(c.tok.text));
  }
  static bool one_input_std(const std::string& u) {
    static const std::set<std::string> k = {"ABS", "NEG", "SQRT", "LN", "LOG", "EXP", "SIN", "COS", "TAN", "ASIN", "ACOS",
                                            "ATAN", "NOT", "TRUNC", "LEN", "MOVE"};
    return k.count(u) > 0 || u.find("_TO_") != std::string::npos || u.find("BCD") != std::string::npos;
  }
  // The inputs of a call in order (a formal call of a standard function put
  // in its order; MUX's IN0, IN1 ... by number).
  std::vector<const Expr*> inputs(const Expr& c) const {
    std::vector<const Expr*> in;
    bool named = !c.names.empty() && c.names[0].kind != Tok::End;
    if (!named || formal_user_call(c)) {
      for (size_t i = 0; i < c.kids.size(); i++) {
        if (named != (c.names[i].kind != Tok::End)) fail(c.kids[i].tok, "a call mixes formal (NAME := x) and positional arguments");
        if (!c.outs[i]) in.push_back(&c.kids[i]);
      }
      return in;
    }
    std::string u = upper(c.tok.text);
    std::vector<std::string> order;
    if (const auto* k = std_inputs(u)) order = *k;
    else if (one_input_std(u)) order = {"IN"};
    else if (u == "MUX") {
      order.push_back("K");
      for (size_t i = 0; i + 1 < c.kids.size(); i++) order.push_back("IN" + std::to_string(i));
    } else {
      for (size_t i = 0; i < c.kids.size(); i++) order.push_back("IN" + std::to_string(i + 1));
    }
    for (const std::string& name : order) {
      size_t i = 0;
      while (i < c.kids.size() && upper(c.names[i].text) != name) i++;
      if (i == c.kids.size()) fail(c.tok, c.tok.text + " needs its input " + name);
      in.push_back(&c.kids[i]);
    }
    if (in.size() != c.kids.size()) fail(c.tok, c.tok.text + "'s inputs are " + join(order));
    return in;
  }
  static std::string join(const std::vector<std::string>& v) {
    std::string s;
    for (const auto& x : v) s += (s.empty() ? "" : ", ") + x;
    return s;
  }

  // The value of e into the CR.  prepare(e) came first.
  void value(const Expr& e) {
    Nest n(depth_, e.tok);
    if (simple(e)) return line(e.tok, "LD", operand(e));
    switch (e.kind) {
      case Expr::Lit:
      case Expr::Var: return;  // simple
      case Expr::Unary:
        value(e.kids[0]);
        return line(e.tok, e.op);
      case Expr::Binary:
        value(e.kids[0]);
        return right(e.tok, e.op, e.kids[1]);
      case Expr::Call: return call_value(e);
    }
  }
  // CR := CR op r
  void right(const Tok& at, const std::string& op, const Expr& r) {
    if (simple(r)) return line(at, op, operand(r));
    std::vector<Tok> inner;
    inner.swap(out_);
    value(r);
    inner.swap(out_);
    // the group's first line is LD x: it becomes op( x
    out_.push_back(word(at, op));
    out_.push_back(punct(at, "("));
    out_.insert(out_.end(), inner.begin() + 1, inner.end());
    out_.push_back(punct(at, ")"));
    eol(at);
  }
  void call_value(const Expr& c) {
    std::string u = upper(c.tok.text);
    if (formal_user_call(c)) {
      std::vector<Tok> opd{punct(c.tok, "(")};
      for (size_t i = 0; i < c.kids.size(); i++) {
        if (i) opd.push_back(punct(c.tok, ","));
        opd.push_back(word(c.names[i], c.names[i].text));
        opd.push_back(punct(c.names[i], c.outs[i] ? "=>" : ":="));
        append(opd, operand(c.kids[i]));
      }
      opd.push_back(punct(c.tok, ")"));
      return line(c.tok, c.tok.text, opd);
    }
    std::vector<const Expr*> in = inputs(c);
    if (in.empty()) fail(c.tok, c.tok.text + "() without inputs");
    value(*in[0]);
    // a standard function's result is of its type: MatIEC's ADD__INT__INT
    // returns an INT, where the operator + computes on C's int (the typed
    // reader's C arithmetic): the IL's MOVE cuts it there
    static const std::set<std::string> cut = {"ADD", "SUB", "MUL", "DIV", "MOD", "AND", "OR", "XOR", "NOT", "NEG"};
    if (extensible(u) || (comparison(u) && in.size() == 2)) {
      for (size_t i = 1; i < in.size(); i++) line(c.tok, u, operand(*in[i]));
      if (cut.count(u)) line(c.tok, "MOVE");
      return;
    }
    if (comparison(u)) {  // IEC 61131-3's extensible compare: GT(a, b, c) = a > b AND b > c (MatIEC's too)
      if (in.size() < 2) fail(c.tok, c.tok.text + "() compares two inputs or more, this call has one");
      line(c.tok, u, operand(*in[1]));
      for (size_t i = 2; i < in.size(); i++) {
        out_.push_back(word(c.tok, "AND"));
        out_.push_back(punct(c.tok, "("));
        append(out_, operand(*in[i - 1]));
        eol(c.tok);
        line(c.tok, u, operand(*in[i]));
        out_.push_back(punct(c.tok, ")"));
        eol(c.tok);
      }
      return;
    }
    std::vector<Tok> opd;
    for (size_t i = 1; i < in.size(); i++) {
      if (i > 1) opd.push_back(punct(c.tok, ","));
      append(opd, operand(*in[i]));
    }
    line(c.tok, c.tok.text, opd);
    if (cut.count(u)) line(c.tok, "MOVE");
  }

  static void append(std::vector<Tok>& a, const std::vector<Tok>& b) { a.insert(a.end(), b.begin(), b.end()); }
  // The IL operand tokens of a simple expression.
  std::vector<Tok> operand(const Expr& e) const {
    if (auto t = temp_.find(&e); t != temp_.end()) return {word(e.tok, t->second)};
    if (e.kind == Expr::Lit) return {e.tok};
    if (foldable(e)) return {word(e.tok, std::to_string(*folded(e)))};
    if (e.kind == Expr::Unary) return {word(e.tok, negated(e.kids[0].tok))};
    std::vector<Tok> o{e.tok};
    for (const Sel& s : e.sels) {
      o.push_back(punct(e.tok, "["));
      for (size_t i = 0; i < s.index.size(); i++) {
        if (i) o.push_back(punct(e.tok, ","));
        append(o, operand(s.index[i]));
      }
      o.push_back(punct(e.tok, "]"));
      if (s.member.kind == Tok::Word) o.push_back(s.member);
    }
    return o;
  }
  // -5, INT#-5, T#-2s, -1.5
  static std::string negated(const Tok& lit) {
    const std::string& t = lit.text;
    size_t hash = t.find('#');
    if (hash != std::string::npos && !std::isdigit((unsigned char)t[0])) {
      std::string v = t.substr(hash + 1);
      return t.substr(0, hash + 1) + (v[0] == '-' ? v.substr(1) : "-" + v);
    }
    return t[0] == '-' ? t.substr(1) : "-" + t;
  }
};

// ---------------------------------------------------------------- the file

class File {
 public:
  // instance: which program instance of a CONFIGURATION of several to write (-1: it must have one)
  explicit File(const std::vector<Tok>& t, int instance = -1, iecil::Recovery* rec = nullptr) : t_(t), instance_(instance), rec_(rec) {}
  const Configuration& config() const { return config_; }
  // Only the CONFIGURATION: its tasks and program instances.
  void read_configuration() {
    instance_ = kJustRead;
    find_configuration();
  }
  static constexpr int kJustRead = -2;

  std::vector<Tok> run() {
    collect_functions();
    find_configuration();
    while (peek().kind != Tok::End) {
      const Tok& k = peek();
      std::string u = upper(k.text);
      if (u == "TYPE") type_block();
      else if (u == "PROGRAM" && !run_.empty() && upper(peek(1).text) != run_) skip_to("END_PROGRAM");
      else if (u == "PROGRAM" || u == "FUNCTION_BLOCK" || u == "FUNCTION") pou(u);
      else if (u == "CONFIGURATION") skip_to("END_CONFIGURATION");
      else if (u == "ACTION" || u == "METHOD" || u == "INTERFACE" || u == "CLASS")
        fail(k, "'" + k.text + "' is not IEC 61131-3 2nd edition; ldc does not read it (docs/st.md)");
      else fail(k, "expected TYPE, FUNCTION_BLOCK, FUNCTION, PROGRAM or CONFIGURATION, found '" + k.text + "'");
    }
    if (!run_.empty() && !ran_) fail(run_tok_, "program type '" + run_tok_.text + "' is not declared in this file");
    out_.push_back(peek());
    return std::move(out_);
  }

 private:
  const std::vector<Tok>& t_;
  int instance_ = -1;
  iecil::Recovery* rec_ = nullptr;  // the statements recover from their errors
  Configuration config_;
  std::string resource_ = "resource";  // the RESOURCE being read
  size_t pos_ = 0;
  std::vector<Tok> out_;
  std::set<std::string> functions_;
  // the CONFIGURATION: the program type its one instance runs, its globals
  std::string run_;
  Tok run_tok_;
  bool ran_ = false;
  std::vector<Tok> globals_;                 // VAR_GLOBAL blocks, as IL reader tokens
  std::map<std::string, Tok> global_names_;  // upper-case

  void skip_to(const char* end) {
    const Tok& k = peek();
    while (!kw(peek(), end)) {
      if (peek().kind == Tok::End) fail(k, "'" + k.text + "' without " + end);
      next();
    }
    next();
  }

  // configuration = CONFIGURATION NAME { var_global } { resource } END_CONFIGURATION
  // resource = RESOURCE NAME ON NAME { var_global } { task } { instance } END_RESOURCE   (or its body alone)
  // task = TASK NAME "(" ... ")" ";"        instance = PROGRAM NAME [ WITH NAME ] ":" NAME [ "(" ... ")" ] ";"
  // ldc compiles one program per ST file: the configuration runs one program
  // instance; its task's interval is ldrun's --period (docs/st.md).
  void find_configuration() {
    size_t save = pos_;
    while (peek().kind != Tok::End && !kw(peek(), "CONFIGURATION")) next();
    if (peek().kind == Tok::End) { pos_ = save; return; }
    const Tok& conf = next();
    config_.name = next().text;
    std::vector<std::pair<Tok, Tok>> instances;  // instance name, program type
    int tasks = 0;
    while (!kw(peek(), "END_CONFIGURATION")) {
      const Tok& k = peek();
      std::string u = upper(k.text);
      if (k.kind == Tok::End) fail(conf, "CONFIGURATION without END_CONFIGURATION");
      if (u == "VAR_GLOBAL") global_block();
      else if (u == "RESOURCE") { next(), resource_ = next().text; if (kw(peek(), "ON")) next(), next(); }
      else if (u == "END_RESOURCE") next();
      else if (u == "TASK") { tasks++; task(); }
      else if (u == "PROGRAM") {
        next();
        Tok inst = next();
        ConfigInstance ci{inst.text, "", "", inst.line, inst.col};
        if (kw(peek(), "WITH")) next(), ci.task = next().text;
        if (!(peek().kind == Tok::Punct && peek().text == ":")) fail(peek(), "expected ':' and the program's type after PROGRAM " + inst.text);
        next();
        instances.push_back({inst, next()});
        ci.program = instances.back().second.text;
        config_.instances.push_back(ci);
        skip_past(";");
      } else if (u == "VAR_ACCESS" || u == "VAR_CONFIG") {
        fail(k, "'" + k.text + "' in a CONFIGURATION is not read (docs/st.md)");
      } else {
        fail(k, "unexpected '" + k.text + "' in the CONFIGURATION");
      }
    }
    if (instances.empty()) fail(conf, "the CONFIGURATION runs no PROGRAM");
    bool several = instances.size() > 1 || tasks > 1;
    for (const auto& [g, tok] : global_names_) config_.globals.push_back(g);
    if (several && instance_ == kJustRead) return;  // import_st compiles each instance
    if (several && instance_ < 0)
      fail(instances.size() > 1 ? instances[1].first : conf,
           "a CONFIGURATION of " + std::to_string(instances.size()) + " program instances and " + std::to_string(tasks) +
               " tasks is a project: `ldc FILE -o DIR` writes the images of its programs (docs/st.md)");
    if (several && size_t(instance_) >= instances.size()) throw std::logic_error("no such program instance");
    run_tok_ = instances[several ? size_t(instance_) : 0].second;
    run_ = upper(run_tok_.text);
    pos_ = save;
  }
  // TASK NAME "(" [INTERVAL ":=" literal] ["," PRIORITY ":=" number] ... ")" ";"
  void task() {
    next();
    const Tok& n = next();
    ConfigTask t{n.text, resource_, "", "", n.line, n.col};
    while (!(peek().kind == Tok::Punct && peek().text == ";")) {
      if (peek().kind == Tok::End) fail(n, "TASK " + n.text + " without its ';'");
      std::string u = upper(next().text);
      if ((u == "INTERVAL" || u == "PRIORITY") && peek().kind == Tok::Punct && peek().text == ":=") {
        next();
        (u == "INTERVAL" ? t.interval : t.priority) = next().text;
      }
    }
    next();
    config_.tasks.push_back(t);
  }
  void skip_past(const char* p) {
    const Tok& k = peek();
    while (!(peek().kind == Tok::Punct && peek().text == p)) {
      if (peek().kind == Tok::End) fail(k, std::string("expected '") + p + "' after '" + k.text + "'");
      next();
    }
    next();
  }
  // VAR_GLOBAL ... END_VAR of the configuration: moved into the program it runs
  void global_block() {
    std::swap(out_, globals_);
    size_t from = out_.size();
    var_block();
    // the names declared: a word after a line end or a ',', before ':', ',' or AT
    for (size_t i = from + 1; i + 1 < out_.size(); i++) {
      const Tok &before = out_[i - 1], &after = out_[i + 1];
      bool starts = before.kind == Tok::Eol || (before.kind == Tok::Punct && before.text == ",");
      if (out_[i].kind == Tok::Word && starts && ends_name(after)) global_names_[upper(out_[i].text)] = out_[i];
    }
    std::swap(out_, globals_);
  }

  const Tok& peek(size_t k = 0) const { return t_[std::min(pos_ + k, t_.size() - 1)]; }
  const Tok& next() { return t_[pos_ < t_.size() - 1 ? pos_++ : pos_]; }
  [[noreturn]] static void fail(const Tok& k, const std::string& m) { throw CompileError(k.line, k.col, m); }
  static bool kw(const Tok& k, const char* w) { return k.kind == Tok::Word && upper(k.text) == w; }
  // Does `after` end a declared name (NAME : ..., NAME, ..., NAME AT ...)?
  static bool ends_name(const Tok& after) {
    return (after.kind == Tok::Punct && (after.text == ":" || after.text == ",")) || kw(after, "AT");
  }
  void eol() { out_.push_back({Tok::Eol, "", peek().line, peek().col}); }

  void collect_functions() {
    for (size_t i = 0; i + 1 < t_.size(); i++)
      if (kw(t_[i], "FUNCTION") && t_[i + 1].kind == Tok::Word) functions_.insert(upper(t_[i + 1].text));
  }

  // Declaration tokens up to `end` (a keyword), copied: a line end after each
  // ';' and a sign joined to the number after it (the IL reader reads -5 as one word).
  // `types`: a TYPE block, whose END_STRUCT may lack its ';' (CODESYS)
  void copy_until(const char* end, const Tok& opener, bool types = false) {
    while (!kw(peek(), end)) {
      const Tok& k = next();
      if (k.kind == Tok::End) fail(opener, "'" + opener.text + "' without " + end);
      if (types && kw(k, "END_STRUCT") && !(peek().kind == Tok::Punct && peek().text == ";")) {
        out_.push_back(k);
        out_.push_back({Tok::Punct, ";", k.line, k.col});
        eol();
        continue;
      }
      if (k.kind == Tok::Punct && (k.text == "-" || k.text == "+") && peek().kind == Tok::Word && signable(peek().text)) {
        Tok n = next();
        if (k.text == "-") n.text = signed_text(n.text);
        n.line = k.line, n.col = k.col;
        out_.push_back(n);
        continue;
      }
      out_.push_back(k);
      if (k.kind == Tok::Punct && k.text == ";") eol();
    }
  }
  static bool signable(const std::string& t) { return std::isdigit((unsigned char)t[0]) || t.find('#') != std::string::npos; }
  static std::string signed_text(const std::string& t) {
    size_t hash = t.find('#');
    if (hash != std::string::npos && !std::isdigit((unsigned char)t[0])) return t.substr(0, hash + 1) + "-" + t.substr(hash + 1);
    return "-" + t;
  }

  // TYPE ... END_TYPE, as the IL reader reads it
  void type_block() {
    const Tok& k = next();
    out_.push_back(k);
    eol();
    copy_until("END_TYPE", k, true);
    out_.push_back(next());
    eol();
  }

  // PROGRAM|FUNCTION_BLOCK|FUNCTION NAME [":" TYPE] { var_block } statements END_...
  void pou(const std::string& kind) {
    size_t decl_start = pos_;
    const Tok& head = next();
    out_.push_back(head);
    out_.push_back(next());  // its name
    if (kind == "FUNCTION") {
      if (peek().kind == Tok::Punct && peek().text == ":") {
        out_.push_back(next());
        out_.push_back(next());
      }
    }
    eol();
    bool runs = kind == "PROGRAM" && !run_.empty();
    ran_ |= runs;
    if (runs) out_.insert(out_.end(), globals_.begin(), globals_.end());
    while (peek().kind == Tok::Word && upper(peek().text).rfind("VAR", 0) == 0) {
      if (runs && kw(peek(), "VAR_EXTERNAL")) external_block();
      else var_block();
    }
    std::string end = "END_" + kind;
    if (sfc_element_start(peek(), peek(1))) {
      if (kind == "FUNCTION") fail(peek(), "a chart in a FUNCTION, which keeps nothing from one call to the next; IEC 61131-3 charts structure programs and function blocks");
      chart(end, decl_start, runs);
    } else {
      Parser p(t_, pos_, functions_, rec_);
      std::vector<Stmt> body = p.statement_list({end.c_str()}, true);
      pos_ = p.pos();
      Writer(out_, functions_, rec_).body(body);
    }
    if (peek().kind == Tok::End) out_.push_back({Tok::Word, end, peek().line, peek().col});  // END_... left out at the end
    else out_.push_back(next());
    eol();
  }
  // A body that is a chart written as text (frontend/st/sfc_text.h): its
  // state declared in a VAR block of its own, its statements written as any
  // body's.  The names the POU declares from decl_start on (a word before ':',
  // ',' or AT), and a configuration's globals, are the variables an action
  // association may name.
  void chart(const std::string& end, size_t decl_start, bool runs) {
    std::set<std::string> vars;
    for (size_t i = decl_start; i + 1 < pos_; i++)
      if (t_[i].kind == Tok::Word && ends_name(t_[i + 1])) vars.insert(upper(t_[i].text));
    if (runs)
      for (const auto& [name, tok] : global_names_) vars.insert(name);
    SfcText c = sfc_to_st(t_, pos_, end, vars);
    out_.push_back({Tok::Word, "VAR", c.body.front().line, c.body.front().col});
    eol();
    for (const SfcText::Var& v : c.vars) {  // NAME : BOOL := init ;
      auto word = [&](Tok::Kind k, const std::string& w) { out_.push_back({k, w, v.at.line, v.at.col}); };
      word(Tok::Word, v.name), word(Tok::Punct, ":"), word(Tok::Word, "BOOL"), word(Tok::Punct, ":="), word(Tok::Word, v.init), word(Tok::Punct, ";");
      eol();
    }
    out_.push_back({Tok::Word, "END_VAR", c.body.front().line, c.body.front().col});
    eol();
    Parser p(c.body, 0, functions_, rec_);
    Writer(out_, functions_, rec_).body(p.statement_list({end.c_str()}, true));
  }
  // VAR_EXTERNAL of the program a CONFIGURATION runs: its globals are the
  // program's own (global_block), so each name is checked and the block dropped
  void external_block() {
    const Tok& head = next();
    while (kw(peek(), "CONSTANT")) next();
    while (!kw(peek(), "END_VAR")) {
      const Tok& n = next();
      if (n.kind == Tok::End) fail(head, "VAR_EXTERNAL without END_VAR");
      if (n.kind == Tok::Word && !global_names_.count(upper(n.text)) &&
          (peek().kind == Tok::Punct && (peek().text == ":" || peek().text == ",")))
        fail(n, "VAR_EXTERNAL '" + n.text + "' is not a VAR_GLOBAL of the CONFIGURATION");
      if (n.kind == Tok::Punct && n.text == ":") skip_past(";");
    }
    next();
  }
  void var_block() {
    const Tok& head = next();
    out_.push_back(head);
    while (kw(peek(), "CONSTANT") || kw(peek(), "RETAIN") || kw(peek(), "NON_RETAIN")) out_.push_back(next());
    eol();
    copy_until("END_VAR", head);
    out_.push_back(next());
    eol();
  }
};

}  // namespace

// Pragmas { ... }: MatIEC copies one among a POU's statements into the C it
// generates, as C code (Beremiz's way of calling C from ST); ldc runs no C, so
// such a program is refused by name.  Elsewhere (declarations, around the
// POUs) a pragma says nothing to the program and is dropped.
std::vector<Tok> pragmas(const std::vector<Tok>& t) {
  std::vector<Tok> out;
  out.reserve(t.size());
  bool in_pou = false, in_var = false, in_body = false;
  for (size_t i = 0; i < t.size(); i++) {
    const Tok& k = t[i];
    if (k.kind == Tok::Punct && k.text == "{") {
      if (in_body)
        throw CompileError(k.line, k.col, "a pragma { ... } among the statements: MatIEC copies it into the C it generates, as C code; ldc runs no C (docs/st.md)");
      continue;
    }
    out.push_back(k);
    std::string u = k.kind == Tok::Word ? upper(k.text) : "";
    if (u == "PROGRAM" || u == "FUNCTION_BLOCK" || u == "FUNCTION") {
      in_pou = true, in_body = false;
      auto word = [&](size_t j) { return j < t.size() && t[j].kind == Tok::Word; };
      if (word(i + 1)) out.push_back(t[++i]);  // the name
      if (word(i + 2) && t[i + 1].kind == Tok::Punct && t[i + 1].text == ":")  // a FUNCTION's ": TYPE"
        out.push_back(t[i + 1]), out.push_back(t[i + 2]), i += 2;
    } else if (u.rfind("END_PROGRAM", 0) == 0 || u == "END_FUNCTION_BLOCK" || u == "END_FUNCTION") {
      in_pou = in_body = false;
    } else if (u.rfind("VAR", 0) == 0 && !in_body) {
      in_var = true;
    } else if (u == "END_VAR") {
      in_var = false;
    } else if (in_pou && !in_var) {
      in_body = true;
    }
  }
  return out;
}

std::vector<Tok> to_il_tokens(const std::vector<Tok>& st, int instance) { return File(pragmas(st), instance).run(); }
std::vector<Tok> to_il_tokens(const std::vector<Tok>& st, int instance, iecil::Recovery& rec) {
  return File(pragmas(st), instance, &rec).run();
}

Configuration configuration(const std::vector<Tok>& st) {
  File f(st);
  f.read_configuration();
  return f.config();
}

}  // namespace ldc::st

namespace ldc {

Program parse_st(std::string_view text, const std::string& filename) {
  return iecil::parse_typed_il(st::to_il_tokens(st::lex(text)), filename, true);
}

Program parse_st(std::string_view text, const std::string& filename, Diagnostics& diag) {
  diag.source(filename, text);
  iecil::Recovery rec(diag, filename);
  std::vector<iecil::Tok> toks = st::lex(text);
  return iecil::parse_typed_il(st::to_il_tokens(toks, -1, rec), filename, true, rec);
}

namespace {

// A program of the typed reader as raw rungs (TreeRung::raw), for the
// configuration's tasks (driver: a project, as a PLCopen configuration's).
TreeProgram raw_tree(Program p) {
  TreeProgram t;
  t.source = p.source, t.aliases = std::move(p.aliases), t.end_labels = std::move(p.end_labels), t.retain = std::move(p.retain);
  t.vars = std::move(p.vars);
  for (Rung& r : p.rungs) {
    TreeRung tr;
    tr.labels = std::move(r.labels), tr.title = std::move(r.title), tr.line = r.line;
    tr.raw = std::move(r.code);
    t.rungs.push_back(std::move(tr));
  }
  return t;
}

// A task's interval, an IEC TIME literal, in whole microseconds.
uint32_t period_us(const st::ConfigTask& t) {
  std::string why;
  auto lit = model::parse_literal(t.interval, why);
  if (!lit || lit->lit.ty != Ty::TIME || int64_t(lit->lit.bits) % 1000 != 0 || int64_t(lit->lit.bits) < 50000 || int64_t(lit->lit.bits) > 10000000000LL)
    throw CompileError(t.line, t.col, "task '" + t.name + "': interval '" + t.interval + "' is not a period ldc can run (a TIME literal, a whole number of microseconds, 50us..10s)");
  return uint32_t(int64_t(lit->lit.bits) / 1000);
}

// The words of POU `name` (its PROGRAM ... END_PROGRAM), and of every
// FUNCTION_BLOCK and FUNCTION (they may name globals as VAR_EXTERNAL), upper-case.
std::set<std::string> words_of(const std::vector<iecil::Tok>& t, const std::string& name) {
  std::set<std::string> w;
  bool in = false;
  for (size_t i = 0; i < t.size(); i++) {
    std::string u = t[i].kind == iecil::Tok::Word ? iecil::upper(t[i].text) : "";
    if ((u == "PROGRAM" && i + 1 < t.size() && iecil::upper(t[i + 1].text) == iecil::upper(name)) || u == "FUNCTION_BLOCK" || u == "FUNCTION") in = true;
    else if (u == "END_PROGRAM" || u == "END_FUNCTION_BLOCK" || u == "END_FUNCTION") in = false;
    else if (in && !u.empty()) w.insert(u);
  }
  return w;
}

// A global that the programs of two tasks name must be one both see: a BOOL
// (a relay, M) or a variable at an input or output (docs/st.md, as
// docs/plcopen.md "Configurations of several tasks"); the others live in each
// program's private memory.  Every program lays the globals out first, from
// the same base, so a shared one is at the same device in each (checked).
void check_shared_globals(const std::vector<iecil::Tok>& toks, const st::Configuration& cfg, const std::vector<Program>& progs,
                          const PlcopenImport& im) {
  std::vector<std::set<std::string>> words;
  for (const st::ConfigInstance& ci : cfg.instances) words.push_back(words_of(toks, ci.program));
  for (const std::string& g : cfg.globals) {
    std::vector<size_t> users;
    for (size_t k = 0; k < words.size(); k++)
      if (words[k].count(g)) users.push_back(k);
    if (users.size() < 2) continue;
    const Alias* first = nullptr;
    for (size_t k : users)
      for (const Alias& a : progs[k].aliases)
        if (iecil::upper(a.name) == g) {
          if (!first) first = &a;
          Dev d = a.dev.dev;
          if (d != Dev::M && d != Dev::X && d != Dev::Y && d != Dev::WX && d != Dev::WY)
            throw CompileError(im.tasks[users[0]].line, im.tasks[users[0]].col,
                               "global variable '" + a.name + "' is used by the programs of tasks '" + im.tasks[users[0]].name + "' and '" +
                                   im.tasks[users[1]].name + "'; ldc keeps it in a program's private memory (" + dev_name(d) +
                                   "), so tasks share only BOOL globals (relays, M) and variables located at inputs and outputs (%I, %Q)");
          if (!(a.dev == first->dev)) throw std::logic_error("global " + a.name + " placed differently in two tasks' programs");
        }
  }
}

// The task of program instance k of the configuration.
PlcopenTask task_of(const st::Configuration& cfg, size_t k) {
  const st::ConfigInstance& ci = cfg.instances[k];
  auto t = std::find_if(cfg.tasks.begin(), cfg.tasks.end(), [&](const st::ConfigTask& x) { return iecil::upper(x.name) == iecil::upper(ci.task); });
  if (ci.task.empty() || t == cfg.tasks.end())
    throw CompileError(ci.line, ci.col, "program instance '" + ci.name + "' has no task (PROGRAM " + ci.name + " WITH TASK : TYPE); ldc runs each program of a configuration in its task");
  for (size_t j = 0; j < k; j++)
    if (iecil::upper(cfg.instances[j].task) == iecil::upper(ci.task))
      throw CompileError(ci.line, ci.col, "task '" + ci.task + "' runs a second program ('" + ci.name + "' after '" + cfg.instances[j].name + "'); ldc runs one program per task of an ST configuration");
  PlcopenTask pt;
  pt.name = t->name, pt.resource = t->resource, pt.program = ci.name;
  pt.line = t->line, pt.col = t->col;
  pt.period_us = period_us(*t);
  if (!t->priority.empty()) {
    if (t->priority.find_first_not_of("0123456789") != std::string::npos || t->priority.size() > 2)
      throw CompileError(t->line, t->col, "task '" + t->name + "': priority '" + t->priority + "' is not one ldc has (0, the highest, .. 99)");
    pt.priority = uint32_t(std::stoul(t->priority));
  }
  return pt;
}

// Has `d` stopped at -fmax-errors (no error after this one is reported)?
bool at_limit(const Diagnostics& d) { return d.options().max_errors > 0 && d.errors() >= d.options().max_errors; }

// One program of the file (the instance of a configuration of several, or
// -1), its own variables' relays from M own_m on.
Program read_program(const std::vector<iecil::Tok>& toks, int instance, const std::string& filename, iecil::Recovery* rec,
                     uint32_t own_m = 0) {
  if (!rec) return iecil::parse_typed_il(st::to_il_tokens(toks, instance), filename, true, nullptr, own_m);
  return iecil::parse_typed_il(st::to_il_tokens(toks, instance, *rec), filename, true, rec, own_m);
}

// The first relay after every one program p names or places a variable in.
uint32_t relays_after(const Program& p) {
  uint32_t m = 0;
  for (const Alias& a : p.aliases)
    if (a.dev.dev == Dev::M) m = std::max(m, a.dev.index + 1);
  for (const VarPlace& v : p.vars)
    if (v.bits == Area::M) m = std::max(m, v.bit_first + v.bit_count);
  for (const Rung& r : p.rungs)
    for (const Instr& in : r.code)
      for (const Operand& o : in.a)
        if (o.kind != OpdKind::None && o.area == Area::M) m = std::max(m, o.index + 1);
  return m;
}

PlcopenImport read_st(std::string_view text, const std::string& filename, Diagnostics* diag) {
  std::optional<iecil::Recovery> rec;
  if (diag) {
    diag->source(filename, text);
    rec.emplace(*diag, filename);
  }
  iecil::Recovery* r = rec ? &*rec : nullptr;
  std::vector<iecil::Tok> toks = st::lex(text);
  st::Configuration cfg = st::configuration(toks);
  PlcopenImport im;
  im.configuration = cfg.name;
  if (cfg.instances.size() <= 1 && cfg.tasks.size() <= 1) {
    im.single = raw_tree(read_program(toks, -1, filename, r));
    return im;
  }
  // with recovery, every program is read (an error in a FUNCTION_BLOCK they
  // share is reported once: Recovery), then the tasks are checked.  Each
  // program's own relays lie after the ones before it: tasks share every relay.
  std::vector<Program> progs;
  uint32_t own_m = 0;
  for (size_t k = 0; k < cfg.instances.size(); k++) {
    if (!r) {
      progs.push_back(read_program(toks, int(k), filename, r, own_m));
      own_m = std::max(own_m, (relays_after(progs.back()) + 15) / 16 * 16);  // a block of 16 of its own
      continue;
    }
    try {
      progs.push_back(read_program(toks, int(k), filename, r, own_m));
      own_m = std::max(own_m, (relays_after(progs.back()) + 15) / 16 * 16);  // a block of 16 of its own
    } catch (const ErrorsReported&) {
      if (at_limit(*diag)) throw;
      progs.emplace_back();
    }
  }
  for (size_t k = 0; k < cfg.instances.size(); k++) {
    if (!r) {
      im.tasks.push_back(task_of(cfg, k));
      continue;
    }
    try {
      im.tasks.push_back(task_of(cfg, k));
    } catch (const CompileError& e) {
      r->report(e);
      im.tasks.emplace_back();
    }
  }
  if (r) r->check();  // the programs of tasks refused are not checked further
  check_shared_globals(toks, cfg, progs, im);
  for (size_t k = 0; k < progs.size(); k++) im.tasks[k].tree = raw_tree(std::move(progs[k]));
  return im;
}

}  // namespace

PlcopenImport import_st(std::string_view text, const std::string& filename) { return read_st(text, filename, nullptr); }
PlcopenImport import_st(std::string_view text, const std::string& filename, Diagnostics& diag) {
  return read_st(text, filename, &diag);
}

}  // namespace ldc
