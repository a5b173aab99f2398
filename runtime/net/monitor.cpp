// runtime/net/monitor.cpp -- see monitor.h.
#include "runtime/net/monitor.h"

#include <arpa/inet.h>
#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstring>
#include <deque>
#include <functional>
#include <map>
#include <mutex>
#include <set>
#include <stdexcept>
#include <thread>
#include <tuple>

#include "ir/ladder.h"
#include "runtime/net/http.h"
#include "runtime/write_shadow.h"
#include "runtime/monitor_page.h"  // generated: kMonitorHtml, kMonitorJs, kMonitorCss

namespace ldc::plc {
namespace {

// ---------------------------------------------------------------- JSON

std::string jstr(std::string_view s) {
  std::string o = "\"";
  for (char c : s) {
    unsigned char u = static_cast<unsigned char>(c);
    if (c == '"' || c == '\\') o += '\\', o += c;
    else if (c == '\n') o += "\\n";
    else if (u < 0x20 || u == 0x7f) {
      char b[8];
      std::snprintf(b, sizeof b, "\\u%04x", u);
      o += b;
    } else o += c;
  }
  return o + "\"";
}
std::string jnum(double v) {
  if (!std::isfinite(v)) return "null";
  char b[32];
  std::snprintf(b, sizeof b, "%.6g", v);
  return b;
}

// ---------------------------------------------------------------- programs

bool is_shared(Area a) { return a == Area::X || a == Area::Y || a == Area::M || a == Area::K || a == Area::WX || a == Area::WY; }

const char* device_prefix_of(Area a) {
  switch (a) {
    case Area::X: return "X";
    case Area::Y: return "Y";
    case Area::M: return "M";
    case Area::K: return "K";
    case Area::S: return "S";
    case Area::TQ: case Area::TW: return "T";
    case Area::CQ: case Area::CW: return "C";
    case Area::WX: return "WX";
    case Area::WY: return "WY";
    case Area::D: return "D";
    case Area::F: return "F";
    default: return "?";
  }
}

// The program of an image, rung by rung as its line map splits it; jump
// targets (byte offsets in the binary IL) become labels L<rung>.
Program program_of(const Image& img) {
  Program p;
  p.source = img.source;
  p.aliases = img.aliases;
  std::vector<Instr> code;
  std::vector<uint32_t> at;
  for (uint32_t off = 0; off < img.il.size();) {
    Instr in;
    at.push_back(off);
    off = decode_instr(img.il, off, in);
    code.push_back(in);
  }
  bool mapped = img.lines.size() == code.size();
  for (size_t k = 0; k < code.size(); k++) {
    uint32_t r = mapped ? img.lines[k].rung : 0;
    while (p.rungs.size() <= r) {
      Rung nr;
      nr.line = mapped ? img.lines[k].line : 0;
      if (p.rungs.size() < img.rung_titles.size()) nr.title = img.rung_titles[p.rungs.size()];
      p.rungs.push_back(std::move(nr));
    }
    if (mapped) code[k].loc = {img.lines[k].line, 1};
    p.rungs[r].code.push_back(code[k]);
  }
  // labels
  std::map<uint32_t, size_t> rung_at;  // IL offset of a rung's first instruction -> rung
  size_t k = 0;
  for (size_t r = 0; r < p.rungs.size(); r++) {
    if (!p.rungs[r].code.empty()) rung_at.emplace(at[k], r);
    k += p.rungs[r].code.size();
  }
  std::set<size_t> labelled;
  bool end_label = false;
  for (Rung& r : p.rungs)
    for (Instr& in : r.code)
      for (Operand& o : in.a)
        if (o.kind == OpdKind::Label) {
          auto it = rung_at.find(o.index);
          if (it != rung_at.end()) o.label = "L" + std::to_string(it->second + 1), labelled.insert(it->second);
          else o.label = "END_OF_SCAN", end_label = true;
        }
  for (size_t r : labelled) p.rungs[r].labels.push_back("L" + std::to_string(r + 1));
  if (end_label) p.end_labels.push_back("END_OF_SCAN");
  p.edge_slots = img.layout.count[int(Area::E)];
  return p;
}

struct Dev {
  std::string name, alias;
  Area area;
  uint32_t index;
  Ty ty = Ty::None;  // its alias's type: shown as --watch shows it (docs/format.md)
};

// ---------------------------------------------------------------- source view
//
// An ST or IEC IL program is shown as its source text, and beside each place
// a line assigns a variable (`x :=`, `=> x`, IL `ST x`) that variable's live
// value.  What a line assigns comes from the code: the destinations of the
// instructions the line map puts on that line, named by the program's
// aliases; where the text names one of them as a target, its value goes
// right after the name.  Temporaries (no alias) and indexed stores (c[i] :=)
// have no fixed name and show nothing.

constexpr size_t kMaxSourceBytes = size_t(4) << 20;  // larger sources are not shown (docs/runtime.md)
constexpr size_t kMaxSourceLines = 200000;

struct SourceWatch {
  std::string name;  // the alias
  Dev dev;
};

struct SourceLine {
  // text pieces, and after piece k (k < marks.size()) the watches marks[k]
  std::vector<std::string> text;
  std::vector<std::vector<uint32_t>> marks;
};

struct SourceView {
  std::string note;  // not shown: why ("" when shown)
  std::vector<SourceLine> lines;
  std::vector<SourceWatch> watches;
};

std::string lowered(std::string s) {
  for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
}
bool ident_start(char c) { return std::isalpha(static_cast<unsigned char>(c)) || c == '_'; }
bool ident_char(char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; }

// A designator the line writes: where it ends in the line, and its spelling
// lower-cased without blanks ("tank.level", "c[3]").
struct Target {
  size_t end;
  std::string key;
};

// The targets of one line: designators followed by `:=`, preceded by `=>`,
// or after an IEC IL store (ST, STN, S, R) at the start of the line.
// Comments (* *) (nested, across lines, `depth` carries them), // comments,
// pragmas { } and strings are skipped.
std::vector<Target> line_targets(const std::string& s, int& depth) {
  std::vector<Target> out;
  size_t i = 0, n = s.size();
  bool after_arrow = false;  // the last token was =>
  bool il_store = false;     // the line so far is an IL store operator
  bool first_token = true;
  while (i < n) {
    if (depth > 0) {
      if (s.compare(i, 2, "(*") == 0) depth++, i += 2;
      else if (s.compare(i, 2, "*)") == 0) depth--, i += 2;
      else i++;
      continue;
    }
    char c = s[i];
    if (c == ' ' || c == '\t' || c == '\r') { i++; continue; }
    if (s.compare(i, 2, "(*") == 0) { depth++, i += 2; continue; }
    if (s.compare(i, 2, "//") == 0) break;
    if (c == '{') {  // a pragma: to its end on this line
      size_t e = s.find('}', i);
      i = e == std::string::npos ? n : e + 1;
      continue;
    }
    if (c == '\'' || c == '"') {
      size_t j = i + 1;
      while (j < n && s[j] != c) j += s[j] == '$' ? 2 : 1;
      i = j + 1, after_arrow = false, first_token = false;
      continue;
    }
    if (s.compare(i, 2, "=>") == 0) { after_arrow = true, i += 2, first_token = false; continue; }
    if (!ident_start(c)) { after_arrow = false, il_store = false, first_token = false, i++; continue; }
    // a designator: ident ( . ident | [ ... ] )*
    std::string key;
    auto word = [&] {
      while (i < n && ident_char(s[i])) key += char(std::tolower(static_cast<unsigned char>(s[i]))), i++;
    };
    word();
    while (i < n) {
      if (s[i] == '.' && i + 1 < n && ident_start(s[i + 1])) key += '.', i++, word();
      else if (s[i] == '[') {
        size_t e = s.find(']', i);
        if (e == std::string::npos) break;
        for (size_t k = i; k <= e; k++)
          if (s[k] != ' ' && s[k] != '\t') key += char(std::tolower(static_cast<unsigned char>(s[k])));
        i = e + 1;
      } else break;
    }
    size_t end = i, j = i;
    while (j < n && (s[j] == ' ' || s[j] == '\t')) j++;
    if (s.compare(j, 2, ":=") == 0 || after_arrow || il_store) out.push_back({end, key});
    il_store = first_token && (key == "st" || key == "stn" || key == "s" || key == "r");
    after_arrow = false;
    first_token = false;
  }
  return out;
}

// The devices each line writes: a destination operand (ops.def letters w,
// d, r) of a fixed device the aliases name, once per line.  By line, then by
// each designator that names it: the alias itself (lower case) and, for a
// member of an instance, the member's own name (a function block's body
// writes `total` of each instance: acc.total, acc2.total) -- a lookup each,
// however long the line.
using Written = std::map<int32_t, std::multimap<std::string, SourceWatch>>;
Written written_by_line(const Program& p, const std::vector<Alias>& aliases) {
  std::map<std::pair<int, uint32_t>, const Alias*> named;
  for (const Alias& al : aliases) {
    Area b = bit_area(al.dev.dev), w = word_area(al.dev.dev);
    if (b != Area::Count) named.emplace(std::make_pair(int(b), al.dev.index), &al);
    if (w != Area::Count) named.emplace(std::make_pair(int(w), al.dev.index), &al);
  }
  Written out;
  std::set<std::tuple<int32_t, int, uint32_t>> seen;  // line, device
  for (const Rung& r : p.rungs)
    for (const Instr& in : r.code) {
      const char* sig = op_info(in.op).operands;
      for (int k = 0; k < in.nopd() && sig[k]; k++) {
        const Operand& o = in.a[k];
        if (!std::strchr("wdr", sig[k]) || (o.kind != OpdKind::Bit && o.kind != OpdKind::Int && o.kind != OpdKind::Real)) continue;
        auto it = named.find({int(o.area), o.index});
        if (it == named.end() || !seen.emplace(in.loc.line, int(o.area), o.index).second) continue;
        const Alias& al = *it->second;
        Dev d{device_prefix_of(o.area) + std::to_string(o.index), al.name, o.area, o.index};
        if (al.ty != Ty::None && al.ty != Ty::BOOL && !area_is_bit(o.area)) d.ty = al.ty;
        std::multimap<std::string, SourceWatch>& line = out[in.loc.line];
        const std::string key = lowered(al.name);
        line.emplace(key, SourceWatch{al.name, d});
        for (size_t dot = key.find('.'); dot != std::string::npos; dot = key.find('.', dot + 1))
          line.emplace(key.substr(dot + 1), SourceWatch{al.name, d});
      }
    }
  return out;
}

SourceView source_view(const std::string& text, const Program& p, const std::vector<Alias>& aliases) {
  SourceView sv;
  if (text.size() > kMaxSourceBytes || size_t(std::count(text.begin(), text.end(), '\n')) >= kMaxSourceLines) {
    sv.note = "the source is larger than " + std::to_string(kMaxSourceBytes >> 20) + " MiB or " +
              std::to_string(kMaxSourceLines) + " lines: the rungs of its code are shown instead";
    return sv;
  }
  auto written = written_by_line(p, aliases);
  std::map<std::pair<int, uint32_t>, uint32_t> watch_of;  // device -> index in sv.watches
  int depth = 0;
  size_t at = 0;
  for (int32_t line = 1; at <= text.size(); line++) {
    size_t nl = text.find('\n', at);
    std::string s = text.substr(at, nl == std::string::npos ? std::string::npos : nl - at);
    if (!s.empty() && s.back() == '\r') s.pop_back();
    SourceLine sl;
    size_t from = 0;
    auto w = written.find(line);
    for (const Target& t : line_targets(s, depth)) {
      if (w == written.end()) break;
      std::vector<uint32_t> marks;
      for (auto [m, end] = w->second.equal_range(t.key); m != end; ++m) {
        const SourceWatch& sw = m->second;
        auto [it, fresh] = watch_of.emplace(std::make_pair(int(sw.dev.area), sw.dev.index), uint32_t(sv.watches.size()));
        if (fresh) sv.watches.push_back(sw);
        marks.push_back(it->second);
      }
      if (marks.empty()) continue;
      sl.text.push_back(s.substr(from, t.end - from));
      sl.marks.push_back(std::move(marks));
      from = t.end;
    }
    sl.text.push_back(s.substr(from));
    sv.lines.push_back(std::move(sl));
    if (nl == std::string::npos) break;
    at = nl + 1;
  }
  return sv;
}

// Forced inputs as one consumer (the shared image's, or one task's) last
// copied them: refreshed when the server changed them and the lock is free,
// so a scan never waits for the server and always has a complete list.
struct ForcedCopy {
  uint64_t version = 0;
  std::vector<ElementWrite> items;
};

// One pin of a drawn function-block box (or compare box): its name, the
// operand it is wired to as spelled (an alias, a device, a constant), its
// side, and where its live value comes from.
struct Pin {
  enum class From : uint8_t { None, Operand, Elapsed, PowerIn, Result, TimerQ, CounterQ };
  std::string name, text;
  bool right = false;
  From from = From::None;
  Operand opd;  // From::Operand (TimerQ/CounterQ: its index)
};

// How an element is drawn with the IEC 61131-3 symbols: kind "no" -| |-,
// "nc" -|/|-, "p" -|P|-, "n" -|N|-, "true", "cmp" (a compare box), "coil"
// -( )-, "ncoil" -(/)-, "set" -(S)-, "reset" -(R)-, "jmp", "end", "fb" (a
// box: timers, counters, moves, arithmetic); `dev` the operand as spelled,
// `device` its device name as the table names it (a contact is forced or
// written by it), `fn` a box's function, `inst` a timer's or counter's instance.
struct ElemSymbol {
  std::string kind, dev, device, fn, inst;
  std::vector<Pin> pins;
};

struct RungView {
  bool drawn = false;
  LadderRung g;
  std::vector<ElemSymbol> syms;    // one per element of g
  std::string why;                 // no ladder form: the reason
  std::vector<std::string> il;     // ... and its instructions
  int line = 0;
  std::string title;
};

// One program as the monitor shows it: built once per program (at start and
// after each online download), never changed, shared by the server's
// requests through a shared_ptr.
struct ProgramView {
  std::string name;
  uint32_t period_us = 0;
  Layout layout;
  std::vector<Alias> aliases;
  std::vector<RungView> rungs;
  std::vector<Dev> devs;
  std::string source_note;  // an ST or IL program whose source is not shown: why
  std::vector<SourceLine> source;    // its source, when shown (then no rungs are drawn)
  std::vector<Dev> source_watches;   // the variables shown in it
  uint64_t gen = 0;          // Runtime::generation of the task when it was built
  int64_t switched_ms = 0;   // the download that brought it (ms since 1970, UTC); 0: the program ldrun started with
  std::string json;          // its part of /api/program
};

struct TaskView {
  std::string name;
  // The program shown: replaced whole by an online download (view_mu, then
  // snap_mu, so that a picture and its program always go together).
  std::mutex view_mu;
  std::shared_ptr<const ProgramView> view;

