// frontend/iecil/typed.cpp -- the typed reader of IEC 61131-3 IL
// (docs/iec-il.md, "Typed programs"): TYPE ... END_TYPE, FUNCTION_BLOCK and
// FUNCTION POUs, variables at their own widths, arrays and structures, read
// into the typed program model (ir/model.h) and lowered to typed IL.
//
// Every rung starts with TRUE: the typed instructions run while the top of
// the bit stack is on, so a rung is straight-line typed code, and a jump or a
// label starts a new one.  The current result (CR) is a typed operand: a
// variable's cell or bit as loaded, or an accumulator of its type after an
// operation.  Calls of the project's FBs and FUNCTIONs are their bodies
// expanded inline over the instance's places (docs/architecture.md).
#include <algorithm>
#include <cctype>
#include <functional>
#include <map>
#include <set>

#include "frontend/diag.h"
#include "frontend/frontend.h"
#include "frontend/iecil/iecil.h"
#include "ir/model.h"
#include "ir/time_scale.h"
#include "ir/typed.h"

namespace ldc::iecil {
namespace {

using namespace model;

// The declared types the classic reader holds (as INT32, REAL, ldc's timers).
bool classic_type(const std::string& u) {
  static const std::set<std::string> k = {"BOOL", "INT", "DINT", "SINT", "UINT", "UDINT", "USINT", "WORD", "DWORD", "BYTE",
                                          "TIME", "REAL", "TON", "TOF", "TP", "CTU", "CTD", "R_TRIG", "F_TRIG",
                                          // refused by both readers: the classic one names it
                                          "WSTRING"};
  return k.count(u) > 0;
}

}  // namespace

// The operators the classic reader knows.
bool classic_operator(const std::string& u) {
  static const std::set<std::string> k = {"LD", "LDN", "ST", "STN", "S", "R", "AND", "ANDN", "OR", "ORN", "XOR", "XORN",
                                          "ADD", "SUB", "MUL", "DIV", "MOD", "GT", "GE", "EQ", "NE", "LT", "LE", "JMP",
                                          "JMPC", "JMPCN", "SHL", "SHR", "CAL", "NOT", "RET", "RETC", "RETCN", "SIN", "COS",
                                          "TAN", "SQRT", "EXP", "LN", "ABS", "MOVE", "PROGRAM", "END_PROGRAM", "END_VAR",
                                          // ldc's own mnemonics: the classic reader names them in its error
                                          "LOAD", "LOADN", "OUT", "OUTN", "SET", "RST", "ANDBLK", "ORBLK", "MPS", "MRD", "MPP"};
  return k.count(u) > 0 || u.rfind("VAR", 0) == 0;
}

// Does the CAL at t[i] pass its arguments as the classic reader takes them,
// each `NAME := operand`?  (Non-formal arguments and `=>` outputs are the
// typed reader's.)
static bool classic_call_args(const std::vector<Tok>& t, size_t i) {
  auto punct_at = [&](size_t j, const char* p) { return j < t.size() && t[j].kind == Tok::Punct && t[j].text == p; };
  if (!punct_at(i + 2, "(")) return true;
  for (size_t j = i + 3; j < t.size() && !punct_at(j, ")"); j += 4) {
    if (!(t[j].kind == Tok::Word && punct_at(j + 1, ":=") && j + 2 < t.size() && t[j + 2].kind == Tok::Word)) return false;
    if (!punct_at(j + 3, ",")) return true;  // the classic reader reports what follows
  }
  return true;
}

bool needs_typed_reader(const std::vector<Tok>& t) {
  bool in_vars = false, line_start = true;
  // the typed reader reads POUs (PROGRAM ... END_PROGRAM); the classic one takes bare IL too
  bool pou = std::any_of(t.begin(), t.end(), [](const Tok& k) { return k.kind == Tok::Word && upper(k.text) == "PROGRAM"; });
  for (size_t i = 0; i < t.size(); i++) {
    const Tok& k = t[i];
    if (k.kind == Tok::Eol) { line_start = true; continue; }
    if (k.kind == Tok::Punct && (k.text == "[" || k.text == "..")) return true;  // an element, a range
    std::string u = k.kind == Tok::Word ? upper(k.text) : "";
    // an operator of the typed reader only (INT_TO_REAL, LIMIT, a FUNCTION ...), after an optional label
    bool labelled = !in_vars && line_start && k.kind == Tok::Word && i + 1 < t.size() && t[i + 1].kind == Tok::Punct && t[i + 1].text == ":";
    if (!in_vars && line_start && k.kind == Tok::Word && !labelled && !classic_operator(u)) return true;
    if (labelled) {  // a label whose code goes on with the CR it is reached with: the typed reader carries it
      size_t j = i + 2;
      while (j < t.size() && t[j].kind == Tok::Eol) j++;
      static const std::set<std::string> anew = {"LD", "LDN", "CAL", "JMP", "RET", "END_PROGRAM"};
      if (pou && j < t.size() && t[j].kind == Tok::Word && !anew.count(upper(t[j].text)) &&
          !(j + 1 < t.size() && t[j + 1].kind == Tok::Punct && t[j + 1].text == ":"))
        return true;
      i++;
      continue;
    }
    if (!in_vars && u == "CAL" && !classic_call_args(t, i)) return true;
    if (line_start && (u == "TYPE" || u == "FUNCTION_BLOCK" || u == "FUNCTION" || u == "VAR_IN_OUT" || u == "VAR_TEMP" ||
                       u == "VAR_EXTERNAL"))
      return true;
    if (u.rfind("VAR", 0) == 0 && line_start) {
      in_vars = true;
      if (i + 1 < t.size() && (upper(t[i + 1].text) == "CONSTANT" || upper(t[i + 1].text) == "RETAIN")) return true;
    }
    if (u == "END_VAR") in_vars = false;
    if (in_vars && k.kind == Tok::Punct && k.text == ":" && i + 1 < t.size() && t[i + 1].kind == Tok::Word &&
        !classic_type(upper(t[i + 1].text)))
      return true;
    line_start = false;
  }
  return false;
}

namespace {

constexpr size_t kMaxInstructions = size_t(1) << 20;  // after inline expansion (48 bytes each)
constexpr int kMaxNesting = 64;  // nested types, initial values, indices: hostile input cannot exhaust the stack
constexpr int kMaxParens = 16;
constexpr size_t kMaxAliasLeaves = 64;  // aliases per structured variable (--watch a[1], p.x)

struct PouSrc {           // where a POU is written
  size_t head = 0;        // its keyword
  size_t body = 0, end = 0;  // its body's tokens, its END_ keyword
  int pou = -1;           // in the model, once declared
  bool declaring = false;
  bool failed = false;     // its heading was refused (reported): its uses say nothing
  std::string kind, name;  // "FUNCTION_BLOCK", as written
};

// A limit of the whole program (rungs, instructions): no line after it can be
// read either, so error recovery stops there.
struct Exhausted : CompileError {
  using CompileError::CompileError;
};

// A name in a POU's scope.
struct Scope {
  int pou = -1;
  std::map<std::string, Ref> names;  // upper-case
  std::string prefix;                // of the labels of this copy
  std::string end_label;             // RET jumps here ("" in the program: RET ends the scan)
};

// The current result: a typed operand (a variable's, an accumulator), or a
// literal whose type is that of its first use.
struct Cr {
  bool defined = false;
  TypeId type = kNoType;
  Operand o;
  std::optional<ParsedLit> lit;  // an untyped number, not yet typed
  // ST's C arithmetic (Reader::promote_cr): the CR is a DINT that stands for
  // an expression of this narrower integer type, computed as C's int
  TypeId narrow = kNoType;
  // where the CR's C arithmetic began (rung, instruction): Reader::narrow_back
  size_t promo_rung = SIZE_MAX, promo_at = 0;
  // the variable LD read, while the CR is still its value (o == var_o): a
  // FUNCTION's first input that is a VAR_IN_OUT binds to it
  std::optional<model::Ref> var;
  Operand var_o;
};

// An operand as written.
struct Val {
  enum Kind { Lit, Ref_, Device } kind = Lit;
  ParsedLit lit;
  TypeId lit_type = kNoType;  // an enumerator's type, or a typed literal's
  model::Ref ref;             // Ref_ and Device (a device's Ref has its area)
  TypeId narrow = kNoType;    // a DINT temporary of ST standing for this type (Cr::narrow)
};

class Reader {
 public:
  Reader(const std::vector<Tok>& toks, const std::string& file, bool from_st, std::optional<UnitBase> unit = std::nullopt,
         Recovery* rec = nullptr)
      : t_(toks), from_st_(from_st), unit_(unit), rec_(rec) {
    p_.source = file;
  }

  void own_m(uint32_t m) { own_m_ = m; }
  Program run() {
    if (!rec_) return run_all();
    Program out;
    try {
      out = run_all();
    } catch (const CompileError& e) {  // the file's structure, the layout, a limit: the reader stops
      // one found after others were reported may follow from them: it says nothing then
      if (!rec_->failed()) rec_->report(e);
    }
    rec_->check();
    return out;
  }
  Program run_all() {
    try {
      find_en_calls();
      scan_top();
      declare_all();
      lay_out();
      lower_program();
      if (rec_ && rec_->failed()) return {};  // the labels of lines refused: their jumps would be reported again
      finish();
    } catch (const ModelError& e) {
      throw CompileError(e.loc.line, e.loc.col, e.message);
    }
    return std::move(p_);
  }
  // After run(), in unit mode: what the caller needs besides the program.
  void unit_facts(Unit& u) const {
    u.init_rungs = init_rungs_;
    Place end = m_.area_base() + m_.used();
    u.end = {end.bit, end.cell, next_timer_};
  }

 private:
  const std::vector<Tok>& t_;
  bool from_st_ = false;
  uint32_t own_m_ = 0;  // the first M of the program's own variables (parse_typed_il with own_m)
  std::optional<UnitBase> unit_;
  Recovery* rec_ = nullptr;  // error recovery: errors are reported and the reader goes on
  // Names whose declaration was refused (reported), and unknown names
  // reported, per POU (upper-case POU name, then name): their uses say nothing.
  std::map<std::string, std::set<std::string>> refused_, unknown_;
  std::set<std::string> failed_types_;  // TYPE entries refused (reported)
  std::set<std::string> unknown_ops_;    // unknown operators reported (upper-case): said once
  std::set<std::string> unknown_types_;  // unknown type names reported (upper-case): their uses, even as a name, say nothing

  // Runs `read` (one declaration or line); with recovery, its error is
  // reported and false returned (the caller skips what it covers).
  template <class F>
  bool recover(F read) {
    if (!rec_) {
      read();
      return true;
    }
    try {
      read();
      return true;
    } catch (const Exhausted&) {
      throw;
    } catch (const CompileError& e) {
      rec_->report(e);
    } catch (const ModelError& e) {
      rec_->report(CompileError(e.loc.line, e.loc.col, e.message));
    }
    return false;
  }
  size_t init_rungs_ = 0;
  size_t pos_ = 0;
  Model m_;
  Program p_;
  std::map<std::string, PouSrc> pou_src_;      // upper-case name
  std::map<std::string, size_t> type_src_;     // a TYPE entry's name token
  std::set<std::string> types_declaring_;
  int program_ = -1;
  std::map<std::string, model::Ref> globals_;  // the program's variables, for VAR_EXTERNAL
  std::map<std::string, Place> scratch_;
  uint32_t next_f_ = 0;

  // ---- tokens
  const Tok& peek(size_t k = 0) const { return t_[std::min(pos_ + k, t_.size() - 1)]; }
  const Tok& next() { return t_[pos_ < t_.size() - 1 ? pos_++ : pos_]; }
  [[noreturn]] static void fail(const Tok& k, const std::string& m) { throw CompileError(k.line, k.col, m); }
  [[noreturn]] static void fail(SrcLoc l, const std::string& m) { throw CompileError(l.line, l.col, m); }
  static SrcLoc loc(const Tok& k) { return {k.line, k.col}; }
  static bool kw(const Tok& k, const char* w) { return k.kind == Tok::Word && upper(k.text) == w; }
  static bool punct(const Tok& k, const char* p) { return k.kind == Tok::Punct && k.text == p; }
  static std::string found(const Tok& k) {
    if (k.kind == Tok::Eol) return " at the end of the line";
    if (k.kind == Tok::End) return " at the end of the file";
    return ", found '" + k.text + "'";
  }
  void skip_eols() {
    while (peek().kind == Tok::Eol) next();
  }
  const Tok& expect(const char* p) {
    skip_eols();
    if (!punct(peek(), p)) fail(peek(), std::string("expected '") + p + "'" + found(peek()));
    return next();
  }
  static bool ident(const std::string& s) {
    if (s.empty() || !(std::isalpha((unsigned char)s[0]) || s[0] == '_')) return false;
    return std::all_of(s.begin(), s.end(), [](char c) { return std::isalnum((unsigned char)c) || c == '_'; });
  }
  const Tok& name_tok(const char* what) {
    skip_eols();
    const Tok& n = next();
    if (n.kind != Tok::Word || !ident(n.text)) fail(n, std::string("expected ") + what + found(n));
    return n;
  }
  void end_line() {
    if (peek().kind != Tok::Eol && peek().kind != Tok::End) fail(peek(), "unexpected '" + peek().text + "' at the end of the line");
    if (peek().kind == Tok::Eol) next();
  }

  // The instances some CAL gives an EN (CAL x(EN := ...)): their calls check
  // it (std_call), by name, in whichever POU.
  std::set<std::string> en_called_;
  void find_en_calls() {
    for (size_t i = 0; i + 2 < t_.size(); i++) {
      if (!(kw(t_[i], "CAL") || kw(t_[i], "CALC") || kw(t_[i], "CALCN")) || t_[i + 1].kind != Tok::Word || !punct(t_[i + 2], "(")) continue;
      for (size_t j = i + 3; j + 1 < t_.size() && !punct(t_[j], ")") && t_[j].kind != Tok::End; j++)
        if (kw(t_[j], "EN") && punct(t_[j + 1], ":=")) en_called_.insert(upper(t_[i + 1].text));
    }
  }

  // ---------------------------------------------------------------- the file's parts

  // Finds every TYPE entry and POU, so a name may be used before it is declared.
  void scan_top() {
    bool have_program = false;
    for (;;) {
      skip_eols();
      const Tok& k = peek();
      if (k.kind == Tok::End) break;
      std::string u = upper(k.text);
      if (u == "TYPE") {
        next();
        scan_types();
      } else if (u == "FUNCTION_BLOCK" || u == "FUNCTION" || u == "PROGRAM") {
        if (u == "PROGRAM" && have_program) fail(k, "a second PROGRAM: ldc reads one program per file");
        have_program |= u == "PROGRAM";
        scan_pou(u);
      } else if (u.rfind("VAR", 0) == 0 && !have_program) {  // a program without its PROGRAM line
        have_program = true;
        scan_pou("");
      } else if (u == "CONFIGURATION" || u == "RESOURCE") {
        fail(k, "'" + k.text + "' is not read from IEC IL files: one program per file (docs/iec-il.md)");
      } else {
        fail(k, "expected TYPE, FUNCTION_BLOCK, FUNCTION or PROGRAM" + found(k));
      }
    }
    if (!have_program) fail(t_.back(), "no PROGRAM in the file" + library_note());
  }
  // A file of FUNCTION_BLOCKs, FUNCTIONs and TYPEs alone (a library, as
  // CODESYS exports one POU per file): what it declares, and what ldc needs.
  std::string library_note() const {
    std::vector<const PouSrc*> pous;
    for (const auto& [key, src] : pou_src_) pous.push_back(&src);
    std::sort(pous.begin(), pous.end(), [](const PouSrc* a, const PouSrc* b) { return a->head < b->head; });
    std::string names;
    for (size_t k = 0; k < pous.size() && k < 3; k++) names += std::string(k ? ", " : "") + pous[k]->kind + " " + pous[k]->name;
    if (pous.size() > 3) names += " and " + std::to_string(pous.size() - 3) + " more";
    if (names.empty())
      return type_src_.empty() ? "" : ": it declares only TYPEs (" + std::to_string(type_src_.size()) + "), which a PROGRAM in the same file would use";
    return ": it declares " + names + ", which only a PROGRAM in the same file can call (ldc compiles a PROGRAM, or a CONFIGURATION of programs)";
  }
  void scan_types() {
    for (;;) {
      skip_eols();
      if (kw(peek(), "END_TYPE")) { next(); return; }
      if (peek().kind == Tok::End) fail(peek(), "TYPE without END_TYPE");
      const Tok& n = name_tok("a type name");
      std::string u = upper(n.text);
      if (type_src_.count(u) || pou_src_.count(u) || m_.find_type(u) != kNoType) fail(n, "a second type named '" + n.text + "'");
      type_src_[u] = pos_ - 1;
      int depth = 0;  // to the ';' that ends the entry
      for (;;) {
        const Tok& k = next();
        if (k.kind == Tok::End) fail(n, "type '" + n.text + "' without its ';'");
        if (kw(k, "STRUCT")) depth++;
        else if (kw(k, "END_STRUCT")) depth--;
        else if (punct(k, "(") || punct(k, "[")) depth++;
        else if (punct(k, ")") || punct(k, "]")) depth--;
        else if (punct(k, ";") && depth == 0) break;
      }
    }
  }
  void scan_pou(const std::string& kind) {
    PouSrc s;
    s.head = pos_;
    std::string name = "main";
    const char* end_kw = kind == "FUNCTION_BLOCK" ? "END_FUNCTION_BLOCK" : kind == "FUNCTION" ? "END_FUNCTION" : "END_PROGRAM";
    if (!kind.empty()) {
      next();
      const Tok& n = name_tok(("the " + kind + "'s name").c_str());
      name = n.text;
      if (pou_src_.count(upper(name)) || type_src_.count(upper(name)) || m_.find_type(name) != kNoType)
        fail(n, "a second POU or type named '" + name + "'");
    }
    size_t i = pos_;
    while (t_[i].kind != Tok::End && !kw(t_[i], end_kw)) {
      if (kw(t_[i], "FUNCTION_BLOCK") || kw(t_[i], "FUNCTION") || kw(t_[i], "PROGRAM") || kw(t_[i], "TYPE"))
        fail(t_[i], std::string("'") + t_[i].text + "' inside " + (kind.empty() ? "the program" : name) + ": " + end_kw + " is missing");
      i++;
    }
    if (t_[i].kind == Tok::End && !kind.empty()) fail(t_[s.head], kind + " " + name + " without " + end_kw);
    s.end = i;
    s.kind = kind, s.name = name;
    pos_ = t_[i].kind == Tok::End ? i : i + 1;
    pou_src_[upper(kind.empty() ? "" : name)] = s;
    if (kind == "PROGRAM" || kind.empty()) program_name_ = upper(kind.empty() ? "" : name);
  }
  std::string program_name_;

  // ---------------------------------------------------------------- declarations

  void declare_all() {
    for (const auto& entry : type_src_) recover([&] { resolve_type_name(entry.first, t_[entry.second]); });
    for (const auto& entry : pou_src_) recover([&] { declare_pou(entry.first); });
    program_ = pou_src_.at(program_name_).pou;
    if (program_ < 0) rec_->check();  // its heading was refused (reported): nothing to lower
  }

  // The TYPE entry whose name is token `at`.
  TypeId declare_type(size_t at) {
    pos_ = at;
    const Tok& n = next();
    expect(":");
    skip_eols();
    Spec sp = type_spec();
    Type ty = sp.id == kNoType ? sp.fresh : m_.type(sp.id);  // a derived type: a copy of its base, named anew
    if (sp.id != kNoType && ty.kind == TypeKind::Block) fail(n, "a TYPE of a FUNCTION_BLOCK: declare its instances directly");
    ty.name = n.text;
    TypeId id = m_.add_type(ty, loc(n));  // before its initial value, which may name its enumerators
    skip_eols();
    if (punct(peek(), ":=")) {
      next();
      m_.types[size_t(id)].init = init_value();
    }
    expect(";");
    return id;
  }
  // A type by name, declaring it (or the FB) first if it is written later.
  TypeId resolve_type_name(const std::string& u, const Tok& at) {
    TypeId id = m_.find_type(u);
    if (id != kNoType) return id;
    if (auto it = type_src_.find(u); it != type_src_.end()) {
      if (failed_types_.count(u)) throw Quiet(at.line, at.col, "type '" + at.text + "' was refused");
      if (types_declaring_.count(u)) fail(at, "type '" + at.text + "' contains itself");
      types_declaring_.insert(u);
      size_t save = pos_;
      TypeId id = kNoType;
      try {
        id = declare_type(it->second);
      } catch (...) {  // with recovery, reported by the caller: the uses of the type say nothing more
        if (!rec_) throw;
        pos_ = save;
        types_declaring_.erase(u);
        failed_types_.insert(u);
        throw;
      }
      pos_ = save;
      types_declaring_.erase(u);
      return id;
    }
    if (auto it = pou_src_.find(u); it != pou_src_.end()) {
      int pou = declare_pou(u);
      if (m_.pous[size_t(pou)].kind == PouKind::FunctionBlock) return m_.pous[size_t(pou)].block;
      fail(at, "'" + at.text + "' is a " + (m_.pous[size_t(pou)].kind == PouKind::Function ? "FUNCTION" : "PROGRAM") +
                   ", not a type");
    }
    if (TypeId b = bistable_type(u); b != kNoType) return b;
    if (u == "WSTRING") fail(at, "type " + at.text + " is not supported (docs/iec-il.md)");
    if (u.rfind("CTU_", 0) == 0 || u.rfind("CTD_", 0) == 0 || u.rfind("CTUD_", 0) == 0)
      fail(at, "unknown type '" + at.text + "': MatIEC's counters are " + u.substr(0, u.find('_')) + " (INT) and " +
                   u.substr(0, u.find('_')) + "_DINT, _LINT, _UDINT, _ULINT (docs/stdlib.md)");
    if (rec_ && !unknown_types_.insert(u).second) throw Quiet(at.line, at.col, "unknown type again");  // reported once
    fail(at, "unknown type '" + at.text + "'");
  }

