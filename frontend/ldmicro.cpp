// frontend/ldmicro.cpp -- the LDmicro importer (docs/ldmicro.md).
//
// An LDmicro file lists each rung as a series of elements, with PARALLEL and
// SERIES blocks.  LDmicro runs a rung by passing one "rung state" bit through
// that list from left to right: a contact or a compare clears it, a coil copies
// it into a bit, a timer or counter replaces it by its own output, a one-shot
// by an edge of it.  Every element executes on every scan.
//
// We translate a rung into a chain of our tree nodes that computes exactly the
// same sequence: the rung state lives on our bit stack (Then/Fork), conditions
// narrow it (a nested Then), outputs hang on it (Fork items), and an element
// whose output is not "state AND something" (a TOF, a counter, a falling
// one-shot...) ends the chain: the next chain starts from the rail with the
// element's output as its condition.  Where a value must survive a chain break
// it is copied into an internal relay of its own (an M allocated after every
// named device).  No new IL is needed; docs/ldmicro.md lists each mapping.
#include <algorithm>
#include <array>
#include <cctype>
#include <climits>
#include <functional>
#include <map>
#include <optional>
#include <set>

#include "frontend/diag.h"
#include "frontend/frontend.h"
#include "frontend/operands.h"
#include "frontend/ldmicro_format.h"
#include "frontend/ldmicro_segments.h"
#include "frontend/treebuild.h"

namespace ldc {
namespace {

using K = TreeNode::Kind;
using namespace treebuild;

[[noreturn]] void fail(int line, int col, const std::string& msg) { throw CompileError(line, col, msg); }

std::string trim(std::string_view s) {
  size_t a = s.find_first_not_of(" \t"), b = s.find_last_not_of(" \t");
  return a == std::string_view::npos ? std::string() : std::string(s.substr(a, b - a + 1));
}

// ------------------------------------------------------------------ source

struct Elem {
  std::string kw;                 // CONTACTS, COIL, ..., SERIES, PARALLEL
  std::vector<std::string> args;  // words after the keyword
  std::vector<int> cols;          // their columns
  std::string rest;               // the text after the keyword (COMMENT)
  std::string text;               // the whole line (STRING's format)
  int line = 0, col = 0;
  std::vector<Elem> kids;  // SERIES / PARALLEL
  SrcLoc loc() const { return {line, col}; }
};

struct SrcRung {
  int line = 0;
  int ldm_index = 0;  // LDmicro's rung number - 1, comment rungs counted
  std::vector<Elem> series;
  bool refused = false;  // an error was reported in it: not translated
};

// ------------------------------------------------------------------ conditions

TreeNode then_node(Cond c, TreeNode action, SrcLoc loc) {
  if (c.k == Cond::True) return action;
  TreeNode cn = c.k == Cond::False ? false_leaf(loc, "0 <> 0") : std::move(c.n);
  if (action.kind == K::Then) {  // Then(a, Then(b, X)) = Then(a AND b, X): same order of evaluation
    TreeNode t;
    t.kind = K::Then;
    t.kids.push_back(make_combined(K::Series, std::move(cn), std::move(action.kids[0])));
    t.kids.push_back(std::move(action.kids[1]));
    return t;
  }
  TreeNode t;
  t.kind = K::Then;
  t.kids.push_back(std::move(cn));
  t.kids.push_back(std::move(action));
  return t;
}

// The chains of one rung.  `frames` is the open chain: frames[0] starts at the
// rail, each further frame narrows the rung state by its condition; actions
// are added to the innermost frame and run under the state it holds.
struct Frame {
  Cond cond;
  std::vector<TreeNode> items;
  SrcLoc loc;
};

class RungBuilder {
 public:
  std::vector<TreeNode> top;  // finished chains, in order
  std::vector<Frame> frames;
  int gen = 0;  // bumped whenever the open chain is closed

  void start(Cond c, SrcLoc loc) {
    frames.clear();
    frames.push_back({std::move(c), {}, loc});
  }
  void narrow(Cond c, SrcLoc loc) { frames.push_back({std::move(c), {}, loc}); }
  void add(TreeNode action) { frames.back().items.push_back(std::move(action)); }
  void pop_to(size_t depth) {
    while (frames.size() > depth) {
      Frame f = std::move(frames.back());
      frames.pop_back();
      if (auto n = close(std::move(f))) frames.back().items.push_back(std::move(*n));
    }
  }
  void close_chain() {
    if (frames.empty()) return;
    pop_to(1);
    if (auto n = close(std::move(frames[0]))) top.push_back(std::move(*n));
    frames.clear();
    gen++;
  }
  void restart(Cond c, SrcLoc loc) {
    close_chain();
    start(std::move(c), loc);
  }
  // A chain of its own: close the open one first; the caller restarts.
  void chain(Cond c, TreeNode action, SrcLoc loc) {
    close_chain();
    top.push_back(then_node(std::move(c), std::move(action), loc));
  }

 private:
  static std::optional<TreeNode> close(Frame f) {
    if (f.items.empty()) return std::nullopt;  // a condition nobody reads
    return then_node(std::move(f.cond), fork_of(std::move(f.items)), f.loc);
  }
};

// ------------------------------------------------------------------ names

enum class NK { Bit, Timer, Counter, Var, Adc, Pwm, Str };

struct Name {
  NK kind = NK::Var;
  DeviceRef dev{Dev::D, 0};
  DeviceRef held{Dev::D, 0};  // Adc: the variable READ_ADC writes
  std::string timer_kind;     // TON, TOF, RTO, TCY
  int line = 0, col = 0;      // first use
};

const char* kind_word(NK k) {
  switch (k) {
    case NK::Bit: return "a bit";
    case NK::Timer: return "a timer";
    case NK::Counter: return "a counter";
    case NK::Var: return "an integer variable";
    case NK::Adc: return "an A/D input";
    case NK::Pwm: return "a PWM output";
    case NK::Str: return "a string variable";
  }
  return "";
}

// Elements ldc refuses, with the reason.
const std::map<std::string, std::string>& unsupported() {
  static const std::map<std::string, std::string> m = [] {
    std::map<std::string, std::string> r;
    for (const char* k : {"UART_SENDn", "UART_RECVn"})
      r[k] = "LDmicro's own compiler no longer translates it (its code is disabled); use UART_SEND or UART_RECV, one byte at a time";
    r["UART_WR"] = "LDmicro's own reader and compiler no longer translate it (their code is disabled); use UART_SEND of a string variable";
    for (const char* k : {"CPRINTF", "SPRINTF", "FPRINTF", "PRINTF", "I2C_PRINTF", "ISP_PRINTF", "UART_PRINTF"})
      r[k] = "LDmicro itself neither reads nor compiles it (its file reader has no entry for it, its compiler no translation); "
             "use STRING and UART_SEND of a string variable";
    for (const char* k : {"GOSUB", "RETURN", "SUBPROG", "ENDSUB"}) r[k] = "LDmicro subroutines are not translated";
    r["SLEEP"] = "it stops the microcontroller until a wake-up event, which an ldc scan cannot do";
    for (const char* k : {"STEPPER", "PULSER", "NPULSE", "NPULSE_OFF", "QUAD_ENCOD"})
      r[k] = "pulse generators and encoders are microcontroller hardware with no ldc equivalent";
    r["ODR"] = "ldc has no translation for it";
    for (const char* k : {"RSFR", "WSFR", "SSFR", "CSFR", "TSFR", "TCSFR"}) r[k] = "microcontroller special function registers do not exist in ldc";
    return r;
  }();
  return m;
}

// The UART elements whose output is a UART flag, whatever their input
// (LDmicro's loader reads UART_SEND_BUSY and UART_UDRE as UART_SEND_READY).
bool is_uart_flag(const std::string& kw) {
  return kw == "UART_RECV_AVAIL" || kw == "UART_SEND_READY" || kw == "UART_SEND_BUSY" || kw == "UART_UDRE";
}
bool is_uart(const std::string& kw) { return kw == "UART_SEND" || kw == "UART_RECV" || is_uart_flag(kw); }

// The UART's fixed devices (docs/ldmicro.md, "UART"): reserved before any
// name is allocated, so that no LDmicro name can land on them.
constexpr uint32_t kUartRx = 1023;    // WX: (sequence << 8) | byte, written by the environment
constexpr uint32_t kUartTx = 1023;    // WY: (sequence << 8) | byte, written by UART_SEND
constexpr uint32_t kUartSeen = 8191;  // D: the last receive word consumed
constexpr uint32_t kUartBusy = 8191;  // M: a byte was sent in this scan
// The SPI and I2C elements (docs/ldmicro.md, "SPI and I2C"): one WY word per
// byte sent and one WX word per byte received, from 1022 down, in program order;
// one D counts the transfers of both buses.
constexpr uint32_t kBusTop = 1022;
constexpr uint32_t kBusSeq = 8190;

bool is_bus(const std::string& k) { return k == "SPI" || k == "SPI_WR" || k == "I2C_RD" || k == "I2C_WR"; }

std::string alias_spelling(const std::string& nm);

bool is_timer_kw(const std::string& k) {
  return k == "TON" || k == "TOF" || k == "RTO" || k == "TCY" || k == "RTL" || k == "THI" || k == "TLO";
}

bool is_segments(const std::string& k) { return k == "7SEGMENTS" || k == "9SEGMENTS" || k == "14SEGMENTS" || k == "16SEGMENTS"; }

bool is_pure_kw(const std::string& kw) {
  static const std::set<std::string> s = {"CONTACTS", "EQU", "NEQ", "GRT", "GEQ", "LES", "LEQ", "SHORT", "OPEN", "COMMENT"};
  return s.count(kw) > 0;
}

// The sizes of a STRING conversion's field (docs/ldmicro.md, "Strings"): the
// digits an INT32 can have in its base, the longest sign or prefix, the fewest
// and most digits printed (precision and zero padding included), and the
// fewest and most characters of sign, prefix and digits together.
struct FieldSizes {
  int maxd = 1, plmax = 0, nzmin = 1, nzmax = 1, cmin = 1, cmax = 1;
};

FieldSizes field_sizes(const ldmicro_format::Spec& s) {
  FieldSizes z;
  if (s.conv == 'c') return z;
  bool hex = s.conv == 'x' || s.conv == 'X', oct = s.conv == 'o';
  bool zero_pad = s.zero && !s.minus && s.prec < 0;
  z.maxd = hex ? 8 : oct ? 11 : 10;
  z.plmax = s.conv == 'd' ? 1 : hex && s.alt ? 2 : 0;
  z.nzmin = s.prec == 0 ? (oct && s.alt ? 1 : 0) : std::max(1, s.prec);
  z.nzmax = std::max({z.maxd + (oct && s.alt ? 1 : 0), s.prec, zero_pad ? s.width : 0});
  z.cmin = z.nzmin + (s.conv == 'd' && (s.plus || s.space) ? 1 : 0);
  if (zero_pad) z.cmin = std::max(z.cmin, s.width);
  z.cmax = z.nzmax + z.plmax;
  return z;
}

// The longest text a STRING with this format makes.
int format_max(const ldmicro_format::Format& f) {
  if (!f.has_spec) return int(f.before.size());
  return int(f.before.size() + f.after.size()) + std::max(f.spec.width, field_sizes(f.spec).cmax);
}

// ------------------------------------------------------------------ importer

class Importer {
 public:
  Importer(std::string_view text, std::string file, Diagnostics* diag = nullptr)
      : text_(text), file_(std::move(file)), diag_(diag) {}
  TreeProgram run();

 private:
  struct Line {
    std::string text;
    int no;
  };
  std::string_view text_;
  std::string file_;
  // Error recovery (docs/diagnostics.md): with diag_, an error in a setting
  // or I/O-list line, or in a rung, is reported and the import goes on with
  // the next line or rung.
  Diagnostics* diag_;
  bool cycle_refused_ = false;  // the CYCLE= line was refused: the timers say nothing about it
  bool rung_refused_ = false;   // a rung was refused: its labels and names are unknown
  bool unit(const std::function<void()>& read);
  std::vector<Line> lines_;
  bool v01_ = false;          // "LDmicro0.1": the classic semantics (docs/ldmicro.md)
  int64_t cycle_us_ = 10000;  // LDmicro's default
  int cycle_line_ = 0;
  int64_t crystal_hz_ = -1;  // CRYSTAL=, for TIME2DELAY
  std::string micro_;        // MICRO=
  std::vector<std::pair<std::string, int>> io_list_;  // names in IO LIST order, with their line
  std::vector<SrcRung> rungs_;
  std::vector<std::string> titles_;  // per rung: the COMMENT rung above it, if any

  std::map<std::string, Name> names_;
  std::vector<std::string> order_;  // first appearance
  uint32_t next_[11] = {};          // next free index per Dev
  std::set<std::pair<int, uint32_t>> used_;
  std::vector<Alias> aliases_;
  Spellings spelled_;  // device -> LDmicro name (for --emit=tree)
  int depth_ = 0;
  static constexpr int kMaxNesting = 100;
  bool mcr_used_ = false;
  bool uart_used_ = false;
  std::vector<DeviceRef> persist_;  // PERSIST variables, in order
  std::set<uint32_t> frozen_;  // relays written once per scan, before they are read
  uint32_t mcr_ = 0;
  std::vector<TreeNode> init_;  // first-scan initialisations
  std::map<std::string, int> width_;  // VAR LIST: a variable's width in bytes (1..4)
  std::map<std::string, int64_t> var_bytes_;  // VAR LIST: every entry's size in bytes (strings too)
  // STRING destinations (docs/ldmicro.md, "Strings"): the name's D word holds
  // the length, `cells` one character per word; `need` is the longest text
  // any STRING writing it can make.
  struct StrVar {
    int need = 0;
    std::vector<uint32_t> cells;
  };
  std::map<std::string, StrVar> strs_;
  std::map<std::pair<int, int>, ldmicro_format::Format> formats_;  // STRING element (line, col) -> its text

  RungBuilder rb_;

  // source
  void read_lines();
  void var_list_entry(const std::string& u);
  size_t header();
  void program(size_t i);
  size_t series(size_t i, std::vector<Elem>& out, const Line& open);
  size_t parallel(size_t i, std::vector<Elem>& out, const Line& open);
  [[noreturn]] void unclosed(const Line& open);
  Elem leaf(const Line& l);
  void check_leaf(const Elem& e);

  // names
  void note(const std::string& name, NK kind, int line, int col, const std::string& tkind = "");
  void collect(const Elem& e);
  void allocate();
  uint32_t take(Dev d, int line, int col);
  uint32_t temp_m(const Elem& e) { return take(Dev::M, e.line, e.col); }
  uint32_t temp_d(const Elem& e) { return take(Dev::D, e.line, e.col); }
  bool is_number(const std::string& s) const;
  int32_t number(const std::string& s, int line, int col) const;
  Operand value(const Elem& e, size_t arg, bool dest = false);
  Name& name_of(const Elem& e, size_t arg);
  std::string spell(const Operand& o) const;