  // the snapshot of its memory, written by the task thread at its scan
  // boundary -- only while the runtime's generation of the task is `gen`,
  // the program's whose layout the buffer has
  std::mutex snap_mu;
  std::vector<uint8_t> mem;
  Layout layout;       // of generation gen (the task thread applies writes with it)
  uint64_t gen = 0;
  uint64_t scan = 0;
  bool taken = false;  // a scan of generation gen was copied
  std::atomic<bool> want{false};

  // its own devices written by clients, and what its thread took of them
  std::unique_ptr<WriteShadow> writes;
  WriteShadow::Batch batch;
  ForcedCopy forced;
};

void collect_devices(ProgramView& t, const Program& p) {
  std::set<std::pair<int, uint32_t>> seen;
  auto add = [&](Area a, uint32_t i) {
    if (a == Area::Sys || a == Area::E || a == Area::TI || a == Area::Count) return;
    if (!seen.insert({int(a), i}).second) return;
    Dev d{std::string(device_prefix_of(a)) + std::to_string(i), "", a, i};
    if (a == Area::TQ || a == Area::CQ) d.name += ".Q";
    for (const Alias& al : t.aliases) {
      Area want_bit = bit_area(al.dev.dev), want_word = word_area(al.dev.dev);
      if (al.dev.index == i && (want_bit == a || want_word == a)) {
        d.alias = al.name;
        if (al.ty != Ty::None && al.ty != Ty::BOOL && !area_is_bit(a)) d.ty = al.ty;
        break;
      }
    }
    t.devs.push_back(d);
  };
  for (const Rung& r : p.rungs)
    for (const Instr& in : r.code)
      for (const Operand& o : in.a) {
        if (o.kind == OpdKind::Bit || o.kind == OpdKind::Int || o.kind == OpdKind::Real) add(o.area, o.index);
        if (o.kind == OpdKind::Timer) add(Area::TW, o.index), add(Area::TQ, o.index);
        if (o.kind == OpdKind::Counter) add(Area::CW, o.index), add(Area::CQ, o.index);
      }
  for (const Alias& al : t.aliases) {
    Area b = bit_area(al.dev.dev), w = word_area(al.dev.dev);
    if (b != Area::Count) add(b, al.dev.index);
    else if (w != Area::Count) add(w, al.dev.index);
  }
  std::sort(t.devs.begin(), t.devs.end(), [](const Dev& a, const Dev& b) {
    return a.area != b.area ? a.area < b.area : a.index < b.index;
  });
}

// ---------------------------------------------------------------- IEC symbols

// The first alias of each device, by the area an operand names it with.
using AliasNames = std::map<std::pair<int, uint32_t>, std::string>;
AliasNames alias_names(const std::vector<Alias>& aliases) {
  AliasNames n;
  for (const Alias& al : aliases) {
    Area b = bit_area(al.dev.dev), w = word_area(al.dev.dev);
    if (b != Area::Count) n.emplace(std::make_pair(int(b), al.dev.index), al.name);
    if (w != Area::Count) n.emplace(std::make_pair(int(w), al.dev.index), al.name);
  }
  return n;
}

// Operand k as the program spells it: its alias, else the device or constant.
std::string spelled(const Instr& in, int k, const AliasNames& names) {
  const Operand& o = in.a[k];
  Area a = o.area;
  if (o.kind == OpdKind::Timer) a = Area::TW;
  else if (o.kind == OpdKind::Counter) a = Area::CW;
  else if (o.kind != OpdKind::Bit && o.kind != OpdKind::Int && o.kind != OpdKind::Real) return operand_text(in, k);
  auto it = names.find({int(a), o.index});
  return it != names.end() ? it->second : operand_text(in, k);
}

// A device as the device table names it (X1, T0.Q, D5).
std::string table_name(Area a, uint32_t i) {
  return device_prefix_of(a) + std::to_string(i) + (a == Area::TQ || a == Area::CQ ? ".Q" : "");
}

// A timer preset in ms as an IEC duration: T#1m30s, T#1s500ms, T#0ms.
std::string iec_duration(int64_t ms) {
  if (ms < 0) return std::to_string(ms) + " ms";
  std::string s = "T#";
  static const std::pair<int64_t, const char*> units[] = {{86400000, "d"}, {3600000, "h"}, {60000, "m"}, {1000, "s"}, {1, "ms"}};
  for (auto [u, name] : units)
    if (ms >= u) s += std::to_string(ms / u) + name, ms %= u;
  return s == "T#" ? "T#0ms" : s;
}

const char* rel_fn(Rel r) {
  switch (r) {
    case Rel::Eq: return "EQ";
    case Rel::Ne: return "NE";
    case Rel::Lt: return "LT";
    case Rel::Le: return "LE";
    case Rel::Gt: return "GT";
    case Rel::Ge: return "GE";
    default: return "CMP";
  }
}

Pin operand_pin(const char* name, const Instr& in, int k, bool right, const AliasNames& names) {
  Pin p{name, spelled(in, k, names), right, Pin::From::Operand, in.a[k]};
  if (in.a[k].kind != OpdKind::Bit && in.a[k].kind != OpdKind::Int && in.a[k].kind != OpdKind::Real) p.from = Pin::From::None;
  return p;
}

// A box of any other output instruction: EN, its inputs IN (IN1, IN2, ...)
// and outputs OUT (OUT1, ...) in operand order, by the op table's letters.
void generic_box(ElemSymbol& s, const Instr& in, const AliasNames& names) {
  const OpInfo& oi = op_info(in.op);
  std::string fn = oi.name;
  if (oi.klass == OpClass::Typed && fn.size() > 1 && fn[0] == 'T') fn = fn.substr(1);  // TADD -> ADD
  if (fn == "WAND" || fn == "WOR" || fn == "WXOR" || fn == "WNOT") fn = fn.substr(1);
  s.kind = "fb", s.fn = fn;
  s.pins.push_back(Pin{"EN", "", false, Pin::From::PowerIn, {}});
  int ins = 0, outs = 0;
  for (int k = 0; k < in.nopd() && oi.operands[k]; k++) {
    char c = oi.operands[k];
    if (std::strchr("wdr", c)) outs++;
    else if (!std::strchr("etcl", c)) ins++;
  }
  int ki = 0, ko = 0;
  for (int k = 0; k < in.nopd() && oi.operands[k]; k++) {
    char c = oi.operands[k];
    bool out = std::strchr("wdr", c) != nullptr;
    if (!out && std::strchr("etcl", c)) continue;
    int& nth = out ? ko : ki;
    std::string name = std::string(out ? "OUT" : "IN") + ((out ? outs : ins) > 1 ? std::to_string(++nth) : "");
    s.pins.push_back(operand_pin(name.c_str(), in, k, out, names));
  }
}

ElemSymbol symbol_of(const LadderElem& e, const AliasNames& names) {
  const Instr& in = e.elem;
  ElemSymbol s;
  auto bit_dev = [&](int k) {
    s.dev = spelled(in, k, names);
    if (in.a[k].kind == OpdKind::Bit) s.device = table_name(in.a[k].area, in.a[k].index);
  };
  switch (in.op) {
    case Op::TRUE: s.kind = "true"; return s;
    case Op::LOAD: s.kind = "no", bit_dev(0); return s;
    case Op::LOADN: s.kind = "nc", bit_dev(0); return s;
    case Op::LOADP: s.kind = "p", bit_dev(0); return s;
    case Op::LOADF: s.kind = "n", bit_dev(0); return s;
    case Op::OUT: s.kind = "coil", bit_dev(0); return s;
    case Op::OUTN: s.kind = "ncoil", bit_dev(0); return s;
    case Op::SET: s.kind = "set", bit_dev(0); return s;
    case Op::RST: s.kind = "reset", bit_dev(0); return s;
    case Op::RSTT: case Op::RSTC: s.kind = "reset", s.dev = spelled(in, 0, names); return s;
    case Op::JMP: s.kind = "jmp", s.dev = operand_text(in, 0); return s;
    case Op::END: s.kind = "end"; return s;
    case Op::TON: case Op::TOF: case Op::TP: case Op::MTON: case Op::MTOF: case Op::MTP: {
      bool matiec = in.op == Op::MTON || in.op == Op::MTOF || in.op == Op::MTP;  // drawn as the IEC timer they are
      s.kind = "fb", s.fn = op_info(in.op).name + (matiec ? 1 : 0), s.inst = spelled(in, 0, names);
      Pin pt = operand_pin("PT", in, 1, false, names);
      if (in.a[1].kind == OpdKind::ConstInt) pt.text = iec_duration(in.a[1].ival);
      Operand q;
      q.index = in.a[0].index;
      s.pins = {Pin{"IN", "", false, Pin::From::PowerIn, {}}, pt, Pin{"Q", "", true, Pin::From::TimerQ, q},
                Pin{"ET", "", true, Pin::From::Elapsed, in.a[0]}};
      return s;
    }
    case Op::CTU: case Op::CTD: {
      bool up = in.op == Op::CTU;
      s.kind = "fb", s.fn = up ? "CTU" : "CTD", s.inst = spelled(in, 0, names);
      Operand q;
      q.index = in.a[0].index;
      s.pins = {Pin{up ? "CU" : "CD", "", false, Pin::From::PowerIn, {}}, operand_pin("PV", in, 1, false, names),
                Pin{"Q", "", true, Pin::From::CounterQ, q}, Pin{"CV", "", true, Pin::From::Operand, in.a[0]}};
      return s;
    }
    default: break;
  }
  if (!e.output) {  // a compare: IN1, IN2 and its result
    s.kind = "cmp", s.fn = rel_fn(op_info(in.op).rel);
    s.pins = {operand_pin("IN1", in, 0, false, names), operand_pin("IN2", in, 1, false, names),
              Pin{"Q", "", true, Pin::From::Result, {}}};
    return s;
  }
  generic_box(s, in, names);
  return s;
}

// ---------------------------------------------------------------- values

struct View {  // a task's snapshot
  const Layout& L;
  const uint8_t* mem;
  const uint8_t* global;
  const uint8_t* base(Area a) const { return is_shared(a) && global ? global : mem; }
  bool bit(Area a, uint32_t i) const { return base(a)[L.addr(a, i)] != 0; }
  int32_t word(Area a, uint32_t i) const {
    int32_t v;
    std::memcpy(&v, base(a) + L.addr(a, i), 4);
    return v;
  }
  float real(uint32_t i) const {
    float v;
    std::memcpy(&v, base(Area::F) + L.addr(Area::F, i), 4);
    return v;
  }
  double num(const Operand& o) const {
    switch (o.kind) {
      case OpdKind::ConstInt: return o.ival;
      case OpdKind::ConstReal: return o.fval;
      case OpdKind::Real: return real(o.index);
      case OpdKind::Int: return word(o.area, o.index);
      case OpdKind::Timer: return word(Area::TW, o.index);
      case OpdKind::Counter: return word(Area::CW, o.index);
      default: return 0;
    }
  }
  std::string text(Area a, uint32_t i) const {
    if (area_is_bit(a)) return bit(a, i) ? "1" : "0";
    if (a == Area::F) {
      char b[32];
      std::snprintf(b, sizeof b, "%g", double(real(i)));
      return b;
    }
    return std::to_string(word(a, i));
  }
  // A device of the table: a typed variable at its type (T#1s, 4294967295, 'text')
  std::string dev_text(const Dev& d) const {
    if (d.ty == Ty::None) return text(d.area, d.index);
    return format_probe(base(d.area), L, Probe{d.alias, d.area, d.index, d.ty});
  }
  std::string opd_text(const Operand& o) const {
    switch (o.kind) {
      case OpdKind::Int: case OpdKind::Real: case OpdKind::Bit: return text(o.area, o.index);
      case OpdKind::Timer: return std::to_string(word(Area::TW, o.index));
      case OpdKind::Counter: return std::to_string(word(Area::CW, o.index));
      default: return "";
    }
  }
};

// Is an input element lit, judged from the image after the scan?  Edge
// contacts, -|P|- and -|N|-, show their device's state (a PLC's online view
// does so: the edge itself lasted one scan and is gone by then), lit while
// the bit is 1; they pass no power in the drawing (edge_contact).
bool closed(const Instr& in, const View& v) {
  auto b = [&] { return v.bit(in.a[0].area, in.a[0].index); };
  switch (in.op) {
    case Op::TRUE: return true;
    case Op::LOAD: case Op::LOADP: case Op::LOADF: return b();
    case Op::LOADN: return !b();
    default: break;
  }
  double x = v.num(in.a[0]), y = v.num(in.a[1]);
  if (!in.a[0].is_real() && !in.a[1].is_real()) x = double(int32_t(x)), y = double(int32_t(y));
  return rel_holds(op_info(in.op).rel, x, y);
}

// The value shown beside an element: the destination of a word output, a
// timer's elapsed ms, a counter's value, a compare's operands.
std::string elem_value(const LadderElem& e, const View& v) {
  const Instr& in = e.elem;
  if (!e.output) {
    if (op_info(in.op).klass == OpClass::Compare) {
      std::string a = v.opd_text(in.a[0]), b = v.opd_text(in.a[1]);
      if (a.empty() && b.empty()) return "";
      return (a.empty() ? "" : a) + (b.empty() ? "" : (a.empty() ? "" : " : ") + b);
    }
    return "";
  }
  switch (in.op) {
    case Op::TON: case Op::TOF: case Op::TP: case Op::RSTT:
      return std::to_string(v.word(Area::TW, in.a[0].index)) + " ms";
    case Op::CTU: case Op::CTD: case Op::RSTC: return std::to_string(v.word(Area::CW, in.a[0].index));
    default: break;
  }
  int n = in.nopd();
  if (n >= 2 && (in.a[n - 1].kind == OpdKind::Int || in.a[n - 1].kind == OpdKind::Real)) return v.opd_text(in.a[n - 1]);
  return "";
}

// A pin's live value: "" where the drawing says it (a constant).
std::string pin_value(const Pin& p, const View& v, bool power_in, bool result) {
  switch (p.from) {
    case Pin::From::Operand: return v.opd_text(p.opd);
    case Pin::From::Elapsed: return v.opd_text(p.opd) + " ms";
    case Pin::From::PowerIn: return power_in ? "1" : "0";
    case Pin::From::Result: return result ? "1" : "0";
    case Pin::From::TimerQ: return v.bit(Area::TQ, p.opd.index) ? "1" : "0";
    case Pin::From::CounterQ: return v.bit(Area::CQ, p.opd.index) ? "1" : "0";
    case Pin::From::None: break;
  }
  return "";
}

bool edge_contact(const Instr& in) { return in.op == Op::LOADP || in.op == Op::LOADF; }

// A rung's state: "n" the power of each net, "e" each element lit (an
// input: conducting, or an edge contact's bit set) or energised (an output), "v" the value shown beside an
// element, "p" the values of a box's pins, in the order of its "p" in /api/program.
std::string rung_state(const RungView& r, const View& v) {
  if (!r.drawn) return "{}";
  const LadderRung& g = r.g;
  std::vector<char> power(size_t(g.nets), 0);
  power[0] = 1;
  std::vector<char> shut(g.elems.size(), 0);
  for (size_t i = 0; i < g.elems.size(); i++)
    if (!g.elems[i].output) shut[i] = closed(g.elems[i].elem, v);
  for (bool changed = true; changed;) {  // the nets form a DAG: this ends
    changed = false;
    for (size_t i = 0; i < g.elems.size(); i++) {
      const LadderElem& e = g.elems[i];
      if (e.output || !shut[i] || edge_contact(e.elem) || !power[size_t(e.in_net)] || power[size_t(e.out_net)]) continue;
      power[size_t(e.out_net)] = 1;
      changed = true;
    }
  }
  std::string n, e, vals, pins;
  for (char p : power) n += p ? '1' : '0';
  for (size_t i = 0; i < g.elems.size(); i++) {
    const LadderElem& el = g.elems[i];
    e += (el.output ? power[size_t(el.in_net)] : shut[i]) ? '1' : '0';
    std::string t = elem_value(el, v);
    if (!t.empty()) vals += (vals.empty() ? "" : ",") + jstr(std::to_string(i)) + ":" + jstr(t);
    if (i >= r.syms.size() || r.syms[i].pins.empty()) continue;
    pins += (pins.empty() ? "" : ",") + jstr(std::to_string(i)) + ":[";
    const std::vector<Pin>& ps = r.syms[i].pins;
    for (size_t k = 0; k < ps.size(); k++)
      pins += (k ? "," : "") + jstr(pin_value(ps[k], v, power[size_t(el.in_net)] != 0, shut[i] != 0));
    pins += "]";
  }
  return "{\"n\":\"" + n + "\",\"e\":\"" + e + "\",\"v\":{" + vals + "},\"p\":{" + pins + "}}";
}

// ---------------------------------------------------------------- writes

std::string lower(std::string_view s) {
  std::string o(s);
  for (char& c : o) c = char(std::tolower(static_cast<unsigned char>(c)));
  return o;
}

bool loopback(const std::string& h) { return h == "::1" || h.rfind("127.", 0) == 0; }
bool wildcard(const std::string& h) { return h == "0.0.0.0" || h == "::"; }

// "a.b.c.d:PORT" or "[v6]:PORT", the literal parsing as an address.
bool ip_literal_with_port(const std::string& h, const std::string& port_suffix) {
  if (h.size() <= port_suffix.size() || h.compare(h.size() - port_suffix.size(), port_suffix.size(), port_suffix) != 0)
    return false;
  std::string a = h.substr(0, h.size() - port_suffix.size());
  unsigned char buf[16];
  if (a.size() > 2 && a.front() == '[' && a.back() == ']') return inet_pton(AF_INET6, a.substr(1, a.size() - 2).c_str(), buf) == 1;
  return inet_pton(AF_INET, a.c_str(), buf) == 1;
}

// Equal strings of equal length, in time independent of where they differ.
bool same_secret(const std::string& a, const std::string& b) {
  if (a.size() != b.size()) return false;
  unsigned char d = 0;
  for (size_t i = 0; i < a.size(); i++) d |= static_cast<unsigned char>(a[i] ^ b[i]);
  return d == 0;
}

// The thread that carries out RUN and STOP for the server, one request at a
// time, so that the server's thread never waits for them.
class ControlThread {
 public:
  static constexpr size_t kMaxJobs = 16;
  struct Job {
    std::function<http::Response()> act;
    http::Response reply;           // valid once done
    std::atomic<bool> done{false};
  };
  ~ControlThread() { stop(); }
  void start() { th_ = std::thread([this] { loop(); }); }
  void stop() {
    {
      std::lock_guard<std::mutex> l(mu_);
      quit_ = true;
    }
    cv_.notify_all();
    if (th_.joinable()) th_.join();
  }
  // nullptr when kMaxJobs wait already
  std::shared_ptr<Job> post(std::function<http::Response()> act) {
    std::lock_guard<std::mutex> l(mu_);
    if (jobs_.size() >= kMaxJobs) return nullptr;
    auto j = std::make_shared<Job>();
    j->act = std::move(act);
    jobs_.push_back(j);
    cv_.notify_one();
    return j;
  }

