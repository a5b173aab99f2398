// frontend/st/sfc_text.cpp -- a chart written as text, as the ST statements
// that run it (docs/st.md, "Sequential function charts").
//
// MatIEC compiles a chart into C that does, every scan (stage4's
// generate_c_sfc): remember each step's flag (prev); clear each action's
// state, set and reset; test the transitions (those with a PRIORITY sorted
// first by it, each clearing its source steps at once when it fires, the
// others in the order written); clear the source steps of the transitions
// that fired, then set their target steps; apply each step's action
// associations with active = X, activated = X AND NOT prev, desactivated =
// NOT X AND prev; store S/R actions; run variable actions' set/reset; run
// each action body whose state is on, in the order written.  The same is
// written here as ST over hidden BOOL variables, named __SFC<kind>_<name>, so
// every engine runs it and a function block's chart lives in its instance.
#include "frontend/st/sfc_text.h"

#include <algorithm>
#include <cstdlib>
#include <map>

#include "ir/model.h"

namespace ldc::st {

using iecil::Tok;
using iecil::upper;

namespace {

bool kw(const Tok& k, const char* w) { return k.kind == Tok::Word && upper(k.text) == w; }
bool punct(const Tok& k, const char* p) { return k.kind == Tok::Punct && k.text == p; }
[[noreturn]] void fail(const Tok& k, const std::string& m) { throw CompileError(k.line, k.col, m); }
std::string found(const Tok& k) { return k.kind == Tok::End ? ", found the end of the file" : ", found '" + k.text + "'"; }

struct Assoc {
  Tok action;
  std::string q;  // "" (none written), N, R, S, P, P0, P1
};
struct Step {
  Tok name;
  bool initial = false;
  std::vector<Assoc> assoc;
};
struct Transition {
  Tok at;
  std::vector<Tok> from, to, cond;
  bool prioritized = false;
  long priority = 0;
};
struct Action {
  Tok name;
  std::vector<Tok> body;
};

class Chart {
 public:
  Chart(const std::vector<Tok>& t, size_t& pos, const std::string& end, const std::set<std::string>& vars)
      : t_(t), pos_(pos), end_(end), vars_(vars) {}

  SfcText run() {
    while (!kw(peek(), end_.c_str()) && peek().kind != Tok::End) element();
    check();
    return write();
  }

 private:
  const std::vector<Tok>& t_;
  size_t& pos_;
  std::string end_;
  const std::set<std::string>& vars_;
  std::vector<Step> steps_;
  std::vector<Transition> trs_;
  std::vector<Action> acts_;
  std::map<std::string, size_t> step_of_, action_of_;  // upper-case name -> index
  std::vector<std::string> var_actions_;                // variables named by associations, first use first
  SfcText out_;

  const Tok& peek(size_t k = 0) const { return t_[std::min(pos_ + k, t_.size() - 1)]; }
  const Tok& next() {
    const Tok& k = peek();
    if (k.kind != Tok::End) pos_++;
    return k;
  }
  void expect(const char* p) {
    if (!punct(peek(), p)) fail(peek(), std::string("expected '") + p + "'" + found(peek()));
    next();
  }
  const Tok& name(const char* what) {
    if (peek().kind != Tok::Word) fail(peek(), std::string("expected ") + what + found(peek()));
    return next();
  }

  // ---------------------------------------------------------------- reading
  // element = step | transition | action
  void element() {
    const Tok& k = peek();
    if (kw(k, "INITIAL_STEP") || kw(k, "STEP")) step();
    else if (kw(k, "TRANSITION")) transition();
    else if (kw(k, "ACTION")) action();
    else fail(k, "expected STEP, TRANSITION or ACTION in a chart written as text" + found(k) + " (a POU body is a chart or statements, not both)");
  }