  // translation
  void translate(const SrcRung& r, size_t index);
  size_t rung_now_ = 0;
  std::map<std::string, size_t> labels_;  // LABEL name -> index in rungs_
  std::set<size_t> targets_;              // rungs_ indices some GOTO jumps to
  size_t goto_target(const Elem& e);
  void series_code(const std::vector<Elem>& s, bool need_out);
  void element(const Elem& e, bool need_out);
  void parallel_code(const Elem& e, bool need_out);
  std::optional<Cond> pure(const Elem& e);
  bool breaks(const Elem& e) const;
  Cond materialize(const Elem& e);
  TreeNode leaf_node(Op op, std::vector<Operand> a, const Elem& e);
  TreeNode out_node(Op op, std::vector<Operand> a, const Elem& e);
  Cond bit_leaf(Op op, Area a, uint32_t i, const Elem& e) { return Cond::of(leaf_node(op, {bit_opd(a, i)}, e)); }
  int32_t timer_ms(const Elem& e, const Name& n);
  int32_t cycle_ms(const Elem& e);
  void timer(const Elem& e);
  void counter(const Elem& e);
  void coil(const Elem& e);
  void uart(const Elem& e);
  std::vector<TreeNode> uart_send_nodes(const Operand& byte, const Elem& e);
  void formatted_string(const Elem& e);
  void plan_string(const Elem& e);
  void string_elem(const Elem& e);
  std::vector<TreeNode> string_digits(const ldmicro_format::Spec& s, const Operand& v, const std::vector<Operand>& r, const Operand& c,
                                      const Elem& e);
  std::vector<TreeNode> string_layout(const ldmicro_format::Format& f, int cv, const std::vector<Operand>& r, const StrVar& sv,
                                      const Operand& len, const Elem& e);
  void uart_send_string(const Elem& e);
  struct BusWords { std::vector<uint32_t> tx; int rx = -1; };
  std::map<std::pair<int, int>, BusWords> bus_words_;  // element (line, col) -> its words
  std::vector<Alias> bus_aliases_;
  int spi_bytes_ = 0, i2c_bytes_ = 0;
  std::map<std::string, uint32_t> seeds_;  // RANDOM: each variable's seed word
  void plan_bus(const Elem& e);
  void bus_transfer(const Elem& e);
  int width_of(const std::string& name) const;
  std::vector<TreeNode> wrap_nodes(const Operand& d, int bytes, const Elem& e);
  void wrap(const Elem& e, size_t arg);
  int arg_width(const Elem& e, size_t arg) const;
  void bit_op(const Elem& e);
  void bcd(const Elem& e);
  void segments(const Elem& e);
  void bus(const Elem& e);
  void move_to_timer(const Elem& e);
  Operand narrow_literal(const Elem& e, size_t lit, size_t var);
};

void Importer::read_lines() {
  int no = 0;
  for (std::string& l : source_lines(text_)) lines_.push_back({std::move(l), ++no});
}

// header = "LDmicro" [version] { setting | IO LIST | VAR LIST | other } "PROGRAM"
// Returns the index of the PROGRAM line.
size_t Importer::header() {
  std::string first = lines_.empty() ? "" : lines_[0].text;
  if (first.rfind("\xEF\xBB\xBF", 0) == 0) first = first.substr(3);
  first = trim(first);
  v01_ = first == "LDmicro0.1";
  for (size_t i = 1; i < lines_.size(); i++) {
    const Line& l = lines_[i];
    std::string t = trim(l.text);
    if (t.empty()) continue;
    if (t == "PROGRAM") return i;
    if (t.rfind("CYCLE=", 0) == 0) {
      cycle_refused_ = !unit([&] {
        size_t e = 6;
        while (e < t.size() && std::isdigit((unsigned char)t[e])) e++;
        if (e == 6 || e - 6 > 12) fail(l.no, 7, "expected the cycle time in microseconds after CYCLE=");
        cycle_us_ = std::stoll(t.substr(6, e - 6));
        if (cycle_us_ > 2000000000) fail(l.no, 7, "cycle time too long (at most 2000000000 us)");
        cycle_line_ = l.no;
      });
      continue;
    }
    if (t.rfind("CRYSTAL=", 0) == 0) {
      size_t e = 8;
      while (e < t.size() && std::isdigit((unsigned char)t[e])) e++;
      if (e > 8 && e - 8 <= 12) crystal_hz_ = std::stoll(t.substr(8, e - 8));
      continue;
    }
    if (t.rfind("MICRO=", 0) == 0) {
      micro_ = t.substr(6);
      continue;
    }
    if (t == "IO LIST" || t == "VAR LIST" || t == "PULL-UP LIST") {
      bool io = t == "IO LIST";
      size_t j = i + 1;
      bool unclosed = false;  // the PROGRAM line came first: the list ends there
      bool refused_entry = false;  // (then a refused entry was its END, most likely)
      for (; j < lines_.size(); j++) {
        std::string u = trim(lines_[j].text);
        if (u == "END") break;
        if (u == "PROGRAM") {
          unclosed = true;
          break;
        }
        if (u.empty()) continue;
        if (!io) {
          if (t == "VAR LIST") var_list_entry(u);
          continue;
        }
        // "name at pin [...]"
        size_t sp = u.find_first_of(" \t");
        std::string name = u.substr(0, sp);
        std::string after = sp == std::string::npos ? "" : trim(u.substr(sp));
        refused_entry |= !unit([&] {
          if (after.rfind("at", 0) != 0) fail(lines_[j].no, int(lines_[j].text.find(u)) + 1, "expected 'name at pin' in the IO LIST");
          io_list_.push_back({name, lines_[j].no});
        });
      }
      if (j == lines_.size()) fail(l.no, 1, t + " is not closed by END");
      if (unclosed) {  // reported, and the PROGRAM line read next
        if (!refused_entry) unit([&] { fail(l.no, 1, t + " is not closed by END (before PROGRAM on line " + std::to_string(lines_[j].no) + ")"); });
        j--;
      }
      i = j;
      continue;
    }
    // MICRO=, CRYSTAL=, BAUD=, COMPILED=, COMPILER= and anything newer: LDmicro
    // ignores lines it does not know, and so do we.
  }
  fail(int(lines_.size()), 1, "no PROGRAM line: an LDmicro file lists its rungs after a line 'PROGRAM'");
}

// VAR LIST lines read "N bytes name [comment]".  Widths 1 to 4 are integer
// variables; longer entries are LDmicro's strings and tables, which keep no width.
void Importer::var_list_entry(const std::string& u) {
  size_t a = u.find(' ');
  if (a == std::string::npos) return;
  std::string n = u.substr(0, a), rest = trim(u.substr(a));
  if (rest.rfind("bytes", 0) != 0 || n.empty() || !std::all_of(n.begin(), n.end(), [](char c) { return std::isdigit((unsigned char)c); })) return;
  std::string name = trim(rest.substr(5));
  name = name.substr(0, name.find_first_of(" \t"));
  if (name.empty() || n.size() > 6) return;
  int w = std::stoi(n);
  var_bytes_[name] = w;
  if (w >= 1 && w <= 4) width_[name] = w;
}

Elem Importer::leaf(const Line& l) {
  Elem e;
  e.line = l.no;
  e.text = l.text;
  size_t st = l.text.find_first_not_of(" \t");
  e.col = int(st) + 1;
  size_t i = st;
  auto word = [&](std::string& w, int& c) {
    while (i < l.text.size() && (l.text[i] == ' ' || l.text[i] == '\t')) i++;
    if (i >= l.text.size()) return false;
    size_t s = i;
    while (i < l.text.size() && l.text[i] != ' ' && l.text[i] != '\t') i++;
    w = l.text.substr(s, i - s);
    c = int(s) + 1;
    return true;
  };
  int c;
  word(e.kw, c);
  e.rest = i < l.text.size() ? l.text.substr(std::min(l.text.size(), i + 1)) : "";
  std::string w;
  while (word(w, c)) {
    e.args.push_back(w);
    e.cols.push_back(c);
  }
  return e;
}

void Importer::unclosed(const Line& open) {
  std::string t = trim(open.text);
  fail(open.no, int(open.text.find_first_not_of(" \t")) + 1, t.substr(0, t.find(' ')) + " is not closed by END before the end of the file");
}

size_t Importer::series(size_t i, std::vector<Elem>& out, const Line& open) {
  if (++depth_ > kMaxNesting) fail(open.no, 1, "SERIES and PARALLEL nested too deeply (more than " + std::to_string(kMaxNesting) + " levels)");
  struct Leave { int& d; ~Leave() { d--; } } leave{depth_};
  for (; i < lines_.size(); i++) {
    const Line& l = lines_[i];
    std::string t = trim(l.text);
    if (t.empty() || t[0] == ';') continue;
    int col = int(l.text.find_first_not_of(" \t")) + 1;
    if (t == "END") return i;
    if (t == "PARALLEL" || t == "SERIES") {
      Elem e;
      e.kw = t;
      e.line = l.no;
      e.col = col;
      i = t == "PARALLEL" ? parallel(i + 1, e.kids, l) : series(i + 1, e.kids, l);
      out.push_back(std::move(e));
      continue;
    }
    Elem e = leaf(l);
    check_leaf(e);
    out.push_back(std::move(e));
  }
  unclosed(open);
}

size_t Importer::parallel(size_t i, std::vector<Elem>& out, const Line& open) {
  if (++depth_ > kMaxNesting) fail(open.no, 1, "SERIES and PARALLEL nested too deeply (more than " + std::to_string(kMaxNesting) + " levels)");
  struct Leave { int& d; ~Leave() { d--; } } leave{depth_};
  for (; i < lines_.size(); i++) {
    const Line& l = lines_[i];
    std::string t = trim(l.text);
    if (t.empty() || t[0] == ';') continue;
    int col = int(l.text.find_first_not_of(" \t")) + 1;
    if (t == "END") return i;
    if (t == "PARALLEL") fail(l.no, col, "PARALLEL directly inside PARALLEL; LDmicro nests them through SERIES");
    if (t == "SERIES") {
      Elem e;
      e.kw = t;
      e.line = l.no;
      e.col = col;
      i = series(i + 1, e.kids, l);
      out.push_back(std::move(e));
      continue;
    }
    Elem e = leaf(l);
    check_leaf(e);
    out.push_back(std::move(e));
  }
  unclosed(open);
}

// The arity of every element we translate; unknown and refused ones end here.
void Importer::check_leaf(const Elem& e) {
  auto arity = [&](size_t lo, size_t hi, const char* form) {
    if (e.args.size() < lo || e.args.size() > hi)
      fail(e.line, e.col, std::string("expected ") + form + " (" + std::to_string(e.args.size()) + " field" +
                              (e.args.size() == 1 ? "" : "s") + " found)");
  };
  const std::string& k = e.kw;
  if (auto it = unsupported().find(k); it != unsupported().end())
    fail(e.line, e.col, "LDmicro element '" + k + "' is not supported: " + it->second);
  if (k == "COMMENT") return;
  if (k == "CONTACTS") arity(2, 3, "CONTACTS name negated [set1]");
  else if (k == "COIL") arity(4, 5, "COIL name negated setOnly resetOnly [toggle]");
  else if (is_timer_kw(k)) arity(2, 3, (k + " name delay [adjust]").c_str());
  else if (k == "CTU" || k == "CTD" || k == "CTC" || k == "CTR") arity(2, 4, (k + " name max [init [inputKind]]").c_str());
  else if (k == "RES") arity(1, 1, "RES name");
  else if (k == "MOVE") arity(2, 2, "MOVE destination source");
  else if (k == "ADD" || k == "SUB" || k == "MUL" || k == "DIV" || k == "MOD" || k == "AND" || k == "OR" || k == "XOR" || k == "SHL")
    arity(3, 3, (k + " destination operand1 operand2").c_str());
  else if (k == "NOT" || k == "NEG") arity(2, 2, (k + " destination operand").c_str());
  else if (k == "EQU" || k == "NEQ" || k == "GRT" || k == "GEQ" || k == "LES" || k == "LEQ") arity(2, 2, (k + " operand1 operand2").c_str());
  else if (k == "OSR" || k == "OSF" || k == "OSL" || k == "OSC" || k == "SHORT" || k == "OPEN" || k == "MASTER_RELAY" || k == "CLRWDT" || k == "LOCK")
    arity(0, 0, k.c_str());
  else if (k == "DELAY") arity(1, 1, "DELAY microseconds");
  else if (k == "RANDOM") arity(1, 1, "RANDOM variable");
  else if (k == "GOTO" || k == "LABEL") arity(1, 1, (k + " label").c_str());
  else if (k == "SEED_RANDOM") arity(2, 2, "SEED_RANDOM variable seed");
  else if (k == "PLACEHOLDER") fail(e.line, e.col, "empty row (PLACEHOLDER); delete it or add instructions, as LDmicro itself requires");
  else if (k == "SHIFT_REGISTER") arity(2, 2, "SHIFT_REGISTER name stages");
  else if (k == "LOOK_UP_TABLE") {
    if (e.args.size() < 4) fail(e.line, e.col, "expected LOOK_UP_TABLE destination index count asString values...");
  } else if (k == "PIECEWISE_LINEAR") {
    if (e.args.size() < 3) fail(e.line, e.col, "expected PIECEWISE_LINEAR destination index count points...");
  } else if (k == "READ_ADC") arity(1, 2, "READ_ADC name [refs]");
  // An older LDmicro saved the resolution as its dialog shows it, spaces and all
  // ("0-100% (6.7 bits)"); LDmicro's reader takes the first word of it and
  // drops the rest (loadsave.cpp, LoadLeafFromFile: sscanf "SET_PWM %s %s %s %s").
  else if (k == "SET_PWM") {
    if (e.args.size() < 2) arity(2, 4, "SET_PWM duty frequency [name [resolution]]");
  }
  else if (k == "SET_BIT" || k == "CLEAR_BIT" || k == "IF_BIT_SET" || k == "IF_BIT_CLEAR") arity(2, 2, (k + " variable bit").c_str());
  else if (k == "UART_SEND" || k == "UART_RECV") arity(1, 3, (k + " variable [bytes wait]").c_str());
  else if (is_uart_flag(k)) arity(0, 0, k.c_str());
  else if (k == "PERSIST") arity(1, 1, "PERSIST variable");
  else if (k == "ROL" || k == "ROR" || k == "SHR" || k == "SR0") arity(3, 3, (k + " destination operand bits").c_str());
  else if (k == "BIN2BCD" || k == "BCD2BIN" || k == "SWAP" || k == "OPPOSITE") arity(2, 2, (k + " destination source").c_str());
  // LDmicro saves TIME2COUNT as a timer, with its adjust field, but reads back
  // only the name and the delay (sscanf "TIME2COUNT %s %s" == 2): the third
  // field is written and never read.
  else if (k == "TIME2COUNT") arity(2, 3, "TIME2COUNT variable delay [adjust]");
  else if (k == "TIME2DELAY") arity(2, 2, "TIME2DELAY variable delay");
  else if (is_bus(k)) {
    arity(8, 8, (k + (k[0] == 'S' ? " name send receive mode modes size first bitrate" : " name send receive mode address register first bitrate")).c_str());
    if (k[0] == 'S' && e.args[5] != "8") fail(e.line, e.cols[5], "SPI transfers of " + e.args[5] + " bits are not supported: ldc's SPI model moves bytes");
  } else if (k == "STRING") {
    if (e.args.size() < 3) fail(e.line, e.col, "expected STRING destination variable format");
  } else if (k == "FORMATTED_STRING") {
    if (e.args.size() < 2) fail(e.line, e.col, "expected FORMATTED_STRING variable length characters... or FORMATTED_STRING variable text");
  }
  else if (is_segments(k)) {
    arity(3, 3, (k + " destination source common").c_str());
    if (e.args[2] != "C" && e.args[2] != "A") fail(e.line, e.cols[2], "expected C (common cathode) or A (common anode), found '" + e.args[2] + "'");
  } else if (k == "BUS") {
    arity(10, 10, "BUS destination source bit0 .. bit7");
    for (size_t i = 2; i < 10; i++)
      if (!is_number(e.args[i]) || number(e.args[i], e.line, e.cols[i]) < 0 || number(e.args[i], e.line, e.cols[i]) > 7)
        fail(e.line, e.cols[i], "BUS bit numbers are 0..7");
  }
  else fail(e.line, e.col, "unknown LDmicro element '" + k + "'");
}

// "RUNG" or "RUNG n": the first line of a rung
static bool is_rung_line(const std::string& t) {
  return t.rfind("RUNG", 0) == 0 && (t.size() == 4 || t[4] == ' ' || t[4] == '\t');
}

// program = { "RUNG" [n] series "END" }
void Importer::program(size_t i) {
  std::string title;
  int count = 0;
  for (i++; i < lines_.size(); i++) {
    const Line& l = lines_[i];
    std::string t = trim(l.text);
    if (t.empty() || t[0] == ';') continue;
    int col = int(l.text.find_first_not_of(" \t")) + 1;
    SrcRung r;
    size_t first = i;
    bool read = unit([&] {
      if (!is_rung_line(t)) fail(l.no, col, "expected RUNG, found '" + t + "'");
      r.line = l.no;
      r.ldm_index = count++;
      i = series(i + 1, r.series, l);
    });
    if (!read) {  // on to the next RUNG line
      rung_refused_ = true;
      for (i = first + 1; i < lines_.size() && !is_rung_line(trim(lines_[i].text)); i++) {
      }
      i--;
      continue;
    }
    if (r.series.size() == 1 && r.series[0].kw == "COMMENT") {
      // a comment rung: its first line titles the next rung
      std::string c = r.series[0].rest;
      size_t cut = c.find("\\r\\n");
      if (cut == std::string::npos) cut = c.find("\\n");
      title = trim(c.substr(0, cut));
      continue;
    }
    rungs_.push_back(std::move(r));
    titles_.push_back(title);
    title.clear();
  }
}

// ------------------------------------------------------------------ names

bool Importer::is_number(const std::string& s) const {
  if (s.empty()) return false;
  if (s[0] == '\'') return true;
  size_t i = (s[0] == '-' || s[0] == '+') ? 1 : 0;
  return i < s.size() && std::isdigit((unsigned char)s[i]);
}

// LDmicro 0.1 reads numbers with atoi (decimal); newer versions also take
// 0x.. 0b.. 0o.. and a leading 0 for octal, and 'c' with C escapes.
int32_t Importer::number(const std::string& s, int line, int col) const {
  if (s[0] == '\'') {
    std::string body = s.size() >= 2 && s.back() == '\'' ? s.substr(1, s.size() - 2) : "";
    int v = -1;
    if (body.size() == 1) v = (unsigned char)body[0];
    else if (body.size() == 2 && body[0] == '\\') {
      static const std::map<char, int> esc = {{'n', 10}, {'r', 13}, {'t', 9}, {'0', 0}, {'\\', 92}, {'\'', 39}, {'"', 34}, {'a', 7}, {'b', 8}, {'f', 12}, {'v', 11}, {'e', 27}};
      if (auto it = esc.find(body[1]); it != esc.end()) v = it->second;
    }
    if (v < 0) fail(line, col, "bad character literal " + s + "; expected one character in single quotes, like 'A' or '\\n'");
    return v;
  }
  bool neg = s[0] == '-';
  size_t i = (s[0] == '-' || s[0] == '+') ? 1 : 0;
  std::string body = s.substr(i);
  int base = 10;
  // 0x 0b 0o in every file (LDmicro 2.x also saves LDmicro0.1 files, with hex
  // numbers in them); a bare leading 0 is octal only in newer files.
  if (body.size() > 1 && body[0] == '0') {
    char p = char(std::tolower((unsigned char)body[1]));
    if (p == 'x') base = 16, body = body.substr(2);
    else if (p == 'b') base = 2, body = body.substr(2);
    else if (p == 'o') base = 8, body = body.substr(2);
    else if (!v01_) base = 8, body = body.substr(1);
  }
  if (body.empty()) fail(line, col, "malformed number '" + s + "'");
  int64_t v = 0;
  for (char c : body) {
    int d = std::isdigit((unsigned char)c) ? c - '0' : (std::tolower((unsigned char)c) >= 'a' && std::tolower((unsigned char)c) <= 'f') ? std::tolower((unsigned char)c) - 'a' + 10 : 99;
    if (d >= base) fail(line, col, "malformed number '" + s + "'" + (v01_ && base == 10 ? " (LDmicro 0.1 files use decimal numbers)" : ""));
    v = v * base + d;
    if (v > 0x100000000LL) break;
  }
  if (neg) v = -v;
  if (v < INT32_MIN || v > INT32_MAX) fail(line, col, "number '" + s + "' does not fit in 32 bits");
  return int32_t(v);
}

void Importer::note(const std::string& name, NK kind, int line, int col, const std::string& tkind) {
  auto it = names_.find(name);
  if (it == names_.end()) {
    Name n;
    n.kind = kind;
    n.timer_kind = tkind;
    n.line = line;
    n.col = col;
    names_[name] = n;
    order_.push_back(name);
    return;
  }
  Name& n = it->second;
  if (n.kind == kind) {
    if (kind == NK::Timer && n.timer_kind != tkind)
      fail(line, col, "timer '" + name + "' is used by both " + n.timer_kind + " (line " + std::to_string(n.line) + ") and " + tkind);
    return;
  }
  // A variable may turn out to be a counter, an A/D input or a PWM output
  // (their values are integers); any other mix is an error.
  if (n.kind == NK::Var && (kind == NK::Counter || kind == NK::Adc || kind == NK::Timer)) {
    n.kind = kind;
    n.timer_kind = tkind;
    return;
  }
  if (kind == NK::Var && (n.kind == NK::Counter || n.kind == NK::Adc || n.kind == NK::Timer)) return;
  fail(line, col, "'" + name + "' is used as " + kind_word(kind) + " here but as " + kind_word(n.kind) + " on line " + std::to_string(n.line));
}

void Importer::collect(const Elem& e) {
  const std::string& k = e.kw;
  auto var = [&](size_t i) {
    if (i < e.args.size() && !is_number(e.args[i])) note(e.args[i], NK::Var, e.line, e.cols[i]);
  };
  if (k == "SERIES" || k == "PARALLEL") {
    for (const Elem& x : e.kids) collect(x);
  } else if (k == "CONTACTS" || k == "COIL") {
    note(e.args[0], NK::Bit, e.line, e.cols[0]);
  } else if (is_timer_kw(k)) {
    note(e.args[0], NK::Timer, e.line, e.cols[0], k);
  } else if (k == "CTU" || k == "CTD" || k == "CTC" || k == "CTR") {
    note(e.args[0], NK::Counter, e.line, e.cols[0]);
    var(1);
    var(2);
  } else if (k == "FORMATTED_STRING") {
    if (e.args[0] != "(none)") var(0);
  } else if (k == "STRING") {
    if (e.args[1] != "(none)") var(1);  // the destination was noted first (run)
  } else if ((k == "UART_SEND" || k == "UART_RECV") && strs_.count(e.args[0])) {
    if (k == "UART_RECV")
      fail(e.line, e.cols[0], "UART_RECV takes one byte into an integer variable; '" + e.args[0] +
                                  "' is a string variable, and LDmicro has no element that receives into a string");
  } else if (is_bus(k)) {
    if (k == "SPI" || k == "I2C_WR") var(1);
    if (k == "SPI" || k == "I2C_RD") var(2);
  } else if (k == "RES") {
    // resolved after every element is seen
  } else if (k == "READ_ADC") {
    note(e.args[0], NK::Adc, e.line, e.cols[0]);
  } else if (k == "SET_PWM") {
    var(0);
    std::string n = e.args.size() >= 3 ? e.args[2] : "P";
    if (n[0] != 'P') n = "P" + n;
    note(n, NK::Pwm, e.line, e.args.size() >= 3 ? e.cols[2] : e.col);
  } else if (k == "SHIFT_REGISTER") {
    int n = number(e.args[1], e.line, e.cols[1]);
    if (n < 1 || n > 256) fail(e.line, e.cols[1], "a shift register has 1 to 256 stages");
    for (int i = 0; i < n; i++) note(e.args[0] + std::to_string(i), NK::Var, e.line, e.cols[0]);
  } else if (k == "LOOK_UP_TABLE" || k == "PIECEWISE_LINEAR" || is_segments(k) || k == "BUS") {
    var(0);
    var(1);

  } else if (k == "DELAY") {
    var(0);
  } else if (k == "TIME2COUNT") {
    var(0);
    var(1);  // a third field is LDmicro's unread adjust (check_leaf)
  } else if (k == "GOTO" || k == "LABEL") {
    // labels, not variables
  } else if (k != "COMMENT" && !e.args.empty() && k != "OSR" && k != "OSF") {
    for (size_t i = 0; i < e.args.size(); i++) var(i);
  }
}

uint32_t Importer::take(Dev d, int line, int col) {
  uint32_t& n = next_[int(d)];
  while (n < device_count(d) && used_.count({int(d), n})) n++;
  if (n >= device_count(d))
    fail(line, col, std::string("out of ") + dev_name(d) + " devices (" + dev_name(d) + "0.." + dev_name(d) +
                        std::to_string(device_count(d) - 1) + ") for this program");
  used_.insert({int(d), n});
  return n++;
}

void Importer::allocate() {
  auto dev_of = [](const std::string& name, NK k) -> Dev {
    switch (k) {
      // X and I (a Modbus contact) are inputs; R and M (a Modbus coil) memory bits
      case NK::Bit: return name[0] == 'X' || name[0] == 'I' ? Dev::X : name[0] == 'Y' ? Dev::Y : Dev::M;
      case NK::Timer: return Dev::T;
      case NK::Counter: return Dev::C;
      case NK::Adc: return Dev::WX;
      case NK::Pwm: return Dev::WY;
      case NK::Var:
      case NK::Str: return Dev::D;
    }
    return Dev::D;
  };
  for (const std::string& nm : order_) {
    Name& n = names_[nm];
    if (n.kind == NK::Bit && std::string_view("XYRIM").find(nm[0]) == std::string_view::npos)
      unit([&] {
        fail(n.line, n.col, "bit '" + nm + "' must be named X... (input), Y... (output), R... (internal relay), "
                            "I... (Modbus contact) or M... (Modbus coil)");
      });
  }
  // names that already spell an ldc device of their kind keep it
  std::set<std::string> placed;
  for (const std::string& nm : order_) {
    Name& n = names_[nm];
    Dev d = dev_of(nm, n.kind);
    auto p = parse_device(nm);
    if (p && p->dev == d && p->index < device_count(d) && !used_.count({int(d), p->index})) {
      n.dev = *p;
      used_.insert({int(d), p->index});
      placed.insert(nm);
    }
  }
  for (const std::string& nm : order_) {
    Name& n = names_[nm];
    if (placed.count(nm)) continue;
    Dev d = dev_of(nm, n.kind);
    n.dev = DeviceRef{d, take(d, n.line, n.col)};
  }
  for (const std::string& nm : order_) {  // the variables READ_ADC fills come after the named ones
    Name& n = names_[nm];
    if (n.kind == NK::Adc) n.held = DeviceRef{Dev::D, take(Dev::D, n.line, n.col)};
  }
  for (const std::string& nm : order_) {  // a string's characters, after every named word
    if (!strs_.count(nm)) continue;
    StrVar& sv = strs_[nm];
    const Name& n = names_.at(nm);
    for (int i = 0; i < sv.need; i++) {
      sv.cells.push_back(take(Dev::D, n.line, n.col));
      spelled_[{int(Dev::D), sv.cells.back()}] = nm + "_" + std::to_string(i);
    }
  }
  std::set<std::string> seen;
  for (const std::string& nm : order_) {
    const Name& n = names_[nm];
    spelled_[{int(n.dev.dev), n.dev.index}] = nm;
    std::string why;
    std::string al = alias_spelling(nm);
    std::string u = upper(al);
    bool spells_device = parse_device(al) || parse_iec_address(al, why);
    if (!is_identifier(al) || u == "DT" || seen.count(u)) continue;
    if (spells_device && !(parse_device(al) && *parse_device(al) == n.dev)) continue;
    seen.insert(u);
    if (!spells_device) aliases_.push_back({al, n.dev});
  }
  for (const std::string& nm : order_) {  // a string's characters: NAME_0, NAME_1, ...
    auto it = strs_.find(nm);
    if (it == strs_.end()) continue;
    for (size_t i = 0; i < it->second.cells.size(); i++) {
      std::string why, al = alias_spelling(nm) + "_" + std::to_string(i);
      if (!is_identifier(al) || seen.count(upper(al)) || parse_device(al) || parse_iec_address(al, why)) continue;
      seen.insert(upper(al));
      aliases_.push_back({al, {Dev::D, it->second.cells[i]}});
    }
  }
}

// LDmicro names may hold '@' and start with '#' (a port, #PORTB); ldc aliases
// are letters, digits and '_'.  '@' is spelled "_at_", '#' "_hash_", any other
// character '_', and a leading digit gets a '_' before it.
std::string alias_spelling(const std::string& nm) {
  std::string r;
  for (char c : nm) {
    if (std::isalnum((unsigned char)c) || c == '_') r += c;
    else if (c == '@') r += "_at_";
    else if (c == '#') r += "_hash_";
    else r += '_';
  }
  if (!r.empty() && std::isdigit((unsigned char)r[0])) r = "_" + r;
  return r;
}

Name& Importer::name_of(const Elem& e, size_t arg) {
  auto it = names_.find(e.args[arg]);
  if (it == names_.end()) fail(e.line, e.cols[arg], "internal: unknown name '" + e.args[arg] + "'");
  return it->second;
}

// An integer operand: a number, a variable, a counter's value, an A/D input's
// last reading.  A timer's value is refused: LDmicro counts it in cycles, ldc in ms.
Operand Importer::value(const Elem& e, size_t arg, bool dest) {
  const std::string& s = e.args[arg];
  int col = e.cols[arg];
  if (is_number(s)) {
    if (dest) fail(e.line, col, "'" + s + "' is a number; it cannot be a destination");
    return const_opd(number(s, e.line, col));
  }
  const Name& n = name_of(e, arg);
  switch (n.kind) {
    case NK::Var: return int_opd(Area::D, n.dev.index);
    case NK::Counter: return int_opd(Area::CW, n.dev.index);
    case NK::Adc:
      if (dest) fail(e.line, col, "'" + s + "' is an A/D input; only READ_ADC writes it");
      return int_opd(Area::D, n.held.index);
    case NK::Timer:
      fail(e.line, col, "timer '" + s + "' used as a number: LDmicro counts a timer in cycles, ldc in milliseconds, so its "
                                       "value has no exact translation");
    case NK::Bit: fail(e.line, col, "'" + s + "' is a bit; an integer is needed here");
    case NK::Str: fail(e.line, col, "'" + s + "' is a string variable; an integer is needed here");
    case NK::Pwm: break;
  }
  fail(e.line, col, "'" + s + "' is a PWM output; only SET_PWM writes it");
}

std::string Importer::spell(const Operand& o) const { return spell_operand(o, spelled_); }

TreeNode Importer::leaf_node(Op op, std::vector<Operand> a, const Elem& e) {
  TreeNode n;
  n.kind = K::Leaf;
  n.elem.op = op;
  n.elem.loc = e.loc();
  for (size_t i = 0; i < a.size(); i++) n.elem.a[i] = a[i];
  static const std::map<Op, const char*> cmp = {{Op::LDEQ, "=="}, {Op::LDNE, "<>"}, {Op::LDLT, "<"},
                                                {Op::LDLE, "<="}, {Op::LDGT, ">"},  {Op::LDGE, ">="}};
  if (auto it = cmp.find(op); it != cmp.end()) n.text = spell(a[0]) + " " + it->second + " " + spell(a[1]);
  else n.text = std::string(op == Op::LOADN ? "/" : op == Op::LOADP ? "P " : op == Op::LOADF ? "N " : "") + spell(a[0]);
  return n;
}

TreeNode Importer::out_node(Op op, std::vector<Operand> a, const Elem& e) {
  TreeNode n;
  n.kind = K::Output;
  n.elem.op = op;
  n.elem.loc = e.loc();
  std::string t = op == Op::OUT ? "" : op == Op::OUTN ? "/" : std::string(op_info(op).name) + " ";
  for (size_t i = 0; i < a.size(); i++) {
    n.elem.a[i] = a[i];
    t += (i ? " " : "") + spell(a[i]);
  }
  n.text = t;
  return n;
}

// ------------------------------------------------------------------ translation

bool Importer::breaks(const Elem& e) const {
  const std::string& k = e.kw;
  if (k == "SERIES" || k == "PARALLEL") {
    for (const Elem& x : e.kids)
      if (breaks(x)) return true;
    return false;
  }
  if (k == "TOF" || k == "RTO" || k == "TCY" || k == "RTL" || k == "THI" || k == "TLO" || k == "OSF" || k == "OSL" || k == "OSC" || k == "MASTER_RELAY") return true;
  if (k == "CTU" || k == "CTD" || k == "CTR") return true;
  if (k == "CTC") return !(v01_ && e.args.size() == 2);
  if (k == "COIL") return e.args.size() == 5 && e.args[4] != "0";
  return is_uart(k) || k == "FORMATTED_STRING";
}

Cond Importer::materialize(const Elem& e) {
  // a chain that starts from a saved state and has done nothing yet holds it already
  if (rb_.frames.size() == 1 && rb_.frames[0].items.empty()) {
    const Cond& c = rb_.frames[0].cond;
    if (c.k == Cond::Expr && c.n.kind == K::Leaf && c.n.elem.op == Op::LOAD && c.n.elem.a[0].area == Area::M &&
        frozen_.count(c.n.elem.a[0].index))
      return c;
  }
  uint32_t m = temp_m(e);
  frozen_.insert(m);
  rb_.add(out_node(Op::OUT, {bit_opd(Area::M, m)}, e));
  return bit_leaf(Op::LOAD, Area::M, m, e);
}

std::optional<Cond> Importer::pure(const Elem& e) {
  const std::string& k = e.kw;
  if (k == "SERIES") {
    Cond c = Cond::yes();
    for (const Elem& x : e.kids) {
      auto p = pure(x);
      if (!p) return std::nullopt;
      c = c_and(std::move(c), std::move(*p));
    }
    return c;
  }
  if (k == "PARALLEL") {
    Cond c = Cond::no();
    for (const Elem& x : e.kids) {
      auto p = pure(x);
      if (!p) return std::nullopt;
      c = c_or(std::move(c), std::move(*p));
    }
    return c;
  }
  if (!is_pure_kw(k)) return std::nullopt;
  if (k == "SHORT" || k == "COMMENT") return Cond::yes();
  if (k == "OPEN") return Cond::no();
  if (k == "CONTACTS") {
    const Name& n = name_of(e, 0);
    int neg = number(e.args[1], e.line, e.cols[1]);
    Area a = n.dev.dev == Dev::X ? Area::X : n.dev.dev == Dev::Y ? Area::Y : Area::M;
    return bit_leaf(neg ? Op::LOADN : Op::LOAD, a, n.dev.index, e);
  }
  static const std::map<std::string, Op> cmp = {{"EQU", Op::LDEQ}, {"NEQ", Op::LDNE}, {"GRT", Op::LDGT},
                                                {"GEQ", Op::LDGE}, {"LES", Op::LDLT}, {"LEQ", Op::LDLE}};
  return Cond::of(leaf_node(cmp.at(k), {narrow_literal(e, 0, 1), narrow_literal(e, 1, 0)}, e));
}

int32_t Importer::cycle_ms(const Elem& e) {
  if (cycle_refused_) throw Cascade();  // what the refused CYCLE= line would have said is unknown
  if (cycle_us_ <= 0) fail(e.line, e.col, e.kw + " needs a cycle time, and this file has CYCLE=" + std::to_string(cycle_us_));
  if (cycle_us_ % 1000)
    fail(e.line, e.col, e.kw + " counts cycles of CYCLE=" + std::to_string(cycle_us_) +
                            " us, which is not a whole number of milliseconds; ldc timers count whole milliseconds");
  return int32_t(cycle_us_ / 1000);
}

// LDmicro turns a delay into a number of cycles, P = (delay + adjust * cycle) / cycle
// (integer division; adjust is -1 in LDmicro 0.1 files unless given), and the
// timer's output changes after P cycles.  ldc's preset is P cycles in ms.
int32_t Importer::timer_ms(const Elem& e, const Name&) {
  int32_t cyc = cycle_ms(e);
  if (!is_number(e.args[1]))
    fail(e.line, e.cols[1], e.kw + " with a variable delay '" + e.args[1] + "' is not supported: LDmicro counts it in cycles");
  int64_t delay = number(e.args[1], e.line, e.cols[1]);
  // TIME2COUNT's adjust is always 0: LDmicro's reader leaves it at the zero of
  // a fresh element, whatever the file's version or third field.
  int64_t adjust = e.kw == "TIME2COUNT" ? 0 : e.args.size() >= 3 ? number(e.args[2], e.line, e.cols[2]) : (v01_ ? -1 : 0);
  if (delay <= 0) fail(e.line, e.cols[1], "timer delay must be positive (it is in microseconds)");
  __int128 p128 = (__int128(delay) + __int128(cycle_us_) * adjust) / cycle_us_;
  if (p128 > INT32_MAX) fail(e.line, e.cols[1], "timer delay too long (at most 2147483647 ms)");
  int64_t p = int64_t(p128);
  if (p < 1)
    fail(e.line, e.cols[1], e.kw + " " + e.args[0] + ": a delay of " + e.args[1] + " us is less than " + (adjust < 0 ? "two cycles" : "one cycle") +
                                " of " + std::to_string(cycle_us_) + " us (LDmicro refuses it too: timer period too short)");
  int64_t ms = p * cyc;
  if (ms > INT32_MAX) fail(e.line, e.cols[1], "timer delay too long (at most 2147483647 ms)");
  return int32_t(ms);
}

void Importer::timer(const Elem& e) {
  Name& n = name_of(e, 0);
  uint32_t t = n.dev.index;
  int32_t pt = timer_ms(e, n);
  SrcLoc loc = e.loc();
  if (e.kw == "TON") {  // output = input AND done: the state narrows
    rb_.add(out_node(Op::TON, {timer_opd(t), const_opd(pt)}, e));
    rb_.narrow(bit_leaf(Op::LOAD, Area::TQ, t, e), loc);
  } else if (e.kw == "TOF") {  // the output outlives the input: a new chain
    rb_.add(out_node(Op::TOF, {timer_opd(t), const_opd(pt)}, e));
    rb_.restart(bit_leaf(Op::LOAD, Area::TQ, t, e), loc);
  } else if (e.kw == "THI" || e.kw == "TLO") {
    // THI: a rising state starts a pulse of P cycles (on while counting); TLO:
    // a falling state (once it has been on) starts a gap of P cycles in an
    // output that is otherwise on.  The count lives in T's word, in ms; the
    // next pulse needs the state back at rest (off for THI, on for TLO).
    bool hi_kind = e.kw == "THI";
    int32_t cyc = cycle_ms(e);
    Cond s = materialize(e);
    uint32_t sm = s.n.elem.a[0].index, st = temp_m(e), lt = temp_m(e), hi = hi_kind ? 0 : temp_m(e), om = temp_m(e);
    frozen_.insert(om);
    Operand tw = int_opd(Area::TW, t);
    auto M = [&](Op op, uint32_t m) { return bit_leaf(op, Area::M, m, e); };
    if (hi_kind) {
      rb_.chain(M(Op::LOAD, sm), out_node(Op::SET, {bit_opd(Area::M, st)}, e), loc);
    } else {
      rb_.chain(c_and(M(Op::LOADN, sm), M(Op::LOAD, hi)), out_node(Op::SET, {bit_opd(Area::M, st)}, e), loc);
      rb_.chain(M(Op::LOAD, sm), out_node(Op::SET, {bit_opd(Area::M, hi)}, e), loc);
    }
    rb_.chain(c_and(M(Op::LOAD, st), Cond::of(leaf_node(Op::LDLT, {tw, const_opd(pt)}, e))), out_node(Op::OUT, {bit_opd(Area::M, lt)}, e), loc);
    rb_.chain(M(Op::LOAD, lt), out_node(Op::ADD, {tw, const_opd(cyc), tw}, e), loc);
    std::vector<TreeNode> rest;
    rest.push_back(out_node(Op::MOV, {const_opd(0), tw}, e));
    rest.push_back(out_node(Op::RST, {bit_opd(Area::M, st)}, e));
    rb_.chain(c_and(c_and(M(Op::LOAD, st), M(Op::LOADN, lt)), M(hi_kind ? Op::LOADN : Op::LOAD, sm)), fork_of(std::move(rest)), loc);
    if (hi_kind) rb_.chain(M(Op::LOAD, lt), out_node(Op::OUT, {bit_opd(Area::M, om)}, e), loc);
    else rb_.chain(c_and(M(Op::LOAD, hi), M(Op::LOADN, lt)), out_node(Op::OUT, {bit_opd(Area::M, om)}, e), loc);
    rb_.restart(M(Op::LOAD, om), loc);
  } else if (e.kw == "RTO" || e.kw == "RTL") {
    // Retentive: count cycles while the input is on, keep the count while it
    // is off; the output is (count before this cycle) >= P, whatever the input.
    // The count lives in the timer's word, in ms (one cycle = CYCLE ms).
    int32_t cyc = cycle_ms(e);
    Cond s = materialize(e);
    uint32_t o = temp_m(e);
    frozen_.insert(o);
    Operand tw = int_opd(Area::TW, t);
    rb_.chain(Cond::of(leaf_node(Op::LDGE, {tw, const_opd(pt)}, e)), out_node(Op::OUT, {bit_opd(Area::M, o)}, e), loc);
    if (e.kw == "RTL") s = bit_leaf(Op::LOADN, Area::M, s.n.elem.a[0].index, e);  // counts while the state is off
    rb_.chain(c_and(std::move(s), Cond::of(leaf_node(Op::LDLT, {tw, const_opd(pt)}, e))),
              out_node(Op::ADD, {tw, const_opd(cyc), tw}, e), loc);
    rb_.restart(bit_leaf(Op::LOAD, Area::M, o, e), loc);
  } else {  // TCY: while on, toggle a bit every P+1 cycles; the output is input AND that bit
    int32_t cyc = cycle_ms(e);
    Cond s = materialize(e);
    uint32_t sm = s.n.elem.a[0].index;
    uint32_t w = temp_m(e), st = temp_m(e);
    Operand tw = int_opd(Area::TW, t);
    rb_.chain(c_and(bit_leaf(Op::LOAD, Area::M, sm, e), Cond::of(leaf_node(Op::LDGE, {tw, const_opd(pt)}, e))),
              out_node(Op::OUT, {bit_opd(Area::M, w)}, e), loc);
    rb_.chain(c_and(bit_leaf(Op::LOAD, Area::M, sm, e), Cond::of(leaf_node(Op::LDLT, {tw, const_opd(pt)}, e))),
              out_node(Op::ADD, {tw, const_opd(cyc), tw}, e), loc);
    rb_.chain(c_or(bit_leaf(Op::LOADN, Area::M, sm, e), bit_leaf(Op::LOAD, Area::M, w, e)), out_node(Op::MOV, {const_opd(0), tw}, e), loc);
    Cond flip = c_or(c_and(bit_leaf(Op::LOAD, Area::M, w, e), bit_leaf(Op::LOADN, Area::M, st, e)),
                     c_and(bit_leaf(Op::LOADN, Area::M, w, e), bit_leaf(Op::LOAD, Area::M, st, e)));
    rb_.chain(std::move(flip), out_node(Op::OUT, {bit_opd(Area::M, st)}, e), loc);
    rb_.restart(c_and(bit_leaf(Op::LOAD, Area::M, sm, e), bit_leaf(Op::LOAD, Area::M, st, e)), loc);
  }
}

void Importer::counter(const Elem& e) {
  Name& n = name_of(e, 0);
  uint32_t c = n.dev.index;
  Operand cw = int_opd(Area::CW, c);
  Operand max = value(e, 1);
  SrcLoc loc = e.loc();
  if (v01_ && e.args.size() == 2) {
    // LDmicro 0.1: CTU/CTD count rising edges without limit, output count >= max;
    // CTC counts rising edges and wraps past max to 0, passing its input on.
    // The count is a 16-bit variable: it wraps from 32767 to -32768 (and back).
    if (e.kw == "CTU" || e.kw == "CTD") {
      rb_.add(out_node(e.kw == "CTU" ? Op::CTU : Op::CTD, {counter_opd(c), e.kw == "CTU" ? max : const_opd(0)}, e));
      if (width_of(e.args[0]) < 4) rb_.chain(Cond::yes(), fork_of(wrap_nodes(cw, width_of(e.args[0]), e)), loc);
      rb_.restart(Cond::of(leaf_node(Op::LDGE, {cw, max}, e)), loc);
    } else if (e.kw == "CTC") {
      Cond s = materialize(e);
      TreeNode wrap = then_node(Cond::of(leaf_node(Op::LDGT, {cw, max}, e)), out_node(Op::MOV, {const_opd(0), cw}, e), loc);
      std::vector<TreeNode> items = wrap_nodes(cw, width_of(e.args[0]), e);
      items.insert(items.begin(), out_node(Op::ADD, {cw, const_opd(1), cw}, e));
      items.push_back(std::move(wrap));
      rb_.add(then_node(bit_leaf(Op::LOADP, Area::M, s.n.elem.a[0].index, e), fork_of(std::move(items)), loc));
    } else {
      fail(e.line, e.col, "CTR is not an LDmicro 0.1 element");
    }
    return;
  }
  // LDmicro 2.x+ (and 0.1 files using the newer fields): the counter starts at
  // `init`, counts on the input's edge of the given kind, and saturates (CTU,
  // CTD) or wraps to init with a one-cycle output pulse (CTC, CTR).
  Operand init = e.args.size() >= 3 ? value(e, 2) : const_opd(0);
  char kind = e.args.size() >= 4 ? e.args[3][0] : '/';
  if (kind != '/' && kind != '\\' && kind != '-' && kind != 'o')
    fail(e.line, e.cols[3], "unknown counter input kind '" + e.args[3] + "' (expected / \\ - or o)");
  Cond s = materialize(e);
  if (init.kind == OpdKind::ConstInt) {
    if (init.ival != 0) init_.push_back(out_node(Op::MOV, {init, cw}, e));
  } else {  // LDmicro loads a variable init when the counter first runs
    rb_.chain(bit_leaf(Op::LOAD, Area::S, kBitFirstScan, e), out_node(Op::MOV, {init, cw}, e), loc);
  }
  uint32_t sm = s.n.elem.a[0].index;
  auto edge = [&]() {
    return kind == '/' ? bit_leaf(Op::LOADP, Area::M, sm, e) : kind == '\\' ? bit_leaf(Op::LOADF, Area::M, sm, e)
           : kind == '-' ? bit_leaf(Op::LOAD, Area::M, sm, e) : bit_leaf(Op::LOADN, Area::M, sm, e);
  };
  auto step = [&](Op op) {  // count one, wrapped to the counter's width
    std::vector<TreeNode> r = wrap_nodes(cw, width_of(e.args[0]), e);
    r.insert(r.begin(), out_node(op, {cw, const_opd(1), cw}, e));
    return fork_of(std::move(r));
  };
  if (e.kw == "CTU") {
    rb_.chain(c_and(edge(), Cond::of(leaf_node(Op::LDLT, {cw, max}, e))), step(Op::ADD), loc);
    rb_.restart(Cond::of(leaf_node(Op::LDGE, {cw, max}, e)), loc);
  } else if (e.kw == "CTD") {
    rb_.chain(c_and(edge(), Cond::of(leaf_node(Op::LDGT, {cw, max}, e))), step(Op::SUB), loc);
    rb_.restart(Cond::of(leaf_node(Op::LDGT, {cw, max}, e)), loc);
  } else {
    bool up = e.kw == "CTC";
    uint32_t w = temp_m(e);
    frozen_.insert(w);
    std::vector<TreeNode> wrap;
    wrap.push_back(out_node(Op::OUT, {bit_opd(Area::M, w)}, e));
    wrap.push_back(out_node(Op::MOV, {init, cw}, e));
    std::vector<TreeNode> items;
    items.push_back(step(up ? Op::ADD : Op::SUB));
    items.push_back(then_node(Cond::of(leaf_node(up ? Op::LDGT : Op::LDLT, {cw, max}, e)), fork_of(std::move(wrap)), loc));
    rb_.chain(edge(), fork_of(std::move(items)), loc);
    rb_.restart(bit_leaf(Op::LOAD, Area::M, w, e), loc);
  }
}

void Importer::coil(const Elem& e) {
  Name& n = name_of(e, 0);
  if (n.dev.dev == Dev::X)
    fail(e.line, e.cols[0], "'" + e.args[0] + "' is " + (e.args[0][0] == 'I' ? "a Modbus contact, an input" : "an input") +
                                "; a coil drives Y... outputs, R... relays or M... Modbus coils");
  Area a = n.dev.dev == Dev::Y ? Area::Y : Area::M;
  int neg = number(e.args[1], e.line, e.cols[1]), set = number(e.args[2], e.line, e.cols[2]),
      reset = number(e.args[3], e.line, e.cols[3]);
  int toggle = e.args.size() == 5 ? number(e.args[4], e.line, e.cols[4]) : 0;
  Operand b = bit_opd(a, n.dev.index);
  if (neg) rb_.add(out_node(Op::OUTN, {b}, e));
  else if (set) rb_.add(out_node(Op::SET, {b}, e));
  else if (reset) rb_.add(out_node(Op::RST, {b}, e));
  else if (toggle) {  // flip the bit on each rising edge of the rung state
    Cond s = materialize(e);
    uint32_t sm = s.n.elem.a[0].index, p = temp_m(e);
    rb_.chain(bit_leaf(Op::LOADP, Area::M, sm, e), out_node(Op::OUT, {bit_opd(Area::M, p)}, e), e.loc());
    Cond flip = c_or(c_and(bit_leaf(Op::LOAD, Area::M, p, e), bit_leaf(Op::LOADN, a, n.dev.index, e)),
                     c_and(bit_leaf(Op::LOADN, Area::M, p, e), bit_leaf(Op::LOAD, a, n.dev.index, e)));
    rb_.chain(std::move(flip), out_node(Op::OUT, {b}, e), e.loc());
    rb_.restart(std::move(s), e.loc());
  } else rb_.add(out_node(Op::OUT, {b}, e));
}

// The UART as word I/O (docs/ldmicro.md, "UART"): the environment writes
// (seq << 8) | byte into WX1023 and counts seq up for each new byte; a byte
// is there while that word differs from D8191, the last word consumed.
// UART_SEND writes (tx_seq << 8) | byte into WY1023, tx_seq counting up modulo
// 2^23, at most once per scan: M8191, cleared at the start of each scan, says
// a byte was sent (the UART is busy) and the element outputs it.
void Importer::uart(const Elem& e) {
  const std::string& k = e.kw;
  SrcLoc loc = e.loc();
  Operand rx = int_opd(Area::WX, kUartRx), seen = int_opd(Area::D, kUartSeen);
  auto fresh = [&] { return Cond::of(leaf_node(Op::LDNE, {rx, seen}, e)); };
  if (k == "UART_RECV_AVAIL") return rb_.restart(fresh(), loc);
  if (is_uart_flag(k)) return rb_.restart(bit_leaf(Op::LOADN, Area::M, kUartBusy, e), loc);
  if (k == "UART_SEND" && strs_.count(e.args[0])) return uart_send_string(e);
  if (e.args.size() >= 2 && number(e.args[1], e.line, e.cols[1]) != 1)
    fail(e.line, e.cols[1], k + " of " + e.args[1] + " bytes is not supported: ldc's UART moves one byte at a time");
  if (e.args.size() >= 3 && number(e.args[2], e.line, e.cols[2]) != 0)
    fail(e.line, e.cols[2], k + " with wait " + e.args[2] + " is not supported: a scan never waits for the UART");
  Cond s = materialize(e);
  if (k == "UART_RECV") {
    Operand var = value(e, 0, true);
    uint32_t got = temp_m(e);
    frozen_.insert(got);
    rb_.chain(c_and(std::move(s), fresh()), out_node(Op::OUT, {bit_opd(Area::M, got)}, e), loc);
    std::vector<TreeNode> take;
    take.push_back(out_node(Op::WAND, {rx, const_opd(255), var}, e));
    take.push_back(out_node(Op::MOV, {rx, seen}, e));
    if (!is_number(e.args[0]))
      for (TreeNode& n : wrap_nodes(var, width_of(e.args[0]), e)) take.push_back(std::move(n));
    rb_.chain(bit_leaf(Op::LOAD, Area::M, got, e), fork_of(std::move(take)), loc);
    rb_.restart(bit_leaf(Op::LOAD, Area::M, got, e), loc);
    return;
  }
  rb_.chain(c_and(std::move(s), bit_leaf(Op::LOADN, Area::M, kUartBusy, e)), fork_of(uart_send_nodes(value(e, 0), e)), loc);
  rb_.restart(bit_leaf(Op::LOAD, Area::M, kUartBusy, e), loc);
}

// Send the low byte of `v` on the UART: the next sequence number and the byte
// into uart_tx, and the transmitter is busy for the rest of the scan.
std::vector<TreeNode> Importer::uart_send_nodes(const Operand& v, const Elem& e) {
  Operand tx = int_opd(Area::WY, kUartTx), byte = int_opd(Area::D, temp_d(e));
  std::vector<TreeNode> send;
  send.push_back(out_node(Op::WAND, {v, const_opd(255), byte}, e));
  send.push_back(out_node(Op::ADD, {tx, const_opd(256), tx}, e));
  send.push_back(out_node(Op::WAND, {tx, const_opd(0x7FFFFF00), tx}, e));
  send.push_back(out_node(Op::WOR, {tx, byte, tx}, e));
  send.push_back(out_node(Op::SET, {bit_opd(Area::M, kUartBusy)}, e));
  return send;
}

// FORMATTED_STRING var text: on a rising edge of its state, the element starts
// sending its text over the UART, one character per scan while the UART is
// free, as LDmicro does; a variable is interpolated where the text says \N
// (N digits, leading zeros as spaces) or \-N (a sign first).  Its output is on
// while the text is being sent.  Everything is per element: a sequence word
// (the next character), the conversion state, and relays for the edge, the
// sending and the leading zeros.
void Importer::formatted_string(const Elem& e) {
  SrcLoc loc = e.loc();
  // the text: character codes after the length, or the rest of the line
  std::string text;
  if (is_number(e.args[1])) {
    int64_t len = number(e.args[1], e.line, e.cols[1]);
    if (len < 0 || int64_t(e.args.size()) != 2 + len)
      fail(e.line, e.cols[1], "FORMATTED_STRING says " + e.args[1] + " characters but lists " + std::to_string(e.args.size() - 2));
    for (size_t i = 2; i < e.args.size(); i++) {
      int32_t c = number(e.args[i], e.line, e.cols[i]);
      if (c < 1 || c > 255) fail(e.line, e.cols[i], "a character code must be 1..255");
      text += char(c);
    }
  } else {
    text = trim(e.rest.substr(e.rest.find(e.args[0]) + e.args[0].size()));
  }
  enum Kind { Char, Digit, Sign };
  struct Step { Kind k; int c; };
  std::vector<Step> steps;
  int digits = -1;
  bool minus = false;
  auto bad = [&](const std::string& why) { fail(e.line, e.col, "FORMATTED_STRING: " + why + " (LDmicro refuses it too)"); };
  for (size_t i = 0; i < text.size(); i++) {
    char c = text[i];
    if (c != '\\') { steps.push_back({Char, (unsigned char)c}); continue; }
    if (i + 1 < text.size() && (std::isdigit((unsigned char)text[i + 1]) || text[i + 1] == '-') && text[i + 1] != '0') {
      if (digits >= 0) bad("more than one \\N escape");
      i++;
      if (text[i] == '-') minus = true, steps.push_back({Sign, 0}), i++;
      if (i >= text.size() || !std::isdigit((unsigned char)text[i]) || text[i] == '0' || text[i] > '5') bad("a \\N escape takes 1 to 5 digits");
      digits = text[i] - '0';
      for (int d = 0; d < digits; d++) steps.push_back({Digit, d});
      continue;
    }
    while (i + 1 < text.size() && text[i + 1] == '0') i++;  // LDmicro skips a \0 before the escape
    if (++i >= text.size()) bad("a \\ at the end of the text");
    static const std::map<char, int> esc = {{'a', 7}, {'b', 8}, {'e', 27}, {'f', 12}, {'n', 10}, {'r', 13}, {'t', 9},
                                            {'v', 11}, {'\'', 39}, {'"', 34}, {'?', 63}, {'\\', 92}};
    char x = text[i];
    if (auto it = esc.find(x); it != esc.end()) { steps.push_back({Char, it->second}); continue; }
    if (x == 'x' || x == 'X') {
      auto hex = [](char h) { return std::isxdigit((unsigned char)h) ? (std::isdigit((unsigned char)h) ? h - '0' : std::tolower(h) - 'a' + 10) : -1; };
      if (i + 2 < text.size() + 0 && hex(text[i + 1]) >= 0 && hex(text[i + 2]) >= 0) {
        steps.push_back({Char, hex(text[i + 1]) * 16 + hex(text[i + 2])});
        i += 2;
        continue;
      }
      bad("bad escape: the form is \\xAB");
    }
    bad(std::string("bad escape '\\") + x + "'");
  }
  bool has_var = e.args[0] != "(none)";
  if (digits >= 0 && !has_var) bad("the text interpolates a variable but none is named");
  if (digits < 0 && has_var) bad("a variable is named but the text has no \\N escape for it");
  Operand var = has_var ? value(e, 0) : const_opd(0);
  int32_t n = int32_t(steps.size());

  Cond s = materialize(e);
  uint32_t sm = s.n.elem.a[0].index;
  uint32_t os = temp_m(e), ds = temp_m(e), lz = temp_m(e), zm = temp_m(e), om = temp_m(e);
  frozen_.insert(om);
  Operand seq = int_opd(Area::D, temp_d(e)), sc = int_opd(Area::D, temp_d(e)), cs = int_opd(Area::D, temp_d(e)),
          ch = int_opd(Area::D, temp_d(e)), t = int_opd(Area::D, temp_d(e));
  auto M = [&](Op op, uint32_t m) { return bit_leaf(op, Area::M, m, e); };
  auto cmp = [&](Op op, Operand a, Operand b) { return Cond::of(leaf_node(op, {a, b}, e)); };
  auto mov = [&](Operand a, Operand d) { return out_node(Op::MOV, {a, d}, e); };
  {  // a rising edge of the state starts the text
    std::vector<TreeNode> start;
    start.push_back(mov(const_opd(0), seq));
    start.push_back(out_node(Op::SET, {bit_opd(Area::M, ds)}, e));
    rb_.chain(c_and(M(Op::LOAD, sm), M(Op::LOADN, os)), fork_of(std::move(start)), loc);
    rb_.chain(M(Op::LOAD, sm), out_node(Op::OUT, {bit_opd(Area::M, os)}, e), loc);
  }
  // sc: the character to send in this scan, -1 for none (all sent, or the UART busy)
  rb_.chain(Cond::yes(), mov(seq, sc), loc);
  rb_.chain(c_or(cmp(Op::LDGE, seq, const_opd(n)), c_and(M(Op::LOAD, ds), bit_leaf(Op::LOAD, Area::M, kUartBusy, e))),
            mov(const_opd(-1), sc), loc);
  int d = 0;
  for (int i = 0; i < n; i++) {
    std::vector<TreeNode> a;
    const Step& st = steps[i];
    if (st.k == Char) {
      a.push_back(mov(const_opd(st.c), ch));
    } else if (st.k == Sign) {  // the sign, and the absolute value to convert
      a.push_back(mov(const_opd(' '), ch));
      a.push_back(then_node(cmp(Op::LDLT, var, const_opd(0)), out_node(Op::SUB, {const_opd(0), var, cs}, e), loc));
      a.push_back(then_node(cmp(Op::LDLT, var, const_opd(0)), mov(const_opd('-'), ch), loc));
      a.push_back(then_node(cmp(Op::LDGE, var, const_opd(0)), mov(var, cs), loc));
    } else {  // one digit, the highest first
      if (d == 0 && !minus) a.push_back(mov(var, cs));
      if (d == 0) a.push_back(out_node(Op::SET, {bit_opd(Area::M, lz)}, e));
      int32_t p = 1;
      for (int j = 0; j < digits - d - 1; j++) p *= 10;
      a.push_back(out_node(Op::DIV, {cs, const_opd(p), ch}, e));
      a.push_back(out_node(Op::MUL, {ch, const_opd(p), t}, e));
      a.push_back(out_node(Op::SUB, {cs, t, cs}, e));
      a.push_back(out_node(Op::ADD, {ch, const_opd('0'), ch}, e));
      if (d != digits - 1) {  // leading zeros but the last become spaces
        a.push_back(then_node(cmp(Op::LDEQ, ch, const_opd('0')), out_node(Op::OUT, {bit_opd(Area::M, zm)}, e), loc));
        a.push_back(then_node(cmp(Op::LDNE, ch, const_opd('0')), out_node(Op::RST, {bit_opd(Area::M, zm)}, e), loc));
        a.push_back(then_node(c_and(M(Op::LOAD, zm), M(Op::LOAD, lz)), mov(const_opd(' '), ch), loc));
        a.push_back(then_node(M(Op::LOADN, zm), out_node(Op::RST, {bit_opd(Area::M, lz)}, e), loc));
      }
      d++;
    }
    rb_.chain(cmp(Op::LDEQ, sc, const_opd(i)), fork_of(std::move(a)), loc);
  }
  std::vector<TreeNode> send = uart_send_nodes(ch, e);
  send.push_back(out_node(Op::ADD, {seq, const_opd(1), seq}, e));
  rb_.chain(c_and(cmp(Op::LDGE, sc, const_opd(0)), M(Op::LOAD, ds)), fork_of(std::move(send)), loc);
  // the output: still sending
  rb_.chain(c_and(cmp(Op::LDLT, seq, const_opd(n)), M(Op::LOAD, ds)), out_node(Op::OUT, {bit_opd(Area::M, om)}, e), loc);
  rb_.chain(cmp(Op::LDGE, seq, const_opd(n)), out_node(Op::RST, {bit_opd(Area::M, ds)}, e), loc);
  rb_.restart(M(Op::LOAD, om), loc);
}

// STRING dest var text: when its state is on, dest := sprintf(text, var), as
// LDmicro's C output does it (docs/ldmicro.md, "Strings").  Here, before any
// name is allocated: the text as LDmicro's reader makes it, split around its
// one conversion, and the longest result, which sizes the destination.
void Importer::plan_string(const Elem& e) {
  const std::string& dest = e.args[0];
  if (dest == "(none)") fail(e.line, e.cols[0], "STRING needs a destination string variable");
  note(dest, NK::Str, e.line, e.cols[0]);
  std::string text;
  bool codes = v01_ && is_number(e.args[2]) && std::all_of(e.args.begin() + 2, e.args.end(), [&](const std::string& a) { return is_number(a); });
  if (codes && int64_t(e.args.size()) == 3 + int64_t(number(e.args[2], e.line, e.cols[2]))) {
    // an LDmicro0.1 file: the length and the character codes, read as LDmicro 4 reads them
    for (size_t i = 3; i < e.args.size(); i++) {
      int32_t c = number(e.args[i], e.line, e.cols[i]);
      text += (c < 32 || c > 127) ? 'X' : char(c);
    }
  } else {
    std::string raw = e.text.substr(size_t(e.cols[2] - 1));
    raw = raw.substr(0, raw.find_last_not_of(" \t\r") + 1);
    text = ldmicro_format::load_text(raw);
  }
  ldmicro_format::Format f;
  if (e.args[1] == "(none)") f.before = text;  // no variable: the text is copied, '%' and all
  else if (std::string why = ldmicro_format::parse(text, f); !why.empty())
    fail(e.line, e.cols[2], "STRING format: " + why);
  StrVar& sv = strs_[dest];
  int need = format_max(f);
  if (auto it = var_bytes_.find(dest); it != var_bytes_.end() && it->second >= 1) need = int(std::min<int64_t>(need, it->second - 1));
  sv.need = std::max(sv.need, need);
  formats_[{e.line, e.col}] = std::move(f);
}

void Importer::string_elem(const Elem& e) {
  const ldmicro_format::Format& f = formats_.at({e.line, e.col});
  const StrVar& sv = strs_.at(e.args[0]);
  Operand len = int_opd(Area::D, name_of(e, 0).dev.index);
  SrcLoc loc = e.loc();
  int cap = int(sv.cells.size()), n1 = int(f.before.size());
  std::vector<TreeNode> x;
  for (int j = 0; j < n1 && j < cap; j++)
    x.push_back(out_node(Op::MOV, {const_opd((unsigned char)f.before[j]), int_opd(Area::D, sv.cells[j])}, e));
  if (!f.has_spec) {
    x.push_back(out_node(Op::MOV, {const_opd(std::min(cap, n1)), len}, e));
    return rb_.add(fork_of(std::move(x)));
  }
  const ldmicro_format::Spec& s = f.spec;
  FieldSizes z = field_sizes(s);
  std::vector<Operand> r;
  for (int q = 0; q < z.cmax; q++) r.push_back(int_opd(Area::D, temp_d(e)));
  Operand c = int_opd(Area::D, temp_d(e));
  for (TreeNode& n : string_digits(s, value(e, 1), r, c, e)) x.push_back(std::move(n));
  if (s.conv == 'c') {
    for (TreeNode& n : string_layout(f, 1, r, sv, len, e)) x.push_back(std::move(n));
    // a NUL character ends the C string where it stands
    int at = n1 + (s.minus ? 0 : std::max(s.width, 1) - 1);
    x.push_back(then_node(Cond::of(leaf_node(Op::LDEQ, {r[0], const_opd(0)}, e)), out_node(Op::MOV, {const_opd(std::min(cap, at)), len}, e), loc));
  } else {
    for (int cv = z.cmin; cv <= z.cmax; cv++)
      x.push_back(then_node(Cond::of(leaf_node(Op::LDEQ, {c, const_opd(cv)}, e)), fork_of(string_layout(f, cv, r, sv, len, e)), loc));
  }
  rb_.add(fork_of(std::move(x)));
}

// The conversion's characters from the right, into r[0], r[1], ... (the last
// digit first, then zeros, then the sign or 0x), and their count into c.
std::vector<TreeNode> Importer::string_digits(const ldmicro_format::Spec& s, const Operand& v, const std::vector<Operand>& r,
                                              const Operand& c, const Elem& e) {
  std::vector<TreeNode> x;
  SrcLoc loc = e.loc();
  auto op = [&](Op o, std::vector<Operand> a) { x.push_back(out_node(o, std::move(a), e)); };
  auto when = [&](Cond cond, TreeNode n) { x.push_back(then_node(std::move(cond), std::move(n), loc)); };
  auto cmp = [&](Op o, Operand a, Operand b) { return Cond::of(leaf_node(o, {a, b}, e)); };
  auto K = [](int32_t k) { return const_opd(k); };
  if (s.conv == 'c') {  // the value as an unsigned char
    op(Op::WAND, {v, K(255), r[0]});
    op(Op::MOV, {K(1), c});
    return x;
  }
  FieldSizes z = field_sizes(s);
  bool hex = s.conv == 'x' || s.conv == 'X', oct = s.conv == 'o', sgn = s.conv == 'd';
  Operand w = int_opd(Area::D, temp_d(e)), u = int_opd(Area::D, temp_d(e)), t = int_opd(Area::D, temp_d(e)),
          nd = int_opd(Area::D, temp_d(e)), nz = int_opd(Area::D, temp_d(e)), pl = int_opd(Area::D, temp_d(e)),
          sg = int_opd(Area::D, temp_d(e));
  op(Op::MOV, {v, w});
  if (s.bits < 32 && sgn)  // h, hh: the value as a short or a char
    for (TreeNode& n : wrap_nodes(w, s.bits / 8, e)) x.push_back(std::move(n));
  if (s.bits < 32 && !sgn) op(Op::WAND, {w, K((1 << s.bits) - 1), w});
  op(Op::MOV, {w, u});  // u: the magnitude, as an unsigned 32-bit pattern
  if (sgn) when(cmp(Op::LDLT, w, K(0)), out_node(Op::SUB, {K(0), w, u}, e));
  op(Op::MOV, {K(1), nd});
  if (!hex && !oct) {  // the first digit of an unsigned value: (u >> 1) / 5 is u / 10
    Operand qq = t;
    Operand q = int_opd(Area::D, temp_d(e));
    op(Op::SHR, {u, K(1), q});
    op(Op::DIV, {q, K(5), q});
    op(Op::MUL, {q, K(10), qq});
    op(Op::SUB, {u, qq, r[0]});
    for (int i = 1; i < z.maxd; i++) {
      when(cmp(Op::LDNE, q, K(0)), out_node(Op::MOV, {K(i + 1), nd}, e));
      op(Op::MOD, {q, K(10), r[i]});
      op(Op::DIV, {q, K(10), q});
    }
  } else {
    int sh = hex ? 4 : 3;
    op(Op::WAND, {u, K((1 << sh) - 1), r[0]});
    for (int i = 1; i < z.maxd; i++) {
      op(Op::SHR, {u, K(sh * i), t});
      when(cmp(Op::LDNE, t, K(0)), out_node(Op::MOV, {K(i + 1), nd}, e));
      op(Op::WAND, {t, K((1 << sh) - 1), r[i]});
    }
  }
  for (int i = 0; i < z.maxd; i++) {
    op(Op::ADD, {r[i], K('0'), r[i]});
    if (hex) when(cmp(Op::LDGT, r[i], K('9')), out_node(Op::ADD, {r[i], K((s.conv == 'x' ? 'a' : 'A') - '9' - 1), r[i]}, e));
  }
  for (int i = z.maxd; i < z.cmax; i++) op(Op::MOV, {K('0'), r[i]});
  if (s.prec == 0) when(cmp(Op::LDEQ, u, K(0)), out_node(Op::MOV, {K(0), nd}, e));
  op(Op::MOV, {nd, nz});
  if (s.prec > 0) when(cmp(Op::LDLT, nz, K(s.prec)), out_node(Op::MOV, {K(s.prec), nz}, e));
  if (oct && s.alt) {  // '#': the first digit printed is a 0
    when(c_and(cmp(Op::LDNE, u, K(0)), cmp(Op::LDEQ, nz, nd)), out_node(Op::ADD, {nz, K(1), nz}, e));
    when(cmp(Op::LDEQ, nz, K(0)), out_node(Op::MOV, {K(1), nz}, e));
  }
  op(Op::MOV, {K(0), pl});
  if (sgn) {
    if (s.plus || s.space) {
      op(Op::MOV, {K(s.plus ? '+' : ' '), sg});
      op(Op::MOV, {K(1), pl});
    }
    std::vector<TreeNode> minus;
    minus.push_back(out_node(Op::MOV, {K('-'), sg}, e));
    minus.push_back(out_node(Op::MOV, {K(1), pl}, e));
    when(cmp(Op::LDLT, w, K(0)), fork_of(std::move(minus)));
  }
  if (hex && s.alt) when(cmp(Op::LDNE, u, K(0)), out_node(Op::MOV, {K(2), pl}, e));
  if (s.zero && !s.minus && s.prec < 0 && s.width > 0) {  // '0': zeros up to the width
    op(Op::SUB, {K(s.width), pl, t});
    when(cmp(Op::LDLT, nz, t), out_node(Op::MOV, {t, nz}, e));
  }
  if (z.plmax > 0)  // the sign or 0x left of the digits
    for (int n = z.nzmin; n <= z.nzmax; n++) {
      std::vector<TreeNode> put;
      if (sgn) put.push_back(out_node(Op::MOV, {sg, r[n]}, e));
      else {
        put.push_back(out_node(Op::MOV, {K(s.conv), r[n]}, e));
        put.push_back(out_node(Op::MOV, {K('0'), r[n + 1]}, e));
      }
      when(cmp(Op::LDEQ, nz, K(n)), fork_of(std::move(put)));
    }
  op(Op::ADD, {nz, pl, c});
  return x;
}

// The destination when the conversion has cv characters: the text before it
// (already there), the field of max(width, cv) characters, justified right
// (spaces first) or left ('-'), and the text after it; cut at the capacity.
std::vector<TreeNode> Importer::string_layout(const ldmicro_format::Format& f, int cv, const std::vector<Operand>& r, const StrVar& sv,
                                              const Operand& len, const Elem& e) {
  std::vector<TreeNode> x;
  int cap = int(sv.cells.size()), n1 = int(f.before.size()), n2 = int(f.after.size());
  int L = std::max(f.spec.width, cv);
  for (int j = 0; j < L + n2 && n1 + j < cap; j++) {
    Operand src;
    if (j >= L) src = const_opd((unsigned char)f.after[j - L]);
    else if (!f.spec.minus) src = j < L - cv ? const_opd(' ') : r[L - 1 - j];
    else src = j < cv ? r[cv - 1 - j] : const_opd(' ');
    x.push_back(out_node(Op::MOV, {src, int_opd(Area::D, sv.cells[n1 + j])}, e));
  }
  x.push_back(out_node(Op::MOV, {const_opd(std::min(cap, n1 + L + n2)), len}, e));
  return x;
}

// UART_SEND of a string variable (LDmicro 5, without wait): while
// the state is on and no text is going out, the element starts sending; then
// each scan with the UART free sends the next character (the string as it
// stands in that scan), until the length is reached.  Output: sending, or
// the UART busy.
void Importer::uart_send_string(const Elem& e) {
  if (e.args.size() >= 3 && number(e.args[2], e.line, e.cols[2]) != 0)
    fail(e.line, e.cols[2], "UART_SEND with wait " + e.args[2] + " is not supported: a scan never waits for the UART");
  SrcLoc loc = e.loc();
  const StrVar& sv = strs_.at(e.args[0]);
  Operand len = int_opd(Area::D, name_of(e, 0).dev.index);
  Cond s = materialize(e);
  uint32_t sm = s.n.elem.a[0].index, act = temp_m(e), om = temp_m(e);
  frozen_.insert(om);
  Operand idx = int_opd(Area::D, temp_d(e)), ch = int_opd(Area::D, temp_d(e));
  auto M = [&](Op op, uint32_t m) { return bit_leaf(op, Area::M, m, e); };
  auto cmp = [&](Op op, Operand a, Operand b) { return Cond::of(leaf_node(op, {a, b}, e)); };
  auto ready = [&] { return c_and(M(Op::LOAD, act), M(Op::LOADN, kUartBusy)); };
  std::vector<TreeNode> start;
  start.push_back(out_node(Op::SET, {bit_opd(Area::M, act)}, e));
  start.push_back(out_node(Op::MOV, {const_opd(0), idx}, e));
  rb_.chain(c_and(M(Op::LOAD, sm), M(Op::LOADN, act)), fork_of(std::move(start)), loc);
  rb_.chain(c_and(ready(), cmp(Op::LDGE, idx, len)), out_node(Op::RST, {bit_opd(Area::M, act)}, e), loc);
  std::vector<TreeNode> send;
  for (size_t i = 0; i < sv.cells.size(); i++)
    send.push_back(then_node(cmp(Op::LDEQ, idx, const_opd(int32_t(i))), out_node(Op::MOV, {int_opd(Area::D, sv.cells[i]), ch}, e), loc));
  for (TreeNode& n : uart_send_nodes(ch, e)) send.push_back(std::move(n));
  send.push_back(out_node(Op::ADD, {idx, const_opd(1), idx}, e));
  rb_.chain(c_and(ready(), cmp(Op::LDLT, idx, len)), fork_of(std::move(send)), loc);
  rb_.chain(c_or(M(Op::LOAD, act), M(Op::LOAD, kUartBusy)), out_node(Op::OUT, {bit_opd(Area::M, om)}, e), loc);
  rb_.restart(M(Op::LOAD, om), loc);
}

// LDmicro variables are 1 to 4 bytes wide (VAR LIST; 2 when not listed, and
// always 2 in LDmicro 0.1 files) and wrap there as two's complement.  ldc words
// are INT32, so every write of a variable is followed by an explicit wrap to its
// width, under the same rung state as the write:
//   d := ((d + 2^(n-1)) AND (2^n - 1)) - 2^(n-1)      (n = 8 * bytes)
// which maps any INT32 to the signed n-bit value with the same low n bits.
int Importer::width_of(const std::string& name) const {
  if (v01_) return 2;
  auto it = width_.find(name);
  return it == width_.end() ? 2 : it->second;
}

std::vector<TreeNode> Importer::wrap_nodes(const Operand& d, int bytes, const Elem& e) {
  std::vector<TreeNode> r;
  if (bytes >= 4) return r;
  int32_t half = int32_t(1) << (8 * bytes - 1);
  r.push_back(out_node(Op::ADD, {d, const_opd(half), d}, e));
  r.push_back(out_node(Op::WAND, {d, const_opd(2 * half - 1), d}, e));
  r.push_back(out_node(Op::SUB, {d, const_opd(half), d}, e));
  return r;
}

// Wrap the variable named by argument `arg` of `e` (the element has just written it).
void Importer::wrap(const Elem& e, size_t arg) {
  if (is_number(e.args[arg])) return;
  auto it = names_.find(e.args[arg]);
  if (it == names_.end() || (it->second.kind != NK::Var && it->second.kind != NK::Counter)) return;
  Operand d = value(e, arg, true);
  for (TreeNode& n : wrap_nodes(d, width_of(e.args[arg]), e)) rb_.add(std::move(n));
}

// The width of argument `arg` (a variable or counter; a number counts as the
// width of the destination, argument 0).
int Importer::arg_width(const Elem& e, size_t arg) const {
  if (!is_number(e.args[arg])) return width_of(e.args[arg]);
  return is_number(e.args[0]) ? 2 : width_of(e.args[0]);
}

// ROL, ROR, SR0 (logical) and SHR (arithmetic) shift the n-bit pattern of the
// source (n = its width), as LDmicro does; the result is wrapped to the
// destination.  A constant shift must be 0..n, as LDmicro requires.
void Importer::bit_op(const Elem& e) {
  const std::string& k = e.kw;
  int n = 8 * arg_width(e, 1);
  Operand src = value(e, 1), k_opd = value(e, 2), dest = value(e, 0, true);
  if (k_opd.kind == OpdKind::ConstInt && (k_opd.ival < 0 || k_opd.ival > n))
    fail(e.line, e.cols[2], "shift of " + e.args[2] + " bits is out of range for the " + std::to_string(n) + "-bit '" + e.args[1] +
                                "': 0 to " + std::to_string(n) + " (LDmicro refuses it too)");
  int32_t mask = n == 32 ? -1 : int32_t((int64_t(1) << n) - 1);
  Operand u = int_opd(Area::D, temp_d(e)), t = int_opd(Area::D, temp_d(e));
  std::vector<TreeNode> r;
  if (k == "SHR") {  // arithmetic: ((x XOR m) >> k) XOR m, m = -1 when x < 0
    r.push_back(out_node(Op::SHR, {src, const_opd(31), t}, e));
    r.push_back(out_node(Op::SUB, {const_opd(0), t, t}, e));
    r.push_back(out_node(Op::WXOR, {src, t, u}, e));
    r.push_back(out_node(Op::SHR, {u, k_opd, u}, e));
    r.push_back(out_node(Op::WXOR, {u, t, dest}, e));
  } else {
    r.push_back(out_node(Op::WAND, {src, const_opd(mask), u}, e));
    if (k == "SR0") {
      r.push_back(out_node(Op::SHR, {u, k_opd, dest}, e));
    } else {  // rotate: (u << k) | (u >> (n - k)) within n bits, or the mirror for ROR
      Operand back = k_opd.kind == OpdKind::ConstInt ? const_opd(n - k_opd.ival) : int_opd(Area::D, temp_d(e));
      if (k_opd.kind != OpdKind::ConstInt) r.push_back(out_node(Op::SUB, {const_opd(n), k_opd, back}, e));
      bool left = k == "ROL";
      r.push_back(out_node(left ? Op::SHL : Op::SHR, {u, k_opd, t}, e));
      r.push_back(out_node(left ? Op::SHR : Op::SHL, {u, back, u}, e));
      r.push_back(out_node(Op::WOR, {t, u, t}, e));
      r.push_back(out_node(Op::WAND, {t, const_opd(mask), dest}, e));
    }
  }
  for (TreeNode& x : r) rb_.add(std::move(x));
  wrap(e, 0);
}

// BIN2BCD: packed BCD, one digit per 4 bits, as many digits as the destination
// holds (the source's n-bit pattern, so -1 in one byte is 255).  BCD2BIN: the
// reverse, one digit per 4 bits of the source.  SWAP: the two halves of one byte
// (nibbles), or bytes 0 and 1 (2 bytes), 0 and 2 (3 bytes), all four reversed
// (4 bytes).  OPPOSITE: the source's n bits in reverse order.
void Importer::bcd(const Elem& e) {
  const std::string& k = e.kw;
  int sw = arg_width(e, 1), n = 8 * sw;
  int32_t mask = n == 32 ? -1 : int32_t((int64_t(1) << n) - 1);
  Operand src = value(e, 1), dest = value(e, 0, true);
  Operand v = int_opd(Area::D, temp_d(e)), r = int_opd(Area::D, temp_d(e)), t = int_opd(Area::D, temp_d(e));
  std::vector<TreeNode> x;
  x.push_back(out_node(Op::WAND, {src, const_opd(mask), v}, e));
  x.push_back(out_node(Op::MOV, {const_opd(0), r}, e));
  if (k == "BIN2BCD") {
    int digits = 2 * arg_width(e, 0);
    for (int i = 0; i < digits; i++) {
      x.push_back(out_node(Op::MOD, {v, const_opd(10), t}, e));
      x.push_back(out_node(Op::DIV, {v, const_opd(10), v}, e));
      x.push_back(out_node(Op::SHL, {t, const_opd(4 * i), t}, e));
      x.push_back(out_node(Op::WOR, {r, t, r}, e));
    }
  } else if (k == "BCD2BIN") {
    int32_t scale = 1;
    for (int i = 0; i < 2 * sw; i++, scale *= 10) {
      x.push_back(out_node(Op::SHR, {v, const_opd(4 * i), t}, e));
      x.push_back(out_node(Op::WAND, {t, const_opd(15), t}, e));
      x.push_back(out_node(Op::MUL, {t, const_opd(scale), t}, e));
      x.push_back(out_node(Op::ADD, {r, t, r}, e));
    }
  } else {
    // (from bit, to bit, width) moves
    std::vector<std::array<int, 3>> moves;
    if (k == "OPPOSITE")
      for (int i = 0; i < n; i++) moves.push_back({i, n - 1 - i, 1});
    else if (sw == 1) moves = {{0, 4, 4}, {4, 0, 4}};
    else if (sw == 2) moves = {{0, 8, 8}, {8, 0, 8}};
    else if (sw == 3) moves = {{0, 16, 8}, {8, 8, 8}, {16, 0, 8}};
    else moves = {{0, 24, 8}, {8, 16, 8}, {16, 8, 8}, {24, 0, 8}};
    for (auto [from, to, w] : moves) {
      x.push_back(out_node(Op::SHR, {v, const_opd(from), t}, e));
      x.push_back(out_node(Op::WAND, {t, const_opd(int32_t((int64_t(1) << w) - 1)), t}, e));
      x.push_back(out_node(Op::SHL, {t, const_opd(to), t}, e));
      x.push_back(out_node(Op::WOR, {r, t, r}, e));
    }
  }
  x.push_back(out_node(Op::MOV, {r, dest}, e));
  for (TreeNode& y : x) rb_.add(std::move(y));
  wrap(e, 0);
}

// 7SEGMENTS dest src C|A (and 9, 14, 16): dest := the segment pattern of the
// character src from LDmicro's table, inverted for a common anode.  A variable
// source is first clamped as LDmicro does it, in place: the degree sign 0xB0
// becomes entry 128, anything outside 0..128 a space.
void Importer::segments(const Elem& e) {
  const int32_t* table = e.kw[0] == '7' ? ldmicro_segments::k7 : e.kw[0] == '9' ? ldmicro_segments::k9
                         : e.kw[1] == '4' ? ldmicro_segments::k14 : ldmicro_segments::k16;
  SrcLoc loc = e.loc();
  Operand dest = value(e, 0, true);
  bool anode = e.args[2] == "A";
  if (is_number(e.args[1])) {
    int32_t c = number(e.args[1], e.line, e.cols[1]);
    c = c == 0xB0 ? 128 : (c < 0 || c > 128) ? ' ' : c;
    rb_.add(out_node(Op::MOV, {const_opd(anode ? ~table[c] : table[c]), dest}, e));
    wrap(e, 0);
    return;
  }
  Operand src = value(e, 1, true), t = int_opd(Area::D, temp_d(e));
  std::vector<TreeNode> items;
  items.push_back(then_node(Cond::of(leaf_node(Op::LDEQ, {src, const_opd(0xB0)}, e)), out_node(Op::MOV, {const_opd(128), src}, e), loc));
  items.push_back(then_node(Cond::of(leaf_node(Op::LDLT, {src, const_opd(0)}, e)), out_node(Op::MOV, {const_opd(' '), src}, e), loc));
  items.push_back(then_node(Cond::of(leaf_node(Op::LDGT, {src, const_opd(128)}, e)), out_node(Op::MOV, {const_opd(' '), src}, e), loc));
  for (int i = 0; i <= 128; i++)
    items.push_back(then_node(Cond::of(leaf_node(Op::LDEQ, {src, const_opd(i)}, e)), out_node(Op::MOV, {const_opd(table[i]), t}, e), loc));
  if (anode) items.push_back(out_node(Op::WNOT, {t, t}, e));
  items.push_back(out_node(Op::MOV, {t, dest}, e));
  rb_.add(fork_of(std::move(items)));
  wrap(e, 0);
}

// BUS dest src b0 .. b7: bit i of dest is bit b_i of src (the low byte).
void Importer::bus(const Elem& e) {
  Operand dest = value(e, 0, true), src = value(e, 1);
  Operand r = int_opd(Area::D, temp_d(e)), t = int_opd(Area::D, temp_d(e));
  std::vector<TreeNode> x;
  x.push_back(out_node(Op::MOV, {const_opd(0), r}, e));
  for (int i = 0; i < 8; i++) {
    int b = number(e.args[2 + i], e.line, e.cols[2 + i]);
    x.push_back(out_node(Op::SHR, {src, const_opd(b), t}, e));
    x.push_back(out_node(Op::WAND, {t, const_opd(1), t}, e));
    x.push_back(out_node(Op::SHL, {t, const_opd(i), t}, e));
    x.push_back(out_node(Op::WOR, {r, t, r}, e));
  }
  x.push_back(out_node(Op::MOV, {r, dest}, e));
  for (TreeNode& y : x) rb_.add(std::move(y));
  wrap(e, 0);
}

// MOVE T v: LDmicro's timer value is a count of cycles; ldc's is milliseconds,
// so the timer's word gets v * CYCLE (the reset of a retentive timer is MOVE T 0).
void Importer::move_to_timer(const Elem& e) {
  Operand tw = int_opd(Area::TW, name_of(e, 0).dev.index);
  int32_t cyc = cycle_ms(e);
  Operand v = value(e, 1);
  if (v.kind == OpdKind::ConstInt) {
    int64_t ms = int64_t(v.ival) * cyc;
    if (ms > INT32_MAX || ms < INT32_MIN) fail(e.line, e.cols[1], "timer value too large in milliseconds");
    rb_.add(out_node(Op::MOV, {const_opd(int32_t(ms)), tw}, e));
  } else {
    rb_.add(out_node(Op::MUL, {v, const_opd(cyc), tw}, e));
  }
}

// A literal compared with a narrower variable is read at the variable's width,
// as LDmicro stores it there: with a 1-byte variable, 0xfd is -3.
Operand Importer::narrow_literal(const Elem& e, size_t lit, size_t var) {
  Operand o = value(e, lit);
  if (o.kind != OpdKind::ConstInt || is_number(e.args[var])) return o;
  int n = 8 * width_of(e.args[var]);
  if (n < 32 && o.ival >= (int64_t(1) << (n - 1)) && o.ival < (int64_t(1) << n)) o.ival -= int32_t(int64_t(1) << n);
  return o;
}

// The words of one SPI or I2C element, reserved before any name is allocated:
// a tx word per byte it sends (SPI_WR sends the characters of its text, or one
// byte when it names a number), an rx word when it receives.
void Importer::plan_bus(const Elem& e) {
  BusWords w;
  bool spi = e.kw[0] == 'S';
  size_t bytes = 1;
  if (e.kw == "SPI_WR" && !is_number(e.args[1])) bytes = e.args[1].size();
  int& count = spi ? spi_bytes_ : i2c_bytes_;
  uint32_t next = kBusTop - uint32_t(spi_bytes_ + i2c_bytes_);
  if (next < bytes + 512) fail(e.line, e.col, "too many SPI and I2C bytes in this program (at most 510)");
  for (size_t i = 0; i < bytes; i++) {
    uint32_t ix = next - uint32_t(i);
    w.tx.push_back(ix);
    used_.insert({int(Dev::WY), ix});
    bus_aliases_.push_back({std::string(spi ? "spi_tx" : "i2c_tx") + std::to_string(++count), {Dev::WY, ix}});
    if (i == 0 && (e.kw == "SPI" || e.kw == "I2C_RD")) {
      w.rx = int(ix);
      used_.insert({int(Dev::WX), ix});
      bus_aliases_.push_back({std::string(spi ? "spi_rx" : "i2c_rx") + std::to_string(count), {Dev::WX, ix}});
    }
  }
  bus_words_[{e.line, e.col}] = w;
}

// One transfer per byte, in this scan, when the state is on: bus_seq counts it
// (modulo 2^23) and the byte's tx word gets (bus_seq << 8) | byte; a read takes
// the low byte of its rx word.  The state passes on (LDmicro's output is its input).
void Importer::bus_transfer(const Elem& e) {
  const BusWords& w = bus_words_.at({e.line, e.col});
  Operand seq = int_opd(Area::D, kBusSeq), t = int_opd(Area::D, temp_d(e));
  std::vector<Operand> bytes;
  if (e.kw == "SPI_WR" && !is_number(e.args[1]))
    for (char c : e.args[1]) bytes.push_back(const_opd((unsigned char)c));
  else if (e.kw == "I2C_RD") bytes.push_back(const_opd(0));
  else bytes.push_back(value(e, 1));
  for (size_t i = 0; i < bytes.size(); i++) {
    Operand tx = int_opd(Area::WY, w.tx[i]);
    rb_.add(out_node(Op::ADD, {seq, const_opd(1), seq}, e));
    rb_.add(out_node(Op::WAND, {seq, const_opd(0x7FFFFF), seq}, e));
    Operand b = bytes[i].kind == OpdKind::ConstInt ? const_opd(bytes[i].ival & 255) : t;
    if (b.kind != OpdKind::ConstInt) rb_.add(out_node(Op::WAND, {bytes[i], const_opd(255), t}, e));
    rb_.add(out_node(Op::SHL, {seq, const_opd(8), tx}, e));
    rb_.add(out_node(Op::WOR, {tx, b, tx}, e));
  }
  if (w.rx >= 0) {
    rb_.add(out_node(Op::WAND, {int_opd(Area::WX, uint32_t(w.rx)), const_opd(255), value(e, 2, true)}, e));
    wrap(e, 2);
  }
}

void Importer::element(const Elem& e, bool need_out) {
  const std::string& k = e.kw;
  SrcLoc loc = e.loc();
  if (k == "SERIES") return series_code(e.kids, need_out);
  if (k == "PARALLEL") return parallel_code(e, need_out);
  if (auto c = pure(e)) {
    if (c->k != Cond::True) rb_.narrow(std::move(*c), loc);
    return;
  }
  if (k == "COIL") return coil(e);
  if (is_uart(k)) return uart(e);
  if (k == "FORMATTED_STRING") return formatted_string(e);
  if (k == "STRING") return string_elem(e);
  if (is_bus(k)) return bus_transfer(e);
  if (k == "PERSIST") {  // the variable is retentive; the state passes on
    auto it = names_.find(e.args[0]);
    if (is_number(e.args[0]) || it == names_.end() || it->second.kind != NK::Var)
      fail(e.line, e.cols[0], "PERSIST needs an integer variable; '" + e.args[0] + "' is " +
                                  (is_number(e.args[0]) ? std::string("a number") : kind_word(it->second.kind)));
    DeviceRef d{Dev::D, it->second.dev.index};
    if (std::find(persist_.begin(), persist_.end(), d) == persist_.end()) persist_.push_back(d);
    return;
  }
  if (is_timer_kw(k)) return timer(e);
  if (k == "CTU" || k == "CTD" || k == "CTC" || k == "CTR") return counter(e);
  if (k == "OSR") {
    Cond s = materialize(e);
    rb_.narrow(bit_leaf(Op::LOADP, Area::M, s.n.elem.a[0].index, e), loc);
    return;
  }
  if (k == "OSF") {
    Cond s = materialize(e);
    rb_.restart(bit_leaf(Op::LOADF, Area::M, s.n.elem.a[0].index, e), loc);
    return;
  }
  if (k == "OSC") {  // while on, on and off in turn, on first: out = state AND NOT last out
    Cond s = materialize(e);
    uint32_t sm = s.n.elem.a[0].index, st = temp_m(e), om = temp_m(e);
    frozen_.insert(om);
    rb_.chain(c_and(bit_leaf(Op::LOAD, Area::M, sm, e), bit_leaf(Op::LOADN, Area::M, st, e)), out_node(Op::OUT, {bit_opd(Area::M, om)}, e), loc);
    rb_.chain(bit_leaf(Op::LOAD, Area::M, om, e), out_node(Op::OUT, {bit_opd(Area::M, st)}, e), loc);
    rb_.restart(bit_leaf(Op::LOAD, Area::M, om, e), loc);
    return;
  }
  if (k == "OSL") {  // on while the state is on; off for one scan after it falls (once it has been on)
    Cond s = materialize(e);
    uint32_t sm = s.n.elem.a[0].index, lo = temp_m(e), hi = temp_m(e), om = temp_m(e);
    frozen_.insert(om);
    rb_.chain(c_or(bit_leaf(Op::LOAD, Area::M, sm, e), bit_leaf(Op::LOAD, Area::M, lo, e)), out_node(Op::OUT, {bit_opd(Area::M, om)}, e), loc);
    std::vector<TreeNode> on;
    on.push_back(out_node(Op::RST, {bit_opd(Area::M, lo)}, e));
    on.push_back(out_node(Op::SET, {bit_opd(Area::M, hi)}, e));
    rb_.chain(bit_leaf(Op::LOAD, Area::M, sm, e), fork_of(std::move(on)), loc);
    rb_.chain(c_and(bit_leaf(Op::LOADN, Area::M, sm, e), bit_leaf(Op::LOAD, Area::M, hi, e)), out_node(Op::SET, {bit_opd(Area::M, lo)}, e), loc);
    rb_.restart(bit_leaf(Op::LOAD, Area::M, om, e), loc);
    return;
  }
  if (k == "CLRWDT" || k == "LOCK" || k == "DELAY" || k == "LABEL") return;
  if (k == "GOTO") {
    size_t t = goto_target(e);
    targets_.insert(t);
    Operand l{OpdKind::Label};
    l.label = "rung" + std::to_string(t + 1);
    rb_.add(out_node(Op::JMP, {l}, e));
    return;
  }
  if (k == "RANDOM" || k == "SEED_RANDOM") {
    // LDmicro's generator: per variable a 32-bit seed, seed := seed * 69069 + 1,
    // and the variable gets the seed's top n bits (n = its width), signed.
    Operand v = value(e, 0, true);
    auto [it, fresh] = seeds_.try_emplace(e.args[0], 0);
    if (fresh) {
      it->second = temp_d(e);
      init_.push_back(out_node(Op::MOV, {const_opd(1), int_opd(Area::D, it->second)}, e));
    }
    Operand seed = int_opd(Area::D, it->second);
    if (k == "SEED_RANDOM") return rb_.add(out_node(Op::MOV, {value(e, 1), seed}, e));
    rb_.add(out_node(Op::MUL, {seed, const_opd(69069), seed}, e));
    rb_.add(out_node(Op::ADD, {seed, const_opd(1), seed}, e));
    rb_.add(out_node(Op::SHR, {seed, const_opd(32 - 8 * width_of(e.args[0])), v}, e));
    wrap(e, 0);
    return;
  }  // no effect on any value: the state passes on
  if (k == "MASTER_RELAY") {
    // LDmicro: if the master relay is off, turn it on; else it takes the rung state.
    Cond s = materialize(e);
    uint32_t sm = s.n.elem.a[0].index;
    rb_.chain(c_or(std::move(s), bit_leaf(Op::LOADN, Area::M, mcr_, e)), out_node(Op::OUT, {bit_opd(Area::M, mcr_)}, e), loc);
    rb_.restart(bit_leaf(Op::LOAD, Area::M, sm, e), loc);
    return;
  }
  if (k == "RES") {
    auto it = names_.find(e.args[0]);
    if (it == names_.end() && rung_refused_) throw Cascade();  // it may be used in the refused rung
    if (it == names_.end()) fail(e.line, e.cols[0], "RES of '" + e.args[0] + "', which no element uses");
    const Name& n = it->second;
    if (n.kind == NK::Timer) {
      if (n.timer_kind == "TON") rb_.add(out_node(Op::RSTT, {timer_opd(n.dev.index)}, e));
      else if (n.timer_kind != "TOF") rb_.add(out_node(Op::MOV, {const_opd(0), int_opd(Area::TW, n.dev.index)}, e));
      else fail(e.line, e.cols[0], "RES of the TOF timer '" + e.args[0] + "' is not supported: LDmicro restarts its off-delay, which ldc's TOF cannot be made to do");
    } else if (n.kind == NK::Counter) {
      if (v01_) rb_.add(out_node(Op::RSTC, {counter_opd(n.dev.index)}, e));
      else {
        // newer LDmicro resets a counter to its init value
        Operand init = const_opd(0);
        std::function<void(const std::vector<Elem>&)> find = [&](const std::vector<Elem>& s) {
          for (const Elem& x : s) {
            if ((x.kw == "CTU" || x.kw == "CTD" || x.kw == "CTC" || x.kw == "CTR") && x.args[0] == e.args[0] && x.args.size() >= 3)
              init = value(x, 2);
            find(x.kids);
          }
        };
        for (const SrcRung& r : rungs_)
          if (!r.refused) find(r.series);
        rb_.add(out_node(Op::MOV, {init, int_opd(Area::CW, n.dev.index)}, e));
      }
    } else if (n.kind == NK::Var) {
      rb_.add(out_node(Op::MOV, {const_opd(0), int_opd(Area::D, n.dev.index)}, e));
    } else {
      fail(e.line, e.cols[0], "RES of " + std::string(kind_word(n.kind)) + " '" + e.args[0] + "' is not supported");
    }
    return;
  }
  if (k == "ROL" || k == "ROR" || k == "SHR" || k == "SR0") return bit_op(e);
  if (k == "BIN2BCD" || k == "BCD2BIN" || k == "SWAP" || k == "OPPOSITE") return bcd(e);
  if (is_segments(k)) return segments(e);
  if (k == "BUS") return bus(e);
  if (k == "TIME2COUNT") {  // the delay as LDmicro's timers count it: cycles
    int32_t cycles = timer_ms(e, name_of(e, 0)) / cycle_ms(e);
    rb_.add(out_node(Op::MOV, {const_opd(cycles), value(e, 0, true)}, e));
    wrap(e, 0);
    return;
  }
  if (k == "TIME2DELAY") {  // the delay in the loop counts of LDmicro's DELAY for the MICRO= at CRYSTAL=
    if (!is_number(e.args[1])) fail(e.line, e.cols[1], "TIME2DELAY needs a number of microseconds");
    if (crystal_hz_ <= 0) fail(e.line, e.col, "TIME2DELAY needs the file's CRYSTAL= clock frequency");
    bool avr = micro_.rfind("Atmel AVR", 0) == 0, pic = micro_.rfind("Microchip PIC1", 0) == 0;
    if (!micro_.empty() && !avr && !pic)
      fail(e.line, e.col, "TIME2DELAY is defined for AVR and PIC microcontrollers only, not '" + micro_ + "' (LDmicro refuses it too)");
    __int128 c = __int128(number(e.args[1], e.line, e.cols[1])) * crystal_hz_ / 1000000;
    if (pic) c /= 4;
    if (avr) c = std::min<__int128>((c - 1) / 4, 0x10000);
    if (pic) c = std::min<__int128>((c - 10) / 6, 0xffff);
    if (c > INT32_MAX) fail(e.line, e.cols[1], "TIME2DELAY result too large");
    rb_.add(out_node(Op::MOV, {const_opd(c <= 0 ? 1 : int32_t(c)), value(e, 0, true)}, e));
    wrap(e, 0);
    return;
  }
  if (k == "MOVE" && !is_number(e.args[0]) && name_of(e, 0).kind == NK::Timer) return move_to_timer(e);
  if (k == "MOVE") {
    rb_.add(out_node(Op::MOV, {value(e, 1), value(e, 0, true)}, e));
    wrap(e, 0);
    return;
  }
  static const std::map<std::string, Op> math = {{"ADD", Op::ADD}, {"SUB", Op::SUB}, {"MUL", Op::MUL}, {"DIV", Op::DIV},
                                                 {"MOD", Op::MOD}, {"AND", Op::WAND}, {"OR", Op::WOR}, {"XOR", Op::WXOR}, {"SHL", Op::SHL}};
  if (auto it = math.find(k); it != math.end()) {
    rb_.add(out_node(it->second, {value(e, 1), value(e, 2), value(e, 0, true)}, e));
    wrap(e, 0);
    return;
  }
  if (k == "NOT") {
    rb_.add(out_node(Op::WNOT, {value(e, 1), value(e, 0, true)}, e));
    wrap(e, 0);
    return;
  }
  if (k == "NEG") {
    rb_.add(out_node(Op::SUB, {const_opd(0), value(e, 1), value(e, 0, true)}, e));
    wrap(e, 0);
    return;
  }
  if (k == "SET_BIT" || k == "CLEAR_BIT" || k == "IF_BIT_SET" || k == "IF_BIT_CLEAR") {
    Operand var = value(e, 0, k == "SET_BIT" || k == "CLEAR_BIT");
    Operand mask;
    if (is_number(e.args[1])) {
      int b = number(e.args[1], e.line, e.cols[1]);
      if (b < 0 || b > 31) fail(e.line, e.cols[1], "bit number " + e.args[1] + " must be 0..31");
      mask = const_opd(int32_t(uint32_t(1) << b));
      if (k == "CLEAR_BIT") mask.ival = ~mask.ival;
    } else {
      mask = int_opd(Area::D, temp_d(e));
      rb_.add(out_node(Op::SHL, {const_opd(1), value(e, 1), mask}, e));
      if (k == "CLEAR_BIT") rb_.add(out_node(Op::WNOT, {mask, mask}, e));
    }
    if (k == "SET_BIT") rb_.add(out_node(Op::WOR, {var, mask, var}, e)), wrap(e, 0);
    else if (k == "CLEAR_BIT") rb_.add(out_node(Op::WAND, {var, mask, var}, e)), wrap(e, 0);
    else {
      Operand t = int_opd(Area::D, temp_d(e));
      rb_.add(out_node(Op::WAND, {var, mask, t}, e));
      rb_.narrow(Cond::of(leaf_node(k == "IF_BIT_SET" ? Op::LDNE : Op::LDEQ, {t, const_opd(0)}, e)), loc);
    }
    return;
  }
  if (k == "SHIFT_REGISTER") {
    // on each rising edge: name{i+1} := name{i}, from the last stage down
    int stages = number(e.args[1], e.line, e.cols[1]);
    Cond s = materialize(e);
    std::vector<TreeNode> moves;
    for (int i = stages - 2; i >= 0; i--) {
      const Name& src = names_.at(e.args[0] + std::to_string(i));
      const Name& dst = names_.at(e.args[0] + std::to_string(i + 1));
      Operand d = int_opd(Area::D, dst.dev.index);
      moves.push_back(out_node(Op::MOV, {int_opd(Area::D, src.dev.index), d}, e));
      if (width_of(e.args[0] + std::to_string(i + 1)) < width_of(e.args[0] + std::to_string(i)))
        for (TreeNode& n : wrap_nodes(d, width_of(e.args[0] + std::to_string(i + 1)), e)) moves.push_back(std::move(n));
    }
    if (!moves.empty()) rb_.add(then_node(bit_leaf(Op::LOADP, Area::M, s.n.elem.a[0].index, e), fork_of(std::move(moves)), loc));
    return;
  }
  if (k == "LOOK_UP_TABLE") {
    int64_t count = number(e.args[2], e.line, e.cols[2]);
    if (count < 1 || int64_t(e.args.size()) < 4 + count)
      fail(e.line, e.col, "LOOK_UP_TABLE lists " + std::to_string(e.args.size() >= 4 ? e.args.size() - 4 : 0) + " values but says " + e.args[2]);
    Operand dest = value(e, 0, true), index = value(e, 1);
    std::vector<TreeNode> items;
    for (int i = 0; i < int(count); i++) {
      Operand v = const_opd(number(e.args[4 + i], e.line, e.cols[4 + i]));
      items.push_back(then_node(Cond::of(leaf_node(Op::LDEQ, {index, const_opd(i)}, e)), out_node(Op::MOV, {v, dest}, e), loc));
    }
    rb_.add(fork_of(std::move(items)));
    wrap(e, 0);
    return;
  }
  if (k == "PIECEWISE_LINEAR") {
    int64_t count = number(e.args[2], e.line, e.cols[2]);
    if (count < 1 || int64_t(e.args.size()) < 3 + 2 * count)
      fail(e.line, e.col, "PIECEWISE_LINEAR needs " + e.args[2] + " (x, y) points");
    std::vector<int32_t> v;
    for (int i = 0; i < 2 * int(count); i++) v.push_back(number(e.args[3 + i], e.line, e.cols[3 + i]));
    for (int i = 1; i < int(count); i++)
      if (int64_t(v[2 * i]) <= v[2 * (i - 1)]) fail(e.line, e.cols[3 + 2 * i], "x values in a piecewise linear table must increase strictly");
    Operand dest = value(e, 0, true), index = value(e, 1);
    std::vector<TreeNode> items;
    for (int i = int(count) - 1; i >= 1; i--) {
      int64_t dx64 = int64_t(v[2 * i]) - v[2 * (i - 1)], dy64 = int64_t(v[2 * i + 1]) - v[2 * (i - 1) + 1];
      if (dx64 > INT32_MAX || dy64 > INT32_MAX || dy64 < INT32_MIN)
        fail(e.line, e.col, "PIECEWISE_LINEAR points too far apart for 32-bit arithmetic");
      int32_t dx = int32_t(dx64), dy = int32_t(dy64);
      std::vector<TreeNode> body;
      body.push_back(out_node(Op::SUB, {index, const_opd(v[2 * (i - 1)]), dest}, e));
      body.push_back(out_node(Op::MUL, {dest, const_opd(dy), dest}, e));
      body.push_back(out_node(Op::DIV, {dest, const_opd(dx), dest}, e));
      body.push_back(out_node(Op::ADD, {dest, const_opd(v[2 * (i - 1) + 1]), dest}, e));
      items.push_back(then_node(Cond::of(leaf_node(Op::LDLE, {index, const_opd(v[2 * i])}, e)), fork_of(std::move(body)), loc));
    }
    if (!items.empty()) rb_.add(fork_of(std::move(items)));
    wrap(e, 0);
    return;
  }
  if (k == "READ_ADC") {
    const Name& n = name_of(e, 0);
    rb_.add(out_node(Op::MOV, {int_opd(Area::WX, n.dev.index), int_opd(Area::D, n.held.index)}, e));
    return;
  }
  if (k == "SET_PWM") {
    std::string pn = e.args.size() >= 3 ? e.args[2] : "P";
    if (pn[0] != 'P') pn = "P" + pn;
    const Name& n = names_.at(pn);
    rb_.add(out_node(Op::MOV, {value(e, 0), int_opd(Area::WY, n.dev.index)}, e));
    return;
  }
  fail(e.line, e.col, "internal: no translation for '" + k + "'");
}

void Importer::series_code(const std::vector<Elem>& s, bool need_out) {
  for (size_t i = 0; i < s.size(); i++) element(s[i], need_out || i + 1 < s.size());
}

// LDmicro: every branch starts from a copy of the state; the state after the
// block is the OR of the branches' final states, each taken when its branch ends.
void Importer::parallel_code(const Elem& e, bool need_out) {
  SrcLoc loc = e.loc();
  if (auto c = pure(e)) {
    if (c->k != Cond::True) rb_.narrow(std::move(*c), loc);
    return;
  }
  size_t n = e.kids.size();
  bool saved_needed = false;
  for (size_t i = 0; i + 1 < n; i++) saved_needed |= breaks(e.kids[i]);
  Cond saved;
  if (saved_needed) saved = materialize(e);
  size_t depth = rb_.frames.size();
  int gen0 = rb_.gen;
  uint32_t po = need_out ? temp_m(e) : 0;
  if (need_out) frozen_.insert(po);  // complete when the block ends, and read only then
  for (size_t i = 0; i < n; i++) {
    if (rb_.gen == gen0) rb_.pop_to(depth);
    else if (saved_needed) rb_.restart(saved, loc);
    else fail(e.line, e.col, "internal: a parallel branch ended its chain unexpectedly");
    element(e.kids[i], need_out);
    if (need_out) rb_.add(out_node(i == 0 ? Op::OUT : Op::SET, {bit_opd(Area::M, po)}, e));
  }
  if (rb_.gen == gen0) {
    rb_.pop_to(depth);
    if (need_out) rb_.narrow(bit_leaf(Op::LOAD, Area::M, po, e), loc);
  } else if (need_out) {
    rb_.restart(bit_leaf(Op::LOAD, Area::M, po, e), loc);
  }
}

// GOTO label: the rung holding LABEL label, or LDmicro's rung number; ldc's
// JMP goes forward only, so a GOTO to this rung or an earlier one (a loop
// inside the cycle) is refused.  A target past the last rung ends the scan's rungs.
size_t Importer::goto_target(const Elem& e) {
  const std::string& l = e.args[0];
  size_t t;
  if (is_number(l)) {
    int64_t n = number(l, e.line, e.cols[0]);
    t = rungs_.size();
    for (size_t i = 0; i < rungs_.size(); i++)
      if (rungs_[i].ldm_index >= n - 1) { t = i; break; }
  } else {
    auto it = labels_.find(l);
    if (it == labels_.end() && rung_refused_) throw Cascade();  // it may be in the refused rung
    if (it == labels_.end()) fail(e.line, e.cols[0], "GOTO: LABEL '" + l + "' not found (LDmicro refuses it too)");
    t = it->second;
  }
  if (t <= rung_now_)
    fail(e.line, e.col, "GOTO to this rung or an earlier one (a loop inside the cycle) is not supported: ldc jumps forward only");
  return t;
}

void Importer::translate(const SrcRung& r, size_t index) {
  rung_now_ = index;
  Elem at;
  at.line = r.line;
  at.col = 1;
  rb_ = RungBuilder();
  rb_.start(mcr_used_ ? bit_leaf(Op::LOAD, Area::M, mcr_, at) : Cond::yes(), at.loc());
  series_code(r.series, false);
  rb_.close_chain();
}

TreeProgram Importer::run() {
  read_lines();
  if (lines_.empty() || trim(lines_[0].text).find("LDmicro") == std::string::npos)
    fail(1, 1, "not an LDmicro file: the first line should be LDmicro0.1, LDmicro0.2 or LDmicro");
  size_t prog = header();
  program(prog);
  for (const auto& io : io_list_) {
    const std::string& nm = io.first;
    int line = io.second;
    char c = nm.empty() ? 0 : nm[0];
    NK k = c == 'X' || c == 'Y' ? NK::Bit : c == 'A' ? NK::Adc : c == 'P' ? NK::Pwm : NK::Var;
    if (k != NK::Var) unit([&] { note(nm, k, line, 1); });
  }
  std::function<void(const std::vector<Elem>&)> walk = [&](const std::vector<Elem>& s) {
    for (const Elem& e : s) {
      collect(e);
      if (e.kw == "MASTER_RELAY") mcr_used_ = true;
    }
  };
  std::function<void(const std::vector<Elem>&)> find_uart = [&](const std::vector<Elem>& s) {
    for (const Elem& e : s) {
      uart_used_ |= is_uart(e.kw) || e.kw == "FORMATTED_STRING";
      find_uart(e.kids);
    }
  };
  std::function<void(const std::vector<Elem>&)> find_bus = [&](const std::vector<Elem>& s) {
    for (const Elem& e : s) {
      if (is_bus(e.kw)) plan_bus(e);
      find_bus(e.kids);
    }
  };
  std::function<void(const std::vector<Elem>&)> find_strings = [&](const std::vector<Elem>& s) {
    for (const Elem& e : s) {
      if (e.kw == "STRING") plan_string(e);
      find_strings(e.kids);
    }
  };
  // each rung's names: a rung with an error is refused, and not translated
  auto in_rung = [&](SrcRung& r, const std::function<void()>& read) {
    if (!r.refused && !unit(read)) r.refused = rung_refused_ = true;
  };
  for (SrcRung& r : rungs_) in_rung(r, [&] { find_strings(r.series); });
  for (SrcRung& r : rungs_) in_rung(r, [&] { walk(r.series), find_uart(r.series), find_bus(r.series); });
  if (!bus_words_.empty()) used_.insert({int(Dev::D), kBusSeq});
  if (uart_used_)
    for (DeviceRef r : {DeviceRef{Dev::WX, kUartRx}, DeviceRef{Dev::WY, kUartTx}, DeviceRef{Dev::D, kUartSeen}, DeviceRef{Dev::M, kUartBusy}})
      used_.insert({int(r.dev), r.index});
  allocate();
  if (uart_used_) {  // their aliases, unless an LDmicro name has taken one
    std::set<std::string> taken;
    for (const Alias& a : aliases_) taken.insert(upper(a.name));
    for (const Alias& a : {Alias{"uart_rx", {Dev::WX, kUartRx}}, Alias{"uart_tx", {Dev::WY, kUartTx}},
                           Alias{"uart_rx_seen", {Dev::D, kUartSeen}}, Alias{"uart_tx_busy", {Dev::M, kUartBusy}}})
      if (!taken.count(upper(a.name))) aliases_.push_back(a);
  }
  if (!bus_words_.empty()) {
    std::set<std::string> taken;
    for (const Alias& a : aliases_) taken.insert(upper(a.name));
    bus_aliases_.push_back({"bus_seq", {Dev::D, kBusSeq}});
    for (const Alias& a : bus_aliases_)
      if (!taken.count(upper(a.name))) aliases_.push_back(a);
  }
  TreeProgram p;
  p.source = file_;
  p.aliases = aliases_;
  Elem top;
  top.line = rungs_.empty() ? int(lines_.size()) : rungs_[0].line;
  top.col = 1;
  if (mcr_used_) {
    // LDmicro sets its master control relay at the start of every cycle
    mcr_ = temp_m(top);
    TreeRung tr;
    tr.line = top.line;
    tr.title = "master control relay on";
    tr.root = out_node(Op::OUT, {bit_opd(Area::M, mcr_)}, top);
    p.rungs.push_back(std::move(tr));
  }
  if (uart_used_) {
    TreeRung tr;
    tr.line = top.line;
    tr.title = "UART transmitter free at the start of the scan";
    tr.root = out_node(Op::OUTN, {bit_opd(Area::M, kUartBusy)}, top);
    p.rungs.push_back(std::move(tr));
  }
  size_t init_at = p.rungs.size();
  std::function<void(const std::vector<Elem>&, size_t)> find_labels = [&](const std::vector<Elem>& s, size_t i) {
    for (const Elem& e : s) {
      if (e.kw == "LABEL" && !labels_.emplace(e.args[0], i).second)
        fail(e.line, e.cols[0], "LABEL '" + e.args[0] + "' is placed twice");
      find_labels(e.kids, i);
    }
  };
  for (size_t i = 0; i < rungs_.size(); i++) unit([&] { find_labels(rungs_[i].series, i); });
  std::vector<std::string> pending;  // labels waiting for the next rung that makes code
  for (size_t i = 0; i < rungs_.size(); i++) {
    if (rungs_[i].refused || !unit([&] { translate(rungs_[i], i); })) continue;
    if (targets_.count(i)) pending.push_back("rung" + std::to_string(i + 1));
    if (rb_.top.empty()) continue;  // only conditions: nothing to do
    TreeRung tr;
    tr.labels = std::move(pending);
    pending.clear();
    tr.line = rungs_[i].line;
    tr.title = titles_[i];
    tr.root = fork_of(std::move(rb_.top));
    p.rungs.push_back(std::move(tr));
  }
  if (!init_.empty()) {
    TreeRung tr;
    tr.line = top.line;
    tr.title = "initial values";
    tr.root = then_node(bit_leaf(Op::LOAD, Area::S, kBitFirstScan, top), fork_of(std::move(init_)), top.loc());
    p.rungs.insert(p.rungs.begin() + long(init_at), std::move(tr));
  }
  p.end_labels = pending;
  for (size_t t : targets_)
    if (t >= rungs_.size()) p.end_labels.push_back("rung" + std::to_string(t + 1));
  p.retain = persist_;
  return p;
}

// Reads one unit (a setting or I/O-list line, a rung, a name): without
// diagnostics its error is thrown; with them it is reported (not a Cascade),
// and false says the unit was refused.
bool Importer::unit(const std::function<void()>& read) { return recover_unit(diag_, file_, read); }

}  // namespace

TreeProgram parse_ldmicro(std::string_view text, const std::string& filename) { return Importer(text, filename).run(); }

TreeProgram parse_ldmicro(std::string_view text, const std::string& filename, Diagnostics& diag) {
  int errors0 = diag.errors();
  TreeProgram p;
  try {
    p = Importer(text, filename, &diag).run();
  } catch (const Cascade&) {
  } catch (const CompileError& e) {  // an error the import cannot go on after (no PROGRAM line, out of devices)
    diag.error(filename, e);
  }
  if (diag.errors() > errors0) throw ErrorsReported();
  return p;
}

}  // namespace ldc