 private:
  void loop() {
    while (true) {
      std::shared_ptr<Job> j;
      {
        std::unique_lock<std::mutex> l(mu_);
        cv_.wait(l, [&] { return quit_ || !jobs_.empty(); });
        if (jobs_.empty()) return;  // quit, and nothing left
        j = jobs_.front();
        jobs_.pop_front();
      }
      try {
        j->reply = j->act();
      } catch (std::exception& e) {
        j->reply = http::Response{500, "text/plain; charset=utf-8", std::string(e.what()) + "\n", false};
      }
      j->done.store(true, std::memory_order_release);
    }
  }
  std::mutex mu_;
  std::condition_variable cv_;
  std::deque<std::shared_ptr<Job>> jobs_;
  bool quit_ = false;
  std::thread th_;
};

// ---------------------------------------------------------------- /api/program

std::string symbol_json(const ElemSymbol& y) {
  std::string s = ",\"k\":" + jstr(y.kind);
  if (!y.dev.empty()) s += ",\"d\":" + jstr(y.dev);
  if (!y.device.empty()) s += ",\"dv\":" + jstr(y.device);
  if (!y.fn.empty()) s += ",\"f\":" + jstr(y.fn);
  if (!y.inst.empty()) s += ",\"inst\":" + jstr(y.inst);
  if (y.pins.empty()) return s;
  s += ",\"p\":[";
  for (size_t k = 0; k < y.pins.size(); k++)
    s += std::string(k ? "," : "") + "[" + jstr(y.pins[k].name) + "," + jstr(y.pins[k].text) + "," +
         (y.pins[k].right ? "1" : "0") + "]";
  return s + "]";
}

// "source": one array a line, its text pieces and between them the
// indexes (in "watch") of the values shown there: ["  n",[0]," := n + 1;"]
std::string source_json(const ProgramView& t) {
  std::string s = ",\"watch\":[";
  for (size_t k = 0; k < t.source_watches.size(); k++) s += (k ? "," : "") + jstr(t.source_watches[k].alias);
  s += "],\"source\":[";
  for (size_t l = 0; l < t.source.size(); l++) {
    const SourceLine& sl = t.source[l];
    s += l ? ",[" : "[";
    for (size_t k = 0; k < sl.text.size(); k++) {
      s += (k ? "," : "") + jstr(sl.text[k]);
      if (k >= sl.marks.size()) continue;
      s += ",[";
      for (size_t m = 0; m < sl.marks[k].size(); m++) s += (m ? "," : "") + std::to_string(sl.marks[k][m]);
      s += "]";
    }
    s += "]";
  }
  return s + "]";
}

// A program's part of /api/program: "gen" and "switched_ms" say which
// download brought it (0, 0: the program ldrun started with); each drawn
// element its IEC symbol ("k", "d", "dv", "f", "inst", and a box's pins "p").
std::string view_json(const ProgramView& t) {
  std::string s = "{\"name\":" + jstr(t.name) + ",\"period_us\":" + std::to_string(t.period_us) +
                  ",\"gen\":" + std::to_string(t.gen) + ",\"switched_ms\":" + std::to_string(t.switched_ms);
  if (!t.source_note.empty()) s += ",\"source_note\":" + jstr(t.source_note);
  if (!t.source.empty()) s += source_json(t);
  s += ",\"rungs\":[";
  for (size_t r = 0; r < t.rungs.size(); r++) {
    const RungView& rv = t.rungs[r];
    s += std::string(r ? "," : "") + "{\"title\":" + jstr(rv.title) + ",\"line\":" + std::to_string(rv.line);
    if (!rv.drawn) {
      s += ",\"why\":" + jstr(rv.why) + ",\"il\":[";
      for (size_t k = 0; k < rv.il.size(); k++) s += (k ? "," : "") + jstr(rv.il[k]);
      s += "]}";
      continue;
    }
    const LadderRung& g = rv.g;
    s += ",\"labels\":[";
    for (size_t k = 0; k < g.labels.size(); k++) s += (k ? "," : "") + jstr(g.labels[k]);
    s += "],\"rows\":[";
    for (size_t k = 0; k < g.rows.size(); k++) s += (k ? "," : "") + jstr(g.rows[k]);
    s += "],\"elems\":[";
    for (size_t k = 0; k < g.elems.size(); k++) {
      const LadderElem& e = g.elems[k];
      s += std::string(k ? "," : "") + "{\"r\":" + std::to_string(e.row) + ",\"c\":" + std::to_string(e.col) +
           ",\"w\":" + std::to_string(e.width) + ",\"o\":" + (e.output ? "1" : "0") + ",\"t\":" + jstr(e.text) +
           ",\"i\":" + std::to_string(e.in_net) + ",\"j\":" + std::to_string(e.out_net) + symbol_json(rv.syms.at(k)) + "}";
    }
    s += "],\"wires\":[";
    for (size_t k = 0; k < g.wires.size(); k++)
      s += std::string(k ? "," : "") + "[" + std::to_string(g.wires[k].row) + "," + std::to_string(g.wires[k].col0) + "," +
           std::to_string(g.wires[k].col1) + "," + std::to_string(g.wires[k].net) + "]";
    s += "],\"links\":[";
    for (size_t k = 0; k < g.links.size(); k++)
      s += std::string(k ? "," : "") + "[" + std::to_string(g.links[k].col) + "," + std::to_string(g.links[k].row0) + "," +
           std::to_string(g.links[k].row1) + "," + std::to_string(g.links[k].net) + "]";
    s += "]}";
  }
  s += "],\"devices\":[";
  for (size_t d = 0; d < t.devs.size(); d++)
    s += std::string(d ? "," : "") + "[" + jstr(t.devs[d].name) + "," + jstr(t.devs[d].alias) + "]";
  return s + "]}";
}

// A program as the monitor shows it: its rungs drawn (or its source with
// the variables each line writes), its devices, its part of /api/program.
std::shared_ptr<const ProgramView> build_view(const MonitorTask& mt, uint64_t gen, int64_t switched_ms) {
  auto t = std::make_shared<ProgramView>();
  t->name = mt.name;
  t->period_us = mt.period_us;
  t->layout = mt.image.layout;
  t->aliases = mt.image.aliases;
  t->gen = gen;
  t->switched_ms = switched_ms;
  Program p = program_of(mt.image);
  collect_devices(*t, p);
  t->source_note = mt.source_note;
  if (!mt.source_text.empty()) {
    SourceView sv = source_view(mt.source_text, p, t->aliases);
    t->source_note = sv.note;
    t->source = std::move(sv.lines);
    for (SourceWatch& w : sv.watches) t->source_watches.push_back(std::move(w.dev));
  }
  const AliasNames names = alias_names(t->aliases);
  const std::vector<Rung> none;  // a program shown as its source draws no rungs
  for (const Rung& r : t->source.empty() ? p.rungs : none) {
    RungView rv;
    rv.line = r.line;
    rv.title = r.title;
    Program one;
    one.aliases = p.aliases;
    one.rungs.push_back(r);
    try {
      Ladder l = draw_ladder(raise_to_tree(one));
      rv.g = std::move(l.rungs.at(0));
      rv.drawn = true;
      for (const LadderElem& e : rv.g.elems) rv.syms.push_back(symbol_of(e, names));
    } catch (std::exception& e) {
      rv.why = e.what();
      for (const Instr& in : r.code) rv.il.push_back(instr_text(in));
    }
    t->rungs.push_back(std::move(rv));
  }
  t->json = view_json(*t);
  return t;
}

}  // namespace

struct Monitor::Impl {
  MonitorOptions opt;
  std::vector<std::unique_ptr<TaskView>> tasks;
  Layout glayout = Layout::standard(0);
  Runtime* rt = nullptr;
  std::unique_ptr<http::Server> server;
  ControlThread control;  // RUN/STOP off the server's thread
  std::vector<TaskStats> stats;  // the server thread's
  std::mutex global_mu;          // the global image's snapshot
  std::vector<uint8_t> global_snap;
  std::atomic<bool> want_global{false};
  std::chrono::steady_clock::time_point stats_at{};
  std::set<std::string> hosts;   // Host values this monitor answers to (lower case, with the port)
  uint16_t port = 0;