  // The standard function blocks, as MatIEC's structures (lib/*.txt,
  // lib/C/iec_std_FB.h): their inputs, then their outputs, then the hidden
  // variables (an R_TRIG's M, a counter's CU_T edge memory ...); computed at
  // each CAL (std_call).
  struct StdFb {
    std::vector<std::pair<const char*, Ty>> vars;
    size_t inputs = 0, outputs = 0;
  };
  static const std::map<std::string, StdFb>& std_fbs() {
    static const std::map<std::string, StdFb> k = [] {
      std::map<std::string, StdFb> m = {
          {"R_TRIG", {{{"CLK", Ty::BOOL}, {"Q", Ty::BOOL}, {"M", Ty::BOOL}}, 1, 1}},
          {"F_TRIG", {{{"CLK", Ty::BOOL}, {"Q", Ty::BOOL}, {"M", Ty::BOOL}}, 1, 1}},
          {"SR", {{{"S1", Ty::BOOL}, {"R", Ty::BOOL}, {"Q1", Ty::BOOL}}, 2, 1}},
          {"RS", {{{"S", Ty::BOOL}, {"R1", Ty::BOOL}, {"Q1", Ty::BOOL}}, 2, 1}},
          {"SEMA", {{{"CLAIM", Ty::BOOL}, {"RELEASE", Ty::BOOL}, {"BUSY", Ty::BOOL}, {"Q_INTERNAL", Ty::BOOL}}, 2, 1}},
          {"RTC", {{{"IN", Ty::BOOL}, {"PDT", Ty::DT}, {"Q", Ty::BOOL}, {"CDT", Ty::DT}, {"PREV_IN", Ty::BOOL},
                    {"OFFSET", Ty::TIME}, {"CURRENT_TIME", Ty::DT}}, 2, 2}},
          {"TON", {{{"IN", Ty::BOOL}, {"PT", Ty::TIME}, {"Q", Ty::BOOL}, {"ET", Ty::TIME}}, 2, 2}},
          {"TOF", {{{"IN", Ty::BOOL}, {"PT", Ty::TIME}, {"Q", Ty::BOOL}, {"ET", Ty::TIME}}, 2, 2}},
          {"TP", {{{"IN", Ty::BOOL}, {"PT", Ty::TIME}, {"Q", Ty::BOOL}, {"ET", Ty::TIME}}, 2, 2}}};
      // the counters of every width MatIEC has (lib/counter.txt): CTU is INT
      for (auto [suffix, t] : {std::pair<const char*, Ty>{"", Ty::INT}, {"_DINT", Ty::DINT}, {"_LINT", Ty::LINT},
                               {"_UDINT", Ty::UDINT}, {"_ULINT", Ty::ULINT}}) {
        std::string s = suffix;
        m["CTU" + s] = {{{"CU", Ty::BOOL}, {"R", Ty::BOOL}, {"PV", t}, {"Q", Ty::BOOL}, {"CV", t}, {"CU_T", Ty::BOOL}}, 3, 2};
        m["CTD" + s] = {{{"CD", Ty::BOOL}, {"LD", Ty::BOOL}, {"PV", t}, {"Q", Ty::BOOL}, {"CV", t}, {"CD_T", Ty::BOOL}}, 3, 2};
        m["CTUD" + s] = {{{"CU", Ty::BOOL}, {"CD", Ty::BOOL}, {"R", Ty::BOOL}, {"LD", Ty::BOOL}, {"PV", t}, {"QU", Ty::BOOL},
                          {"QD", Ty::BOOL}, {"CV", t}, {"CD_T", Ty::BOOL}, {"CU_T", Ty::BOOL}}, 5, 3};
      }
      return m;
    }();
    return k;
  }
  std::map<TypeId, std::string> bistables_;
  TypeId rtc_type_ = kNoType;
  TypeId bistable_type(const std::string& u) {
    auto it = std_fbs().find(u);
    if (it == std_fbs().end()) return kNoType;
    Type t;
    t.kind = TypeKind::Struct;
    t.name = u;
    for (const auto& [v, ty] : it->second.vars) t.members.push_back({v, m_.elem(ty), {}, {}});
    Init on;  // MatIEC's EN and ENO of every block, both TRUE at first (std_call)
    on.kind = Init::Value, on.value.lit = {Ty::BOOL, 1};
    // F_TRIG's M starts TRUE in the library OpenPLC ships (no pulse on the
    // first scan; upstream MatIEC starts it FALSE), as the PLCopen reader has it
    if (u == "F_TRIG") t.members[2].init = on;
    t.members.push_back({"EN", m_.elem(Ty::BOOL), {}, on});
    t.members.push_back({"ENO", m_.elem(Ty::BOOL), {}, on});
    TypeId id = m_.add_type(t, {1, 1});
    bistables_[id] = u;
    if (u == "RTC") rtc_type_ = id;
    return id;
  }

  // type_spec = NAME [ "(" lo ".." hi ")" ] | ARRAY "[" range { "," range } "]" OF type_spec
  //           | STRUCT { decl } END_STRUCT | "(" NAME { "," NAME } ")"
  // A spec names a type (`id`) or describes a new one (`fresh`).
  struct Spec {
    TypeId id = kNoType;
    Type fresh;
  };
  int nesting_ = 0;
  struct Nest {  // one level of nesting, refused beyond kMaxNesting
    Nest(int& n, const Tok& at) : n_(n) {
      if (++n_ > kMaxNesting) throw CompileError(at.line, at.col, "nested deeper than " + std::to_string(kMaxNesting) + " levels");
    }
    ~Nest() { n_--; }
    int& n_;
  };
  Spec type_spec() {
    skip_eols();
    Nest nest(nesting_, peek());
    const Tok& k = next();
    Spec sp;
    Type& ty = sp.fresh;
    if (punct(k, "(")) {  // an enumeration
      ty.kind = TypeKind::Enum;
      for (;;) {
        const Tok& e = name_tok("an enumerator");
        std::string u = upper(e.text);
        if (std::find(ty.enumerators.begin(), ty.enumerators.end(), u) != ty.enumerators.end()) fail(e, "enumerator '" + e.text + "' twice");
        ty.enumerators.push_back(u);
        skip_eols();
        if (punct(peek(), ",")) { next(); continue; }
        expect(")");
        break;
      }
      return sp;
    }
    if (kw(k, "ARRAY")) {
      ty.kind = TypeKind::Array;
      expect("[");
      for (;;) {
        Dim d;
        skip_eols();
        d.lo = int32_t(int_const(next()));
        expect("..");
        skip_eols();
        d.hi = int32_t(int_const(next()));
        ty.dims.push_back(d);
        skip_eols();
        if (punct(peek(), ",")) { next(); continue; }
        expect("]");
        break;
      }
      skip_eols();
      if (!kw(peek(), "OF")) fail(peek(), "expected OF" + found(peek()));
      next();
      skip_eols();
      const Tok& of = peek();
      ty.of = use_type(type_spec(), of);
      return sp;
    }
    if (kw(k, "STRUCT")) {
      ty.kind = TypeKind::Struct;
      for (;;) {
        skip_eols();
        if (kw(peek(), "END_STRUCT")) { next(); break; }
        if (peek().kind == Tok::End) fail(k, "STRUCT without END_STRUCT");
        std::vector<Tok> names = name_list("a member name");
        Declared d = type_and_init();
        for (const Tok& n : names) ty.members.push_back({n.text, d.type, {}, d.init});
      }
      return sp;
    }
    if (k.kind != Tok::Word || !ident(k.text)) fail(k, "expected a type" + found(k));
    TypeId base = resolve_type_name(upper(k.text), k);
    if (m_.type(base).scalar() && m_.scalar_ty(base) == Ty::STRING && punct(peek(), "[")) {
      // STRING[n]: MatIEC's C generator ignores n (no visitor for it): a STRING of 126 bytes (docs/iec-il.md)
      next();
      const Tok& n = next();
      if (int_const(n) < 1) fail(n, "a STRING's length is at least 1");
      expect("]");
      sp.id = base;
      return sp;
    }
    if (punct(peek(), "(")) {  // a subrange
      next();
      if (!m_.type(base).scalar() || !typed::is_int_kind(m_.scalar_ty(base))) fail(k, "a subrange of a non-integer type");
      ty.kind = TypeKind::Subrange;
      ty.elem = m_.scalar_ty(base);
      skip_eols();
      ty.lo = int_const(next());
      expect("..");
      skip_eols();
      ty.hi = int_const(next());
      expect(")");
      return sp;
    }
    sp.id = base;
    return sp;
  }
  TypeId use_type(const Spec& sp, const Tok& at) {
    if (sp.id != kNoType) return sp.id;
    return m_.add_type(sp.fresh, loc(at));
  }
  int64_t int_const(const Tok& k) {
    std::string why;
    auto p = parse_literal(k.text, why);
    if (!p || !p->untyped_int || p->lit.ty == Ty::ULINT) fail(k, "expected an integer constant" + found(k));
    if (p->ival < INT32_MIN || p->ival > INT32_MAX) fail(k, "bound outside DINT: " + k.text);
    return p->ival;
  }

  // init = literal | NAME (an enumerator) | "[" item { "," item } "]" | "(" NAME ":=" init { "," ... } ")"
  // item = init | count "(" init ")"
  Init init_value() {
    skip_eols();
    Nest nest(nesting_, peek());
    const Tok& k = next();
    Init in;
    in.loc = loc(k);
    if (punct(k, "[")) {
      in.kind = Init::List;
      for (;;) {
        skip_eols();
        uint32_t count = 1;
        if (peek().kind == Tok::Word && punct(peek(1), "(")) {
          int64_t c = int_const(next());
          if (c < 0) fail(peek(), "a negative repeat count");
          count = uint32_t(c);
          next();
          in.list.push_back({count, init_value()});
          expect(")");
        } else {
          in.list.push_back({count, init_value()});
        }
        skip_eols();
        if (punct(peek(), ",")) { next(); continue; }
        expect("]");
        return in;
      }
    }
    if (punct(k, "(")) {
      in.kind = Init::Fields;
      for (;;) {
        const Tok& n = name_tok("a member name");
        expect(":=");
        in.fields.push_back({upper(n.text), init_value()});
        skip_eols();
        if (punct(peek(), ",")) { next(); continue; }
        expect(")");
        return in;
      }
    }
    in.kind = Init::Value;
    if (k.kind != Tok::Word) fail(k, "expected an initial value" + found(k));
    std::string why;
    auto p = parse_literal(k.text, why);
    if (p) { in.value = *p; return in; }
    if (!why.empty()) fail(k, why);
    auto e = enumerator(k.text);
    if (!e) fail(k, "expected a literal initial value" + found(k));
    in.value.lit = {Ty::DINT, uint64_t(e->second)};
    return in;
  }
  // An enumerator (NAME, or TYPE#NAME): its type and value.
  std::optional<std::pair<TypeId, int64_t>> enumerator(const std::string& text) {
    std::string u = upper(text), ty;
    if (size_t h = u.find('#'); h != std::string::npos) ty = u.substr(0, h), u = u.substr(h + 1);
    for (size_t i = 0; i < m_.types.size(); i++) {
      const Type& t = m_.types[i];
      if (t.kind != TypeKind::Enum || (!ty.empty() && upper(t.name) != ty)) continue;
      auto it = std::find(t.enumerators.begin(), t.enumerators.end(), u);
      if (it != t.enumerators.end()) return std::make_pair(TypeId(i), int64_t(it - t.enumerators.begin()));
    }
    return std::nullopt;
  }

  int declare_pou(const std::string& u) {
    PouSrc& s = pou_src_.at(u);
    if (s.pou >= 0) return s.pou;
    if (s.failed) throw Quiet(t_[s.head].line, t_[s.head].col, "POU '" + s.name + "' was refused");
    if (s.declaring) fail(t_[s.head], "'" + t_[s.head + 1].text + "' contains an instance of itself");
    size_t save = pos_;
    if (!rec_) return declare_pou(s);
    try {
      return declare_pou(s);
    } catch (...) {  // reported by the caller: the uses of the POU say nothing more
      pos_ = save;
      s.declaring = false;
      s.failed = true;
      throw;
    }
  }
  int declare_pou(PouSrc& s) {
    s.declaring = true;
    size_t save = pos_;
    pos_ = s.head;
    Pou p;
    p.loc = loc(t_[s.head]);
    std::string kind = upper(t_[s.head].text);
    p.kind = kind == "FUNCTION_BLOCK" ? PouKind::FunctionBlock : kind == "FUNCTION" ? PouKind::Function : PouKind::Program;
    if (kind == "FUNCTION_BLOCK" || kind == "FUNCTION" || kind == "PROGRAM") {
      next();
      p.name = next().text;
      if (p.kind == PouKind::Function) {
        expect(":");
        skip_eols();
        const Tok& rt = next();
        p.result = resolve_type_name(upper(rt.text), rt);
        if (!m_.type(p.result).scalar()) fail(rt, "a FUNCTION returns an elementary type here, not " + m_.type_name(p.result));
      }
      end_line();
    } else {
      p.name = "main";
    }
    skip_eols();
    while (peek().kind == Tok::Word && upper(peek().text).rfind("VAR", 0) == 0) {
      var_block(p);
      skip_eols();
    }
    s.body = pos_;
    if (p.kind != PouKind::Program) {  // IEC's implicit EN and ENO
      auto has = [&](const char* n) {
        return std::any_of(p.vars.begin(), p.vars.end(), [&](const Var& v) { return upper(v.name) == n; });
      };
      if (!has("EN")) {
        Var en{"EN", m_.elem(Ty::BOOL), VarClass::Input, false, false, {}, {}, p.loc};
        en.init.kind = Init::Value, en.init.value.lit = {Ty::BOOL, 1};
        p.vars.push_back(en);
      }
      if (!has("ENO")) p.vars.push_back({"ENO", m_.elem(Ty::BOOL), VarClass::Output, false, false, {}, {}, p.loc});
    }
    pos_ = save;
    s.pou = m_.add_pou(p);
    m_.pous[size_t(s.pou)].body = int(s.body);
    s.declaring = false;
    return s.pou;
  }

  void var_block(Pou& p) {
    const Tok& head = next();
    std::string h = upper(head.text);
    VarClass cls = h == "VAR_INPUT" ? VarClass::Input : h == "VAR_OUTPUT" ? VarClass::Output : h == "VAR_IN_OUT" ? VarClass::InOut
                 : h == "VAR_TEMP" ? VarClass::Temp : h == "VAR_EXTERNAL" ? VarClass::External : h == "VAR_GLOBAL" ? VarClass::Global
                 : h == "VAR" ? VarClass::Local : VarClass(255);
    if (cls == VarClass(255)) fail(head, "unknown variable block '" + head.text + "'");
    if ((cls == VarClass::InOut || cls == VarClass::External) && p.kind == PouKind::Program && cls == VarClass::InOut)
      fail(head, "a PROGRAM has no VAR_IN_OUT here (ldc runs one program)");
    if (cls == VarClass::Global && p.kind != PouKind::Program) fail(head, "VAR_GLOBAL belongs to the program");
    bool constant = false, retain = false;
    while (kw(peek(), "CONSTANT") || kw(peek(), "RETAIN") || kw(peek(), "NON_RETAIN")) {
      constant |= kw(peek(), "CONSTANT");
      retain |= kw(peek(), "RETAIN");
      next();
    }
    end_line();
    for (;;) {
      skip_eols();
      if (kw(peek(), "END_VAR")) { next(); end_line(); return; }
      if (peek().kind == Tok::End) fail(head, "'" + head.text + "' block without END_VAR");
      size_t start = pos_;
      if (!recover([&] { decl(p, cls, constant, retain); })) skip_decl(start, p.name);
    }
  }
  // After a refused declaration: the names it declares (what comes before
  // its ':' or AT) are remembered, so that their uses say nothing, and the
  // reader goes on after its ';' (or at the END_VAR of a declaration
  // without one).
  void skip_decl(size_t start, const std::string& pou) {
    pos_ = start;
    bool naming = true;
    int depth = 0;
    for (;;) {
      const Tok& k = peek();
      if (k.kind == Tok::End || (depth == 0 && kw(k, "END_VAR"))) break;
      next();
      if (punct(k, ":") || kw(k, "AT")) naming = false;
      if (naming && k.kind == Tok::Word) refused_[upper(pou)].insert(upper(k.text));
      if (kw(k, "STRUCT") || punct(k, "(") || punct(k, "[")) depth++;
      else if ((kw(k, "END_STRUCT") || punct(k, ")") || punct(k, "]")) && depth > 0) depth--;
      else if (punct(k, ";") && depth == 0) break;
    }
    if (pos_ == start) next();
  }

  // decl = NAME { "," NAME } [ "AT" location ] ":" type_spec [ ":=" init ] ";"
  void decl(Pou& p, VarClass cls, bool constant, bool retain) {
    std::vector<Tok> names = name_list("a variable name");
    std::optional<DeviceRef> at;
    skip_eols();
    if (kw(peek(), "AT")) {
      next();
      const Tok& a = next();
      if (names.size() > 1) fail(a, "one variable per AT location");
      if (p.kind != PouKind::Program) fail(a, "a located variable (AT) belongs to the program, not to " + p.name);
      std::string why;
      if (a.kind == Tok::Word) at = a.text[0] == '%' ? iec_address(a.text, why) : parse_device(a.text);
      if (!at) fail(a, why.empty() ? "expected a location (%IX0.0, %QW2, %MD1 ... or an ldc device)" + found(a) : why);
      if (at->index >= device_count(at->dev)) fail(a, "location " + a.text + " is outside ldc's devices");
      at_tok_ = a;
    }
    bool no_init = cls == VarClass::InOut || cls == VarClass::External;
    Declared d = type_and_init(no_init ? std::string("a ") + var_class_name(cls) : "");
    if (at) check_location(*at, d.type);
    for (const Tok& n : names)
      p.vars.push_back({n.text, d.type, cls, constant, retain, d.init, at, loc(n)});
  }
  // NAME {"," NAME}: the names one declaration (or structure member) declares.
  std::vector<Tok> name_list(const char* what) {
    std::vector<Tok> names{name_tok(what)};
    while (punct(peek(), ",")) next(), names.push_back(name_tok(what));
    return names;
  }
  // ':' spec [':=' init] ';' after the names: the type and the initial value of
  // a variable or a structure member.  `init_refused` names a section whose
  // variables have none ("a VAR_IN_OUT"); "" if they may.
  struct Declared {
    TypeId type;
    Init init;
  };
  Declared type_and_init(const std::string& init_refused = "") {
    expect(":");
    skip_eols();
    const Tok& tt = peek();
    Declared d{use_type(type_spec(), tt), {}};
    skip_eols();
    if (punct(peek(), ":=")) {
      next();
      d.init = init_value();
      if (!init_refused.empty()) fail(d.init.loc, init_refused + " has no initial value");
    }
    expect(";");
    return d;
  }
  Tok at_tok_;
  void check_location(DeviceRef d, TypeId id) {
    Ty t = m_.scalar_ty(id);
    if (t == Ty::None) fail(at_tok_, "a located variable is of an elementary type here, not " + m_.type_name(id));
    bool bit = bit_area(d.dev) != Area::Count && d.dev != Dev::T && d.dev != Dev::C;
    Area w = word_area(d.dev);
    bool ok = t == Ty::BOOL ? bit
                            : w != Area::Count && d.dev != Dev::T && d.dev != Dev::C && (w == Area::F) == (t == Ty::REAL) &&
                                  d.index + uint32_t(ty_info(t).cells) <= device_count(d.dev);
    if (!ok) fail(at_tok_, "location " + at_tok_.text + " does not fit type " + m_.type_name(id));
  }

  // ---------------------------------------------------------------- layout

