// frontend/sfc.cpp -- the .sfc reader (docs/sfc.md): a sequential function
// chart in text, line by line.  Pass 1 reads declarations; pass 2 reads the
// structure (steps, transitions, selections, simultaneous sequences, jumps)
// into steps and scopes; pass 3, when every step name is known, reads the
// transition conditions and the action bodies (ladder through parse_ld, IL
// through parse_il_text) and lowers them to IL.
#include <algorithm>
#include <cstring>
#include <functional>
#include <map>
#include <set>

#include "frontend/diag.h"
#include "frontend/frontend.h"
#include "frontend/operands.h"
#include "frontend/treebuild.h"

namespace ldc {
namespace {

using namespace treebuild;

[[noreturn]] void fail(int line, int col, const std::string& msg) { throw CompileError(line, col, msg); }

// (Cascade and Stop: frontend/diag.h; a Stop here is a limit of the whole chart.)

struct Tok {
  std::string text;
  int col = 0;
};

bool word_char(char c) {
  return std::isalnum((unsigned char)c) || c == '_' || c == '%' || c == '.' || c == '#';
}

// Words and operators of one line; `#` or `//` at the start of a token begins a comment.
// An unexpected character is thrown, after `out` holds the tokens before it.
void tokens_into(const std::string& line, int lineno, std::vector<Tok>& out) {
  size_t i = 0;
  while (i < line.size()) {
    char c = line[i];
    if (c == ' ' || c == '\t' || c == '\r') { i++; continue; }
    if (c == '#' || (c == '/' && i + 1 < line.size() && line[i + 1] == '/')) break;
    Tok t;
    t.col = int(i) + 1;
    bool num = std::isdigit((unsigned char)c) ||
               (c == '-' && i + 1 < line.size() && std::isdigit((unsigned char)line[i + 1]));
    if (word_char(c) || num) {
      t.text += line[i++];
      while (i < line.size()) {
        char d = line[i];
        bool exp_sign = num && (d == '+' || d == '-') && (t.text.back() == 'e' || t.text.back() == 'E');
        if (!word_char(d) && !exp_sign) break;
        t.text += d;
        i++;
      }
    } else {
      static const char* two[] = {"==", "<>", "!=", "<=", ">=", "&&", "||"};
      for (const char* op : two)
        if (line.compare(i, 2, op) == 0) t.text = op;
      if (t.text.empty()) {
        if (!std::strchr("()!&|=<>{}", c))
          fail(lineno, t.col, std::string("unexpected character '") + c + "'");
        t.text = std::string(1, c);
      }
      i += t.text.size();
    }
    out.push_back(std::move(t));
  }
}

// The tokens of a line whose unexpected characters are read as blanks (error
// recovery: the line's error is reported; its words still say what it is).
std::vector<Tok> tokens_blanking(std::string line, int lineno) {
  for (int tries = 0; tries < 64; tries++) {
    std::vector<Tok> out;
    try {
      tokens_into(line, lineno, out);
      return out;
    } catch (const CompileError& e) {
      line[size_t(e.col - 1)] = ' ';
    }
  }
  return {};
}

struct Line {
  std::string text;
  int no;
  std::vector<Tok> toks;
  std::string kw;  // the first token, upper case
  bool refused = false;  // an error was reported on it: its condition or action is not read
};

struct PendingT {  // a transition waiting for its target
  uint32_t step;
  size_t index;
};

struct Body {  // an action body, read in pass 3
  uint32_t step;
  bool on_entry, ladder;
  size_t first, last;  // line indexes of its text (last excluded)
  int header_line;
};

struct Cond_ {  // a transition condition, read in pass 3
  uint32_t step;
  size_t index;
  size_t line;  // line index; tokens from 1
};

struct Jump {
  std::vector<PendingT> from;
  uint32_t scope;
  Tok name;
  int line;
};

class SfcParser {
 public:
  SfcParser(std::string_view text, std::string file, Diagnostics* diag = nullptr)
      : text_(text), file_(std::move(file)), diag_(diag) {}
  Chart chart();

 private:
  std::string_view text_;
  std::string file_;
  // Error recovery (docs/diagnostics.md): with diag_, a wrong declaration,
  // step, transition, action, jump, condition or body is reported and the
  // reader goes on with the next line; the structure is kept (a wrong step is
  // still a step, a missing transition is supplied) so that one mistake gives
  // one error.  Said nothing more: the uses of a refused alias or step name,
  // what the step flags of a refused `flags` line would have said, the end of
  // a chart whose `select` or `parallel` was not closed.
  Diagnostics* diag_;
  std::set<std::string> refused_names_;  // upper case
  bool flags_refused_ = false, unclosed_ = false;
  bool unit(const std::function<void()>& read);
  void report(int line, int col, const std::string& msg) {
    unit([&] { fail(line, col, msg); });
  }
  void quiet_if_refused(const CompileError& e) const;
  size_t skip_line();
  void skip_block();
  std::vector<Line> lines_;
  size_t pos_ = 0;  // next line of pass 2
  Chart c_;
  bool have_flags_ = false;
  int flags_line_ = 0;
  std::map<std::string, DeviceRef> names_;  // aliases and steps, upper case
  std::map<std::string, uint32_t> step_names_;
  std::map<uint32_t, uint32_t> timers_;     // timer -> step
  std::vector<Alias> aliases_;              // the file's own
  std::vector<Body> bodies_;
  std::vector<Cond_> conds_;
  std::vector<Jump> jumps_;
  uint32_t next_label_ = 0;