  // Writes: shared devices (X Y M K WX WY) in one shadow, applied to the
  // global image by the first task at its boundary; each task's own devices
  // (D F T C S) in its shadow, applied to its memory.  The scan takes a
  // shadow with one swap and never waits (runtime/write_shadow.h).
  std::unique_ptr<WriteShadow> shared_writes;
  WriteShadow::Batch shared_batch;  // under the global image's lock
  // Forced inputs: the server's map, and the copies the scans apply.
  std::mutex fmu;
  std::map<std::pair<int, uint32_t>, uint32_t> forced;  // shared inputs held at a value
  std::atomic<uint64_t> forced_version{0};
  std::atomic<bool> any_forced{false};
  ForcedCopy forced_shared;  // under the global image's lock

  // ---- on the task threads
  void refresh(ForcedCopy& c) {
    if (forced_version.load(std::memory_order_acquire) == c.version) return;
    std::unique_lock<std::mutex> l(fmu, std::try_to_lock);
    if (!l.owns_lock()) return;  // the server is changing it: the next scan
    c.items.clear();
    for (auto& [k, bits] : forced) c.items.push_back({Area(k.first), k.second, bits, ~0u});
    c.version = forced_version.load(std::memory_order_relaxed);
  }
  // `c`: the task's scan, whose engine is told of each write (none for the global image)
  void apply(ForcedCopy& fc, WriteShadow& shadow, WriteShadow::Batch& batch, uint8_t* mem, const Layout& L,
             const ScanContext* c = nullptr) {
    if (any_forced.load(std::memory_order_relaxed) || !fc.items.empty()) {
      refresh(fc);
      for (const ElementWrite& w : fc.items) {
        apply_element(w, mem, L);
        if (c) c->written(L, w.area, w.index);
      }
    }
    if (shadow.take(batch))
      for (const ElementWrite& w : batch.writes) {
        apply_element(w, mem, L);
        if (c) c->written(L, w.area, w.index);
      }
  }
  void apply_shared(uint8_t* global) { apply(forced_shared, *shared_writes, shared_batch, global, glayout); }
  // Forced outputs and relays (Y, M, K, WY) hold their value at every scan
  // boundary: put back after the scan, before the outputs are published, in
  // the global image and in the task's memory (whose shared areas have the
  // global image's offsets); the next scan reads them so.  Global image locked.
  void hold_forced(uint8_t* global, uint8_t* mem, const ScanContext& c) {
    if (!any_forced.load(std::memory_order_relaxed) && forced_shared.items.empty()) return;
    for (const ElementWrite& w : forced_shared.items) {
      if (w.area == Area::X || w.area == Area::WX) continue;  // inputs: the scan does not write them
      apply_element(w, global, glayout);
      apply_element(w, mem, glayout);
      c.written(glayout, w.area, w.index);
    }
  }
  // The runtime's generation of a task: that of the memory its thread holds.
  uint64_t generation(size_t task) const { return rt ? rt->generation(task) : 0; }
  // A task's own writes go into its memory only with the layout of the
  // program that memory belongs to: after a download, from the scan on that
  // the monitor has the new program (until then they wait in the shadow).
  void apply_private(const ScanContext& c, uint8_t* mem) {
    if (c.task >= tasks.size()) return;
    TaskView& t = *tasks[c.task];
    if (!t.snap_mu.try_lock()) return;  // the server reads the picture: the next scan
    if (t.gen == generation(c.task)) apply(t.forced, *t.writes, t.batch, mem, t.layout, &c);
    t.snap_mu.unlock();
  }
  // The global image is copied by whichever task reaches its boundary first
  // (a held task does not scan, yet its shared devices stay current).
  void snapshot(size_t task, uint64_t scan, const uint8_t* mem, const uint8_t* global) {
    if (task >= tasks.size()) return;
    TaskView& t = *tasks[task];
    if (t.want.load(std::memory_order_relaxed) && t.snap_mu.try_lock()) {  // busy: the next scan
      if (t.gen == generation(task)) {  // else the memory of a program the monitor does not show yet
        std::memcpy(t.mem.data(), mem, t.mem.size());
        t.scan = scan;
        t.taken = true;
        t.want.store(false, std::memory_order_relaxed);
      }
      t.snap_mu.unlock();
    }
    if (global && want_global.load(std::memory_order_relaxed) && global_mu.try_lock()) {
      std::memcpy(global_snap.data(), global, global_snap.size());
      global_mu.unlock();
      want_global.store(false, std::memory_order_relaxed);
    }
  }