  // step = ("INITIAL_STEP" | "STEP") NAME ":" { NAME "(" [ qualifier { "," indicator } ] ")" ";" } "END_STEP"
  void step() {
    Step s;
    s.initial = kw(next(), "INITIAL_STEP");
    s.name = name("a step name");
    expect(":");
    while (!kw(peek(), "END_STEP")) {
      if (peek().kind == Tok::End) fail(s.name, "STEP '" + s.name.text + "' without END_STEP");
      Assoc a;
      a.action = name("an action name or END_STEP");
      expect("(");
      if (!punct(peek(), ")")) {
        const Tok& q = name("an action qualifier");
        a.q = upper(q.text);
        if (a.q == "L" || a.q == "D" || a.q == "SD" || a.q == "DS" || a.q == "SL")
          fail(q, "qualifier " + a.q + " of action '" + a.action.text + "' is timed; ldc translates N, S, R, P, P0 and P1");
        if (a.q != "N" && a.q != "S" && a.q != "R" && a.q != "P" && a.q != "P0" && a.q != "P1")
          fail(q, "'" + q.text + "' is not an action qualifier (N, R, S, L, D, P, P0, P1, SD, DS, SL)");
        while (punct(peek(), ",")) next(), name("an indicator variable");  // indicators: MatIEC writes no code for them
      }
      expect(")");
      expect(";");
      s.assoc.push_back(a);
    }
    next();
    if (step_of_.count(upper(s.name.text))) fail(s.name, "a second step named '" + s.name.text + "'");
    step_of_[upper(s.name.text)] = steps_.size();
    steps_.push_back(std::move(s));
  }

  // steps = NAME | "(" NAME { "," NAME } ")"
  std::vector<Tok> steps() {
    std::vector<Tok> v;
    if (!punct(peek(), "(")) return {name("a step name")};
    next();
    v.push_back(name("a step name"));
    while (punct(peek(), ",")) next(), v.push_back(name("a step name"));
    expect(")");
    return v;
  }

  // transition = "TRANSITION" [ NAME ] [ "(" "PRIORITY" ":=" INTEGER ")" ]
  //              "FROM" steps "TO" steps ":=" expression ";" "END_TRANSITION"
  void transition() {
    Transition tr;
    tr.at = next();
    if (peek().kind == Tok::Word && !kw(peek(), "FROM")) next();  // its name
    if (punct(peek(), "(")) {
      next();
      if (!kw(peek(), "PRIORITY")) fail(peek(), "expected PRIORITY" + found(peek()));
      next();
      expect(":=");
      const Tok& n = name("the priority, an integer");
      char* e = nullptr;
      tr.priority = std::strtol(n.text.c_str(), &e, 10);
      if (*e || n.text.size() > 9) fail(n, "the priority '" + n.text + "' is not a whole number");
      tr.prioritized = true;
      expect(")");
    }
    if (!kw(peek(), "FROM")) fail(peek(), "expected FROM" + found(peek()));
    next();
    tr.from = steps();
    if (!kw(peek(), "TO")) fail(peek(), "expected TO" + found(peek()));
    next();
    tr.to = steps();
    if (punct(peek(), ":")) fail(peek(), "a transition condition written in IL; ldc reads conditions written in ST (':= expression;')");
    expect(":=");
    int depth = 0;
    while (depth > 0 || !punct(peek(), ";")) {
      const Tok& k = peek();
      if (k.kind == Tok::End || kw(k, "END_TRANSITION")) fail(tr.at, "the transition's condition has no ';'");
      depth += punct(k, "(") - punct(k, ")");
      tr.cond.push_back(next());
    }
    if (tr.cond.empty()) fail(peek(), "the transition has no condition");
    next();
    if (!kw(peek(), "END_TRANSITION")) fail(peek(), "expected END_TRANSITION" + found(peek()));
    next();
    trs_.push_back(std::move(tr));
  }

  // action = "ACTION" NAME ":" statements "END_ACTION"
  void action() {
    Action a;
    next();
    a.name = name("an action name");
    expect(":");
    while (!kw(peek(), "END_ACTION")) {
      if (peek().kind == Tok::End) fail(a.name, "ACTION '" + a.name.text + "' without END_ACTION");
      a.body.push_back(next());
    }
    next();
    if (action_of_.count(upper(a.name.text))) fail(a.name, "a second action named '" + a.name.text + "'");
    action_of_[upper(a.name.text)] = acts_.size();
    acts_.push_back(std::move(a));
  }