  // The variable area lies after every M, D and F the file names itself.
  void lay_out() {
    uint32_t m = 0, d = 0, f = 0;
    for (const Tok& k : t_) {
      if (k.kind != Tok::Word) continue;
      std::string why;
      std::optional<DeviceRef> r = k.text[0] == '%' ? iec_address(k.text, why) : parse_device(k.text);
      if (!r || r->index >= device_count(r->dev)) continue;
      if (r->dev == Dev::M) m = std::max(m, r->index + 1);
      if (r->dev == Dev::D) d = std::max(d, r->index + 2);  // room for a 64-bit value located there
      if (r->dev == Dev::F) f = std::max(f, r->index + 2);
    }
    if (unit_) {
      m = std::max(m, unit_->m), d = std::max(d, unit_->d);
      f = device_count(Dev::F);  // every REAL in D: the caller's F devices stay its own
      next_timer_ = unit_->t;
    }
    m_.set_area(m, d);
    next_f_ = f;
    const Pou& prog = m_.pous[size_t(program_)];
    for (const Var& v : prog.vars) {
      model::Ref r;
      r.type = v.type;
      r.writable = !v.constant;
      Ty st = m_.scalar_ty(v.type);
      if (v.at) {
        r.bits = bit_area(v.at->dev), r.cells = word_area(v.at->dev);
        r.at = {v.at->index, v.at->index};
        if (r.bits == Area::X || (st != Ty::BOOL && r.cells == Area::WX)) r.writable = false;
      } else if (st == Ty::REAL && next_f_ < device_count(Dev::F)) {  // a REAL of the program in F: --watch shows it as REAL
        r.cells = Area::F;
        r.at = {0, next_f_++};
      } else {
        if (v.cls != VarClass::Global) m_.skip_bits_to(own_m_);
        r.at = m_.place(m_.type(v.type).size, v.loc);
      }
      globals_[upper(v.name)] = r;
      if (!v.at) {  // a located variable is its device; the others are carried by name online
        Size sz = m_.type(v.type).size;
        p_.vars.push_back({v.name, layout_text(v.type), sz.bits ? r.bits : Area::Count, sz.bits ? r.at.bit : 0, sz.bits,
                           sz.cells ? r.cells : Area::Count, sz.cells ? r.at.cell : 0, sz.cells});
      }
      if (v.retain)
        for (uint32_t c = 0; c < m_.type(v.type).size.cells && r.cells == Area::D; c++) p_.retain.push_back({Dev::D, r.at.cell + c});
      aliases(v.name, r);
    }
  }
  // The text of a type that changes when its layout does (VarPlace::type): an
  // elementary type's name; an enumeration's, a composite's name (or kind)
  // and a hash (FNV-1a, 64 bits) of its enumerators, dimensions, members'
  // names, offsets and types -- a hash, so that types nested many times do
  // not make the text grow with every use.
  std::map<TypeId, std::string> layout_texts_;
  std::string layout_text(TypeId id) {
    if (auto it = layout_texts_.find(id); it != layout_texts_.end()) return it->second;
    const Type& t = m_.type(id);
    std::string text;
    if (t.kind == TypeKind::Elem || t.kind == TypeKind::Subrange) {
      text = ty_info(t.elem).name;
    } else {
      uint64_t h = 1469598103934665603ull;
      auto mix = [&](const std::string& part) {
        for (unsigned char c : part + '\x1f') h = (h ^ c) * 1099511628211ull;
      };
      mix(std::to_string(int(t.kind)));
      for (const std::string& e : t.enumerators) mix(e);
      for (const Dim& d : t.dims) mix(std::to_string(d.lo) + ".." + std::to_string(d.hi));
      if (t.of != kNoType) mix(layout_text(t.of));
      for (const Member& mb : t.members)
        if (mb.type != kNoType)
          mix(mb.name + ":" + layout_text(mb.type) + "@" + std::to_string(mb.offset.bits) + "," + std::to_string(mb.offset.cells));
      static const char* kinds[] = {"ELEM", "ENUM", "SUBRANGE", "ARRAY", "STRUCT", "BLOCK"};
      char hex[17];
      std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(h));
      text = (t.name.empty() ? std::string(kinds[int(t.kind)]) : t.name) + "#" + hex;
    }
    return layout_texts_[id] = text;
  }
  // --watch names: the variable, and the scalars of a structured one (p.x, a[1], a[1].on)
  void aliases(const std::string& name, const model::Ref& r) {
    size_t n = 0;
    std::function<void(const std::string&, TypeId, Place)> walk = [&](const std::string& nm, TypeId id, Place at) {
      if (n >= kMaxAliasLeaves) return;
      const Type& t = m_.type(id);
      if (t.scalar()) {
        Operand o = operand_at(t.elem, at, r.bits, r.cells);
        Dev d = o.area == Area::M ? Dev::M : o.area == Area::D ? Dev::D : o.area == Area::F ? Dev::F : o.area == Area::X ? Dev::X
              : o.area == Area::Y ? Dev::Y : o.area == Area::K ? Dev::K : o.area == Area::WX ? Dev::WX : o.area == Area::WY ? Dev::WY : Dev::S;
        if (upper(nm) == "DT") return;  // a program's name wins over a device spelling (docs/format.md); DT is a type
        Alias a{nm, {d, o.index}, t.elem};  // typed: a watch shows it at its width
        if (a.ty == Ty::BOOL || !alias_type_problem(a).empty()) a.ty = Ty::None;  // a BOOL is its bit either way
        p_.aliases.push_back(std::move(a));
        n++;
        return;
      }
      if (t.kind == TypeKind::Array) {
        uint32_t count = 1;
        for (const Dim& dm : t.dims) count *= dm.count();
        Size e = m_.type(t.of).size;
        for (uint32_t k = 0; k < count && n < kMaxAliasLeaves; k++) {
          std::string idx;
          uint32_t rest = k;
          std::vector<int64_t> ix(t.dims.size());
          for (size_t j = t.dims.size(); j-- > 0;) ix[j] = t.dims[j].lo + int64_t(rest % t.dims[j].count()), rest /= t.dims[j].count();
          for (size_t j = 0; j < ix.size(); j++) idx += (j ? "," : "") + std::to_string(ix[j]);
          walk(nm + "[" + idx + "]", t.of, at + e * k);
        }
        return;
      }
      for (const Member& mb : t.members)
        if (mb.type != kNoType) walk(nm + "." + mb.name, mb.type, at + mb.offset);
    };
    walk(name, r.type, r.at);
  }

  Operand scratch(const std::string& key, Ty t) {
    std::string k = key + "." + ty_info(t).name;
    auto it = scratch_.find(k);
    if (it == scratch_.end()) it = scratch_.emplace(k, m_.place(m_.type(m_.elem(t)).size, SrcLoc{1, 1})).first;
    return operand_at(t, it->second);
  }

  // A string literal's cells, written by moves into a scratch STRING of its
  // own (docs/il.md, "Strings": the IL has no STRING constants).
  Operand string_literal(const std::string& bytes, const std::string& key) {
    Operand o = scratch("str." + key, Ty::STRING);
    std::vector<uint32_t> cells = string_cells(bytes);
    Operand c = o;
    typed(Op::TMOVE, Ty::DINT, Operand::typed_const(cells[0]), c);
    for (size_t k = 1; k <= (bytes.size() + 3) / 4; k++) {
      c.index = o.index + uint32_t(k);
      typed(Op::TMOVE, Ty::DWORD, Operand::typed_const(cells[k]), c);
    }
    return o;
  }

  // ---------------------------------------------------------------- code

  Rung* rung_ = nullptr;
  int depth_ = 0;
  std::vector<std::string> pending_labels_;
  struct Jump { std::string label; SrcLoc at; size_t rung; };
  std::vector<Jump> jumps_;
  // The CR a forward jump takes to its label (MatIEC keeps the CR in one
  // variable, so the code after a label goes on with the value it was
  // reached with): where the jump is (its JMP's rung and index: a store goes
  // right before it, so it runs exactly when the jump is taken) and the CR.
  struct CrJump { size_t rung, index; Cr cr; };
  std::map<std::string, std::vector<CrJump>> cr_jumps_;
  std::map<std::string, Cr> carried_;  // labels placed whose code goes on with the CR: its place
  bool dead_ = false;                  // after an unconditional JMP or RET: no way on from above
  std::set<std::string> labels_;
  SrcLoc here_;
  size_t instructions_ = 0;
  int copies_ = 0;
  std::vector<int> expanding_;  // POUs being expanded, outermost first
  int paren_base_ = 0;          // parentheses open in the callers

  void start_rung() {
    if (p_.rungs.size() >= kMaxRungs) throw Exhausted(here_.line, here_.col, "more than " + std::to_string(kMaxRungs) + " rungs (after expanding the calls inline)");
    Rung r;
    r.line = here_.line;
    r.labels = std::move(pending_labels_);
    pending_labels_.clear();
    p_.rungs.push_back(std::move(r));
    rung_ = &p_.rungs.back();
    depth_ = 0;
    emit(Op::TRUE);
  }
  void ensure_rung() {
    if (!rung_) start_rung();
  }
  void emit(Op op, Operand a = {}, Operand b = {}, Operand c = {}, Ty ty = Ty::None, Ty src = Ty::None) {
    if (!rung_) start_rung();
    Instr in;
    in.op = op, in.ty = ty, in.src = src;
    in.a[0] = a, in.a[1] = b, in.a[2] = c;
    for (int i = 0; i < in.nopd(); i++)
      if (op_info(op).operands[i] == 'e') in.a[i] = Operand{OpdKind::Edge, Area::Sys, p_.edge_slots++};
    in.loc = here_;
    depth_ += op_info(op).push - op_info(op).pop;
    if (++instructions_ > kMaxInstructions)
      throw Exhausted(here_.line, here_.col, "more than " + std::to_string(kMaxInstructions) + " IL instructions after expanding the calls inline");
    rung_->code.push_back(in);
  }
  void typed(Op op, Ty t, Operand a, Operand b = {}, Operand c = {}, Ty u = Ty::None) {
    if (!op_takes(op, t, u))
      fail(here_, std::string(op_info(op).name + 1) + " does not take " + ty_info(t).name + (u != Ty::None ? std::string(" and ") + ty_info(u).name : ""));
    emit(op, a, b, c, t, u);
  }
  void label_here(const std::string& l) {
    drop_jump_to_next(l);
    rung_ = nullptr;
    pending_labels_.push_back(l);
  }
  // A rung that ends with a jump to the label placed right after it (ST's
  // `JMP end` of an IF's last branch, with only labels between): taken or
  // not, the scan goes on at that label, so the jump is dropped (no code for
  // it in any engine).
  void drop_jump_to_next(const std::string& l) {
    if (!rung_ && p_.rungs.empty()) return;
    Rung& r = rung_ ? *rung_ : p_.rungs.back();  // (without a rung open, no code came since the last one ended)
    if (r.code.size() < 2 || r.code.back().op != Op::JMP || r.code.back().a[0].label.str() != l) return;
    r.code.pop_back();
  }
  void jump_to(const std::string& l) {
    Operand o{OpdKind::Label};
    o.label = l;
    jumps_.push_back({l, here_, 0});
    emit(Op::JMP, o);
    jumps_.back().rung = p_.rungs.size() - 1;
  }

  // ---- values at places

  Ty ty_of(TypeId id) const { return m_.scalar_ty(id); }
  std::string a_type(TypeId id) const {  // "an INT", "a DINT"
    std::string n = m_.type_name(id);
    return (std::string("AEIOUaeiou").find(n[0]) != std::string::npos ? "an " : "a ") + n;
  }
  // The index sequence of a Ref with variable indices; returns after the IDX
  // that the LDX/STX must follow.  Its base is the Ref's place (every
  // variable index at its lower bound) and its stride in the base's area.
  std::pair<Operand, int32_t> index(const model::Ref& r) {
    Ty t = ty_of(r.type);
    Operand base = operand_at(t, r.at, r.bits, r.cells);
    if (r.steps.size() == 1) {
      const IndexStep& s = r.steps[0];
      typed(Op::TIDX, s.index_ty, s.index, Operand::typed_const(uint64_t(int64_t(s.dim.lo))),
            Operand::typed_const(uint64_t(int64_t(s.dim.hi))));
      fix_k(rung_->code.back());
      return {base, stride_of(t, s.stride)};
    }
    // several: each index checked by its own IDX (the fault names it), the
    // element's offset summed in a DINT, then one IDX over the whole span
    Operand off = scratch("xoff", Ty::DINT), tmp = scratch("xtmp", Ty::DINT);
    typed(Op::TMOVE, Ty::DINT, Operand::typed_const(0), off);
    int64_t span = 0;
    for (const IndexStep& s : r.steps) {
      typed(Op::TIDX, s.index_ty, s.index, Operand::typed_const(uint64_t(int64_t(s.dim.lo))), Operand::typed_const(uint64_t(int64_t(s.dim.hi))));
      fix_k(rung_->code.back());
      typed(Op::TLDX, Ty::DINT, tmp, k_const(0), tmp);  // the check alone: stride 0 reads tmp back
      fix_k(rung_->code.back());
      if (s.index_ty == Ty::DINT) typed(Op::TMOVE, Ty::DINT, s.index, tmp);
      else typed(Op::TCONV, Ty::DINT, s.index, tmp, {}, s.index_ty);
      int32_t st = stride_of(t, s.stride);
      typed(Op::TSUB, Ty::DINT, tmp, Operand::typed_const(uint64_t(int64_t(s.dim.lo))), tmp);
      typed(Op::TMUL, Ty::DINT, tmp, Operand::typed_const(uint64_t(int64_t(st))), tmp);
      typed(Op::TADD, Ty::DINT, off, tmp, off);
      span += int64_t(s.dim.hi - s.dim.lo) * st;
    }
    typed(Op::TIDX, Ty::DINT, off, Operand::typed_const(0), Operand::typed_const(uint64_t(span)));
    fix_k(rung_->code.back());
    return {base, 1};
  }
  static Operand k_const(int32_t v) {
    Operand o{OpdKind::ConstInt};
    o.ival = v;
    return o;
  }
  // IDX's bounds and LDX/STX's stride are INT32 constants (k), not typed ones
  static void fix_k(Instr& in) {
    const char* sig = op_info(in.op).operands;
    for (int i = 0; sig[i]; i++)
      if (sig[i] == 'k' && in.a[i].kind == OpdKind::ConstT) in.a[i] = k_const(int32_t(uint32_t(in.a[i].bits())));
  }
  Operand load(const model::Ref& r, const std::string& key) {
    Ty t = ty_of(r.type);
    if (r.direct()) return operand_at(t, r.at, r.bits, r.cells);
    auto [base, stride] = index(r);
    Operand d = scratch(key, t);
    typed(Op::TLDX, t, base, k_const(stride), d);
    return d;
  }
  void store(const model::Ref& r, Operand v, const Tok& at) {
    if (!r.writable) fail(at, "'" + at.text + "' cannot be written (an input, or a CONSTANT)");
    Ty t = ty_of(r.type);
    if (r.direct()) {
      Operand d = operand_at(t, r.at, r.bits, r.cells);
      if (t == Ty::BOOL ? !operand_area_ok('w', d.area, d.index) : !operand_area_ok('d', d.area, d.index))
        fail(at, "'" + at.text + "' cannot be written (an input)");
      if (!(d == v)) typed(Op::TMOVE, t, v, d);
      return;
    }
    auto [base, stride] = index(r);
    typed(Op::TSTX, t, v, base, k_const(stride));
  }
  // a whole structured value (block move, element by element)
  void copy_value(TypeId id, const model::Ref& from, const model::Ref& to, const Tok& at) {
    if (!from.direct() || !to.direct()) fail(at, "a structured value selected by a variable index cannot be copied whole");
    const Type& t = m_.type(id);
    if (t.scalar()) {
      model::Ref f = from, d = to;
      f.type = d.type = id;
      store(d, load(f, "copy"), at);
      return;
    }
    if (t.kind == TypeKind::Array) {
      uint32_t n = 1;
      for (const Dim& dm : t.dims) n *= dm.count();
      Size e = m_.type(t.of).size;
      for (uint32_t k = 0; k < n; k++) {
        model::Ref f = from, d = to;
        f.at = from.at + e * k, d.at = to.at + e * k;
        copy_value(t.of, f, d, at);
      }
      return;
    }
    for (const Member& mb : t.members) {
      if (mb.type == kNoType) continue;
      model::Ref f = from, d = to;
      f.at = from.at + mb.offset, d.at = to.at + mb.offset;
      copy_value(mb.type, f, d, at);
    }
  }

  // ---- names

  Scope* scope_ = nullptr;

  // An operand: a literal, an enumerator, a variable path (a.b[i, 2].c), a device.
  Val operand(const std::string& key, bool raw = false) {
    skip_eols();
    const Tok& k = next();
    if (k.kind != Tok::Word) fail(k, "expected an operand" + found(k));
    if (st_temp(k.text)) return raw ? temp_val(k) : demoted(temp_val(k), key);
    Val v;
    std::string why;
    if (auto p = parse_literal(k.text, why)) {
      v.lit = *p;
      v.lit_type = p->lit.ty == Ty::None || p->untyped_int || p->untyped_real ? kNoType : m_.elem(p->lit.ty);
      return v;
    }
    if (!why.empty()) fail(k, why);
    std::string head = upper(k.text.substr(0, k.text.find('.')));
    if (!scope_->names.count(head))
      if (auto e = enumerator(k.text)) {
        v.lit.lit = {Ty::DINT, uint64_t(e->second)};
        v.lit_type = e->first;
        return v;
      }
    v.kind = Val::Ref_;
    v.ref = path(k, key);
    return v;
  }
  // "unknown variable 'strat'; did you mean 'start'?" with a note at the
  // declaration of the variable of the scope the name is a typo of
  // (docs/diagnostics.md); the compiler's own temporaries (__...) are not offered.
  [[noreturn]] void unknown_variable(const Tok& k, const std::string& name) {
    if (rec_) {
      const std::string& pou = upper(m_.pous[size_t(scope_->pou)].name);
      if (refused_[pou].count(upper(name)) || unknown_types_.count(upper(name)) || !unknown_[pou].insert(upper(name)).second)
        throw Quiet(k.line, k.col, "unknown variable '" + name + "' again");
    }
    std::string msg = "unknown variable '" + name + "'" + (scope_->pou == program_ ? "" : " in " + m_.pous[size_t(scope_->pou)].name);
    std::vector<std::string> names;
    for (const auto& [n, r] : scope_->names)
      if (!n.starts_with("__")) names.push_back(n);
    std::string near = closest_name(name, names);
    if (near.empty()) fail(k, msg);
    std::vector<DiagNote> notes;
    for (const Var& v : m_.pous[size_t(scope_->pou)].vars)
      if (upper(v.name) == near) {
        near = v.name;  // as declared
        if (v.loc.line > 0) notes.push_back({v.loc.line, v.loc.col, "'" + v.name + "' declared here"});
      }
    throw NotedError(k.line, k.col, msg + "; did you mean '" + near + "'?", notes);
  }
  model::Ref path(const Tok& k, const std::string& key) {
    Nest nest(nesting_, k);
    std::vector<std::string> parts;
    std::string text = k.text;
    size_t st = 0;
    for (size_t i = 0; i <= text.size(); i++)
      if (i == text.size() || text[i] == '.') parts.push_back(text.substr(st, i - st)), st = i + 1;
    model::Ref r;
    std::string head = upper(parts[0]);
    if (auto it = scope_->names.find(head); it != scope_->names.end()) {
      r = it->second;
    } else if (rec_ && refused_[upper(m_.pous[size_t(scope_->pou)].name)].count(head)) {
      throw Quiet(k.line, k.col, "'" + parts[0] + "' was refused");  // even where its name spells a device (F1)
    } else if (text[0] == '%' || (parse_device(text) && parts.size() == 1)) {
      return device(k);
    } else {
      unknown_variable(k, parts[0]);
    }
    SrcLoc at = loc(k);
    for (size_t i = 1; i < parts.size(); i++) {
      if (parts[i].empty()) fail(k, "an empty member name in '" + k.text + "'");
      r = m_.select_member(r, parts[i], at);
    }
    while (punct(peek(), "[")) {
      next();
      std::vector<std::pair<Operand, Ty>> idx;
      for (;;) {
        const Tok& it = peek();
        Val iv = operand(key + "i" + std::to_string(idx.size()));
        idx.push_back(index_operand(iv, it, key + "i" + std::to_string(idx.size())));
        if (punct(peek(), ",")) { next(); continue; }
        if (!punct(peek(), "]")) fail(peek(), "expected ',' or ']'" + found(peek()));
        next();
        break;
      }
      r = m_.select_element(r, idx, at);
      if (peek().kind == Tok::Word && peek().text[0] == '.') {  // a[1].x
        const Tok& mk = next();
        std::string rest = mk.text.substr(1);
        size_t s2 = 0;
        for (size_t i = 0; i <= rest.size(); i++)
          if (i == rest.size() || rest[i] == '.') {
            if (i == s2) fail(mk, "an empty member name");
            r = m_.select_member(r, rest.substr(s2, i - s2), loc(mk));
            s2 = i + 1;
          }
      }
    }
    return r;
  }
  std::pair<Operand, Ty> index_operand(const Val& v, const Tok& k, const std::string& key) {
    if (v.kind == Val::Lit) {
      if (!v.lit.untyped_int || v.lit.lit.ty == Ty::ULINT) {
        if (v.lit_type != kNoType && typed::is_int_kind(v.lit.lit.ty) && ty_info(v.lit.lit.ty).kind != TyKind::Bits)
          return {Operand::typed_const(v.lit.lit.bits), v.lit.lit.ty};
        fail(k, "an array index must be an integer (SINT .. ULINT): '" + k.text + "' is not one");
      }
      return {Operand::typed_const(uint64_t(v.lit.ival)), Ty::LINT};
    }
    Ty t = ty_of(v.ref.type);
    if (t == Ty::None) fail(k, "an array index must be an integer (SINT .. ULINT), '" + k.text + "' is " + a_type(v.ref.type));
    return {load(v.ref, key), t};
  }
  model::Ref device(const Tok& k) {
    std::string why;
    std::optional<DeviceRef> d = k.text[0] == '%' ? iec_address(k.text, why) : parse_device(k.text);
    if (!d) fail(k, why.empty() ? "unknown variable '" + k.text + "'" : why);
    if (d->index >= device_count(d->dev)) fail(k, "device index out of range: " + k.text);
    if (d->dev == Dev::T || d->dev == Dev::C) fail(k, "timers and counters are not available in a program with typed declarations yet");
    model::Ref r;
    r.bits = bit_area(d->dev), r.cells = word_area(d->dev);
    r.at = {d->index, d->index};
    r.type = m_.elem(r.bits != Area::Count ? Ty::BOOL : r.cells == Area::F ? Ty::REAL : Ty::DINT);
    r.writable = d->dev != Dev::X && d->dev != Dev::WX && d->dev != Dev::K;
    return r;
  }

  // ---- the current result

  Cr cr_;
  struct Paren { std::string op; Cr saved; SrcLoc at; Tok tok; };
  std::vector<Paren> parens_;