  // ---- on the server thread
  std::string state_json() {
    std::string s = "{\"state\":" + jstr(rt ? state_name(rt->state()) : "?");
    // The runtime's statistics sort its sample rings under a lock the task only
    // try_locks (a sample is lost while it is held): refreshed twice a second.
    auto now = std::chrono::steady_clock::now();
    if (rt && now - stats_at > std::chrono::milliseconds(500)) stats = rt->stats(), stats_at = now;
    const std::vector<TaskStats>& st = stats;
    s += ",\"tasks\":[";
    std::vector<uint8_t> mem, global;
    {
      std::lock_guard<std::mutex> l(global_mu);
      global = global_snap;
    }
    want_global.store(true, std::memory_order_relaxed);
    for (size_t ti = 0; ti < tasks.size(); ti++) {
      TaskView& tv = *tasks[ti];
      std::shared_ptr<const ProgramView> pv;
      uint64_t scan, gen;
      bool taken;
      {
        std::lock_guard<std::mutex> lv(tv.view_mu);
        std::lock_guard<std::mutex> ls(tv.snap_mu);
        pv = tv.view;
        mem = tv.mem, scan = tv.scan, gen = tv.gen, taken = tv.taken;
      }
      tv.want.store(true, std::memory_order_relaxed);
      const ProgramView& t = *pv;
      View v{t.layout, mem.data(), global.data()};
      // "gen": the program these values belong to (a page showing another
      // one fetches /api/program again); "pending": a download brought it
      // and no scan of it was seen yet: no values, rather than zeros.
      bool pending = gen > 0 && !taken;
      s += std::string(ti ? "," : "") + "{\"name\":" + jstr(t.name) + ",\"gen\":" + std::to_string(gen) +
           ",\"scan\":" + std::to_string(scan) + ",\"held\":" + (rt && rt->task_held(ti) ? "true" : "false") +
           (pending ? ",\"pending\":true" : "");
      if (ti < st.size()) {
        const TaskStats& x = st[ti];
        s += ",\"scans\":" + std::to_string(x.scans) + ",\"overruns\":" + std::to_string(x.overruns) +
             ",\"scan_us\":{\"median\":" + jnum(x.scan_us.median) + ",\"p99\":" + jnum(x.scan_us.p99) +
             ",\"max\":" + jnum(x.scan_us.max) + "},\"jitter_us\":{\"median\":" + jnum(x.jitter_us.median) +
             ",\"p99\":" + jnum(x.jitter_us.p99) + ",\"max\":" + jnum(x.jitter_us.max) + "}";
      }
      if (pending) {
        s += ",\"rungs\":[],\"dev\":[]}";
        continue;
      }
      s += ",\"rungs\":[";
      for (size_t r = 0; r < t.rungs.size(); r++) s += (r ? "," : "") + rung_state(t.rungs[r], v);
      if (!t.source.empty()) {
        s += "],\"src\":[";
        for (size_t d = 0; d < t.source_watches.size(); d++) s += (d ? "," : "") + jstr(v.dev_text(t.source_watches[d]));
      }
      s += "],\"dev\":[";
      for (size_t d = 0; d < t.devs.size(); d++) s += (d ? "," : "") + jstr(v.dev_text(t.devs[d]));
      s += "]}";
    }
    std::lock_guard<std::mutex> l(fmu);
    // "forced": the inputs held, "fv": the value each is held at
    std::string names, values;
    for (auto& [k, bits] : forced) {
      names += std::string(names.empty() ? "" : ",") + jstr(device_prefix_of(Area(k.first)) + std::to_string(k.second));
      values += std::string(values.empty() ? "" : ",") + std::to_string(int32_t(bits));
    }
    return s + "],\"forced\":[" + names + "],\"fv\":[" + values + "]}";
  }