  // ---------------------------------------------------------------- checking
  void check() {
    if (steps_.empty()) fail(peek(), "the chart has no step");
    bool initial = false;
    for (const Step& s : steps_) initial |= s.initial;
    if (!initial) fail(steps_[0].name, "the chart has no INITIAL_STEP");
    for (Transition& tr : trs_) {
      for (const auto* list : {&tr.from, &tr.to})
        for (const Tok& s : *list)
          if (!step_of_.count(upper(s.text))) fail(s, "transition " + std::string(list == &tr.from ? "from" : "to") + " '" + s.text + "', which is no step of the chart");
      flags(tr.cond);
    }
    for (Action& a : acts_) flags(a.body);
    for (const Step& s : steps_)
      for (const Assoc& a : s.assoc) {
        std::string u = upper(a.action.text);
        if (vars_.count(u)) {
          if (std::find(var_actions_.begin(), var_actions_.end(), u) == var_actions_.end()) var_actions_.push_back(u);
        } else if (!action_of_.count(u)) {
          fail(a.action, "step '" + s.name.text + "' names '" + a.action.text + "', which is neither an ACTION of the chart nor a variable");
        }
      }
  }
  // STEP.X in a condition or an action: the step's flag; STEP.T refused
  void flags(std::vector<Tok>& toks) const {
    for (Tok& k : toks) {
      if (k.kind != Tok::Word) continue;
      std::string u = upper(k.text);
      size_t dot = u.find('.');
      if (dot == std::string::npos || !step_of_.count(u.substr(0, dot)) || vars_.count(u.substr(0, dot))) continue;
      std::string field = u.substr(dot + 1);
      if (field == "X") k.text = "__SFCX_" + u.substr(0, dot);
      else if (field == "T") fail(k, "'" + k.text + "', the time a step has been active, is not translated by ldc");
      else fail(k, "'" + k.text + "': a step has X (active) and T (its time); ." + field + " is neither");
    }
  }

  // ---------------------------------------------------------------- writing
  static std::string X(const Tok& step) { return "__SFCX_" + upper(step.text); }
  static std::string prev(const Tok& step) { return "__SFCP_" + upper(step.text); }
  static std::string tr_flag(size_t i) { return "__SFCT" + std::to_string(i); }
  static std::string state(const std::string& a) { return "__SFCA_" + a; }
  static std::string set(const std::string& a) { return "__SFCS_" + a; }
  static std::string reset(const std::string& a) { return "__SFCR_" + a; }
  static std::string stored(const std::string& a) { return "__SFCM_" + a; }

  void var(const std::string& n, bool init, const Tok& at) { out_.vars.push_back({n, init ? "TRUE" : "FALSE", at}); }
  // the words of `text` (separated by blanks) as tokens at `at`
  void say(const Tok& at, const std::string& text) {
    size_t i = 0;
    while (i < text.size()) {
      size_t j = text.find(' ', i);
      if (j == std::string::npos) j = text.size();
      if (j > i) {
        std::string w = text.substr(i, j - i);
        bool p = w == ":=" || w == ";" || w == "(" || w == ")" || w == ",";
        out_.body.push_back({p ? Tok::Punct : Tok::Word, w, at.line, at.col});
      }
      i = j + 1;
    }
  }
  void say(const std::vector<Tok>& toks) { out_.body.insert(out_.body.end(), toks.begin(), toks.end()); }
  std::string all_active(const std::vector<Tok>& steps) const {
    std::string s;
    for (const Tok& k : steps) s += (s.empty() ? "" : " AND ") + X(k);
    return s;
  }
  void assign_each(const Tok& at, const std::vector<Tok>& steps, const char* value) {
    for (const Tok& s : steps) say(at, X(s) + " := " + value + " ;");
  }

  SfcText write() {
    for (const Step& s : steps_) var(X(s.name), s.initial, s.name), var(prev(s.name), false, s.name);
    for (size_t i = 0; i < trs_.size(); i++) var(tr_flag(i), false, trs_[i].at);
    for (const Action& a : acts_)
      for (auto f : {state, set, reset, stored}) var(f(upper(a.name.text)), false, a.name);
    for (const std::string& v : var_actions_) var(set(v), false, steps_[0].name), var(reset(v), false, steps_[0].name);

    for (const Step& s : steps_) say(s.name, prev(s.name) + " := " + X(s.name) + " ;");
    for (const Action& a : acts_) {
      std::string u = upper(a.name.text);
      say(a.name, state(u) + " := FALSE ; " + set(u) + " := FALSE ; " + reset(u) + " := FALSE ;");
    }
    for (const std::string& v : var_actions_) say(steps_[0].name, set(v) + " := FALSE ; " + reset(v) + " := FALSE ;");
    transitions();
    for (const Step& s : steps_)
      for (const Assoc& a : s.assoc) association(s, a);
    for (const Action& a : acts_) {
      std::string u = upper(a.name.text);
      say(a.name, "IF " + set(u) + " THEN " + stored(u) + " := TRUE ; END_IF ; IF " + reset(u) + " THEN " + stored(u) +
                      " := FALSE ; END_IF ; " + state(u) + " := " + state(u) + " OR " + stored(u) + " ;");
    }
    for (const std::string& v : var_actions_)
      say(steps_[0].name, "IF " + reset(v) + " THEN " + v + " := FALSE ; ELSIF " + set(v) + " THEN " + v + " := TRUE ; END_IF ;");
    for (const Action& a : acts_) {
      say(a.name, "IF " + state(upper(a.name.text)) + " THEN");
      say(a.body);
      say(a.name, "END_IF ;");
    }
    out_.body.push_back({Tok::End, "", peek().line, peek().col});
    return std::move(out_);
  }