  void need_cr(const Tok& k) {
    if (!cr_.defined)
      fail(k, "'" + k.text + "' needs a current result: after a label, a jump, a call or at the start, begin with LD");
  }
  Ty cr_ty() const { return cr_.lit ? Ty::None : ty_of(cr_.type); }
  // The BOOL CR as a bit device (a constant is put in an accumulator first).
  Operand cr_bit() {
    if (cr_.o.kind != OpdKind::ConstT) return cr_.o;
    Operand d = acc(Ty::BOOL);
    typed(Op::TMOVE, Ty::BOOL, cr_.o, d);
    cr_.o = d;
    return d;
  }
  // Skips a variable path (name, [indices], .members) without lowering it.
  void skip_path() {
    next();
    while (punct(peek(), "[")) {
      int depth = 0;
      do {
        if (punct(peek(), "[")) depth++;
        if (punct(peek(), "]")) depth--;
        if (peek().kind == Tok::Eol || peek().kind == Tok::End) fail(peek(), "expected ']'" + found(peek()));
        next();
      } while (depth > 0);
      if (peek().kind == Tok::Word && peek().text[0] == '.') next();
    }
  }
  void need_bool(const Tok& k) {
    need_cr(k);
    if (cr_.lit || cr_ty() != Ty::BOOL)
      fail(k, "'" + k.text + "' needs a BOOL current result, this one is " + (cr_.lit ? std::string("a number") : m_.type_name(cr_.type)));
  }
  // The CR as an operand of type t (an untyped literal takes t).
  void type_cr(TypeId t, const Tok& at) {
    if (!cr_.lit) return;
    std::string why;
    Ty st = ty_of(t);
    if (st == Ty::None) fail(at, "a number where " + a_type(t) + " is wanted");
    auto v = literal_as(*cr_.lit, st, why);
    if (!v) fail(at, why);
    cr_.lit.reset();
    cr_.type = t;
    cr_.o = Operand::typed_const(v->bits);
  }
  // An untyped CR that meets another untyped number: DINT or LREAL (IEC's defaults)
  void default_cr(const Tok& at) {
    if (cr_.lit) type_cr(m_.elem(cr_.lit->untyped_real ? Ty::LREAL : Ty::DINT), at);
  }
  // v as a source operand of type t
  Operand value_as(const Val& v, TypeId t, const Tok& k, const std::string& key, const char* what) {
    Ty st = ty_of(t);
    if (v.kind == Val::Lit) {
      if (v.lit_type != kNoType && m_.type(v.lit_type).kind == TypeKind::Enum) {
        if (!m_.same_type(v.lit_type, t) && v.lit_type != t) fail(k, "'" + k.text + "' is " + a_type(v.lit_type) + ", not " + a_type(t));
        return Operand::typed_const(v.lit.lit.bits);
      }
      if (m_.type(t).kind == TypeKind::Enum) fail(k, "'" + k.text + "' is not " + a_type(t));
      std::string why;
      auto l = literal_as(v.lit, st, why);
      if (!l) fail(k, why);
      if (st == Ty::STRING) return string_literal(v.lit.str, key);
      return Operand::typed_const(l->bits);
    }
    if (!m_.same_type(v.ref.type, t))
      fail(k, std::string(what) + " of " + a_type(t) + " and '" + k.text + "', " + a_type(v.ref.type) +
                  ": convert it first (" + m_.type_name(v.ref.type) + "_TO_" + m_.type_name(t) + ")");
    return load(v.ref, key);
  }
  TypeId val_type(const Val& v) const {
    if (v.kind == Val::Lit) return v.lit_type;
    return v.ref.type;
  }
  void set_cr(TypeId t, Operand o) {
    cr_ = Cr{};
    cr_.defined = true, cr_.type = t, cr_.o = o;
  }
  Operand acc(Ty t) { return scratch("acc" + std::to_string(paren_base_ + int(parens_.size())), t); }

  // ---------------------------------------------------------------- lowering

  void lower_program() {
    Scope s;
    s.pou = program_;
    s.names = globals_;
    scope_ = &s;
    here_ = {1, 1};
    initial_values();
    if (rtc_type_ != kNoType) clock_rung();
    init_rungs_ = p_.rungs.size();
    rung_ = nullptr;
    lower_body(program_);
    scope_ = nullptr;
  }

  // Written on the first scan, before anything else (S1).
  void initial_values() {
    struct Init1 { Ty ty; Operand to; uint64_t bits; };
    std::vector<Init1> stores;
    for (const Var& v : m_.pous[size_t(program_)].vars) {
      const model::Ref& r = globals_.at(upper(v.name));
      const bool input = v.at && (r.bits == Area::X || r.cells == Area::WX);
      if (unit_ && v.at && unit_->callers.count(upper(v.name))) continue;  // the caller initialises it
      if (input && v.init.kind != Init::None && !from_st_)
        recover([&] { fail(v.init.loc, "an input (" + v.name + ") has no initial value: the I/O writes it"); });
      if (input) continue;  // ST as OpenPLC Editor writes it gives inputs one (:= 0): the I/O overwrites it before the first scan
      std::vector<Model::Store> one;
      // with recovery, a variable whose initial value is refused has none
      if (!recover([&] { m_.initial_stores(v.type, r.at, v.init.kind == Init::None ? nullptr : &v.init, one); })) continue;
      for (auto& st : one) stores.push_back({st.ty, operand_at(st.ty, st.at, r.bits, r.cells), st.bits});
    }
    if (stores.empty()) return;
    start_rung();
    emit(Op::LOAD, Operand{OpdKind::Bit, Area::S, kBitFirstScan});
    for (const auto& st : stores) typed(Op::TMOVE, st.ty, Operand::typed_const(st.bits), st.to);
    rung_ = nullptr;
  }

  // Lowers the body of POU `pou` in the current scope.
  void lower_body(int pou) {
    PouSrc& s = src_of(pou);
    size_t save = pos_;
    pos_ = s.body;
    cr_ = Cr{};
    rung_ = nullptr;
    bool skipping = false, refused = false;
    while (pos_ < s.end) {
      if (peek().kind == Tok::Eol) { next(); continue; }
      if (!rec_) { line(); continue; }
      size_t start = pos_;
      if (skipping && !sync_line()) { skip_line(s.end); continue; }
      skipping = false;
      if (recover([&] { line(); })) continue;
      // the line refused: the ones after it that go on with its value are
      // skipped too, up to the next that starts anew
      pos_ = start;
      skip_line(s.end);
      cr_ = Cr{};
      parens_.clear();
      rung_ = nullptr;
      skipping = refused = true;
    }
    if (!parens_.empty() && !refused) fail(parens_.back().at, "'(' is never closed");
    parens_.clear();
    pos_ = save;
  }
  void skip_line(size_t end) {
    while (pos_ < end && peek().kind != Tok::Eol && peek().kind != Tok::End) next();
  }
  // Does the line at pos_ start anew, not going on with the value of the line
  // before it: a label; in ST, the first line of a statement; in IL, a line
  // that loads a value, calls a block, or jumps or returns unconditionally.
  bool sync_line() const {
    if (peek().kind == Tok::Word && punct(peek(1), ":")) return true;
    if (from_st_) return pos_ > 0 && t_[pos_ - 1].kind == Tok::Eol && t_[pos_ - 1].statement;
    std::string u = upper(peek().text);
    return peek().kind == Tok::Word && (u == "LD" || u == "LDN" || u == "CAL" || u == "JMP" || u == "RET");
  }
  PouSrc& src_of(int pou) {
    for (auto& [u, s] : pou_src_)
      if (s.pou == pou) return s;
    throw std::logic_error("POU without source");
  }

  // line = [ NAME ":" ] [ instruction ] EOL
  void line() {
    const Tok& first = peek();
    if (first.kind == Tok::Word && punct(peek(1), ":")) {
      if (!ident(first.text)) fail(first, "bad label name '" + first.text + "'");
      if (!parens_.empty()) fail(first, "a label inside parentheses");
      std::string l = scope_->prefix + first.text;
      if (!labels_.insert(l).second) fail(first, "duplicate label '" + first.text + "'");
      pos_ += 2;
      Cr in = carry_to(l);  // before label_here: the way in from above stores into the current rung
      label_here(l);
      cr_ = in;
      dead_ = false;
      if (peek().kind == Tok::Eol || peek().kind == Tok::End) { end_line(); return; }
    }
    const Tok& op = next();
    here_ = loc(op);
    if (punct(op, ")")) {
      close_paren(op);
      end_line();
      return;
    }
    if (op.kind != Tok::Word) fail(op, "expected an IL operator" + found(op));
    dead_ = false;
    instruction(op);
    end_line();
  }

  // Does the line at pos_ go on with the CR (an operator other than a load, a
  // call, a jump or a return, which start anew)?
  bool uses_cr_next() const {
    size_t i = pos_;
    while (i < t_.size() && t_[i].kind == Tok::Eol) i++;
    if (i >= t_.size() || t_[i].kind != Tok::Word) return false;
    if (i + 1 < t_.size() && t_[i + 1].kind == Tok::Punct && t_[i + 1].text == ":") return false;  // another label
    std::string u = upper(t_[i].text);
    static const std::set<std::string> anew = {"LD", "LDN", "CAL", "JMP", "RET", "LOOP", "END_FUNCTION_BLOCK", "END_FUNCTION",
                                               "END_PROGRAM"};
    return !anew.count(u);
  }
  // Label `l` is placed here: the CR its code goes on with, when every way in
  // (the forward jumps to it and the line above, unless it jumped or
  // returned) brings a CR of one type.  Each way stores its CR into the
  // label's place (docs/iec-il.md, "The current result at a label").
  Cr carry_to(const std::string& l) {
    auto js = cr_jumps_.find(l);
    if (js == cr_jumps_.end() || !uses_cr_next()) return Cr{};
    std::vector<Cr> ways;
    for (const CrJump& j : js->second) ways.push_back(j.cr);
    if (!dead_) ways.push_back(cr_);
    for (const Cr& w : ways)
      if (!w.defined || w.lit || w.type != ways[0].type) return Cr{};  // "needs a current result" at its use
    Ty t = ty_of(ways[0].type);
    Operand place = scratch("cr." + l, t);
    if (!dead_) typed(Op::TMOVE, t, cr_.o, place);
    std::map<size_t, std::vector<const CrJump*>> by_rung;  // stores before each jump, the last first
    for (const CrJump& j : js->second) by_rung[j.rung].push_back(&j);
    for (auto& [r, list] : by_rung) {
      std::sort(list.begin(), list.end(), [](const CrJump* a, const CrJump* b) { return a->index > b->index; });
      for (const CrJump* j : list) {
        std::vector<Instr>& code = p_.rungs[r].code;
        Instr st;
        st.op = Op::TMOVE, st.ty = t, st.a[0] = j->cr.o, st.a[1] = place, st.loc = code.empty() ? here_ : code[std::min(j->index, code.size() - 1)].loc;
        code.insert(code.begin() + std::ptrdiff_t(cr_store_at(code, j->index, l)), st);
      }
    }
    carried_[l] = Cr{true, ways[0].type, place, {}};
    return carried_[l];
  }
  // Where a way in by a jump to `l` recorded at `index` stores its CR: right
  // before that jump (instructions placed before it since move it down), and
  // never between an IDX or ARGS and the instruction that reads it, which
  // must follow at once (the IL's check; a store into an array element ends
  // with IDX, STX: found by ST's 10^5 random programs, seed 91283)
  static size_t cr_store_at(const std::vector<Instr>& code, size_t index, const std::string& l) {
    size_t at = std::min(index, code.size());
    for (size_t k = at; k < code.size(); k++)
      if (code[k].op == Op::JMP && code[k].a[0].kind == OpdKind::Label && code[k].a[0].label == l) {
        at = k;
        break;
      }
    while (at > 0 && (code[at - 1].op == Op::TIDX || code[at - 1].op == Op::TARGS)) at--;
    return at;
  }
  // A jump back to label `l` placed above, whose code goes on with the CR:
  // this way in stores its CR there too, of the label's type.
  void carry_back(const std::string& l, const Cr& cr, const Tok& op) {
    auto it = carried_.find(l);
    if (it == carried_.end()) return;
    if (!cr.defined || cr.lit || cr.type != it->second.type)
      fail(op, "the code at label '" + l.substr(scope_->prefix.size()) + "' goes on with the current result of type " +
                   ty_info(ty_of(it->second.type)).name + ", which this jump does not bring");
    typed(Op::TMOVE, ty_of(it->second.type), cr.o, it->second.o);
  }

  void instruction(const Tok& op) {
    std::string u = upper(op.text);
    // ST's C arithmetic: what does not compute on C's int gets the value cut
    // to its type first (an ST into an expression's temporary __Tn keeps it;
    // a CASE's selector __Sn is cut, as MatIEC's __case_expression of the
    // selector's type; LD replaces it)
    if (cr_.narrow != kNoType && !c_int_op(u) && u != "LD" && u != "LDN" && !punct(peek(), "(") &&
        !(u == "ST" && st_temp(peek().text) && upper(peek().text).rfind("__T", 0) == 0))
      demote();
    if (punct(peek(), "(") && u != "CAL" && u != "CALC" && u != "CALCN" && !is_function(u)) {
      next();
      return open_paren(op, u);
    }
    if (u == "LD" || u == "LDN") return load_op(op, u == "LDN");
    if (u == "ST" || u == "STN") return store_op(op, u == "STN");
    if (u == "S" || u == "R") return set_reset(op, u == "S");
    if (u == "JMP" || u == "JMPC" || u == "JMPCN") return jump(op, u);
    if (from_st_ && (u == "__ANDTHEN" || u == "__ORELSE")) return short_circuit(op, u == "__ANDTHEN");
    if (u == "LOOP" && from_st_) return loop(op);
    if (u == "RET" || u == "RETC" || u == "RETCN") return ret(op, u);
    if (u == "CAL" || u == "CALC" || u == "CALCN") return call(op, u);
    if (binary_op(u)) {
      need_cr(op);
      Tok k = peek();
      Val v = operand("b", c_int_op(u));
      return binary(op, u, v, k);
    }
    if (u == "MOVE") { need_cr(op); return; }
    if (u == "NOT") return not_op(op);
    if (string_fn(u)) return string_function(op, u);
    if (unary_fn(u) || conversion(u) || u == "TRUNC") return function1(op, u);
    if (auto b = bcd_conversion(u)) return bcd(op, *b);
    if (auto f = time_function(u)) return time_arith(op, *f);
    if (auto f = time_scaling(u)) {
      need_cr(op);
      Tok k = peek();
      Val v = operand("b");
      return time_scale(op, f->mul, f->in2, v, k);
    }
    if (u == "MIN" || u == "MAX" || u == "LIMIT" || u == "SEL" || u == "MUX") return selection(op, u);
    if (is_function(u)) return user_function(op, u);
    static const std::set<std::string> ldc_ops = {"LOAD", "LOADN", "OUT", "OUTN", "SET", "RST", "ANDBLK", "ORBLK", "MPS", "MRD", "MPP"};
    if (rec_ && !unknown_ops_.insert(u).second) throw Quiet(op.line, op.col, "unknown operator again");  // reported once
    fail(op, "unknown IL operator '" + op.text + "'" +
                 (ldc_ops.count(u) ? std::string(" (this file is read as IEC IL; ldc's own IL starts with a '.rung' line)") : ""));
  }
  static bool binary_op(const std::string& u) {
    static const std::set<std::string> k = {"AND", "ANDN", "OR", "ORN", "XOR", "XORN", "ADD", "SUB", "MUL", "DIV", "MOD",
                                            "GT", "GE", "EQ", "NE", "LT", "LE", "SHL", "SHR", "ROL", "ROR", "EXPT"};
    return k.count(u) > 0;
  }
  static bool unary_fn(const std::string& u) {
    static const std::set<std::string> k = {"ABS", "NEG", "SQRT", "LN", "LOG", "EXP", "SIN", "COS", "TAN", "ASIN", "ACOS", "ATAN"};
    return k.count(u) > 0;
  }
  // A_TO_B, A and B elementary: (A, B)
  static std::optional<std::pair<Ty, Ty>> conversion(const std::string& u) {
    size_t p = u.find("_TO_");
    if (p == std::string::npos) return std::nullopt;
    auto a = ty_from_name(u.substr(0, p)), b = ty_from_name(u.substr(p + 4));
    if (!a || !b) return std::nullopt;
    return std::make_pair(*a, *b);
  }
  // MatIEC's BCD conversions (lib/standard_functions.txt): X_TO_BCD_Y and
  // X_TO_BCD (X an unsigned integer, Y a bit string; X_TO_BCD gives the bit
  // string of X's width), X_BCD_TO_Y and BCD_TO_Y (the CR's bit string).
  struct Bcd {
    bool to_bcd = false;
    Ty from = Ty::None, to = Ty::None;  // from None: the CR's type
  };
  static std::optional<Bcd> bcd_conversion(const std::string& u) {
    auto uint_ty = [](const std::string& n) -> std::optional<Ty> {
      auto t = ty_from_name(n);
      if (t && ty_info(*t).kind == TyKind::Unsigned) return t;
      return std::nullopt;
    };
    auto bits_ty = [](const std::string& n) -> std::optional<Ty> {
      auto t = ty_from_name(n);
      if (t && ty_info(*t).kind == TyKind::Bits) return t;
      return std::nullopt;
    };
    static const std::map<Ty, Ty> same_width = {{Ty::USINT, Ty::BYTE}, {Ty::UINT, Ty::WORD}, {Ty::UDINT, Ty::DWORD}, {Ty::ULINT, Ty::LWORD}};
    if (size_t p = u.find("_TO_BCD"); p != std::string::npos && p > 0) {
      auto from = uint_ty(u.substr(0, p));
      std::string rest = u.substr(p + 7);
      if (!from) return std::nullopt;
      if (rest.empty()) return Bcd{true, *from, same_width.at(*from)};
      if (rest[0] != '_') return std::nullopt;
      auto to = bits_ty(rest.substr(1));
      if (!to) return std::nullopt;
      return Bcd{true, *from, *to};
    }
    if (u.rfind("BCD_TO_", 0) == 0) {
      auto to = uint_ty(u.substr(7));
      if (!to) return std::nullopt;
      return Bcd{false, Ty::None, *to};
    }
    if (size_t p = u.find("_BCD_TO_"); p != std::string::npos && p > 0) {
      auto from = bits_ty(u.substr(0, p)), to = uint_ty(u.substr(p + 8));
      if (!from || !to) return std::nullopt;
      return Bcd{false, *from, *to};
    }
    return std::nullopt;
  }
  // MatIEC's time and date arithmetic (lib/C/iec_std_functions.h): each is
  // __time_add or __time_sub of two timespecs, here nanoseconds (IN1 the CR)
  struct TimeFn {
    Ty in1, in2, out;
    bool add;
  };
  static std::optional<TimeFn> time_function(const std::string& u) {
    static const std::map<std::string, TimeFn> k = {
        {"ADD_TIME", {Ty::TIME, Ty::TIME, Ty::TIME, true}},      {"SUB_TIME", {Ty::TIME, Ty::TIME, Ty::TIME, false}},
        {"ADD_TOD_TIME", {Ty::TOD, Ty::TIME, Ty::TOD, true}},    {"ADD_DT_TIME", {Ty::DT, Ty::TIME, Ty::DT, true}},
        {"SUB_TOD_TIME", {Ty::TOD, Ty::TIME, Ty::TOD, false}},   {"SUB_DT_TIME", {Ty::DT, Ty::TIME, Ty::DT, false}},
        {"SUB_DATE_DATE", {Ty::DATE, Ty::DATE, Ty::TIME, false}}, {"SUB_TOD_TOD", {Ty::TOD, Ty::TOD, Ty::TIME, false}},
        {"SUB_DT_DT", {Ty::DT, Ty::DT, Ty::TIME, false}},         {"CONCAT_DATE_TOD", {Ty::DATE, Ty::TOD, Ty::DT, true}}};
    auto it = k.find(u);
    if (it == k.end()) return std::nullopt;
    return it->second;
  }
  void time_arith(const Tok& op, const TimeFn& f) {
    need_cr(op);
    if (cr_.lit) type_cr(m_.elem(f.in1), op);
    if (cr_ty() != f.in1) fail(op, op.text + " takes a " + ty_info(f.in1).name + " first, this result is " + m_.type_name(cr_.type));
    Tok k = peek();
    Val v = operand("b");
    Operand b = value_as(v, m_.elem(f.in2), k, "b", op.text.c_str());
    Operand d = acc(f.out);
    typed(f.add ? Op::TADD : Op::TSUB, Ty::LINT, cr_.o, b, d);  // ns: LINT arithmetic on the cells
    set_cr(m_.elem(f.out), d);
  }
  // MatIEC's MULTIME / DIVTIME (lib/standard_functions.txt; MUL_TIME / DIV_TIME
  // as IEC 61131-3's 2nd edition names them), overloaded on IN2's ANY_NUM or
  // typed (MULTIME_INT ...); in2 None: the operand's type.
  struct TimeScale {
    bool mul;
    Ty in2;
  };
  static std::optional<TimeScale> time_scaling(const std::string& u) {
    for (const char* base : {"MULTIME", "MUL_TIME", "DIVTIME", "DIV_TIME"}) {
      const std::string b = base;
      if (u.rfind(b, 0) != 0) continue;
      const bool mul = b[0] == 'M';
      if (u.size() == b.size()) return TimeScale{mul, Ty::None};
      auto t = u[b.size()] == '_' ? ty_from_name(u.substr(b.size() + 1)) : std::nullopt;
      if (t && any_num(*t)) return TimeScale{mul, *t};
    }
    return std::nullopt;
  }
  static bool any_num(Ty t) {
    const TyKind k = ty_info(t).kind;
    return k == TyKind::Signed || k == TyKind::Unsigned || k == TyKind::Real;
  }
  // CR := CR * IN2 or CR / IN2, a TIME by a number (ANY_NUM, as an LREAL), as
  // MatIEC's __time_mul and __time_div compute it (ir/time_scale.h).
  void time_scale(const Tok& op, bool mul, Ty in2, const Val& v, const Tok& k) {
    if (cr_.lit) type_cr(m_.elem(Ty::TIME), op);
    if (cr_ty() != Ty::TIME) fail(op, op.text + " takes a TIME first, this result is " + m_.type_name(cr_.type));
    TypeId vt = in2 != Ty::None ? m_.elem(in2) : val_type(v);
    if (vt == kNoType) vt = m_.elem(Ty::LREAL);  // an untyped number: its value as an LREAL
    const Ty u = ty_of(vt);
    if (u == Ty::None || !any_num(u)) fail(k, op.text + " takes a number second (ANY_NUM), '" + k.text + "' is " + a_type(vt));
    Operand b = value_as(v, vt, k, "b", op.text.c_str());
    Operand x = scratch("tm.x", Ty::LREAL), d = acc(Ty::TIME);
    if (u == Ty::LREAL) typed(Op::TMOVE, Ty::LREAL, b, x);
    else typed(Op::TCONV, Ty::LREAL, b, x, {}, u);
    auto temp = [&](const char* n, Ty t) { return scratch(std::string("tm.") + n, t); };
    for (const TypedStep& st : time_scale_steps(mul, cr_.o, x, d, temp)) typed(st.op, st.t, st.a, st.b, st.c, st.u);
    set_cr(m_.elem(Ty::TIME), d);
  }
  bool is_function(const std::string& u) const {
    int p = m_.find_pou(u);
    return p >= 0 && m_.pous[size_t(p)].kind == PouKind::Function;
  }