  std::shared_ptr<const ProgramView> view_of(size_t ti) {
    std::lock_guard<std::mutex> l(tasks[ti]->view_mu);
    return tasks[ti]->view;
  }

  // /api/program: every task's program as shown now.  A page compares each
  // task's "gen" with the "gen" of the values it gets.
  std::string program_json() {
    std::string s = "{\"write\":" + std::string(opt.write ? "true" : "false") +
                    ",\"token\":" + std::string(opt.token.empty() ? "false" : "true") + ",\"tasks\":[";
    for (size_t ti = 0; ti < tasks.size(); ti++) s += (ti ? "," : "") + view_of(ti)->json;
    return s + "]}";
  }

  // An online download switched task `ti` to `img` (IoDriver::program_replaced,
  // on the thread that asked for it): the new program's view replaces the old
  // one together with an empty picture of the new layout, taken at its first scan.
  void program_replaced(size_t ti, const Image& img);

  // The Host values this monitor answers to, once its port is known: its
  // listen address; the loopback names when it listens on loopback or on
  // every address; the names of --monitor-host.  A browser sends the name it
  // resolved, so a page of another site whose name was rebound to this
  // address still names that site, and is refused.
  void allow_hosts(uint16_t listen_port) {
    port = listen_port;
    const std::string ps = ":" + std::to_string(port);
    hosts.insert(lower(opt.host.find(':') != std::string::npos ? "[" + opt.host + "]" : opt.host) + ps);
    if (loopback(opt.host) || wildcard(opt.host))
      for (const char* n : {"127.0.0.1", "localhost", "[::1]"}) hosts.insert(n + ps);
    for (const std::string& h : opt.hosts) {
      bool has_port = h.back() != ']' && h.find(':') != std::string::npos;
      hosts.insert(lower(has_port ? h : h + ps));
    }
  }

  bool host_ok(const http::Request& r) const {
    const std::string* h = r.header("host");
    if (!h) return r.version == "HTTP/1.0";  // no browser sends that (and no rebinding without a name)
    std::string v = lower(*h);
    if (hosts.count(v) || (port == 80 && hosts.count(v + ":80"))) return true;
    // listening on every address: any of them, given as an address (an
    // address literal is never rebound; a name must be given by --monitor-host)
    return wildcard(opt.host) && ip_literal_with_port(v, ":" + std::to_string(port));
  }

  // A POST from a page of this monitor: the browser says where the page
  // came from (Origin; Sec-Fetch-Site on newer ones); clients that are not
  // browsers send neither.
  std::string cross_origin(const http::Request& r) const {
    const std::string* host = r.header("host");
    if (const std::string* o = r.header("origin"); o && (!host || lower(*o) != "http://" + lower(*host)))
      return "cross-origin request refused (Origin: " + *o + "); only the monitor's own page may write";
    if (const std::string* f = r.header("sec-fetch-site"); f && lower(*f) != "same-origin")
      return "cross-site request refused (Sec-Fetch-Site: " + *f + "); only the monitor's own page may write";
    return "";
  }

  std::string token_refusal(const http::Request& r) const {
    if (opt.token.empty()) return "";
    const std::string* t = r.header("x-ldc-token");
    if (!t) return "this monitor needs its write token: open the page once as http://HOST:PORT/?token=TOKEN (ldrun "
                   "printed the address at start), or send the header X-LDC-Token";
    if (!same_secret(*t, opt.token)) return "wrong write token (X-LDC-Token); each run of ldrun has its own unless --monitor-token gives one";
    return "";
  }

  // ---- /api/state: a picture taken after the request, without waiting on
  // the server thread: the first call asks the tasks for a snapshot; the
  // request is parked (the server asks again every few ms) until each
  // scanning task took one, or 250 ms passed.  In STOP or FAULT nothing
  // scans: the last picture at once.
  bool snapshot_ready() const {
    if (want_global.load()) return false;
    for (size_t k = 0; k < tasks.size(); k++)
      if (tasks[k]->want.load() && !(rt && rt->task_held(k))) return false;
    return true;
  }
  http::Response state_reply(const http::Request& r) {
    if (r.retries == 0) {
      for (auto& t : tasks) t->want.store(true);
      want_global.store(true);
    }
    bool scanning = rt && rt->state() == State::Run;
    if (scanning && !snapshot_ready() && r.waited_ms < 250) return http::Response{200, "", "", false, true};
    return {200, "application/json", state_json(), false};
  }