  void read_lines();
  void declarations();
  void alias(const Line& l);
  void flags(const Line& l);
  int col_of(int line) const {  // the first word of a line
    const Line& l = lines_[size_t(line - 1)];
    return l.toks.empty() ? 1 : l.toks[0].col;
  }
  const Line* peek();
  bool at_end_of_block();
  struct SeqEnd {
    std::vector<PendingT> pending;
    bool last_is_plain_step = false, last_is_parallel = false, jumped = false, empty = true;
    int last_line = 0;
    uint32_t last_step = 0;
  };
  SeqEnd sequence(uint32_t scope, int depth, int prev, bool expect_step, bool top);
  uint32_t step(uint32_t scope, bool top_first);
  void step_timer(uint32_t s, const Line& l, size_t k);
  void step_actions(uint32_t s);
  bool unknown_line_ = false;  // a line refused as no action: it may have been the missing transition
  uint32_t parallel(uint32_t scope, int depth);
  uint32_t stand_in_step(uint32_t scope, int line);
  std::vector<PendingT> select(uint32_t scope, int depth, int prev);
  uint32_t new_step(const std::string& name, int line, uint32_t scope);
  uint32_t new_scope();
  void action(uint32_t s, const Line& l);
  void resolve_jumps();
  void read_conditions();
  void read_condition(const Cond_& cd);
  void read_body(const Body& bd, const std::vector<Alias>& known);
  void read_bodies();
  void check_writes();