  // LD / LDN
  void load_op(const Tok& op, bool neg) {
    if (!parens_.empty() && cr_.defined) fail(op, "LD inside parentheses: write it after the opening operator (AND( x)");
    if (from_st_ && peek().text == "__ZERO") return zero_temp(op);
    Tok k = peek();
    Val v = operand("ld", true);
    load_val(op, neg, v, k);
  }
  void load_val(const Tok& op, bool neg, const Val& v, const Tok& k) {
    ensure_rung();
    if (v.kind == Val::Lit && v.lit_type == kNoType) {
      if (neg) fail(op, "LDN of a number");
      cr_ = Cr{};
      cr_.defined = true;
      cr_.lit = v.lit;
      return;
    }
    TypeId t = val_type(v);
    if (!m_.type(t).scalar()) {
      if (neg) fail(op, "LDN of " + a_type(t));
      cr_ = Cr{};
      cr_.defined = true, cr_.type = t;
      whole_ = v.ref;  // a structured value: only ST may follow
      whole_tok_ = k;
      return;
    }
    Operand o = v.kind != Val::Lit ? load(v.ref, "ld")
              : v.lit.lit.ty == Ty::STRING ? string_literal(v.lit.str, "ld") : Operand::typed_const(v.lit.lit.bits);
    set_cr(t, o);
    cr_.narrow = v.narrow;
    if (v.kind == Val::Ref_ && v.narrow == kNoType && !neg) cr_.var = v.ref, cr_.var_o = o;
    if (neg && v.narrow != kNoType) return not_op(op);
    if (neg) {
      Ty st = ty_of(t);
      if (st != Ty::BOOL && ty_info(st).kind != TyKind::Bits) fail(op, "LDN needs a BOOL or a bit string, '" + k.text + "' is " + a_type(t));
      Operand d = acc(st);
      typed(Op::TNOT, st, o, d);
      cr_.o = d;
    }
  }
  model::Ref whole_;
  Tok whole_tok_;
  bool cr_whole() const { return cr_.defined && !cr_.lit && !m_.type(cr_.type).scalar(); }

  void store_op(const Tok& op, bool neg) {
    need_cr(op);
    Tok k = peek();
    if (k.kind != Tok::Word) fail(k, "'" + op.text + "' needs an operand" + found(k));
    if (st_temp(k.text)) return store_temp(k);
    Val v = operand("st");
    if (v.kind == Val::Lit) fail(k, "'" + k.text + "' cannot be written (a constant)");
    if (cr_whole()) {
      if (neg) fail(op, "STN of " + a_type(cr_.type));
      if (v.ref.type != cr_.type) fail(k, "ST of " + a_type(cr_.type) + " into '" + k.text + "', " + a_type(v.ref.type));
      if (!v.ref.writable) fail(k, "'" + k.text + "' cannot be written (an input, or a CONSTANT)");
      copy_value(cr_.type, whole_, v.ref, k);
      return;
    }
    if (!m_.type(v.ref.type).scalar()) fail(k, "ST of a single value into '" + k.text + "', " + a_type(v.ref.type));
    type_cr(v.ref.type, op);
    if (!m_.same_type(cr_.type, v.ref.type) && !(m_.type(cr_.type).kind == TypeKind::Enum && cr_.type == v.ref.type))
      fail(k, (from_st_ ? "assignment of " + a_type(cr_.type) + " value to '" : "ST of " + a_type(cr_.type) + " result into '") +
                  k.text + "', " + a_type(v.ref.type) + ": convert it first (" + m_.type_name(cr_.type) + "_TO_" +
                  m_.type_name(v.ref.type) + ")");
    Operand val = cr_.o;
    Ty t = ty_of(cr_.type);
    if (neg) {
      if (t != Ty::BOOL && ty_info(t).kind != TyKind::Bits) fail(op, "STN needs a BOOL or bit-string result");
      val = scratch("stn", t);
      typed(Op::TNOT, t, cr_.o, val);
    }
    // the operation that computed the CR writes the variable itself
    Instr* last = rung_ && !rung_->code.empty() ? &rung_->code.back() : nullptr;
    if (!neg && v.ref.direct() && v.ref.writable && last && last->ty == t && op_info(last->op).klass == OpClass::Typed &&
        op_info(last->op).push == 0 && last->op != Op::TSTX && last->op != Op::TIDX && last->a[last->nopd() - 1] == cr_.o &&
        is_acc(cr_.o)) {
      Operand d = operand_at(t, v.ref.at, v.ref.bits, v.ref.cells);
      if (t == Ty::BOOL ? operand_area_ok('w', d.area, d.index) : operand_area_ok('d', d.area, d.index)) {
        last->a[last->nopd() - 1] = d;
        cr_.o = d;
        return;
      }
    }
    store(v.ref, val, k);
    if (v.ref.direct()) cr_.o = operand_at(t, v.ref.at, v.ref.bits, v.ref.cells);
  }
  // ---- the temporaries of ST (frontend/st): __T1, __S1 ... take the type
  // of the value stored into them; one place per name, type and inline copy.
  struct Temp { TypeId type; Operand o; TypeId narrow = kNoType; };
  std::map<std::string, Temp> temps_;
  // A name of two leading underscores that the scope declares is a variable
  // (the state of a chart written as text, frontend/st/sfc_text.h).
  bool st_temp(const std::string& name) const {
    return from_st_ && name.rfind("__", 0) == 0 && !scope_->names.count(upper(name));
  }
  void store_temp(const Tok& k) {
    next();
    default_cr(k);
    if (cr_whole()) fail(k, "a structured value in an expression: assign it to a variable of its type");
    Ty t = ty_of(cr_.type);
    Operand d = scratch("st" + scope_->prefix + k.text, t);
    typed(Op::TMOVE, t, cr_.o, d);
    temps_[scope_->prefix + k.text] = {cr_.type, d, cr_.narrow};
    cr_.o = d;
  }
  // LD __ZERO / ST x (ST's EN, frontend/st): x, a temporary already typed
  // by the value it holds otherwise or a variable, set to its type's initial
  // value
  void zero_temp(const Tok& op) {
    next();
    end_line();
    skip_eols();
    const Tok& st = next();
    if (!kw(st, "ST")) fail(op, "__ZERO outside its ST form");
    Tok k = peek();
    Val v = operand("zero");
    if (v.kind != Val::Ref_ || !m_.type(v.ref.type).scalar()) fail(k, "EN of a call whose value is not elementary");
    Ty t = ty_of(v.ref.type);
    if (t == Ty::STRING) fail(op, "a STRING function called with EN: not compiled (docs/st.md)");
    ensure_rung();
    store(v.ref, Operand::typed_const(0), k);
    cr_ = Cr{};
  }
  Val temp_val(const Tok& k) const {
    auto it = temps_.find(scope_->prefix + k.text);
    // with recovery, a temporary whose store was refused (reported) says nothing more
    if (it == temps_.end() && rec_ && rec_->failed()) throw Quiet(k.line, k.col, "temporary not written");
    if (it == temps_.end()) fail(k, "'" + k.text + "' is read before it is written (a name beginning with two underscores is an ST temporary of ldc's)");
    return cell_val(it->second.type, it->second.o, it->second.narrow);
  }
  // A value of type t in the compiler's own cell o (a temporary, a scratch).
  static Val cell_val(TypeId t, const Operand& o, TypeId narrow = kNoType) {
    Val v;
    v.kind = Val::Ref_;
    v.ref.type = t;
    v.ref.at = {o.index, o.index};
    v.ref.bits = Area::M;
    v.ref.cells = Area::D;
    v.narrow = narrow;
    return v;
  }

  bool is_acc(const Operand& o) const {
    for (const auto& [k, p] : scratch_)
      if (k.rfind("acc", 0) == 0 && (o.area == Area::D ? p.cell == o.index : o.area == Area::M && p.bit == o.index)) return true;
    return false;
  }

  void set_reset(const Tok& op, bool set) {
    need_bool(op);
    Tok k = peek();
    Val v = operand("sr");
    if (v.kind == Val::Lit || ty_of(v.ref.type) != Ty::BOOL) fail(k, std::string(set ? "S" : "R") + " needs a BOOL variable, '" + k.text + "' is not one");
    if (!v.ref.writable) fail(k, "'" + k.text + "' cannot be written (an input, or a CONSTANT)");
    if (v.ref.direct()) {
      Operand d = operand_at(Ty::BOOL, v.ref.at, v.ref.bits, v.ref.cells);
      if (!operand_area_ok('w', d.area, d.index)) fail(k, "'" + k.text + "' cannot be written (an input)");
      emit(Op::LOAD, cr_bit());
      emit(set ? Op::SET : Op::RST, d);
      emit(Op::MPP);
      return;
    }
    // an element: x := x OR CR (S), x := x AND NOT CR (R)
    Operand x = load(v.ref, "sr"), h = scratch("srh", Ty::BOOL);
    if (set) typed(Op::TOR, Ty::BOOL, x, cr_.o, h);
    else typed(Op::TNOT, Ty::BOOL, cr_.o, h), typed(Op::TAND, Ty::BOOL, x, h, h);
    store(v.ref, h, k);
  }

  void not_op(const Tok& op) {
    need_cr(op);
    default_cr(op);
    if (c_int_cr()) {  // C's ~ of an int: the bits of the DINT, as a DWORD
      mark_promotion();
      promote_cr();
      Operand d = acc(Ty::DINT);
      typed(Op::TNOT, Ty::DWORD, cr_.o, d);
      cr_.o = d;
      return;
    }
    Ty t = cr_ty();
    if (t != Ty::BOOL && ty_info(t).kind != TyKind::Bits) fail(op, "NOT needs a BOOL or bit-string result, this one is " + m_.type_name(cr_.type));
    Operand d = acc(t);
    typed(Op::TNOT, t, cr_.o, d);
    cr_.o = d;
  }

  // ---- ST's arithmetic on C's int.  MatIEC writes an ST expression as the
  // same C expression (generate_c_base.cc, print_binary_expression), and C
  // computes SINT INT USINT UINT BYTE WORD operands as int: `a * b / c` of
  // INTs divides the whole product, `u - 201 < 0` of a USINT 200 is TRUE,
  // `NOT w` of a WORD is negative; the value is cut to its type where it is
  // stored or passed to a function or block (a function's result is of its
  // type).  So from ST, an operator on one of those types computes in DINT
  // (C's int on every target MatIEC runs) and the CR remembers the type it
  // stands for (Cr::narrow); IL keeps IEC's one type per result.
  bool c_int_type(TypeId t) const {
    if (!from_st_ || t == kNoType || m_.type(t).kind == TypeKind::Enum) return false;
    Ty st = ty_of(t);
    return st == Ty::SINT || st == Ty::INT || st == Ty::USINT || st == Ty::UINT || st == Ty::BYTE || st == Ty::WORD;
  }
  bool c_int_cr() const { return cr_.defined && !cr_.lit && (cr_.narrow != kNoType || c_int_type(cr_.type)); }
  static bool c_int_op(const std::string& u) {
    static const std::set<std::string> k = {"ADD", "SUB", "MUL", "DIV", "MOD", "GT", "GE", "EQ", "NE", "LT", "LE",
                                            "AND", "ANDN", "OR", "ORN", "XOR", "XORN", "NOT", "NEG"};
    return k.count(u) > 0;
  }
  // an operand of narrow type t as C's int
  Operand widen(const Operand& o, Ty t) {
    if (o.kind == OpdKind::ConstT) return Operand::typed_const(typed::conv(Ty::DINT, t, o.bits()));
    Operand d = scratch("cint" + std::to_string(paren_base_ + int(parens_.size())), Ty::DINT);
    typed(Op::TCONV, Ty::DINT, o, d, {}, t);
    return d;
  }
  // Where the CR's C arithmetic begins: before an operation's first code.
  void mark_promotion() {
    if (cr_.narrow != kNoType) return;
    ensure_rung();
    cr_.promo_rung = p_.rungs.size() - 1, cr_.promo_at = rung_->code.size();
  }
  void promote_cr() {
    if (cr_.narrow != kNoType) return;
    Ty t = ty_of(cr_.type);
    Operand d = acc(Ty::DINT);
    if (cr_.o.kind == OpdKind::ConstT) d = widen(cr_.o, t);
    else typed(Op::TCONV, Ty::DINT, cr_.o, d, {}, t);
    cr_.narrow = cr_.type, cr_.type = m_.elem(Ty::DINT), cr_.o = d;
  }
  // the CR cut to the type it stands for
  void demote() {
    if (cr_.narrow == kNoType) return;
    if (narrow_back()) return;
    Ty t = ty_of(cr_.narrow);
    Operand d = acc(t);
    typed(Op::TCONV, t, cr_.o, d, {}, Ty::DINT);
    cr_.type = cr_.narrow, cr_.narrow = kNoType, cr_.o = d;
  }
  // ADD SUB MUL NEG and the bit logic give the same bits of the narrow type
  // on int as on the type itself (arithmetic modulo 2^n): a CR computed by
  // them alone from the narrow operands, cut now, is computed in its own type
  // instead, with no conversion (`x := a + 1` of INTs stays ADD.INT).  Only
  // the CR's own code since its promotion, in its rung, is rewritten.
  bool narrow_back() {
    if (!rung_ || cr_.promo_rung != p_.rungs.size() - 1 || cr_.promo_at > rung_->code.size()) return false;
    std::vector<Instr>& code = rung_->code;
    Ty t = ty_of(cr_.narrow);
    auto ring = [](const Instr& in) {
      if (in.ty == Ty::DINT) return in.op == Op::TADD || in.op == Op::TSUB || in.op == Op::TMUL || in.op == Op::TNEG;
      return in.ty == Ty::DWORD && (in.op == Op::TAND || in.op == Op::TOR || in.op == Op::TXOR || in.op == Op::TNOT);
    };
    for (size_t i = cr_.promo_at; i < code.size(); i++) {
      const Instr& in = code[i];
      bool widen = in.op == Op::TCONV && in.ty == Ty::DINT && in.src == t;
      if (!widen && !ring(in)) return false;
    }
    std::vector<std::pair<Operand, Operand>> was;  // a widened cell and its narrow source
    auto source = [&](const Operand& o) {
      if (o.kind == OpdKind::ConstT) return Operand::typed_const(typed::norm(t, o.bits()));
      for (const auto& [cell, src] : was)
        if (cell == o) return src;
      return o;
    };
    std::vector<Instr> out;
    for (size_t i = cr_.promo_at; i < code.size(); i++) {
      Instr in = code[i];
      if (in.op == Op::TCONV) {
        std::erase_if(was, [&](const auto& w) { return w.first == in.a[1]; });
        was.push_back({in.a[1], source(in.a[0])});
        continue;
      }
      int n = in.nopd();
      for (int k = 0; k + 1 < n; k++) in.a[k] = source(in.a[k]);
      std::erase_if(was, [&](const auto& w) { return w.first == in.a[n - 1]; });
      in.ty = t;
      out.push_back(in);
    }
    if (out.empty()) return false;  // the CR was only widened: a cut is a move
    for (const Instr& in : out)
      if (!op_takes(in.op, t, Ty::None)) return false;
    code.resize(cr_.promo_at);
    code.insert(code.end(), out.begin(), out.end());
    cr_.type = cr_.narrow, cr_.narrow = kNoType, cr_.o = out.back().a[out.back().nopd() - 1];
    return true;
  }
  // v cut to the type it stands for, into a place of its own (key: the operand's)
  Val demoted(const Val& v, const std::string& key) {
    if (v.narrow == kNoType) return v;
    Ty t = ty_of(v.narrow);
    Operand d = scratch("cut." + key, t);
    typed(Op::TCONV, t, load(v.ref, "cut"), d, {}, Ty::DINT);
    return cell_val(v.narrow, d);
  }
  // CR := CR op v on C's int, where ST's C computes it so; false: not such an operation
  bool c_int_binary(const Tok& op, const std::string& u, const Val& v, const Tok& k) {
    if (!from_st_ || !c_int_op(u) || u == "NOT" || u == "NEG") return false;
    if (cr_.lit) {
      TypeId vt = v.narrow != kNoType ? v.narrow : val_type(v);
      if (vt == kNoType || !m_.type(vt).scalar()) return false;
      type_cr(vt, op);
    }
    TypeId t = cr_.narrow != kNoType ? cr_.narrow : cr_.type;
    bool bitwise = u.rfind("AND", 0) == 0 || u.rfind("OR", 0) == 0 || u.rfind("XOR", 0) == 0;
    // Of two values that are their type's own (not yet C's int), AND OR XOR,
    // the compares and MOD are the same either way, and so is DIV but for a
    // signed type's least value by -1 (its quotient is one past the type)
    bool exact = cr_.narrow == kNoType && v.narrow == kNoType;
    bool same = bitwise || u == "MOD" || (u != "ADD" && u != "SUB" && u != "MUL" && u != "DIV") ||
                (u == "DIV" && !typed::is_signed(ty_of(t)));
    if (!c_int_type(t) || (exact && same)) return false;
    mark_promotion();
    Operand b;
    if (v.narrow != kNoType) {
      if (!m_.same_type(v.narrow, t))
        fail(k, std::string(op.text) + " of " + a_type(t) + " and '" + k.text + "', " + a_type(v.narrow) + ": convert it first (" +
                    m_.type_name(v.narrow) + "_TO_" + m_.type_name(t) + ")");
      b = load(v.ref, "b");
    } else {
      b = widen(value_as(v, t, k, "b", op.text.c_str()), ty_of(t));
    }
    promote_cr();
    bool neg = u == "ANDN" || u == "ORN" || u == "XORN";
    const Op o = typed_binary_op(neg ? u.substr(0, u.size() - 1) : u);
    if (bitwise) {  // C's & | ^ of ints: the bits of the DINTs, as DWORDs
      if (b.kind == OpdKind::ConstT) b = Operand::typed_const(typed::norm(Ty::DWORD, b.bits()));
      if (neg) {
        Operand nb = scratch("nb", Ty::DWORD);
        typed(Op::TNOT, Ty::DWORD, b, nb);
        b = nb;
      }
      Operand d = acc(Ty::DINT);
      typed(o, Ty::DWORD, cr_.o, b, d);
      cr_.o = d;
      return true;
    }
    apply(op, o, b, neg);
    return true;
  }
  // the typed instruction of a binary IL operator (ANDN ORN XORN: their base)
  static Op typed_binary_op(const std::string& base) {
    static const std::map<std::string, Op> ops = {
        {"AND", Op::TAND}, {"OR", Op::TOR}, {"XOR", Op::TXOR}, {"ADD", Op::TADD}, {"SUB", Op::TSUB}, {"MUL", Op::TMUL},
        {"DIV", Op::TDIV}, {"MOD", Op::TMOD}, {"EXPT", Op::TEXPT}, {"GT", Op::TGT}, {"GE", Op::TGE}, {"EQ", Op::TEQ},
        {"NE", Op::TNE}, {"LT", Op::TLT}, {"LE", Op::TLE}};
    return ops.at(base);
  }