  static http::Response text(int code, const std::string& body) {
    return http::Response{code, "text/plain; charset=utf-8", body + "\n", false};
  }

  http::Response write(const http::Request& r) {
    auto task_name = http::form_value(r.body, "task");
    auto device = http::form_value(r.body, "device");
    auto value = http::form_value(r.body, "value");
    auto force = http::form_value(r.body, "force");
    size_t ti = 0;
    if (task_name && !task_name->empty()) {
      ti = SIZE_MAX;
      for (size_t i = 0; i < tasks.size(); i++)
        if (tasks[i]->name == *task_name) ti = i;
      if (ti == SIZE_MAX) return text(400, "unknown task '" + *task_name + "'");
    }
    if (!device || device->empty()) return text(400, "missing device=");
    Probe p;
    try {
      p = resolve_probe(*device, view_of(ti)->aliases);
    } catch (std::exception& e) { return text(400, e.what()); }
    bool writable = p.area == Area::X || p.area == Area::Y || p.area == Area::M || p.area == Area::K || p.area == Area::WX ||
                    p.area == Area::WY || p.area == Area::D || p.area == Area::F || p.area == Area::TW ||
                    p.area == Area::CW || (p.area == Area::S && p.index == kBitError);
    if (!writable) return text(400, *device + " cannot be written from the monitor");
    bool release = force && *force == "0";
    bool hold = force && *force == "1";
    if (force && !release && !hold) return text(400, "force= is 1 (hold) or 0 (release)");
    if ((hold || release) && !is_shared(p.area))
      return text(400, "only inputs, outputs and relays (X, WX, Y, WY, M, K) are forced; write " + *device + " once");
    if (p.ty != Ty::None && !hold && !release) return write_typed(ti, p, value.value_or(""));
    uint32_t bits = 0;
    if (!release) {
      if (!value) return text(400, "missing value=");
      const std::string& v = *value;
      char* end = nullptr;
      if (area_is_bit(p.area)) {
        if (v != "0" && v != "1") return text(400, "a bit is 0 or 1, not '" + v + "'");
        bits = v == "1";
      } else if (p.area == Area::F) {
        errno = 0;
        float f = std::strtof(v.c_str(), &end);
        if (v.empty() || *end) return text(400, "bad REAL '" + v + "'");
        if (!std::isfinite(f))
          return text(400, errno == ERANGE ? "REAL '" + v + "' is out of range (the largest is 3.40282e+38)"
                                           : "a REAL is a finite number, not '" + v + "'");
        std::memcpy(&bits, &f, 4);
      } else {
        errno = 0;
        long long x = std::strtoll(v.c_str(), &end, 0);
        if (v.empty() || *end || errno || x < INT32_MIN || x > int64_t(UINT32_MAX)) return text(400, "bad INT32 '" + v + "'");
        bits = uint32_t(int32_t(x));
      }
    }
    if (hold || release) return force_input(p, bits, release);
    const ElementWrite w{p.area, p.index, bits, ~0u};
    WriteShadow& shadow = is_shared(p.area) ? *shared_writes : *tasks[ti]->writes;
    if (shadow.post(std::span<const ElementWrite>(&w, 1)) == 0)
      return text(503, "busy: " + std::to_string(shadow.capacity()) +
                           " devices are written and wait for a scan to take them (is the PLC in STOP?); "
                           "write them again once it runs, or write devices already waiting");
    return text(200, "queued for the next scan");
  }

  // A typed variable written by name, as a trace cell of its type (T#1s500ms,
  // 'text', 18446744073709551615): all its cells in one post, so the scan
  // that takes them sees the whole value.
  http::Response write_typed(size_t ti, const Probe& p, const std::string& v) {
    if (v.empty()) return text(400, "missing value=");
    if (std::string why = trace_cell_problem(p, v); !why.empty()) return text(400, why);
    const Layout L = view_of(ti)->layout;
    Memory scratch(L);
    put_trace_cell(scratch.data(), L, p, v);
    std::vector<ElementWrite> ws;
    for (uint32_t c = 0; c < uint32_t(ty_info(p.ty).cells); c++) {
      uint32_t cell;
      std::memcpy(&cell, scratch.data() + L.addr(p.area, p.index + c), 4);
      ws.push_back(ElementWrite{p.area, p.index + c, cell, ~0u});
    }
    WriteShadow& shadow = is_shared(p.area) ? *shared_writes : *tasks[ti]->writes;
    if (shadow.post(std::span<const ElementWrite>(ws)) == 0)
      return text(503, "busy: " + std::to_string(shadow.capacity()) +
                           " devices are written and wait for a scan to take them (is the PLC in STOP?); "
                           "write them again once it runs, or write devices already waiting");
    return text(200, "queued for the next scan");
  }

  http::Response force_input(const Probe& p, uint32_t bits, bool release) {
    std::lock_guard<std::mutex> l(fmu);
    auto key = std::make_pair(int(p.area), p.index);
    if (release) {
      forced.erase(key);
    } else {
      if (!forced.count(key) && forced.size() >= opt.max_forced)
        return text(503, "busy: " + std::to_string(opt.max_forced) + " devices are forced already; release one first");
      forced[key] = bits;
    }
    forced_version.fetch_add(1, std::memory_order_release);
    any_forced.store(!forced.empty(), std::memory_order_relaxed);
    return text(200, release ? "released" : "forced");
  }

  // RUN/STOP go to the control thread (a STOP saves retentive memory: a file
  // written and fsynced); the request is parked until it is done.
  http::Response run_or_stop(const http::Request& r, bool run) {
    if (r.retries > 0) {
      auto& job = *std::static_pointer_cast<ControlThread::Job>(r.state);
      if (job.done.load(std::memory_order_acquire)) return job.reply;
      if (r.waited_ms > 4000) return text(202, std::string(run ? "RUN" : "STOP") + " requested; still under way");
      return http::Response{200, "", "", false, true};
    }
    if (!rt) return text(409, "no runtime");
    Runtime* runtime = rt;
    std::function<http::Response()> act;
    auto task = http::form_value(r.body, "task");
    if (task && !task->empty()) {  // one task: held or released, the others run on
      size_t ti = rt->find_task(*task);
      if (ti == SIZE_MAX) return text(400, "unknown task '" + *task + "'");
      act = [runtime, ti, run, name = *task] {
        if (run) runtime->run_task(ti);
        else runtime->stop_task(ti);
        return text(200, name + (runtime->task_held(ti) ? " STOP" : " RUN"));
      };
    } else {
      act = [runtime, run] {
        if (run) runtime->run();
        else runtime->stop();
        return text(200, state_name(runtime->state()));
      };
    }
    std::shared_ptr<ControlThread::Job> job = control.post(std::move(act));
    if (!job) return text(503, "busy: " + std::to_string(ControlThread::kMaxJobs) + " RUN/STOP requests are waiting already");
    r.state = job;
    return http::Response{200, "", "", false, true};
  }

  http::Response handle(const http::Request& r) {
    if (!host_ok(r))
      return text(421, "this monitor answers to its own address only (Host: " + std::string(r.header("host") ? *r.header("host") : "") +
                           "); give other names it is reached by with --monitor-host");
    const std::string& p = r.path;
    bool get = r.method == "GET" || r.method == "HEAD";
    if (p == "/" || p == "/index.html" || p == "/monitor.js" || p == "/monitor.css" || p == "/api/program" ||
        p == "/api/state" || p == "/api/events") {
      if (!get) return text(405, "use GET");
      if (p == "/monitor.js") return {200, "text/javascript; charset=utf-8", kMonitorJs, false};
      if (p == "/monitor.css") return {200, "text/css; charset=utf-8", kMonitorCss, false};
      if (p == "/api/program") return {200, "application/json", program_json(), false};
      if (p == "/api/state") return state_reply(r);
      if (p == "/api/events") {
        for (auto& t : tasks) t->want.store(true);
        return {200, "text/event-stream", "retry: 1000\n\ndata: " + state_json() + "\n\n", true};
      }
      return {200, "text/html; charset=utf-8", kMonitorHtml, false};
    }
    if (p == "/api/write" || p == "/api/run" || p == "/api/stop") {
      if (r.method != "POST") return text(405, "use POST");
      if (!opt.write) return text(403, "read-only monitor: start ldrun with --monitor-write to allow RUN/STOP and writes");
      const std::string* h = r.header("x-ldc-monitor");
      if (!h || *h != "1") return text(403, "missing header X-LDC-Monitor: 1 (sent by the monitor page)");
      if (std::string why = cross_origin(r); !why.empty()) return text(403, why);
      if (std::string why = token_refusal(r); !why.empty()) return text(403, why);
      const std::string* ct = r.header("content-type");
      if (!r.body.empty() && (!ct || ct->rfind("application/x-www-form-urlencoded", 0) != 0))
        return text(415, "the body is application/x-www-form-urlencoded");
      if (p == "/api/write") return write(r);
      return run_or_stop(r, p == "/api/run");
    }
    return text(404, "no such page: " + p);
  }
};

namespace {

class MonitorDriver : public IoDriver {
 public:
  MonitorDriver(std::unique_ptr<IoDriver> inner, std::shared_ptr<Monitor::Impl> m) : inner_(std::move(inner)), m_(std::move(m)) {}
  void attach(uint8_t* global, const Layout& layout, uint32_t block_size) override {
    m_->glayout = layout;
    m_->global_snap.assign(layout.size, 0);
    inner_->attach(global, layout, block_size);
  }
  void read_inputs(uint8_t* global, const ScanContext& c) override {
    inner_->read_inputs(global, c);
    m_->apply_shared(global);
  }
  void hold_outputs(uint8_t* global, uint8_t* mem, const ScanContext& c) override {
    inner_->hold_outputs(global, mem, c);
    m_->hold_forced(global, mem, c);
  }
  void write_outputs(const uint8_t* global, const ScanContext& c) override { inner_->write_outputs(global, c); }
  void safe_outputs(const uint8_t* global) override { inner_->safe_outputs(global); }
  void state_changed(State s) override { inner_->state_changed(s); }
  void before_scan(const ScanContext& c, uint8_t* mem, std::optional<int32_t>& dt) override {
    inner_->before_scan(c, mem, dt);
    m_->apply_private(c, mem);
  }
  void after_scan(const ScanContext& c, const uint8_t* mem, const uint8_t* global) override {
    inner_->after_scan(c, mem, global);
    m_->snapshot(c.task, c.scan, mem, global);
  }
  void detach() override { inner_->detach(); }
  // The download has happened: a failure here must not undo it, only be said.
  void program_replaced(size_t task, const Image& image) override {
    inner_->program_replaced(task, image);
    try {
      m_->program_replaced(task, image);
    } catch (const std::exception& e) {
      if (m_->opt.log)
        m_->opt.log(std::string("ldrun: monitor: cannot show the new program of task ") + std::to_string(task) + ": " + e.what() +
                    "; the page shows the old one without values");
    }
  }