  DeviceRef device(const Tok& t);
  Operand bit(const Tok& t, bool writable);
  Operand value(const Tok& t);
  Cond condition(const std::vector<Tok>& t, size_t& i, bool neg, int line, int depth);
  Cond term(const std::vector<Tok>& t, size_t& i, bool neg, int line, int depth);
  Cond factor(const std::vector<Tok>& t, size_t& i, bool neg, int line, int depth);
  SfcBody lower_body(const TreeProgram& tp, Program p);
};

void SfcParser::read_lines() {
  int no = 0;
  for (std::string& t : source_lines(text_)) {
    Line l;
    l.text = std::move(t);
    l.no = ++no;
    lines_.push_back(std::move(l));
  }
}

bool opens_body(const Line& l) {
  if (!l.toks.empty() && l.toks.back().text == "{") return true;
  if (!l.refused) return false;  // a refused line (its tokens cut short): by its text
  size_t e = l.text.find_last_not_of(" \t\r");
  return e != std::string::npos && l.text[e] == '{';
}

// Pass 1.  decl = "alias" NAME "=" DEVICE | "flags" Mn ;  body lines are skipped.
void SfcParser::declarations() {
  c_.flag_base = 4096;
  for (size_t i = 0; i < lines_.size(); i++) {
    Line& l = lines_[i];
    l.refused = !unit([&] { tokens_into(l.text, l.no, l.toks); });
    if (l.refused) l.toks = tokens_blanking(l.text, l.no);  // the line keeps its place in the chart
    if (l.toks.empty()) continue;
    l.kw = upper(l.toks[0].text);
    if (opens_body(l)) {
      size_t j = i + 1;
      while (j < lines_.size()) {
        std::string t = lines_[j].text;
        t.erase(0, t.find_first_not_of(" \t"));
        while (!t.empty() && (t.back() == ' ' || t.back() == '\t' || t.back() == '\r')) t.pop_back();
        if (t == "}") break;
        j++;
      }
      if (j == lines_.size()) throw Stop(l.no, l.toks.back().col, "action body not closed: a line with '}' alone ends it");
      i = j;
      lines_[j].kw = "}";
      continue;
    }
    if (l.kw == "ALIAS") {
      const auto& t = l.toks;
      if (unit([&] { alias(l); }) || t.size() < 2 || names_.count(upper(t[1].text))) continue;
      refused_names_.insert(upper(t[1].text));  // its uses say nothing
    } else if (l.kw == "FLAGS") {
      flags_refused_ = !unit([&] { flags(l); });
    }
  }
}

// alias = "alias" NAME "=" DEVICE
void SfcParser::alias(const Line& l) {
  const auto& t = l.toks;
  if (t.size() != 4 || t[2].text != "=") fail(l.no, t[0].col, "expected: alias NAME = DEVICE");
  std::string why;
  if (!is_identifier(t[1].text)) fail(l.no, t[1].col, "alias name '" + t[1].text + "' must be letters, digits and _");
  if (parse_device(t[1].text) || parse_iec_address(t[1].text, why))
    fail(l.no, t[1].col, "'" + t[1].text + "' cannot be an alias name: it is a device");
  if (names_.count(upper(t[1].text))) fail(l.no, t[1].col, "alias '" + t[1].text + "' is already defined");
  DeviceRef d;
  try {
    d = device(t[3]);
  } catch (CompileError& e) { fail(l.no, e.col, e.what()); }
  names_[upper(t[1].text)] = d;
  aliases_.push_back({t[1].text, d});
}

// flags = "flags" Mn
void SfcParser::flags(const Line& l) {
  if (have_flags_) fail(l.no, l.toks[0].col, "the step flags are already placed (line " + std::to_string(flags_line_) + ")");
  if (l.toks.size() != 2) fail(l.no, l.toks[0].col, "expected: flags Mn (the first of the step flags)");
  auto d = parse_device(l.toks[1].text);
  if (!d || d->dev != Dev::M || d->index >= device_count(Dev::M))
    fail(l.no, l.toks[1].col, "expected an M device (M0..M8191) for the step flags");
  c_.flag_base = d->index;
  have_flags_ = true;
  flags_line_ = l.no;
}

DeviceRef SfcParser::device(const Tok& t) { return resolve_device(t.text, t.col, names_, "device, alias or step"); }

Operand SfcParser::bit(const Tok& t, bool writable) {
  DeviceRef d = device(t);
  Area a = bit_area(d.dev);
  if (a == Area::Count) fail(0, t.col, t.text + " is a word; a bit is needed here (compare words, e.g. " + t.text + " <> 0)");
  if (writable && (d.dev == Dev::X || d.dev == Dev::T || d.dev == Dev::C || (d.dev == Dev::S && d.index != kBitError)))
    fail(0, t.col, t.text + " cannot be written: actions drive Y, M, K or S0");
  return Operand{OpdKind::Bit, a, d.index};
}

Operand SfcParser::value(const Tok& t) {
  std::string why;
  bool named = names_.count(upper(t.text)) || parse_device(t.text) || t.text[0] == '%';
  if (!named) {
    auto c = parse_constant(t.text, why);
    if (!c) fail(0, t.col, why.empty() ? "unknown device, alias or step '" + t.text + "'" : why);
    return *c;
  }
  DeviceRef d = device(t);
  Area a = word_area(d.dev);
  if (a == Area::Count) fail(0, t.col, t.text + " is a bit; a word or a constant is needed in a compare");
  return Operand{area_is_real(a) ? OpdKind::Real : OpdKind::Int, a, d.index};
}

const Line* SfcParser::peek() {
  while (pos_ < lines_.size() && (lines_[pos_].toks.empty() || lines_[pos_].kw == "ALIAS" || lines_[pos_].kw == "FLAGS"))
    pos_++;
  return pos_ < lines_.size() ? &lines_[pos_] : nullptr;
}

bool SfcParser::at_end_of_block() {
  const Line* l = peek();
  return !l || l->kw == "BRANCH" || l->kw == "END";
}

uint32_t SfcParser::new_scope() {
  c_.scopes.emplace_back();
  return uint32_t(c_.scopes.size() - 1);
}

uint32_t SfcParser::new_step(const std::string& name, int line, uint32_t scope) {
  if (c_.steps.size() >= kMaxSfcSteps)
    throw Stop(line, 1, "too many steps (at most " + std::to_string(kMaxSfcSteps) + ", simultaneous sequences included)");
  uint32_t s = uint32_t(c_.steps.size());
  if (c_.flag_base + 3 * (s + 1) > device_count(Dev::M))
    throw Stop(line, 1, "the step flags do not fit: 3 M bits per step from M" + std::to_string(c_.flag_base) +
                            " pass M8191 (lower 'flags')");
  SfcStep st;
  st.name = name;
  st.line = line;
  st.scope = scope;
  c_.steps.push_back(std::move(st));
  if (c_.scopes[scope].steps.empty()) c_.scopes[scope].first = s;
  c_.scopes[scope].steps.push_back(s);
  return s;
}

// step = [ "initial" ] "step" NAME [ "timer" Tn ] { action }
// With recovery a wrong step line is still a step (named after its line when
// its name is refused, the name then remembered as refused).
uint32_t SfcParser::step(uint32_t scope, bool top_first) {
  const Line& l = lines_[pos_++];
  const auto& t = l.toks;
  size_t k = 0;
  if (l.kw == "INITIAL") {
    if (!top_first) report(l.no, t[0].col, "only the chart's first step is initial");
    k = 1;
  } else if (top_first) {
    report(l.no, t[0].col, "the chart starts with its initial step: 'initial step NAME'");
  }
  std::string key;
  bool named = unit([&] {
    if (k >= t.size() || upper(t[k].text) != "STEP") fail(l.no, t[0].col, "expected: initial step NAME");
    if (k + 1 >= t.size()) fail(l.no, t[k].col, "expected a step name after 'step'");
    const Tok& name = t[k + 1];
    std::string why;
    if (!is_identifier(name.text)) fail(l.no, name.col, "step name '" + name.text + "' must be letters, digits and _");
    if (parse_device(name.text) || parse_iec_address(name.text, why))
      fail(l.no, name.col, "'" + name.text + "' cannot be a step name: it is a device");
    key = upper(name.text);
    if (auto it = step_names_.find(key); it != step_names_.end())
      fail(l.no, name.col, "duplicate step '" + name.text + "' (first defined on line " +
                               std::to_string(c_.steps[it->second].line) + ")");
    if (names_.count(key)) fail(l.no, name.col, "'" + name.text + "' is already an alias");
  });
  if (!named && k + 1 < t.size() && !names_.count(upper(t[k + 1].text)) && !step_names_.count(upper(t[k + 1].text)))
    refused_names_.insert(upper(t[k + 1].text));  // jumps to it and conditions on it say nothing
  uint32_t s = new_step(named ? t[k + 1].text : "step_line_" + std::to_string(l.no), l.no, scope);
  if (named) {
    step_names_[key] = s;
    names_[key] = DeviceRef{Dev::M, c_.flag(s)};
  }
  if (named && k + 2 < t.size()) unit([&] { step_timer(s, l, k + 2); });
  step_actions(s);
  return s;
}

// "timer" Tn after the step's name (toks[k] is "timer")
void SfcParser::step_timer(uint32_t s, const Line& l, size_t k) {
  const auto& t = l.toks;
  if (upper(t[k].text) != "TIMER" || k + 2 != t.size()) fail(l.no, t[k].col, "expected: step NAME [timer Tn]");
  auto d = parse_device(t[k + 1].text);
  if (!d || d->dev != Dev::T || d->index >= device_count(Dev::T))
    fail(l.no, t[k + 1].col, "expected a timer T0..T255 for the step's time");
  if (auto it = timers_.find(d->index); it != timers_.end())
    fail(l.no, t[k + 1].col, "timer " + t[k + 1].text + " already times step '" + c_.steps[it->second].name + "'");
  timers_[d->index] = s;
  c_.steps[s].timer = int32_t(d->index);
}

// The action lines under step s, up to the next structure line.
void SfcParser::step_actions(uint32_t s) {
  static const char* structure[] = {"STEP", "INITIAL", "TRANSITION", "SELECT", "PARALLEL", "BRANCH", "END", "JUMP"};
  while (const Line* a = peek()) {
    if (std::find(std::begin(structure), std::end(structure), a->kw) != std::end(structure)) break;
    unit([&] { action(s, *a); });
  }
}

// action = ("N" | "S" | "R") BIT | ("N" | "P") ("ladder" | "il") "{" lines "}"
void SfcParser::action(uint32_t s, const Line& l) {
  const auto& t = l.toks;
  size_t here = pos_;
  pos_ = skip_line();  // its body too: a wrong header does not make the body's lines the chart's
  if (l.refused) return;  // its error is said
  if (l.kw != "N" && l.kw != "S" && l.kw != "R" && l.kw != "P") {
    bool run = unknown_line_;  // the lines after a refused one (a body whose '{' was lost, say): quiet
    unknown_line_ = true;
    if (run) throw Cascade();
    fail(l.no, t[0].col, "expected an action (N, S, R or P), a transition, or a step; found '" + t[0].text + "'");
  }
  unknown_line_ = false;
  if (opens_body(l)) {
    std::string kind = t.size() == 3 ? upper(t[1].text) : "";
    if (t.size() != 3 || (kind != "LADDER" && kind != "IL") || l.kw == "S" || l.kw == "R")
      fail(l.no, t[0].col, "expected: N ladder {, N il {, P ladder { or P il {");
    bodies_.push_back({s, l.kw == "P", kind == "LADDER", here + 1, pos_ - 1, l.no});
    return;
  }
  if (l.kw == "P") fail(l.no, t[0].col, "P takes a body: P ladder { ... } or P il { ... }");
  if (t.size() != 2) fail(l.no, t[0].col, "expected: " + l.kw + " BIT, or " + l.kw + " ladder { ... }");
  Operand b;
  try {
    b = bit(t[1], true);
  } catch (CompileError& e) { fail(l.no, e.col, e.what()); }
  if (l.kw == "N") {
    auto it = std::find_if(c_.nbits.begin(), c_.nbits.end(), [&](const SfcNBit& n) { return n.bit == b; });
    if (it == c_.nbits.end()) c_.nbits.push_back({b, {s}});
    else if (std::find(it->steps.begin(), it->steps.end(), s) == it->steps.end()) it->steps.push_back(s);
  } else {
    Instr in;
    in.op = l.kw == "S" ? Op::SET : Op::RST;
    in.a[0] = b;
    in.loc = {l.no, t[1].col};
    c_.steps[s].bits.push_back(in);
  }
}

// sequence = step_item { trans_item ( step_item | jump ) }      (from a step)
//          | trans_item { step_item trans_item } [ jump ]       (a selection branch)
// step_item = step | parallel ;  trans_item = transition | select
SfcParser::SeqEnd SfcParser::sequence(uint32_t scope, int depth, int prev, bool expect_step, bool top) {
  SeqEnd e;
  bool first = true;
  for (;;) {
    if (at_end_of_block()) {
      const Line* l = peek();
      if (!top || !l) break;
      // a 'branch' or 'end' outside select and parallel: reported, skipped; after a
      // 'branch' (its 'select' or 'parallel' lost) the rest of that block is skipped
      // too, and it stands for the transition or step the chart needs there
      report(l->no, l->toks[0].col, "'" + l->toks[0].text + "' outside 'select' or 'parallel'");
      bool lost = l->kw == "BRANCH";
      pos_++;
      if (lost) {
        skip_block();
        while (peek() && peek()->kw == "BRANCH") pos_++, skip_block();
        if (peek()) pos_++;  // its 'end'
        unknown_line_ = true;
      }
      continue;
    }
    const Line& l = *peek();
    const Tok& h = l.toks[0];
    e.empty = false;
    if (e.jumped) {  // reported, and the rest of the block skipped
      report(l.no, h.col, "unreachable: nothing can follow a jump, or a selection whose branches all jump");
      skip_block();
      continue;
    }
    if (expect_step) {
      uint32_t s;
      if (l.kw == "STEP" || l.kw == "INITIAL") s = step(scope, top && first);
      else if (l.kw == "PARALLEL") {
        if (top && first) report(l.no, h.col, "the chart starts with its initial step: 'initial step NAME'");
        s = parallel(scope, depth + 1);
      } else if (l.kw == "JUMP") {
        if (l.toks.size() != 2) report(l.no, h.col, "expected: jump STEP");
        else jumps_.push_back({e.pending, scope, l.toks[1], l.no});
        e.pending.clear();
        e.jumped = true;
        pos_++;
        continue;
      } else if (l.kw == "TRANSITION" || l.kw == "SELECT") {
        // reported; a step stands in for the missing one (the line is read next)
        if (!unknown_line_)  // (else the block refused above was the step)
          report(l.no, h.col, first ? "a simultaneous branch starts with a step"
                                    : "expected a step or a jump: steps and transitions alternate");
        unknown_line_ = false;
        s = stand_in_step(scope, l.no);
      } else {
        // reported; the line stands for a step, the action lines below are its
        // (before the first step: a wrong declaration, skipped)
        report(l.no, h.col, "expected a step, 'parallel' or 'jump'; found '" + h.text + "'");
        pos_ = skip_line();
        bool action = l.kw == "N" || l.kw == "S" || l.kw == "R" || l.kw == "P";
        if (top && first && !action) {  // a wrong declaration, most likely: its name's uses say nothing
          if (l.toks.size() >= 2 && is_identifier(l.toks[1].text) && !names_.count(upper(l.toks[1].text)))
            refused_names_.insert(upper(l.toks[1].text));
          continue;
        }
        s = stand_in_step(scope, l.no);
        step_actions(s);
      }
      for (const PendingT& p : e.pending) c_.steps[p.step].out[p.index].target = s;
      e.pending.clear();
      prev = int(s);
      e.last_is_plain_step = !c_.steps[s].parallel;
      e.last_is_parallel = c_.steps[s].parallel;
      e.last_line = c_.steps[s].line;
      e.last_step = s;
      expect_step = false;
    } else {
      if (l.kw == "TRANSITION") {
        SfcTransition t;
        t.line = l.no;
        for (size_t k = 1; k < l.toks.size(); k++) {
          const std::string& w = l.toks[k].text;
          bool glued = k == 1 || w == ")" || l.toks[k - 1].text == "(" || l.toks[k - 1].text == "!";
          t.text += (glued ? "" : " ") + w;
        }
        bool has_cond = l.toks.size() >= 2 || l.refused;
        if (!has_cond) report(l.no, h.col, "a transition needs a condition (TRUE for none)");
        c_.steps[uint32_t(prev)].out.push_back(std::move(t));
        size_t idx = c_.steps[uint32_t(prev)].out.size() - 1;
        if (has_cond && !l.refused) conds_.push_back({uint32_t(prev), idx, pos_});
        e.pending = {{uint32_t(prev), idx}};
        pos_++;
      } else if (l.kw == "SELECT") {
        e.pending = select(scope, depth + 1, prev);
        if (e.pending.empty()) e.jumped = true;
      } else {
        if (l.kw == "JUMP") {
          report(l.no, h.col, "a jump follows a transition");
        } else if (l.kw == "STEP" || l.kw == "INITIAL" || l.kw == "PARALLEL") {
          if (!unknown_line_)  // (else the line refused above was the transition)
            report(l.no, h.col, first ? "a selection branch starts with its transition"
                                      : "expected a transition between two steps");
        } else {
          report(l.no, h.col, "expected a transition or 'select'; found '" + h.text + "'");
          pos_ = skip_line();  // the line stands for the transition
        }
        // a transition stands in for the missing one (a jump or step line is read next)
        c_.steps[uint32_t(prev)].out.push_back(SfcTransition{});
        c_.steps[uint32_t(prev)].out.back().line = l.no;
        e.pending = {{uint32_t(prev), c_.steps[uint32_t(prev)].out.size() - 1}};
      }
      unknown_line_ = false;
      e.last_is_plain_step = e.last_is_parallel = false;
      expect_step = true;
    }
    first = false;
  }
  return e;
}

// A step in place of a missing or refused one (error recovery only).
uint32_t SfcParser::stand_in_step(uint32_t scope, int line) {
  return new_step("step_line_" + std::to_string(line), line, scope);
}

// The line after the one at pos_ (after its body, if it opens one).
size_t SfcParser::skip_line() {
  size_t i = pos_;
  if (opens_body(lines_[i])) {
    i++;
    while (lines_[i].kw != "}") i++;
  }
  return i + 1;
}

// Skips the rest of a block: up to its 'branch' or 'end' (those of nested
// selections and simultaneous sequences skipped with them).
void SfcParser::skip_block() {
  int depth = 0;
  while (const Line* l = peek()) {
    if (depth == 0 && (l->kw == "BRANCH" || l->kw == "END")) return;
    if (l->kw == "SELECT" || l->kw == "PARALLEL") depth++;
    else if (l->kw == "END") depth--;
    pos_ = skip_line();
  }
}

// parallel = "parallel" branch { branch } "end" ;  branch = "branch" sequence
uint32_t SfcParser::parallel(uint32_t scope, int depth) {
  const Line& l = lines_[pos_++];
  if (depth > kMaxSfcNesting)
    throw Stop(l.no, l.toks[0].col, "selections and simultaneous sequences nested too deeply (at most " +
                                        std::to_string(kMaxSfcNesting) + ")");
  if (l.toks.size() != 1) report(l.no, l.toks[1].col, "unexpected text after 'parallel'");
  uint32_t s = new_step("parallel_line_" + std::to_string(l.no), l.no, scope);
  c_.steps[s].parallel = true;
  const Line* b;
  while ((b = peek()) && b->kw == "BRANCH") {
    if (b->toks.size() != 1) report(b->no, b->toks[1].col, "unexpected text after 'branch'");
    int bline = b->no, bcol = b->toks[0].col;
    pos_++;
    uint32_t sc = new_scope();
    c_.steps[s].branches.push_back(sc);
    SeqEnd e = sequence(sc, depth, -1, true, false);
    if (e.empty) report(bline, bcol, "empty simultaneous branch: a branch needs at least one step");
    else if (!e.last_is_plain_step)
      report(e.pending.empty() ? bline : c_.steps[e.pending[0].step].out[e.pending[0].index].line,
             e.pending.empty() ? bcol : col_of(c_.steps[e.pending[0].step].out[e.pending[0].index].line),
             "unbalanced join: a simultaneous branch must end with a step (the join waits for it)");
    c_.scopes[sc].last = e.last_step;
  }
  if (!b || b->kw != "END") {
    unclosed_ = true;
    report(l.no, l.toks[0].col, "unbalanced join: 'parallel' is not closed by 'end'");
    return s;
  }
  if (c_.steps[s].branches.size() < 2)
    report(b->no, b->toks[0].col, "a simultaneous sequence needs at least two branches");
  if (b->toks.size() != 1) report(b->no, b->toks[1].col, "unexpected text after 'end'");
  pos_++;
  return s;
}

// select = "select" branch { branch } "end" ;  branch = "branch" sequence (from a transition)
std::vector<PendingT> SfcParser::select(uint32_t scope, int depth, int prev) {
  const Line& l = lines_[pos_++];
  if (depth > kMaxSfcNesting)
    throw Stop(l.no, l.toks[0].col, "selections and simultaneous sequences nested too deeply (at most " +
                                        std::to_string(kMaxSfcNesting) + ")");
  if (l.toks.size() != 1) report(l.no, l.toks[1].col, "unexpected text after 'select'");
  std::vector<PendingT> all;
  int branches = 0;
  const Line* b;
  while ((b = peek()) && b->kw == "BRANCH") {
    if (b->toks.size() != 1) report(b->no, b->toks[1].col, "unexpected text after 'branch'");
    int bline = b->no, bcol = b->toks[0].col;
    pos_++;
    branches++;
    SeqEnd e = sequence(scope, depth, prev, false, false);
    if (e.empty) report(bline, bcol, "empty selection branch: a branch starts with its transition");
    else if (!e.jumped && e.pending.empty())
      report(e.last_line, col_of(e.last_line), "a selection branch must end with a transition (the selection joins after 'end') or a jump");
    all.insert(all.end(), e.pending.begin(), e.pending.end());
  }
  if (!b || b->kw != "END") {
    unclosed_ = true;
    report(l.no, l.toks[0].col, "'select' is not closed by 'end'");
    return all;
  }
  if (branches < 2) report(b->no, b->toks[0].col, "a selection needs at least two branches");
  if (b->toks.size() != 1) report(b->no, b->toks[1].col, "unexpected text after 'end'");
  pos_++;
  return all;
}

void SfcParser::resolve_jumps() {
  for (const Jump& j : jumps_) unit([&] {
    auto it = step_names_.find(upper(j.name.text));
    if (it == step_names_.end() && refused_names_.count(upper(j.name.text))) throw Cascade();  // its step line was refused
    if (it == step_names_.end()) fail(j.line, j.name.col, "unknown step '" + j.name.text + "'");
    uint32_t s = it->second;
    if (c_.steps[s].scope != j.scope)
      fail(j.line, j.name.col, "jump to step '" + j.name.text +
                                   "' in another sequence: a jump stays in its own sequence or simultaneous branch");
    for (const PendingT& p : j.from) c_.steps[p.step].out[p.index].target = s;
  });
}

// An error that names a refused alias or step ('NAME') follows from that
// refusal: a Cascade.
void SfcParser::quiet_if_refused(const CompileError& e) const {
  std::string m = upper(e.what());
  for (const std::string& n : refused_names_)
    if (m.find("'" + n + "'") != std::string::npos) throw Cascade();
}

// cond   = term { ("OR" | "|" | "||") term }
// term   = factor { ("AND" | "&" | "&&") factor }
// factor = ("NOT" | "!") factor | "(" cond ")" | "TRUE" | "FALSE" | BIT | VALUE cmp VALUE
// NOT is pushed down to the leaves (De Morgan), so the IL needs no negation of a block.
Cond SfcParser::condition(const std::vector<Tok>& t, size_t& i, bool neg, int line, int depth) {
  Cond c = term(t, i, neg, line, depth);
  while (i < t.size() && (upper(t[i].text) == "OR" || t[i].text == "|" || t[i].text == "||")) {
    i++;
    Cond r = term(t, i, neg, line, depth);
    c = neg ? c_and(std::move(c), std::move(r)) : c_or(std::move(c), std::move(r));
  }
  return c;
}

Cond SfcParser::term(const std::vector<Tok>& t, size_t& i, bool neg, int line, int depth) {
  Cond c = factor(t, i, neg, line, depth);
  while (i < t.size() && (upper(t[i].text) == "AND" || t[i].text == "&" || t[i].text == "&&")) {
    i++;
    Cond r = factor(t, i, neg, line, depth);
    c = neg ? c_or(std::move(c), std::move(r)) : c_and(std::move(c), std::move(r));
  }
  return c;
}

Cond SfcParser::factor(const std::vector<Tok>& t, size_t& i, bool neg, int line, int depth) {
  if (depth > 64) fail(line, t[std::min(i, t.size() - 1)].col, "condition nested too deeply");
  if (i >= t.size()) fail(line, t.back().col + int(t.back().text.size()), "the condition is incomplete");
  const Tok& w = t[i];
  std::string u = upper(w.text);
  if (u == "NOT" || u == "!") {
    i++;
    if (i >= t.size()) fail(line, w.col, "NOT needs an operand");
    return factor(t, i, !neg, line, depth + 1);
  }
  if (u == "(") {
    i++;
    Cond c = condition(t, i, neg, line, depth + 1);
    if (i >= t.size() || t[i].text != ")") fail(line, w.col, "'(' is not closed");
    i++;
    return c;
  }
  if (u == "TRUE" || u == "FALSE") {
    i++;
    return (u == "TRUE") != neg ? Cond::yes() : Cond::no();
  }
  if (!word_char(w.text[0]) && w.text[0] != '-') fail(line, w.col, "expected a bit, a compare, NOT or '(' here, found '" + w.text + "'");
  static const std::pair<const char*, Op> cmps[] = {{"=", Op::LDEQ},  {"==", Op::LDEQ}, {"<>", Op::LDNE}, {"!=", Op::LDNE},
                                                    {"<", Op::LDLT},  {"<=", Op::LDLE}, {">", Op::LDGT},  {">=", Op::LDGE}};
  TreeNode n;
  n.kind = K::Leaf;
  n.elem.loc = {line, w.col};
  n.text = w.text;
  const std::pair<const char*, Op>* cmp = nullptr;
  if (i + 1 < t.size())
    for (const auto& p : cmps)
      if (t[i + 1].text == p.first) cmp = &p;
  try {
    if (cmp) {
      if (i + 2 >= t.size()) fail(line, t[i + 1].col, std::string("a value is needed after '") + cmp->first + "'");
      n.elem.a[0] = value(w);
      n.elem.a[1] = value(t[i + 2]);
      Op op = cmp->second;
      if (neg) {
        if (n.elem.a[0].is_real() || n.elem.a[1].is_real())
          fail(line, w.col, "NOT of a REAL compare (false with NaN both ways): write the opposite compare");
        op = compare_op(negate(op_info(op).rel));
      }
      n.elem.op = op;
      n.text += std::string(" ") + cmp->first + " " + t[i + 2].text;
      i += 3;
    } else {
      n.elem.a[0] = bit(w, false);
      n.elem.op = neg ? Op::LOADN : Op::LOAD;
      i++;
    }
  } catch (CompileError& e) { fail(line, e.col, e.what()); }
  return Cond::of(std::move(n));
}

void SfcParser::read_conditions() {
  for (const Cond_& cd : conds_) unit([&] {
    try {
      read_condition(cd);
    } catch (const CompileError& e) {
      quiet_if_refused(e);
      throw;
    }
  });
}

void SfcParser::read_condition(const Cond_& cd) {
  {
    const Line& l = lines_[cd.line];
    size_t i = 1;
    if (l.toks.size() < 2) fail(l.no, l.toks[0].col, "a transition needs a condition");
    Cond c = condition(l.toks, i, false, l.no, 0);
    if (i < l.toks.size()) fail(l.no, l.toks[i].col, "unexpected '" + l.toks[i].text + "' in the condition");
    TreeNode n = c.k == Cond::Expr ? std::move(c.n) : false_leaf({l.no, l.toks[1].col}, "FALSE");
    TreeProgram tp;
    tp.source = file_;
    TreeRung r;
    r.line = l.no;
    TreeNode out;
    out.kind = K::Output;
    out.elem.op = Op::OUT;
    out.elem.a[0] = Operand{OpdKind::Bit, Area::M, 0};
    out.elem.loc = {l.no, l.toks[0].col};
    if (c.k == Cond::True) {
      r.root = out;
      r.root.elem.loc = {l.no, l.toks[1].col};
    } else {
      r.root.kind = K::Then;
      r.root.kids = {std::move(n), std::move(out)};
    }
    tp.rungs.push_back(std::move(r));
    Program p = lower_to_il(tp);
    std::vector<Instr> code = std::move(p.rungs[0].code);
    code.pop_back();  // the OUT: only the pushed condition is kept
    if (code.empty()) {
      Instr tr;
      tr.op = Op::TRUE;
      tr.loc = {l.no, l.toks[1].col};
      code.push_back(tr);
    }
    c_.steps[cd.step].out[cd.index].cond = std::move(code);
  }
}

// Labels made unique per body, edge slots moved after the chart's.
SfcBody SfcParser::lower_body(const TreeProgram& tp, Program p) {
  (void)tp;
  std::string prefix = "sfcb" + std::to_string(next_label_++) + "_";
  auto rename = [&](std::string& s) { s = prefix + upper(s); };
  SfcBody b;
  for (Rung& r : p.rungs) {
    for (auto& l : r.labels) rename(l);
    for (Instr& in : r.code)
      for (int k = 0; k < in.nopd(); k++) {
        if (in.a[k].kind == OpdKind::Label) in.a[k].label = prefix + upper(in.a[k].label.str());
        if (in.a[k].kind == OpdKind::Edge) in.a[k].index += c_.edge_slots;
      }
  }
  for (auto& l : p.end_labels) rename(l);
  if (uint64_t(c_.edge_slots) + p.edge_slots > (1u << 20)) fail(p.rungs.empty() ? 1 : p.rungs[0].line, 1, "too many edge instructions");
  c_.edge_slots += p.edge_slots;
  b.rungs = std::move(p.rungs);
  b.end_labels = std::move(p.end_labels);
  return b;
}

void SfcParser::read_bodies() {
  std::vector<Alias> known = aliases_;
  for (const SfcStep& s : c_.steps)
    if (!s.parallel) known.push_back({s.name, DeviceRef{Dev::M, c_.flag(uint32_t(&s - c_.steps.data()))}});
  for (const Body& bd : bodies_) unit([&] {
    try {
      read_body(bd, known);
    } catch (const CompileError& e) {
      quiet_if_refused(e);
      throw;
    }
  });
}

void SfcParser::read_body(const Body& bd, const std::vector<Alias>& known) {
  {
    int first_no = bd.first < lines_.size() ? lines_[bd.first].no : bd.header_line + 1;
    int shift = first_no - 1;  // body line 1 is file line first_no
    std::string text;
    bool any = false;
    for (size_t i = bd.first; i < bd.last; i++) {
      text += lines_[i].text + "\n";
      std::string t = lines_[i].text;
      t.erase(0, t.find_first_not_of(" \t"));
      if (!t.empty() && t[0] != '#' && t.rfind("//", 0) != 0 && t[0] != ';') any = true;
    }
    if (!any) fail(bd.header_line, 1, "empty action body");
    Program p;
    TreeProgram tp;
    try {
      if (bd.ladder) {
        tp = parse_ld(text, file_, known);
        for (TreeRung& r : tp.rungs) r.line += shift;
        std::vector<TreeNode*> stack;
        for (TreeRung& r : tp.rungs) stack.push_back(&r.root);
        while (!stack.empty()) {
          TreeNode* n = stack.back();
          stack.pop_back();
          if (n->elem.loc.line) n->elem.loc.line += shift;
          for (TreeNode& k : n->kids) stack.push_back(&k);
        }
        if (!tp.aliases.empty()) aliases_.insert(aliases_.end(), tp.aliases.begin(), tp.aliases.end());
        p = lower_to_il(tp);
      } else {
        // the body is IL text (docs/il.md) without `.rung line N` first and `.end` last
        shift = first_no - 2;
        p = parse_il_text(".rung line " + std::to_string(first_no) + "\n" + text + ".end\n", file_);
        for (Rung& r : p.rungs)
          for (Instr& in : r.code) in.loc.line += shift;
        if (!p.aliases.empty()) fail(bd.header_line, 1, "an IL action body cannot declare aliases (.alias)");
      }
    } catch (CompileError& e) {
      fail(e.line ? e.line + shift : bd.header_line, e.col, e.what());
    }
    for (Rung& r : p.rungs)
      for (Instr& in : r.code)
        if (in.op == Op::END) fail(in.loc.line, in.loc.col, "END in an action would end the whole scan; jump to a label instead");
    SfcBody b = lower_body(tp, std::move(p));
    SfcStep& st = c_.steps[bd.step];
    SfcBody& into = bd.on_entry ? st.on_entry : st.body;
    if (into.rungs.empty() && into.end_labels.empty()) into = std::move(b);
    else {
      for (Rung& r : b.rungs) {
        r.labels.insert(r.labels.begin(), into.end_labels.begin(), into.end_labels.end());
        into.end_labels.clear();
        into.rungs.push_back(std::move(r));
      }
      into.end_labels.insert(into.end_labels.end(), b.end_labels.begin(), b.end_labels.end());
    }
  }
}

// Actions may read the step flags but not write them.
void SfcParser::check_writes() {
  uint32_t lo = c_.flag_base, hi = c_.flag_base + 3 * uint32_t(c_.steps.size());
  auto check = [&](const Instr& in) {
    for (int k = 0; k < in.nopd(); k++)
      if (op_info(in.op).operands[k] == 'w' && in.a[k].area == Area::M && in.a[k].index >= lo && in.a[k].index < hi)
        fail(in.loc.line, in.loc.col, "M" + std::to_string(in.a[k].index) + " is a step flag (M" + std::to_string(lo) +
                                          "..M" + std::to_string(hi - 1) + "): actions may read it, not write it");
  };
  if (flags_refused_) return;  // where the flags would have been is not known
  for (const SfcStep& s : c_.steps) unit([&] {  // a step's first such write
    for (const Instr& in : s.bits) check(in);
    for (const SfcBody* b : {&s.on_entry, &s.body})
      for (const Rung& r : b->rungs)
        for (const Instr& in : r.code) check(in);
  });
  for (const SfcNBit& n : c_.nbits)
    if (n.bit.area == Area::M && n.bit.index >= lo && n.bit.index < hi) unit([&] {
      Instr in;
      in.op = Op::OUT;
      in.a[0] = n.bit;
      in.loc = {c_.steps[n.steps[0]].line, 1};
      check(in);
    });
}

// chart = { decl } sequence EOF    (the sequence starts with the initial step)
Chart SfcParser::chart() {
  read_lines();
  declarations();
  c_.source = file_;
  new_scope();
  int errors0 = diag_ ? diag_->errors() : 0;
  SeqEnd e = sequence(0, 0, -1, true, true);
  if (c_.steps.empty() && !(diag_ && diag_->errors() > errors0))
    fail(std::max(1, int(lines_.size())), 1, "no steps: a chart starts with 'initial step NAME'");
  if (!e.pending.empty() && !unclosed_)
    report(c_.steps[e.pending[0].step].out[e.pending[0].index].line,
           col_of(c_.steps[e.pending[0].step].out[e.pending[0].index].line), "transition to nowhere: a step or a jump must follow it");
  if (e.last_is_parallel && !unclosed_)
    report(e.last_line, col_of(e.last_line), "unbalanced join: this simultaneous sequence is never joined (add a transition after its 'end')");
  resolve_jumps();
  read_conditions();
  read_bodies();
  check_writes();
  c_.initial = 0;
  c_.aliases = aliases_;
  for (const SfcStep& s : c_.steps)
    if (!s.parallel) c_.aliases.push_back({s.name, DeviceRef{Dev::M, c_.flag(uint32_t(&s - c_.steps.data()))}});
  return c_;
}

// Reads one unit (a declaration, a step line, an action, a jump, a condition,
// a body): without diagnostics its error is thrown; with them it is reported
// (not a Cascade), and false says the unit was refused.  A Stop goes on up.
bool SfcParser::unit(const std::function<void()>& read) { return recover_unit(diag_, file_, read); }

}  // namespace

Chart parse_sfc(std::string_view text, const std::string& filename) { return SfcParser(text, filename).chart(); }

Chart parse_sfc(std::string_view text, const std::string& filename, Diagnostics& diag) {
  int errors0 = diag.errors();
  Chart c;
  try {
    c = SfcParser(text, filename, &diag).chart();
  } catch (const CompileError& e) {  // a Stop: a limit of the whole chart, or a body not closed
    diag.error(filename, e);
  }
  if (diag.errors() > errors0) throw ErrorsReported();
  return c;
}

}  // namespace ldc