  // The binary operators: CR := CR op v
  void binary(const Tok& op, const std::string& u, const Val& v_in, const Tok& k) {
    if (cr_whole()) fail(op, "'" + op.text + "' of " + a_type(cr_.type));
    if (c_int_binary(op, u, v_in, k)) return;
    if (cr_.narrow != kNoType) demote();
    const Val v = demoted(v_in, "b");
    bool shift = u == "SHL" || u == "SHR" || u == "ROL" || u == "ROR";
    if (cr_.lit) {
      TypeId vt = val_type(v);
      if (vt != kNoType && !shift && m_.type(vt).scalar()) type_cr(vt, op);
      else default_cr(op);
    }
    TypeId t = cr_.type;
    Ty st = ty_of(t);
    if (shift) {
      TypeId nt = val_type(v);
      Ty nst = nt == kNoType ? Ty::INT : ty_of(nt);
      Operand n = v.kind == Val::Lit && nt == kNoType ? value_as(v, m_.elem(Ty::INT), k, "b", op.text.c_str()) : value_as(v, nt, k, "b", op.text.c_str());
      if (ty_info(st).kind != TyKind::Bits) fail(op, op.text + " works on bit strings (BYTE WORD DWORD LWORD), this result is " + m_.type_name(t));
      if (!typed::is_int_kind(nst) || ty_info(nst).kind == TyKind::Time || ty_info(nst).kind == TyKind::Date)
        fail(k, "a shift count is an integer, '" + k.text + "' is not one");
      Op o = u == "SHL" ? Op::TSHL : u == "SHR" ? Op::TSHR : u == "ROL" ? Op::TROL : Op::TROR;
      Operand d = acc(st);
      typed(o, st, cr_.o, n, d, nst);
      cr_.o = d;
      return;
    }
    if ((u == "MUL" || u == "DIV") && st == Ty::TIME) {  // MatIEC's MUL / DIV of (TIME, ANY_NUM)
      const TypeId vt = val_type(v);
      if (vt == kNoType || (m_.type(vt).scalar() && any_num(ty_of(vt)))) return time_scale(op, u == "MUL", Ty::None, v, k);
    }
    bool neg = u == "ANDN" || u == "ORN" || u == "XORN";
    std::string base = neg ? u.substr(0, u.size() - 1) : u;
    if (u == "EXPT" && v.kind == Val::Ref_ && typed::is_real(st) && ty_of(v.ref.type) != st && typed::is_int_kind(ty_of(v.ref.type))) {
      // REAL ** ANY_INT (MatIEC's EXPT takes an integer exponent too): the exponent converted first
      Operand e = scratch("expt", st);
      typed(Op::TCONV, st, load(v.ref, "b"), e, {}, ty_of(v.ref.type));
      Operand d = acc(st);
      typed(Op::TEXPT, st, cr_.o, e, d);
      cr_.o = d;
      return;
    }
    Operand b = value_as(v, t, k, "b", op.text.c_str());
    apply(op, typed_binary_op(base), b, neg);
  }
  // CR := CR o b (b already an operand of the CR's type); a compare gives a BOOL
  void apply(const Tok& op, Op o, Operand b, bool neg_b) {
    Ty st = cr_ty();
    if (!op_takes(o, st, Ty::None))
      fail(op, "'" + op.text + "' does not take " + a_type(cr_.type) + (o == Op::TMOD ? " (MOD is for integers)" : ""));
    if (neg_b) {
      Operand nb = scratch("nb", st);
      typed(Op::TNOT, st, b, nb);
      b = nb;
    }
    if (op_info(o).push) {  // a compare pushes its result: keep it in a BOOL accumulator
      Operand d = acc(Ty::BOOL);
      typed(o, st, cr_.o, b);
      emit(Op::OUT, d);
      emit(Op::MPP);
      set_cr(m_.elem(Ty::BOOL), d);
      return;
    }
    Operand d = acc(st);
    bool error = false;
    (void)error;
    typed(o, st, cr_.o, b, d);
    cr_.o = d;
  }

  void open_paren(const Tok& op, const std::string& u) {
    need_cr(op);
    if (!binary_op(u) || u == "SHL" || u == "SHR" || u == "ROL" || u == "ROR")
      fail(op, "'" + op.text + "(' is not supported: parentheses follow AND OR XOR (N), ADD SUB MUL DIV MOD EXPT and the compares");
    if (int(parens_.size()) >= kMaxParens) fail(op, "parentheses nested deeper than " + std::to_string(kMaxParens));
    if (cr_whole()) fail(op, "'" + op.text + "' of " + a_type(cr_.type));
    Cr saved = cr_;
    if (!saved.lit) {  // the CR is kept in a temporary of this depth: the group may overwrite what it names
      Ty t = cr_ty();
      Operand tmp = scratch("paren" + std::to_string(paren_base_ + int(parens_.size())), t);
      typed(Op::TMOVE, t, cr_.o, tmp);
      saved.o = tmp;
    }
    parens_.push_back({u, saved, here_, op});
    cr_ = Cr{};
    if (peek().kind == Tok::Word) {
      Tok k = peek();
      Val v = operand("p", true);
      load_val(op, false, v, k);
      // a number in the group takes the outer type (ADD( 5 ...), but not
      // in a BOOL group, where it is compared first (AND( 5 GT x ))
      if (!saved.lit && cr_.lit && ty_of(saved.type) != Ty::BOOL) type_cr(saved.type, k);
    } else {  // "ADD(" alone: the next line is LD x
      end_line();
      skip_eols();
      const Tok& ld = next();
      if (!kw(ld, "LD") && !kw(ld, "LDN")) fail(ld, "after '" + op.text + "(' comes its first operand, or LD/LDN on the next line");
      here_ = loc(ld);
      Tok k = peek();
      Val v = operand("p", true);
      load_val(ld, kw(ld, "LDN"), v, k);
    }
  }
  void close_paren(const Tok& k) {
    if (parens_.empty()) fail(k, "')' without '('");
    need_cr(k);
    Paren pr = parens_.back();
    parens_.pop_back();
    Cr inner = cr_;
    cr_ = pr.saved;
    // the group's value as the right operand
    Val v;
    if (inner.lit) {
      v.lit = *inner.lit;
    } else {
      if (!m_.type(inner.type).scalar()) fail(k, "a group of " + a_type(inner.type));
      // move the inner value out of the accumulator of the outer depth, which apply writes
      Operand tmp = scratch("rparen" + std::to_string(paren_base_ + int(parens_.size())), ty_of(inner.type));
      typed(Op::TMOVE, ty_of(inner.type), inner.o, tmp);
      v = cell_val(inner.type, tmp, inner.narrow);
    }
    binary(pr.tok, pr.op, v, k);
  }

  // ST's AND / OR whose right side may fault (frontend/st, short_circuit):
  // on a BOOL CR, C's && and || -- jump past the right side where the CR
  // decides (AND: FALSE, OR: TRUE); on a bit string, C's & and |, nothing.
  void short_circuit(const Tok& op, bool and_then) {
    need_cr(op);
    if (!cr_.lit && cr_ty() == Ty::BOOL) return jump(op, and_then ? "JMPCN" : "JMPC");
    next();  // the label: both sides are computed
  }
  void jump(const Tok& op, const std::string& u) {
    const Tok& k = next();
    if (k.kind != Tok::Word || !ident(k.text)) fail(k, "expected a label name" + found(k));
    if (!parens_.empty()) fail(op, "a jump inside parentheses");
    std::string target = scope_->prefix + k.text;
    // to a label already placed: a loop, the IL's LOOP (docs/il.md "Loops")
    auto go = [&](Cr at_target) {
      if (!labels_.count(target)) {
        jump_to(target);
        cr_jumps_[target].push_back({p_.rungs.size() - 1, rung_->code.size() - 1, at_target});
        return;
      }
      carry_back(target, at_target, op);
      Operand o{OpdKind::Label};
      o.label = target;
      emit(Op::LOOP, o);
    };
    // taken, JMPC's CR is TRUE and JMPCN's FALSE
    auto known = [&](bool v) { return Cr{true, m_.elem(Ty::BOOL), Operand::typed_const(v ? 1 : 0), {}}; };
    if (u == "JMP") {
      ensure_rung();
      go(cr_);
      rung_ = nullptr;
      cr_ = Cr{};
      dead_ = true;
      return;
    }
    need_bool(op);
    if (fuse_compare(u == "JMPC")) {
      go(known(u == "JMPC"));
      emit(Op::MPP);
      return;
    }
    emit(u == "JMPC" ? Op::LOAD : Op::LOADN, cr_bit());
    go(known(u == "JMPC"));
    emit(Op::MPP);
  }
  // A conditional jump or return right after the compare that made the CR
  // (`GT.DINT a b  OUT acc  MPP`, apply): the compare's push is the jump's
  // condition, negated for JMPCN / RETCN (exact but on REAL and LREAL, where
  // NOT (a <= b) also holds for a NaN: those keep the accumulator), and the
  // accumulator is not written.  Where the jump is not taken the CR is known
  // -- FALSE after JMPC, TRUE after JMPCN -- and so it becomes that constant.
  // Leaves the compare's push for the jump (true), or changes nothing.
  bool fuse_compare(bool when_true) {
    if (!rung_ || rung_->code.size() < 3) return false;
    std::vector<Instr>& c = rung_->code;
    Instr& cmp = c[c.size() - 3];
    const Instr &out = c[c.size() - 2], &mpp = c.back();
    const OpInfo& oi = op_info(cmp.op);
    if (!(oi.klass == OpClass::Typed && oi.push == 1) || out.op != Op::OUT || mpp.op != Op::MPP || !(out.a[0] == cr_.o))
      return false;
    if (!when_true) {
      if (typed::is_real(cmp.ty)) return false;
      static const Op kByRel[] = {Op::TEQ, Op::TNE, Op::TLT, Op::TLE, Op::TGT, Op::TGE};  // ops.def's REL order
      cmp.op = kByRel[int(negate(oi.rel))];
    }
    c.pop_back(), c.pop_back();
    depth_ += 1;  // the OUT left the stack alone; the MPP's pop is undone
    cr_.o = Operand::typed_const(when_true ? 0 : 1);
    return true;
  }

  // LOOP label (ST's loops only, frontend/st): the back edge to a label
  // already placed (docs/il.md "Loops"), taken always
  void loop(const Tok& op) {
    const Tok& k = next();
    std::string target = scope_->prefix + k.text;
    if (!labels_.count(target)) fail(op, "LOOP to a label not placed before it");
    ensure_rung();
    Operand o{OpdKind::Label};
    o.label = target;
    emit(Op::LOOP, o);
    rung_ = nullptr;
    cr_ = Cr{};
  }

  void ret(const Tok& op, const std::string& u) {
    if (!parens_.empty()) fail(op, "a return inside parentheses");
    auto leave = [&] {
      if (scope_->end_label.empty()) emit(Op::END);
      else jump_to(scope_->end_label);
    };
    if (u == "RET") {
      ensure_rung();
      leave();
      rung_ = nullptr;
      cr_ = Cr{};
      return;
    }
    need_bool(op);
    if (!fuse_compare(u == "RETC")) emit(u == "RETC" ? Op::LOAD : Op::LOADN, cr_bit());
    leave();
    emit(Op::MPP);
  }

  // ---- calls of the project's POUs, expanded inline