 private:
  std::unique_ptr<IoDriver> inner_;
  std::shared_ptr<Monitor::Impl> m_;
};


}  // namespace

std::pair<std::string, uint16_t> parse_monitor_address(const std::string& s, bool remote) {
  std::string host = "127.0.0.1", port = s;
  if (!s.empty() && s[0] == '[') {
    size_t close = s.find(']');
    if (close == std::string::npos || close + 1 >= s.size() || s[close + 1] != ':')
      throw std::runtime_error("--monitor: expected [IPv6]:PORT, got '" + s + "'");
    host = s.substr(1, close - 1), port = s.substr(close + 2);
  } else if (size_t colon = s.rfind(':'); colon != std::string::npos) {
    host = s.substr(0, colon), port = s.substr(colon + 1);
  }
  if (host == "localhost") host = "127.0.0.1";
  if (port.empty() || port.size() > 5 || port.find_first_not_of("0123456789") != std::string::npos || std::stoul(port) > 65535)
    throw std::runtime_error("--monitor: bad port '" + port + "' (0..65535; 0 picks a free one)");
  if (host.empty()) throw std::runtime_error("--monitor: empty host in '" + s + "'");
  if (!loopback(host) && !remote)
    throw std::runtime_error("--monitor: " + host + " is not a loopback address; the monitor serves this machine only unless "
                             "--monitor-remote is given (docs/runtime.md, \"The monitor\": security)");
  return {host, uint16_t(std::stoul(port))};
}

void parse_monitor_hosts(const std::string& list, std::vector<std::string>& out) {
  size_t s = 0;
  while (true) {
    size_t e = list.find(',', s);
    std::string n = list.substr(s, e == std::string::npos ? std::string::npos : e - s);
    // NAME or NAME:PORT; [v6] or [v6]:PORT
    std::string name = n, port;
    bool port_given = false;
    if (!n.empty() && n[0] == '[') {
      size_t close = n.find(']');
      if (close == std::string::npos || (close + 1 < n.size() && n[close + 1] != ':'))
        throw std::runtime_error("--monitor-host: expected [IPv6] or [IPv6]:PORT, got '" + n + "'");
      name = n.substr(0, close + 1);
      port_given = close + 1 < n.size();
      if (port_given) port = n.substr(close + 2);
      unsigned char buf[16];
      if (inet_pton(AF_INET6, name.substr(1, name.size() - 2).c_str(), buf) != 1)
        throw std::runtime_error("--monitor-host: '" + name + "' is not an IPv6 address");
    } else if (size_t colon = n.find(':'); colon != std::string::npos) {
      name = n.substr(0, colon), port = n.substr(colon + 1), port_given = true;
      if (name.empty()) throw std::runtime_error("--monitor-host: empty name in '" + n + "'");
    }
    if (name.empty()) throw std::runtime_error("--monitor-host: empty name in '" + list + "'");
    if (name[0] != '[' && (name.size() > 253 || name.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789.-") !=
                                                  std::string::npos))
      throw std::runtime_error("--monitor-host: '" + name + "' is not a host name (letters, digits, '.', '-') or address");
    if (port_given) {
      if (port.empty() || port.size() > 5 || port.find_first_not_of("0123456789") != std::string::npos || std::stoul(port) == 0 ||
          std::stoul(port) > 65535)
        throw std::runtime_error("--monitor-host: bad port in '" + n + "' (1..65535)");
    }
    out.push_back(n);
    if (e == std::string::npos) break;
    s = e + 1;
  }
}

void check_monitor_token(const std::string& t) {
  if (t.size() < 16 || t.size() > 128 ||
      t.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789._~-") != std::string::npos)
    throw std::runtime_error("--monitor-token: 16 to 128 characters of A-Z a-z 0-9 . _ ~ - (a guessable token protects nothing)");
}

std::string make_monitor_token() {
  unsigned char b[16];
  int fd = open("/dev/urandom", O_RDONLY | O_CLOEXEC);
  size_t got = 0;
  while (fd >= 0 && got < sizeof b) {
    ssize_t n = read(fd, b + got, sizeof b - got);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    got += size_t(n);
  }
  if (fd >= 0) close(fd);
  if (got < sizeof b)
    throw std::runtime_error(std::string("--monitor-remote --monitor-write: cannot read /dev/urandom for the write token (") +
                             std::strerror(errno) + "); give one with --monitor-token");
  static const char hex[] = "0123456789abcdef";
  std::string t;
  for (unsigned char c : b) t += hex[c >> 4], t += hex[c & 15];
  return t;
}

Monitor::Monitor(std::vector<MonitorTask> tasks, MonitorOptions opt) : impl_(std::make_shared<Impl>()) {
  impl_->opt = std::move(opt);
  impl_->shared_writes = std::make_unique<WriteShadow>(impl_->opt.write_backlog);
  for (MonitorTask& mt : tasks) {
    auto t = std::make_unique<TaskView>();
    t->name = mt.name;
    t->view = build_view(mt, 0, 0);
    t->layout = t->view->layout;
    t->mem.assign(t->layout.size, 0);
    t->writes = std::make_unique<WriteShadow>(impl_->opt.write_backlog);
    impl_->tasks.push_back(std::move(t));
  }
}

void Monitor::Impl::program_replaced(size_t ti, const Image& img) {
  if (ti >= tasks.size()) return;
  TaskView& t = *tasks[ti];
  std::shared_ptr<const ProgramView> old;
  {
    std::lock_guard<std::mutex> l(t.view_mu);
    old = t.view;
  }
  MonitorTask mt{t.name, old->period_us, img, "", ""};
  if (opt.source_of) opt.source_of(ti, img, mt.source_text, mt.source_note);
  const int64_t now_ms =
      std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::system_clock::now().time_since_epoch()).count();
  std::shared_ptr<const ProgramView> v = build_view(mt, generation(ti), now_ms);
  std::lock_guard<std::mutex> lv(t.view_mu);
  std::lock_guard<std::mutex> ls(t.snap_mu);
  t.view = v;
  t.layout = v->layout;
  t.mem.assign(v->layout.size, 0);
  t.gen = v->gen;
  t.scan = 0;
  t.taken = false;
  t.want.store(true, std::memory_order_relaxed);
}

Monitor::~Monitor() { stop(); }

std::unique_ptr<IoDriver> Monitor::wrap(std::unique_ptr<IoDriver> inner) {
  return std::make_unique<MonitorDriver>(std::move(inner), impl_);
}

void Monitor::attach(Runtime* rt) { impl_->rt = rt; }

void Monitor::start() {
  http::Server::Config c;
  const MonitorOptions& o = impl_->opt;
  c.host = o.host;
  c.port = o.port;
  c.max_connections = o.max_connections;
  c.max_per_address = o.max_per_address;
  c.max_streams = o.max_streams;
  c.tick_ms = o.tick_ms;
  c.log = o.log;
  Impl* m = impl_.get();
  c.bound = [m](uint16_t port) { m->allow_hosts(port); };
  impl_->server = std::make_unique<http::Server>(
      c, [m](const http::Request& r) { return m->handle(r); },
      [m]() -> std::string {
        if (!m->server || m->server->streams() == 0) return "";
        return "data: " + m->state_json() + "\n\n";
      });
  impl_->control.start();
  impl_->server->start();
}

void Monitor::stop() {
  if (impl_->server) impl_->server->stop();
  impl_->control.stop();
}

uint16_t Monitor::port() const { return impl_->server ? impl_->server->port() : 0; }

}  // namespace ldc::plc