  // the fire test in MatIEC's order (PRIORITY first, by it; then as written),
  // then the steps cleared and set in the order written
  void transitions() {
    std::vector<size_t> order;
    for (size_t i = 0; i < trs_.size(); i++) {
      auto at = order.end();
      if (trs_[i].prioritized) {
        at = order.begin();
        while (at != order.end() && (trs_[*at].prioritized ? trs_[*at].priority : 0) <= trs_[i].priority) ++at;
      }
      order.insert(at, i);
    }
    for (size_t i : order) {
      const Transition& tr = trs_[i];
      say(tr.at, "IF " + all_active(tr.from) + " THEN " + tr_flag(i) + " := (");
      say(tr.cond);
      say(tr.at, ") ;");
      if (tr.prioritized) {
        say(tr.at, "IF " + tr_flag(i) + " THEN");
        assign_each(tr.at, tr.from, "FALSE");
        say(tr.at, "END_IF ;");
      }
      say(tr.at, "ELSE " + tr_flag(i) + " := FALSE ; END_IF ;");
    }
    for (size_t i = 0; i < trs_.size(); i++) {
      if (trs_[i].prioritized) continue;
      say(trs_[i].at, "IF " + tr_flag(i) + " THEN");
      assign_each(trs_[i].at, trs_[i].from, "FALSE");
      say(trs_[i].at, "END_IF ;");
    }
    for (size_t i = 0; i < trs_.size(); i++) {
      say(trs_[i].at, "IF " + tr_flag(i) + " THEN");
      assign_each(trs_[i].at, trs_[i].to, "TRUE");
      say(trs_[i].at, "END_IF ;");
    }
  }

  // one action association of step s, as MatIEC's generate_c_sfc writes it
  void association(const Step& s, const Assoc& a) {
    std::string u = upper(a.action.text);
    bool variable = vars_.count(u) > 0;
    std::string target = variable ? u : state(u);
    std::string active = X(s.name), activated = "( " + X(s.name) + " AND NOT " + prev(s.name) + " )",
                desactivated = "( NOT " + X(s.name) + " AND " + prev(s.name) + " )";
    const Tok& at = a.action;
    if (a.q.empty()) {
      if (!variable) say(at, "IF " + active + " THEN " + target + " := TRUE ; END_IF ;");  // a variable: MatIEC sets only its action state
    } else if (a.q == "N") {
      say(at, "IF " + active + " THEN " + target + " := TRUE ; END_IF ; IF " + desactivated + " THEN " + target + " := FALSE ; END_IF ;");
    } else if (a.q == "S" || a.q == "R") {
      say(at, "IF " + active + " THEN " + (a.q == "S" ? set(u) : reset(u)) + " := TRUE ; END_IF ;");
    } else {  // P, P1, P0
      say(at, "IF " + (a.q == "P0" ? desactivated : activated) + " THEN " + target + " := TRUE ; ELSE " + target + " := FALSE ; END_IF ;");
    }
  }
};

}  // namespace

bool sfc_element_start(const Tok& k, const Tok& next) {
  if (kw(k, "INITIAL_STEP") || kw(k, "STEP") || kw(k, "ACTION")) return next.kind == Tok::Word;
  return kw(k, "TRANSITION") && (next.kind == Tok::Word || punct(next, "("));
}

SfcText sfc_to_st(const std::vector<Tok>& t, size_t& pos, const std::string& end, const std::set<std::string>& variables) {
  return Chart(t, pos, end, variables).run();
}

}  // namespace ldc::st