  // CAL inst [ "(" [ arg { "," arg } ] ")" ]; arg = NAME ":=" operand | NAME "=>" variable
  void call(const Tok& op, const std::string& u) {
    if (!parens_.empty()) fail(op, "CAL inside parentheses");
    const Tok& k = peek();
    if (k.kind != Tok::Word) fail(k, "'" + op.text + "' needs an instance" + found(k));
    Val iv = operand("cal");
    bool bistable = iv.kind == Val::Ref_ && bistables_.count(iv.ref.type);
    if (iv.kind != Val::Ref_ || (m_.type(iv.ref.type).kind != TypeKind::Block && !bistable))
      fail(k, "'" + k.text + "' is not an instance of a FUNCTION_BLOCK");
    if (!iv.ref.direct() && iv.ref.steps.size() > 1)
      fail(k, "an instance chosen by more than one variable index (fbs[i, j], fbs[i].inner[j]): ldc calls instances chosen by one (docs/iec-il.md)");
    std::string skip;
    if (u != "CAL") {  // CALC / CALCN: the call runs only if the CR is (not) TRUE
      need_bool(op);
      skip = "_ldc_call" + std::to_string(copies_) + "_" + std::to_string(++skips_);
      emit(u == "CALC" ? Op::LOADN : Op::LOAD, cr_bit());
      jump_to(skip);
      emit(Op::MPP);
    }
    int pou = m_.type(iv.ref.type).pou;
    std::vector<std::pair<Tok, Val>> in;
    std::vector<std::pair<Tok, size_t>> out;
    if (punct(peek(), "(")) {
      next();
      std::vector<Param> params = bistable ? std_params(bistables_.at(iv.ref.type)) : pou_params(m_.pous[size_t(pou)]);
      args(in, out, &params, k.text);
    }
    auto one = [&](const model::Ref& r) {
      if (bistable) std_call(bistables_.at(iv.ref.type), r, in, out, en_called_.count(upper(k.text)) > 0);
      else expand(pou, r, in, out, op);
    };
    if (iv.ref.direct()) one(iv.ref);
    else dispatch(iv.ref, k, one);
    if (!skip.empty()) label_here(skip);
    cr_ = Cr{};  // the CR is undefined after a call
  }
  // An instance chosen by a variable index (fbs[i](...)): the index checked as
  // any index is (its fault names it), then the call expanded once per
  // element, each run when the index is that element's (docs/iec-il.md).
  static constexpr uint32_t kMaxDispatch = 256;
  template <class Call>
  void dispatch(const model::Ref& r, const Tok& at, const Call& one) {
    const IndexStep& s = r.steps[0];
    if (s.dim.count() > kMaxDispatch)
      fail(at, "a call of one of " + std::to_string(s.dim.count()) + " instances chosen by a variable index: ldc expands the call once per instance, at most " +
                   std::to_string(kMaxDispatch));
    ensure_rung();
    Operand idx = scratch("calidx" + std::to_string(++skips_), s.index_ty), tmp = scratch("xtmp", Ty::DINT);
    typed(Op::TMOVE, s.index_ty, s.index, idx);  // the body may change the variable: the index as it was
    typed(Op::TIDX, s.index_ty, idx, Operand::typed_const(uint64_t(int64_t(s.dim.lo))), Operand::typed_const(uint64_t(int64_t(s.dim.hi))));
    fix_k(rung_->code.back());
    typed(Op::TLDX, Ty::DINT, tmp, k_const(0), tmp);  // the check alone: stride 0 reads tmp back
    fix_k(rung_->code.back());
    for (uint32_t e = 0; e < s.dim.count(); e++) {
      std::string next_el = "_ldc_cal" + std::to_string(copies_) + "_" + std::to_string(++skips_);
      ensure_rung();
      typed(Op::TNE, s.index_ty, idx, Operand::typed_const(uint64_t(int64_t(s.dim.lo) + e)));
      jump_to(next_el);
      emit(Op::MPP);
      model::Ref el = r;
      el.steps.clear();
      el.at = r.at + s.stride * e;
      one(el);
      label_here(next_el);
    }
  }
  int skips_ = 0;
  // A block's parameters in their declared order, as MatIEC's
  // function_param_iterator takes them for a non-formal call: the inputs,
  // outputs, in-outs and externals as written (EN and ENO, implicit, left out).
  struct Param {
    std::string name;
    VarClass cls;
  };
  static std::vector<Param> pou_params(const Pou& p) {
    std::vector<Param> r;
    for (const Var& v : p.vars)
      if (v.cls == VarClass::Input || v.cls == VarClass::Output || v.cls == VarClass::InOut || v.cls == VarClass::External)
        r.push_back({v.name, v.cls});
    return r;
  }
  static std::vector<Param> std_params(const std::string& kind) {
    const StdFb& fb = std_fbs().at(kind);
    std::vector<Param> r;
    for (size_t i = 0; i < fb.inputs + fb.outputs; i++)
      r.push_back({fb.vars[i].first, i < fb.inputs ? VarClass::Input : VarClass::Output});
    return r;
  }
  // arg = NAME ":=" operand | NAME "=>" variable | operand.  Operands alone
  // (a non-formal call of an instance, `CAL t(x, T#1s, done)`) go to `params`
  // in order, as MatIEC's generated C assigns them: an input or in-out takes
  // the value, an output's variable takes the output after the call.  A call
  // is all formal or all non-formal, as MatIEC's grammar has it.
  void args(std::vector<std::pair<Tok, Val>>& in, std::vector<std::pair<Tok, size_t>>& out,
            const std::vector<Param>* params = nullptr, const std::string& callee = "") {
    skip_eols();
    size_t positional = 0, named = 0;
    while (!punct(peek(), ")")) {
      skip_eols();
      size_t ahead = 1;
      while (peek(ahead).kind == Tok::Eol) ahead++;
      if (params && !(peek().kind == Tok::Word && (punct(peek(ahead), ":=") || punct(peek(ahead), "=>")))) {
        if (named) fail(peek(), "a call mixes formal (NAME := x) and non-formal arguments");
        non_formal(in, out, *params, positional++, callee);
        skip_eols();
        if (punct(peek(), ",")) { next(); skip_eols(); continue; }
        if (!punct(peek(), ")")) fail(peek(), "expected ',' or ')'" + found(peek()));
        continue;
      }
      if (positional) fail(peek(), "a call mixes formal (NAME := x) and non-formal arguments");
      named++;
      const Tok& n = name_tok("a parameter name");
      skip_eols();
      if (punct(peek(), ":=")) {
        next();
        Tok vk = peek();
        in.push_back({n, operand("arg" + std::to_string(in.size()))});
        (void)vk;
      } else if (punct(peek(), "=>")) {
        next();
        skip_eols();
        out.push_back({n, pos_});
        skip_path();  // read in the caller's scope after the call
      } else {
        fail(peek(), "expected ':=' or '=>' after the parameter name" + found(peek()));
      }
      skip_eols();
      if (punct(peek(), ",")) { next(); skip_eols(); continue; }
      if (!punct(peek(), ")")) fail(peek(), "expected ',' or ')'" + found(peek()));
    }
    next();
  }
  // The k-th argument of a non-formal call, bound to the k-th parameter.
  void non_formal(std::vector<std::pair<Tok, Val>>& in, std::vector<std::pair<Tok, size_t>>& out,
                  const std::vector<Param>& params, size_t k, const std::string& callee) {
    Tok at = peek();
    if (k >= params.size())
    {
      std::string names;
      for (const Param& q : params) names += (names.empty() ? "" : ", ") + q.name;
      fail(at, "'" + callee + "' is called with more than its " + std::to_string(params.size()) + " parameters (" + names + ")");
    }
    const Param& p = params[k];
    at.text = p.name;  // the argument stands for its parameter by name from here on
    if (p.cls == VarClass::External)
      fail(peek(), "argument " + std::to_string(k + 1) + " of '" + callee + "' falls on its VAR_EXTERNAL '" + p.name +
                       "', which takes no argument: name the parameters (NAME := x)");
    if (p.cls != VarClass::Output) {
      in.push_back({at, operand("arg" + std::to_string(in.size()))});
      return;
    }
    const Tok& v = peek();
    std::string why;
    if (v.kind != Tok::Word || st_temp(v.text) || parse_literal(v.text, why))
      fail(v, "argument " + std::to_string(k + 1) + " of '" + callee + "' is its output '" + p.name + "': it needs a variable");
    out.push_back({at, pos_});
    skip_path();  // read in the caller's scope after the call
  }
  // The token position of an output argument's variable, to read it again in the caller's scope.
  void expand(int pou, const model::Ref& inst, const std::vector<std::pair<Tok, Val>>& in,
              const std::vector<std::pair<Tok, size_t>>& out, const Tok& at) {
    Model::expand_guard(m_, expanding_, pou, loc(at));
    const Pou& p = m_.pous[size_t(pou)];
    const Type& block = m_.type(p.block);
    Scope s;
    s.pou = pou;
    s.prefix = "_ldc_" + std::to_string(++copies_) + "_";
    s.end_label = s.prefix + "end";
    // the instance's names: its variables at their places, externals the program's globals
    for (size_t i = 0; i < p.vars.size(); i++) {
      const Var& v = p.vars[i];
      const Member& mb = block.members[i];
      if (v.cls == VarClass::External) {
        auto g = globals_.find(upper(v.name));
        if (g == globals_.end()) fail(v.loc, "VAR_EXTERNAL '" + v.name + "' of " + p.name + " is not a VAR_GLOBAL of the program");
        if (g->second.type != v.type && !m_.same_type(g->second.type, v.type))
          fail(v.loc, "VAR_EXTERNAL '" + v.name + "' is " + a_type(v.type) + ", the global " + a_type(g->second.type));
        s.names[upper(v.name)] = g->second;
        continue;
      }
      if (v.cls == VarClass::InOut) continue;  // bound below
      model::Ref r;
      r.type = v.type;
      r.at = inst.at + mb.offset;
      r.writable = !v.constant;
      s.names[upper(v.name)] = r;
    }
    if (p.kind == PouKind::Function) {
      model::Ref r;
      r.type = p.result;
      r.at = inst.at + block.members.back().offset;
      s.names[upper(p.name)] = r;
    }
    // inputs (in the caller's scope), in-outs bound to the caller's variables
    ensure_rung();
    // VAR_TEMP (and all of a FUNCTION's variables: an input left out too, EN
    // TRUE) start from their initial values at every call, before the inputs
    std::vector<Model::Store> stores;
    for (size_t i = 0; i < p.vars.size(); i++) {
      const Var& v = p.vars[i];
      bool fresh = v.cls == VarClass::Temp ||
                   (p.kind == PouKind::Function && v.cls != VarClass::InOut && v.cls != VarClass::External);
      if (fresh) m_.initial_stores(v.type, inst.at + block.members[i].offset, v.init.kind == Init::None ? nullptr : &v.init, stores, true);
    }
    if (p.kind == PouKind::Function) m_.initial_stores(p.result, inst.at + block.members.back().offset, nullptr, stores, true);
    for (const auto& st : stores) typed(Op::TMOVE, st.ty, Operand::typed_const(st.bits), operand_at(st.ty, st.at));
    for (const auto& [n, v] : in) {
      int i = var_index(p, n.text);
      if (i < 0 || (p.vars[size_t(i)].cls != VarClass::Input && p.vars[size_t(i)].cls != VarClass::InOut))
        fail(n, p.name + " has no input '" + n.text + "'" + inputs_of(p));
      const Var& var = p.vars[size_t(i)];
      if (var.cls == VarClass::InOut) {
        if (v.kind != Val::Ref_ || !v.ref.direct()) fail(n, "VAR_IN_OUT " + n.text + " needs a variable (not a constant or an element at a variable index)");
        if (v.ref.type != var.type && !m_.same_type(v.ref.type, var.type))
          fail(n, "VAR_IN_OUT " + n.text + " is " + a_type(var.type) + ", the argument " + a_type(v.ref.type));
        s.names[upper(var.name)] = v.ref;
        continue;
      }
      model::Ref dst = s.names.at(upper(var.name));
      if (!m_.type(var.type).scalar()) {
        if (v.kind != Val::Ref_ || v.ref.type != var.type) fail(n, "input " + n.text + " is " + a_type(var.type));
        copy_value(var.type, v.ref, dst, n);
        continue;
      }
      dst.writable = true;
      store(dst, value_as(v, var.type, n, "arg", "the input"), n);
    }
    for (const Var& v : p.vars)
      if (v.cls == VarClass::InOut && !s.names.count(upper(v.name)))
        fail(at, "the call of " + p.name + " needs VAR_IN_OUT " + v.name + " :=");
    // EN and ENO (MatIEC: ENO := EN; without EN the body is skipped)
    Operand en = operand_of(m_, s.names.at("EN")), eno = operand_of(m_, s.names.at("ENO"));
    typed(Op::TMOVE, Ty::BOOL, en, eno);
    emit(Op::LOADN, en);
    jump_to(s.end_label);
    emit(Op::MPP);
    // the body
    Scope* caller = scope_;
    Cr caller_cr = cr_;
    auto caller_parens = std::move(parens_);
    parens_.clear();
    int base = paren_base_;
    paren_base_ += int(caller_parens.size()) + 1;
    // the caller's scope is back however the body ends: an error of the body
    // thrown out of it is the calling line's, which error recovery goes on after
    struct Back {
      Reader& r;
      Scope* scope;
      int base;
      size_t expanding;
      ~Back() { r.scope_ = scope, r.paren_base_ = base, r.expanding_.resize(expanding); }
    } back{*this, caller, base, expanding_.size()};
    expanding_.push_back(pou);
    scope_ = &s;
    SrcLoc call_at = here_;
    lower_body(pou);
    expanding_.pop_back();
    scope_ = caller;
    paren_base_ = base;
    parens_ = std::move(caller_parens);
    cr_ = caller_cr;
    here_ = call_at;
    label_here(s.end_label);
    labels_.insert(s.end_label);
    // outputs, in the caller's scope
    for (const auto& [n, vt] : out) {
      int i = var_index(p, n.text);
      if (i < 0 || p.vars[size_t(i)].cls != VarClass::Output) fail(n, p.name + " has no output '" + n.text + "'");
      size_t save = pos_;
      pos_ = vt;
      Tok k = peek();
      Val v = operand("out");
      pos_ = save;
      if (v.kind != Val::Ref_) fail(k, "an output goes to a variable, '" + k.text + "' is not one");
      const Var& var = p.vars[size_t(i)];
      model::Ref src;
      src.type = var.type;
      src.at = inst.at + block.members[size_t(i)].offset;
      if (v.ref.type != var.type && !m_.same_type(v.ref.type, var.type))
        fail(k, "output " + n.text + " is " + a_type(var.type) + ", '" + k.text + "' " + a_type(v.ref.type));
      copy_value(var.type, src, v.ref, k);
    }
  }
  // The standard blocks as MatIEC computes them (lib/iec_std_FB.h, the C of
  // lib/*.txt), in typed instructions:
  //   R_TRIG  Q := CLK AND NOT M; M := CLK
  //   F_TRIG  Q := NOT CLK AND NOT M; M := NOT CLK
  //   SR      Q1 := S1 OR (NOT R AND Q1)
  //   RS      Q1 := NOT R1 AND (S OR Q1)
  //   SEMA    Q_INTERNAL := CLAIM OR (Q_INTERNAL AND NOT RELEASE); BUSY := Q_INTERNAL
  //   RTC, CTU* CTD* CTUD*: rtc(), counter()
  void std_call(const std::string& kind, const model::Ref& inst, const std::vector<std::pair<Tok, Val>>& in,
                const std::vector<std::pair<Tok, size_t>>& out, bool en_checked) {
    ensure_rung();
    const StdFb& fb = std_fbs().at(kind);
    const size_t ninputs = fb.inputs;
    const Type& t = m_.type(inst.type);
    auto mem = [&](const char* n) { return operand_of(m_, m_.select_member(inst, n, here_)); };
    // EN and ENO, members of every block as MatIEC has them (TRUE at first):
    // with EN FALSE the inputs are set, ENO goes FALSE and the body does not
    // run.  The check is made at the calls of an instance that some call
    // gives an EN (`en_checked`); elsewhere EN stays TRUE and ENO with it.
    for (const auto& [n, v] : in) {
      if (upper(n.text) != "EN") continue;
      store(m_.select_member(inst, "EN", loc(n)), value_as(v, m_.elem(Ty::BOOL), n, "arg", "EN"), n);
    }
    for (const auto& [n, v] : in) {
      if (upper(n.text) == "EN") continue;
      const Member* mb = m_.member(inst.type, n.text);
      if (!mb || size_t(mb - t.members.data()) >= ninputs)
        fail(n, kind + " has no input '" + n.text + "' (" + input_names(t, ninputs) + ")");
      store(m_.select_member(inst, n.text, loc(n)), value_as(v, mb->type, n, "arg", "the input"), n);
    }
    std::string skip;
    if (en_checked) {
      skip = "_ldc_en" + std::to_string(copies_) + "_" + std::to_string(++skips_);
      typed(Op::TMOVE, Ty::BOOL, mem("EN"), mem("ENO"));
      emit(Op::LOADN, mem("EN"));
      jump_to(skip);
      emit(Op::MPP);
    }
    Operand h = scratch("bist", Ty::BOOL), g = scratch("bist2", Ty::BOOL);
    if (kind == "R_TRIG") {
      typed(Op::TNOT, Ty::BOOL, mem("M"), h);
      typed(Op::TAND, Ty::BOOL, mem("CLK"), h, mem("Q"));
      typed(Op::TMOVE, Ty::BOOL, mem("CLK"), mem("M"));
    } else if (kind == "F_TRIG") {
      typed(Op::TOR, Ty::BOOL, mem("CLK"), mem("M"), h);
      typed(Op::TNOT, Ty::BOOL, h, mem("Q"));
      typed(Op::TNOT, Ty::BOOL, mem("CLK"), mem("M"));
    } else if (kind == "SR") {
      typed(Op::TNOT, Ty::BOOL, mem("R"), h);
      typed(Op::TAND, Ty::BOOL, h, mem("Q1"), h);
      typed(Op::TOR, Ty::BOOL, mem("S1"), h, mem("Q1"));
    } else if (kind == "RS") {
      typed(Op::TOR, Ty::BOOL, mem("S"), mem("Q1"), h);
      typed(Op::TNOT, Ty::BOOL, mem("R1"), g);
      typed(Op::TAND, Ty::BOOL, g, h, mem("Q1"));
    } else if (kind == "SEMA") {
      typed(Op::TNOT, Ty::BOOL, mem("RELEASE"), h);
      typed(Op::TAND, Ty::BOOL, mem("Q_INTERNAL"), h, h);
      typed(Op::TOR, Ty::BOOL, mem("CLAIM"), h, mem("Q_INTERNAL"));
      typed(Op::TMOVE, Ty::BOOL, mem("Q_INTERNAL"), mem("BUSY"));
    } else if (kind == "RTC") {
      rtc(mem);
    } else if (kind.rfind("CT", 0) == 0) {
      counter(kind, fb.vars[ninputs - 1].second, mem);
    } else {
      timer(kind, inst, mem);
    }
    if (en_checked) label_here(skip);
    for (const auto& [n, at] : out) {
      const Member* mb = m_.member(inst.type, n.text);
      size_t i = mb ? size_t(mb - t.members.data()) : 0;
      if (!mb || ((i < ninputs || i >= ninputs + fb.outputs) && upper(n.text) != "ENO"))
        fail(n, kind + " has no output '" + n.text + "'");
      TypeId mt = mb->type;
      size_t save = pos_;
      pos_ = at;
      Tok k = peek();
      Val v = operand("out");
      pos_ = save;
      if (v.kind != Val::Ref_) fail(k, "an output goes to a variable, '" + k.text + "' is not one");
      if (!m_.same_type(v.ref.type, mt)) fail(k, "output " + n.text + " is " + a_type(mt) + ", '" + k.text + "' " + a_type(v.ref.type));
      copy_value(mt, m_.select_member(inst, n.text, loc(n)), v.ref, k);
    }
  }
  // `edge` := clk AND NOT mem; mem := clk (the R_TRIG a MatIEC counter calls first)
  template <class Mem>
  Operand rising(Mem mem, const char* clk, const char* memory, const char* key) {
    Operand e = scratch(key, Ty::BOOL);
    typed(Op::TNOT, Ty::BOOL, mem(memory), e);
    typed(Op::TAND, Ty::BOOL, mem(clk), e, e);
    typed(Op::TMOVE, Ty::BOOL, mem(clk), mem(memory));
    return e;
  }
  // MatIEC's counters (lib/counter.txt), of CV's and PV's type t:
  //   CTU   CU_T(CU); IF R THEN CV := 0 ELSIF CU_T.Q AND (CV < PV) THEN CV := CV+1 END_IF; Q := CV >= PV
  //   CTD   CD_T(CD); IF LD THEN CV := PV ELSIF CD_T.Q AND (CV > 0) THEN CV := CV-1 END_IF; Q := CV <= 0
  //   CTUD  CD_T(CD); CU_T(CU); IF R THEN CV := 0 ELSIF LD THEN CV := PV
  //         ELSIF NOT (CU_T.Q AND CD_T.Q) THEN (IF CU_T.Q AND CV < PV THEN CV := CV+1
  //         ELSIF CD_T.Q AND CV > 0 THEN CV := CV-1); QU := CV >= PV; QD := CV <= 0
  // so CV stops at PV counting up and at 0 counting down: it never wraps.
  template <class Mem>
  void counter(const std::string& kind, Ty t, Mem mem) {
    const Operand zero = Operand::typed_const(0), one = Operand::typed_const(1);
    bool up = kind.rfind("CTUD", 0) != 0 && kind.rfind("CTU", 0) == 0, down = kind.rfind("CTD", 0) == 0;
    if (up) {
      Operand cu = rising(mem, "CU", "CU_T", "cu_t");
      emit(Op::LOAD, mem("R"));
      typed(Op::TMOVE, t, zero, mem("CV"));
      emit(Op::MPP);
      typed(Op::TLT, t, mem("CV"), mem("PV"));
      emit(Op::AND, cu);
      emit(Op::ANDN, mem("R"));
      typed(Op::TADD, t, mem("CV"), one, mem("CV"));
      emit(Op::MPP);
      typed(Op::TGE, t, mem("CV"), mem("PV"));
      emit(Op::OUT, mem("Q"));
      emit(Op::MPP);
      return;
    }
    if (down) {
      Operand cd = rising(mem, "CD", "CD_T", "cd_t");
      emit(Op::LOAD, mem("LD"));
      typed(Op::TMOVE, t, mem("PV"), mem("CV"));
      emit(Op::MPP);
      typed(Op::TGT, t, mem("CV"), zero);
      emit(Op::AND, cd);
      emit(Op::ANDN, mem("LD"));
      typed(Op::TSUB, t, mem("CV"), one, mem("CV"));
      emit(Op::MPP);
      typed(Op::TLE, t, mem("CV"), zero);
      emit(Op::OUT, mem("Q"));
      emit(Op::MPP);
      return;
    }
    Operand cd = rising(mem, "CD", "CD_T", "cd_t"), cu = rising(mem, "CU", "CU_T", "cu_t");
    emit(Op::LOAD, mem("R"));
    typed(Op::TMOVE, t, zero, mem("CV"));
    emit(Op::MPP);
    emit(Op::LOAD, mem("LD"));
    emit(Op::ANDN, mem("R"));
    typed(Op::TMOVE, t, mem("PV"), mem("CV"));
    emit(Op::MPP);
    // the two branches exclude each other (CU_T.Q and not, CD_T.Q and not), so
    // the second reads CV as the first found it
    typed(Op::TLT, t, mem("CV"), mem("PV"));
    emit(Op::AND, cu);
    emit(Op::ANDN, cd);
    emit(Op::ANDN, mem("R"));
    emit(Op::ANDN, mem("LD"));
    typed(Op::TADD, t, mem("CV"), one, mem("CV"));
    emit(Op::MPP);
    typed(Op::TGT, t, mem("CV"), zero);
    emit(Op::AND, cd);
    emit(Op::ANDN, cu);
    emit(Op::ANDN, mem("R"));
    emit(Op::ANDN, mem("LD"));
    typed(Op::TSUB, t, mem("CV"), one, mem("CV"));
    emit(Op::MPP);
    typed(Op::TGE, t, mem("CV"), mem("PV"));
    emit(Op::OUT, mem("QU"));
    emit(Op::MPP);
    typed(Op::TLE, t, mem("CV"), zero);
    emit(Op::OUT, mem("QD"));
    emit(Op::MPP);
  }
  // MatIEC's RTC (lib/rtc.txt): CURRENT_TIME := the clock;
  //   IF IN THEN (IF NOT PREV_IN THEN OFFSET := PDT - CURRENT_TIME); CDT := CURRENT_TIME + OFFSET
  //   ELSE CDT := CURRENT_TIME; Q := IN; PREV_IN := IN
  // The clock is ldrun's scan clock (clock_rung): DT#1970-01-01-00:00:00 plus
  // the simulated time since the first scan.  DT and TIME are both signed
  // nanoseconds, so __time_sub and __time_add are LINT arithmetic on them.
  template <class Mem>
  void rtc(Mem mem) {
    typed(Op::TMOVE, Ty::DT, clock_cell(), mem("CURRENT_TIME"));
    Operand h = scratch("rtc_rise", Ty::BOOL);
    typed(Op::TNOT, Ty::BOOL, mem("PREV_IN"), h);
    typed(Op::TAND, Ty::BOOL, mem("IN"), h, h);
    emit(Op::LOAD, h);
    typed(Op::TSUB, Ty::LINT, mem("PDT"), mem("CURRENT_TIME"), mem("OFFSET"));
    emit(Op::MPP);
    emit(Op::LOAD, mem("IN"));
    typed(Op::TADD, Ty::LINT, mem("CURRENT_TIME"), mem("OFFSET"), mem("CDT"));
    emit(Op::MPP);
    emit(Op::LOADN, mem("IN"));
    typed(Op::TMOVE, Ty::DT, mem("CURRENT_TIME"), mem("CDT"));
    emit(Op::MPP);
    typed(Op::TMOVE, Ty::BOOL, mem("IN"), mem("Q"));
    typed(Op::TMOVE, Ty::BOOL, mem("IN"), mem("PREV_IN"));
  }
  Operand clock_cell() { return scratch("rtc_clock", Ty::DT); }
  // The scan clock of an RTC, first in the program: a hidden TON that runs
  // every scan (IN always on, its preset the largest) gives this scan's dt in
  // its ET, which is added to the clock (ns) and cleared.  Its first scan is
  // the TON's rising one, ET 0: the clock is 0 on the first scan and then the
  // sum of the dt of the scans after it.
  void clock_rung() {
    if (next_timer_ >= device_count(Dev::T)) fail(here_, "more than " + std::to_string(device_count(Dev::T)) + " timers (RTC's clock takes one)");
    uint32_t n = next_timer_++;
    start_rung();
    Operand pt{OpdKind::ConstInt};
    pt.ival = INT32_MAX;
    emit(Op::TON, Operand{OpdKind::Timer, Area::Sys, n}, pt);
    Operand et{OpdKind::Int, Area::TW, n}, ns = scratch("rtc_dt", Ty::LINT);
    Operand clock = clock_cell();  // hidden state: carried online under its own name
    p_.vars.push_back({"__rtc_clock", "DT", Area::Count, 0, 0, clock.area, clock.index, uint32_t(ty_info(Ty::DT).cells)});
    typed(Op::TCONV, Ty::LINT, et, ns, {}, Ty::DINT);
    typed(Op::TMUL, Ty::LINT, ns, Operand::typed_const(1000000), ns);
    typed(Op::TADD, Ty::LINT, clock_cell(), ns, clock_cell());
    typed(Op::TMOVE, Ty::DINT, Operand::typed_const(0), et);
    rung_ = nullptr;
  }
  static std::string input_names(const Type& t, size_t n) {
    std::string s;
    for (size_t i = 0; i < n; i++) s += (i ? ", " : "") + t.members[i].name;
    return s;
  }
  // TON TOF TP on ldc's timers (docs/il.md), one device per instance, as the
  // classic reader maps them; the instance's Q and ET are copied from the
  // device after the call (ET: ms to TIME's ns).
  std::map<uint64_t, uint32_t> devices_;  // instance place -> T number
  uint32_t next_timer_ = 0;
  template <class Mem>
  void timer(const std::string& kind, const model::Ref& inst, Mem mem) {
    uint64_t key = (uint64_t(inst.at.bit) << 32) | inst.at.cell;
    auto it = devices_.find(key);
    if (it == devices_.end()) {
      if (next_timer_ >= device_count(Dev::T)) fail(here_, std::string("more than ") + std::to_string(device_count(Dev::T)) + " timer instances");
      it = devices_.emplace(key, next_timer_++).first;
    }
    uint32_t n = it->second;
    // PT in whole ms, rounded up: ldc's timers count whole ms of dt, and
    // ET >= 3.5 ms holds exactly when ET >= 4 ms (TIME is ns; read as a LINT)
    Operand ns = scratch("ptns", Ty::LINT), ms = scratch("pt", Ty::DINT);
    if (auto pt = constant_in(mem("PT"))) {  // PT := T#30s right before: the ms known now (the same C arithmetic)
      ms = Operand{OpdKind::ConstInt};
      ms.ival = int32_t(uint32_t(uint64_t((int64_t(*pt) + 999999) / 1000000)));
    } else {
      typed(Op::TADD, Ty::LINT, mem("PT"), Operand::typed_const(999999), ns);
      typed(Op::TDIV, Ty::LINT, ns, Operand::typed_const(1000000), ns);
      typed(Op::TCONV, Ty::DINT, ns, ms, {}, Ty::LINT);
    }
    emit(Op::LOAD, mem("IN"));
    emit(kind == "TON" ? Op::MTON : kind == "TOF" ? Op::MTOF : Op::MTP, Operand{OpdKind::Timer, Area::Sys, n}, ms);
    emit(Op::MPP);
    timer_et(kind, n, mem);
    typed(Op::TMOVE, Ty::BOOL, Operand{OpdKind::Bit, Area::TQ, n}, mem("Q"));
  }
  // The instance's ET as MatIEC's state machines leave it: the device's ms as
  // ns while timing or reset; PT itself on the scan the timer completes (TON:
  // Q rises; TOF: Q falls with IN off; TP: the pulse ends with IN on), which
  // a PT of part of a ms (T#3.5ms) shows; then held, whatever PT becomes.
  // The instance's Q, not yet copied, is the Q of the scan before.
  template <class Mem>
  void timer_et(const std::string& kind, uint32_t n, Mem mem) {
    Operand tq{OpdKind::Bit, Area::TQ, n}, et = scratch("etns", Ty::LINT);
    typed(Op::TCONV, Ty::LINT, Operand{OpdKind::Int, Area::TW, n}, et, {}, Ty::DINT);
    typed(Op::TMUL, Ty::LINT, et, Operand::typed_const(1000000), et);
    // ET := from where the conditions hold: `LOAD g; MOVE; MPP` (a condition
    // of several in a BOOL of its own first), which native code selects
    // without a branch (docs/x86.md, "Select")
    auto under = [&](std::initializer_list<std::pair<Op, Operand>> conds, const Operand& from) {
      if (conds.size() > 1) {
        Operand h = scratch("etcond", Ty::BOOL);
        for (const auto& [op, o] : conds) emit(op, o);
        emit(Op::OUT, h);
        emit(Op::MPP);
        emit(Op::LOAD, h);
      } else {
        emit(conds.begin()->first, conds.begin()->second);
      }
      typed(Op::TMOVE, Ty::TIME, from, mem("ET"));
      emit(Op::MPP);
    };
    if (kind == "TON") {
      under({{Op::LOADN, tq}}, et);
      under({{Op::LOAD, tq}, {Op::ANDN, mem("Q")}}, mem("PT"));
    } else if (kind == "TOF") {
      under({{Op::LOAD, tq}}, et);
      under({{Op::LOADN, tq}, {Op::ANDN, mem("IN")}, {Op::AND, mem("Q")}}, mem("PT"));
    } else {
      under({{Op::LOAD, tq}, {Op::ORN, mem("IN")}}, et);
      under({{Op::LOADN, tq}, {Op::AND, mem("IN")}, {Op::AND, mem("Q")}}, mem("PT"));
    }
  }

  // The constant the open rung surely moved into `cell` (a typed MOVE of a
  // constant, run with the power known on: the rung's TRUE, however many
  // conditions were pushed and popped since), if nothing may have written it
  // since; else nullopt.  The rung is straight-line code (labels only start
  // rungs), so a walk over it from its start decides.
  std::optional<uint64_t> constant_in(const Operand& cell) const {
    if (!rung_) return std::nullopt;
    std::vector<char> on;  // the stack: 1 where the value is surely 1
    std::optional<uint64_t> v;
    for (const Instr& in : rung_->code) {
      const OpInfo& oi = op_info(in.op);
      if (oi.klass == OpClass::Typed) {
        if (oi.push) { on.push_back(0); continue; }
        const int d = in.nopd() - 1;
        const Ty dt = operand_type(in, d);
        const uint32_t cells = dt == Ty::STRING ? 33 : std::max(1, int(ty_info(dt == Ty::None ? Ty::DINT : dt).cells));
        const bool stx = in.op == Op::TSTX, to_cell = !stx && oi.operands[d] == 'r' && in.a[d].area == cell.area &&
                                                       in.a[d].index < cell.index + 2 && in.a[d].index + cells > cell.index;
        if (stx && in.a[1].area == cell.area) v.reset();
        if (!to_cell) continue;
        v.reset();
        if (in.op == Op::TMOVE && in.a[d].index == cell.index && in.a[0].kind == OpdKind::ConstT && !on.empty() && on.back())
          v = in.a[0].bits();
        continue;
      }
      switch (in.op) {
        case Op::TRUE: on.push_back(1); break;
        case Op::LOAD: case Op::LOADN: case Op::LOADP: case Op::LOADF: on.push_back(0); break;
        case Op::AND: case Op::ANDN: if (!on.empty()) on.back() = 0; break;
        case Op::OR: case Op::ORN: break;  // 1 OR x is 1; an unknown top stays unknown
        case Op::MPS: if (on.empty()) return std::nullopt; on.push_back(on.back()); break;
        case Op::MRD: if (on.size() < 2) return std::nullopt; on.back() = on[on.size() - 2]; break;
        case Op::MPP: if (on.empty()) return std::nullopt; on.pop_back(); break;
        case Op::ANDBLK: case Op::ORBLK: {
          if (on.size() < 2) return std::nullopt;
          const char a = on.back();
          on.pop_back();
          on.back() = in.op == Op::ORBLK ? char(on.back() || a) : char(on.back() && a);
          break;
        }
        case Op::OUT: case Op::OUTN: case Op::SET: case Op::RST: break;  // bits: not a typed cell
        case Op::TON: case Op::TOF: case Op::TP:  // the top is their input; they write their T cells only
        case Op::MTON: case Op::MTOF: case Op::MTP: break;
        default: return std::nullopt;
      }
    }
    return v;
  }
  static int var_index(const Pou& p, const std::string& name) {
    std::string u = upper(name);
    for (size_t i = 0; i < p.vars.size(); i++)
      if (upper(p.vars[i].name) == u) return int(i);
    return -1;
  }
  static std::string inputs_of(const Pou& p) {
    std::string s;
    for (const Var& v : p.vars)
      if (v.cls == VarClass::Input || v.cls == VarClass::InOut) s += (s.empty() ? "" : ", ") + v.name;
    return s.empty() ? "" : " (" + s + ")";
  }

  // A FUNCTION: `LD a  F b, c` (the CR is the first input) or `F(x := a, y := b)`.
  std::map<int, Place> frames_;
  void user_function(const Tok& op, const std::string& u) {
    int pou = m_.find_pou(u);
    const Pou& p = m_.pous[size_t(pou)];
    if (!frames_.count(pou)) frames_[pou] = m_.place(m_.type(p.block).size, p.loc);  // one frame per FUNCTION
    model::Ref frame;
    frame.type = p.block;
    frame.at = frames_[pou];
    std::vector<std::pair<Tok, Val>> in;
    std::vector<std::pair<Tok, size_t>> out;
    if (punct(peek(), "(")) {
      next();
      args(in, out);
    } else {
      need_cr(op);
      std::vector<const Var*> inputs;
      for (const Var& v : p.vars)
        if ((v.cls == VarClass::Input || v.cls == VarClass::InOut) && upper(v.name) != "EN") inputs.push_back(&v);
      if (inputs.empty()) fail(op, p.name + " has no input for the current result");
      // the CR is the first input; a VAR_IN_OUT binds to the variable LD read
      Val first;
      if (inputs[0]->cls == VarClass::InOut) {
        if (!cr_.var || !(cr_.o == cr_.var_o))
          fail(op, "the VAR_IN_OUT " + inputs[0]->name + " of " + p.name + " needs a variable, not a computed value");
        first.kind = Val::Ref_, first.ref = *cr_.var;
      } else if (cr_.lit) {
        first.lit = *cr_.lit;
      } else if (cr_whole()) {
        first.kind = Val::Ref_, first.ref = whole_;
      } else {
        first.kind = Val::Ref_;
        Operand tmp = scratch("farg", ty_of(cr_.type));
        typed(Op::TMOVE, ty_of(cr_.type), cr_.o, tmp);
        first.ref.type = cr_.type;
        first.ref.at = {tmp.index, tmp.index};
      }
      Tok ft = op;
      ft.text = inputs[0]->name;
      in.push_back({ft, first});
      size_t k = 1;
      while (peek().kind == Tok::Word) {
        if (k >= inputs.size()) fail(peek(), p.name + " takes " + std::to_string(inputs.size()) + " input(s)");
        Tok n = peek();
        n.text = inputs[k]->name;
        in.push_back({n, operand("farg" + std::to_string(k))});
        k++;
        if (punct(peek(), ",")) next();
        else break;
      }
    }
    expand(pou, frame, in, out, op);
    // the result is the CR (in an accumulator: the next call of F overwrites its frame)
    ensure_rung();
    Ty rt = ty_of(p.result);
    Operand d = acc(rt);
    typed(Op::TMOVE, rt, operand_at(rt, frame.at + m_.type(p.block).members.back().offset), d);
    set_cr(p.result, d);
  }

  // ---- standard functions of one input: the CR
  void function1(const Tok& op, const std::string& u) {
    need_cr(op);
    if (auto c = conversion(u)) {
      auto [from, to] = *c;
      if (cr_.lit) type_cr(m_.elem(from), op);
      if (cr_ty() != from && !(cr_whole()))
        fail(op, op.text + " converts a " + ty_info(from).name + ", this result is " + m_.type_name(cr_.type));
      if (cr_whole()) fail(op, op.text + " of " + a_type(cr_.type));
      Operand d = acc(to);
      if (from == to) typed(Op::TMOVE, to, cr_.o, d);
      else typed(Op::TCONV, to, cr_.o, d, {}, from);
      set_cr(m_.elem(to), d);
      return;
    }
    default_cr(op);
    Ty t = cr_ty();
    if (u == "TRUNC") {
      if (!typed::is_real(t)) fail(op, "TRUNC takes a REAL or LREAL, this result is " + m_.type_name(cr_.type));
      Operand d = acc(Ty::DINT);
      typed(Op::TTRUNC, Ty::DINT, cr_.o, d, {}, t);
      set_cr(m_.elem(Ty::DINT), d);
      return;
    }
    if (u == "NEG" && c_int_cr()) mark_promotion(), promote_cr(), t = Ty::DINT;  // C's unary - of an int
    static const std::map<std::string, Op> fns = {{"ABS", Op::TABS}, {"NEG", Op::TNEG}, {"SQRT", Op::TSQRT}, {"LN", Op::TLN},
                                                  {"LOG", Op::TLOG}, {"EXP", Op::TEXP}, {"SIN", Op::TSIN}, {"COS", Op::TCOS},
                                                  {"TAN", Op::TTAN}, {"ASIN", Op::TASIN}, {"ACOS", Op::TACOS}, {"ATAN", Op::TATAN}};
    Op o = fns.at(u);
    if (!op_takes(o, t, Ty::None)) fail(op, op.text + " does not take " + a_type(cr_.type));
    Operand d = acc(t);
    typed(o, t, cr_.o, d);
    cr_.o = d;
  }

  // BCD conversions as MatIEC's __uint_to_bcd and __bcd_to_uint
  // (lib/C/iec_std_lib.h), unrolled over the digits in 64 bits:
  //   X_TO_BCD_Y  res := 0; for digit k: res := res OR ((IN MOD 10) SHL 4k); IN := IN / 10
  //               then (Y)res: a digit beyond Y's width is cut off.  MatIEC
  //               shifts a 17th..20th digit of a ULINT by 64 and more (C leaves
  //               that undefined); ldc's SHL gives 0 there (docs/il.md), so they
  //               are dropped.
  //   X_BCD_TO_Y  a nibble above 9 (__test_bcd): 0, ENO FALSE (ldc: S0 set);
  //               else sum(nibble_k * 10^k), then (Y): modulo Y's width
  void bcd(const Tok& op, const Bcd& b) {
    need_cr(op);
    Ty from = b.from;
    if (cr_.lit) type_cr(m_.elem(from != Ty::None ? from : Ty::LWORD), op);
    if (from == Ty::None) {
      from = cr_ty();
      if (from == Ty::None || ty_info(from).kind != TyKind::Bits)
        fail(op, op.text + " converts a bit string (BYTE .. LWORD), this result is " + m_.type_name(cr_.type));
    }
    if (cr_ty() != from) fail(op, op.text + " converts a " + ty_info(from).name + ", this result is " + m_.type_name(cr_.type));
    const int bits = ty_info(from).bits;
    Operand x = scratch("bcd_x", Ty::ULINT), res = scratch("bcd_r", Ty::ULINT), dig = scratch("bcd_d", Ty::ULINT);
    typed(Op::TCONV, Ty::ULINT, cr_.o, x, {}, from);
    typed(Op::TMOVE, Ty::ULINT, Operand::typed_const(0), res);
    if (b.to_bcd) {
      // the digits of the largest value of `from`: 3 5 10 20
      const int digits = bits == 8 ? 3 : bits == 16 ? 5 : bits == 32 ? 10 : 20;
      for (int k = 0; k < digits; k++) {
        typed(Op::TMOD, Ty::ULINT, x, Operand::typed_const(10), dig);
        typed(Op::TDIV, Ty::ULINT, x, Operand::typed_const(10), x);
        typed(Op::TSHL, Ty::LWORD, dig, Operand::typed_const(uint64_t(4 * k)), dig, Ty::USINT);
        typed(Op::TOR, Ty::LWORD, res, dig, res);
      }
      Operand d = acc(b.to);
      typed(Op::TCONV, b.to, res, d, {}, Ty::LWORD);
      set_cr(m_.elem(b.to), d);
      return;
    }
    // Horner from the highest nibble: res := res * 10 + nibble; bad := nibble > 9
    Operand bad = scratch("bcd_bad", Ty::BOOL);
    typed(Op::TMOVE, Ty::BOOL, Operand::typed_const(0), bad);
    for (int k = bits / 4 - 1; k >= 0; k--) {
      typed(Op::TSHR, Ty::LWORD, x, Operand::typed_const(uint64_t(4 * k)), dig, Ty::USINT);
      typed(Op::TAND, Ty::LWORD, dig, Operand::typed_const(15), dig);
      typed(Op::TGT, Ty::ULINT, dig, Operand::typed_const(9));
      emit(Op::OR, bad);
      emit(Op::OUT, bad);
      emit(Op::MPP);
      typed(Op::TMUL, Ty::ULINT, res, Operand::typed_const(10), res);
      typed(Op::TADD, Ty::ULINT, res, dig, res);
    }
    Operand d = acc(b.to);
    typed(Op::TCONV, b.to, res, d, {}, Ty::ULINT);
    emit(Op::LOAD, bad);
    typed(Op::TMOVE, b.to, Operand::typed_const(0), d);
    emit(Op::SET, Operand{OpdKind::Bit, Area::S, kBitError});
    emit(Op::MPP);
    set_cr(m_.elem(b.to), d);
  }

  // The character-string functions (MatIEC's Table 29; docs/il.md "Strings"):
  // the CR, a STRING, is the first input; the others follow, separated by
  // commas: LEN, LEFT L, RIGHT L, MID L, P, CONCAT s {, s}, INSERT s, P,
  // DELETE L, P, REPLACE s, L, P, FIND s.  LEN and FIND give an INT.
  static bool string_fn(const std::string& u) {
    static const std::set<std::string> k = {"LEN", "LEFT", "RIGHT", "MID", "CONCAT", "INSERT", "DELETE", "REPLACE", "FIND"};
    return k.count(u) > 0;
  }
  void string_function(const Tok& op, const std::string& u) {
    need_cr(op);
    if (cr_.lit || cr_whole() || cr_ty() != Ty::STRING)
      fail(op, op.text + " takes a STRING as its first input (the current result), this one is " +
                   (cr_.lit ? std::string("a number") : a_type(cr_.type)));
    std::vector<std::pair<Tok, Val>> args;
    while (peek().kind == Tok::Word) {
      Tok k = peek();
      args.push_back({k, operand("s" + std::to_string(args.size()))});
      if (punct(peek(), ",")) next();
      else break;
    }
    static const std::map<std::string, std::string> kArgs = {  // s: a STRING, n: an integer
        {"LEN", ""}, {"LEFT", "n"}, {"RIGHT", "n"}, {"MID", "nn"}, {"CONCAT", "s"}, {"INSERT", "sn"},
        {"DELETE", "nn"}, {"REPLACE", "snn"}, {"FIND", "s"}};
    const std::string& want = kArgs.at(u);
    if (args.size() != want.size() && !(u == "CONCAT" && args.size() > 1))
      fail(op, op.text + " takes " + std::to_string(want.size() + 1) + " inputs: the current result and " +
                   std::to_string(want.size()) + " after it, separated by commas");
    const TypeId str = m_.elem(Ty::STRING);
    auto sarg = [&](size_t i) { return value_as(args[i].second, str, args[i].first, "s" + std::to_string(i), op.text.c_str()); };
    auto narg = [&](size_t i, Ty& ty) {  // an integer; an untyped number is a DINT
      TypeId vt = val_type(args[i].second);
      ty = vt == kNoType ? Ty::DINT : ty_of(vt);
      TyKind kd = ty == Ty::None ? TyKind::Real : ty_info(ty).kind;
      if (kd != TyKind::Signed && kd != TyKind::Unsigned)
        fail(args[i].first, op.text + "'s length and position are integers, '" + args[i].first.text + "' is not one");
      return value_as(args[i].second, m_.elem(ty), args[i].first, "n" + std::to_string(i), op.text.c_str());
    };
    // ARGS L P: both of one type (LINT if they differ)
    auto set_args = [&](size_t li, size_t pi) {
      Ty lt = Ty::DINT, pt = Ty::DINT;
      Operand l = li < args.size() ? narg(li, lt) : Operand::typed_const(0);
      Operand p = narg(pi, pt);
      if (li >= args.size()) lt = pt;
      Ty t = lt == pt ? lt : Ty::LINT;
      auto widen = [&](Operand o, Ty from, const char* key) {
        if (from == t) return o;
        if (o.kind == OpdKind::ConstT) return Operand::typed_const(typed::conv(t, from, o.bits()));
        Operand w = scratch(key, t);
        typed(Op::TCONV, t, o, w, {}, from);
        return w;
      };
      typed(Op::TARGS, t, widen(l, lt, "argl"), widen(p, pt, "argp"));
    };
    Operand in = cr_.o;
    if (u == "LEN" || u == "FIND") {
      Operand d = acc(Ty::INT);
      if (u == "LEN") typed(Op::TLEN, Ty::INT, in, d, {}, Ty::STRING);
      else typed(Op::TFIND, Ty::INT, in, sarg(0), d, Ty::STRING);
      set_cr(m_.elem(Ty::INT), d);
      return;
    }
    Operand d = acc(Ty::STRING);
    if (u == "LEFT" || u == "RIGHT") {
      Ty lt;
      Operand l = narg(0, lt);
      typed(u == "LEFT" ? Op::TLEFT : Op::TRIGHT, Ty::STRING, in, l, d, lt);
    } else if (u == "CONCAT") {  // MatIEC's CONCAT of n inputs: each cut at 126 in turn, as a chain of two
      for (size_t i = 0; i < args.size(); i++) {
        typed(Op::TCONCAT, Ty::STRING, in, sarg(i), d);
        in = d;
      }
    } else if (u == "MID" || u == "DELETE") {
      set_args(0, 1);
      typed(u == "MID" ? Op::TMID : Op::TDELETE, Ty::STRING, in, d);
    } else if (u == "INSERT") {
      Operand s2 = sarg(0);
      set_args(99, 1);
      typed(Op::TINSERT, Ty::STRING, in, s2, d);
    } else {  // REPLACE
      Operand s2 = sarg(0);
      set_args(1, 2);
      typed(Op::TREPLACE, Ty::STRING, in, s2, d);
    }
    set_cr(str, d);
  }

  // MIN MAX (extensible), LIMIT, SEL; the CR is the first input
  void selection(const Tok& op, const std::string& u) {
    need_cr(op);
    std::vector<std::pair<Tok, Val>> args;
    while (peek().kind == Tok::Word) {
      Tok k = peek();
      args.push_back({k, operand("sel" + std::to_string(args.size()))});
      if (punct(peek(), ",")) next();
      else break;
    }
    if (u == "MUX") {  // MUX(K, IN0, ..): IN_K; K outside gives the type's initial value, 0 (MatIEC's __mux)
      if (args.empty()) fail(op, "MUX takes K (the current result) and its inputs");
      default_cr(op);
      Ty kt = cr_ty();
      if (kt == Ty::None || !(ty_info(kt).kind == TyKind::Signed || ty_info(kt).kind == TyKind::Unsigned))
        fail(op, "MUX's K (the current result) is an integer, this one is " + a_type(cr_.type));
      TypeId t = kNoType;
      for (const auto& a : args)
        if (t == kNoType) t = val_type(a.second);
      if (t == kNoType) t = m_.elem(args[0].second.lit.untyped_real ? Ty::LREAL : Ty::DINT);
      Ty st = ty_of(t);
      if (st == Ty::None) fail(op, "MUX of " + a_type(t));
      Operand k = scratch("muxk", kt), d = acc(st);
      typed(Op::TMOVE, kt, cr_.o, k);
      typed(Op::TMOVE, st, Operand::typed_const(0), d);
      for (size_t i = 0; i < args.size(); i++) {
        Operand in = value_as(args[i].second, t, args[i].first, "sel" + std::to_string(i), "MUX");
        typed(Op::TEQ, kt, k, Operand::typed_const(uint64_t(i)));
        typed(Op::TMOVE, st, in, d);
        emit(Op::MPP);
      }
      set_cr(t, d);
      return;
    }
    if (u == "SEL") {  // SEL(G, IN0, IN1): G ? IN1 : IN0 (MatIEC)
      need_bool(op);
      if (args.size() != 2) fail(op, "SEL takes G (the current result), IN0 and IN1");
      TypeId t = val_type(args[0].second);
      if (t == kNoType) t = val_type(args[1].second);
      if (t == kNoType) t = m_.elem(args[0].second.lit.untyped_real || args[1].second.lit.untyped_real ? Ty::LREAL : Ty::DINT);
      Ty st = ty_of(t);
      if (st == Ty::None) fail(op, "SEL of " + a_type(t));
      Operand g = scratch("selg", Ty::BOOL), d = acc(st);
      typed(Op::TMOVE, Ty::BOOL, cr_.o, g);
      Operand in0 = value_as(args[0].second, t, args[0].first, "sel0", "SEL");
      Operand in1 = value_as(args[1].second, t, args[1].first, "sel1", "SEL");
      typed(Op::TMOVE, st, in0, d);
      emit(Op::LOAD, g);
      typed(Op::TMOVE, st, in1, d);
      emit(Op::MPP);
      set_cr(t, d);
      return;
    }
    if (args.empty()) fail(op, op.text + " needs more inputs after the current result");
    if (cr_.lit) {
      TypeId vt = val_type(args[0].second);
      if (vt != kNoType) type_cr(vt, op);
      else default_cr(op);
    }
    TypeId t = cr_.type;
    Ty st = ty_of(t);
    if (u == "LIMIT") {  // LIMIT(MN, IN, MX) = IN > MN ? (IN < MX ? IN : MX) : MN (MatIEC)
      if (args.size() != 2) fail(op, "LIMIT takes MN (the current result), IN and MX");
      Operand mn = cr_.o, d = acc(st);
      if (mn == d) mn = scratch("limmn", st), typed(Op::TMOVE, st, cr_.o, mn);
      Operand in = value_as(args[0].second, t, args[0].first, "sel0", "LIMIT");
      Operand mx = value_as(args[1].second, t, args[1].first, "sel1", "LIMIT");
      typed(Op::TMOVE, st, mn, d);
      typed(Op::TGT, st, in, mn);
      typed(Op::TMIN, st, mx, in, d);  // MatIEC's MIN(MX, IN): IN < MX ? IN : MX
      emit(Op::MPP);
      cr_.o = d;
      return;
    }
    Op o = u == "MIN" ? Op::TMIN : Op::TMAX;
    for (size_t i = 0; i < args.size(); i++) {
      Operand b = value_as(args[i].second, t, args[i].first, "sel" + std::to_string(i), op.text.c_str());
      Operand d = acc(st);
      typed(o, st, cr_.o, b, d);
      cr_.o = d;
    }
  }

  // ---------------------------------------------------------------- the end

  void finish() {
    p_.end_labels = std::move(pending_labels_);
    std::map<std::string, size_t> where;
    for (size_t r = 0; r < p_.rungs.size(); r++)
      for (auto& l : p_.rungs[r].labels) where[l] = r;
    for (auto& l : p_.end_labels) where[l] = p_.rungs.size();
    for (const Jump& j : jumps_) {
      auto w = where.find(j.label);
      std::string shown = j.label.rfind("_ldc_", 0) == 0 ? j.label.substr(j.label.find('_', 5) + 1) : j.label;
      if (w == where.end()) fail(j.at, "undefined label '" + shown + "'");
      if (w->second <= j.rung)
        fail(j.at, "backward jump to '" + shown + "': ldc runs every instruction at most once per scan (jumps go forward)");
    }
    if (p_.rungs.empty()) fail(t_.back(), "the program has no instructions");
  }
};

}  // namespace

Program parse_typed_il(const std::vector<Tok>& t, const std::string& filename, bool from_st) {
  return Reader(t, filename, from_st).run();
}

Program parse_typed_il(const std::vector<Tok>& t, const std::string& filename, bool from_st, Recovery& rec) {
  return Reader(t, filename, from_st, std::nullopt, &rec).run();
}

Program parse_typed_il(const std::vector<Tok>& t, const std::string& filename, bool from_st, Recovery* rec, uint32_t own_m) {
  Reader r(t, filename, from_st, std::nullopt, rec);
  r.own_m(own_m);
  return r.run();
}

void Recovery::report(const CompileError& e) {
  // a Quiet error follows from one reported; were there none, it is reported itself
  if (dynamic_cast<const Quiet*>(&e) && reported_ > 0) return;
  if (!seen_.insert({e.line, e.col}).second) return;  // one error per place
  reported_++;
  diag_.error(file_, e);
}

void Recovery::check() const {
  if (reported_ > 0) throw ErrorsReported();
}

Unit parse_typed_unit(const std::vector<Tok>& t, const std::string& filename, UnitBase base) {
  Reader r(t, filename, true, base);
  Unit u;
  u.prog = r.run();
  r.unit_facts(u);
  return u;
}

}  // namespace ldc::iecil
