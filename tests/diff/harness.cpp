// tests/diff/harness.cpp -- two engines side by side, scan by scan (harness.h).
#include "tests/diff/harness.h"

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <climits>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>

#include "backend-c/backend_c.h"
#include "backend-c/c_shared.h"
#include "driver/driver.h"
#include "driver/targets.h"
#include "driver/x86_target.h"
#include "frontend/frontend.h"
#include "runtime/change_driven.h"
#include "runtime/fastinterp.h"

namespace ldc::diff {

std::unique_ptr<Engine> make_interp(const Program& p) {
  BinaryIl bin = encode_il(p);
  if (std::string why = validate_il(bin.code, p.layout()); !why.empty()) throw std::runtime_error("IL " + why);
  return make_interp_engine(bin.code, p.layout());
}

std::unique_ptr<Engine> make_native(const Program& p) {
  NativeBuild nb = build_x86(p, p.source);
  return make_native_engine(map_checked_code(nb.asm_result.code, 0, p.layout()));
}

std::unique_ptr<Engine> make_native_o1(const Program& p) {
  NativeBuild nb = build_x86(p, p.source, as::Mode::Blockwise, 1);
  return make_native_engine(map_checked_code(nb.asm_result.code, 0, p.layout()));
}

std::unique_ptr<Engine> make_native_o2(const Program& p) {
  NativeBuild nb = build_x86(p, p.source, as::Mode::Blockwise, 2);
  return make_native_engine(map_checked_code(nb.asm_result.code, 0, p.layout()));
}

std::unique_ptr<Engine> make_fast_interp(const Program& p) {
  BinaryIl bin = encode_il(p);
  if (std::string why = validate_il(bin.code, p.layout()); !why.empty()) throw std::runtime_error("IL " + why);
  return make_fast_interp_engine(bin.code, p.layout());
}

std::unique_ptr<Engine> make_c_route(const Program& p) {
  std::string dir = (std::filesystem::temp_directory_path() / "ldc_diff_c_XXXXXX").string();
  if (!mkdtemp(dir.data())) throw std::runtime_error("mkdtemp: " + std::string(std::strerror(errno)));
  struct Rm {
    std::string d;
    ~Rm() { std::error_code ec; std::filesystem::remove_all(d, ec); }  // the loaded object stays mapped
  } rm{dir};
  return make_shared_object_engine(build_c_shared_object(p, dir), kCScanSymbol);
}

namespace {
std::unique_ptr<Engine> c40_engine(const Program& p, const char* name, bool code) {
  FoundEngine fe = find_engine(name);
  if (!fe.engine) throw std::runtime_error(std::string("no engine ") + name);
  Image img;
  if (code) {
    img = target_image(*fe.target, p, p.source, 0);
  } else {
    img.layout = p.layout();
    img.il = encode_il(p).code;
    img.aliases = p.aliases;
    if (std::string why = validate_il(img.il, img.layout); !why.empty()) throw std::runtime_error("IL " + why);
  }
  return fe.engine->make(img);
}
}  // namespace

std::unique_ptr<Engine> make_c40sim(const Program& p) { return c40_engine(p, "c40sim", true); }
std::unique_ptr<Engine> make_c40interp(const Program& p) { return c40_engine(p, "c40interp", false); }

std::unique_ptr<Engine> make_change_driven(const Program& p, const EngineFactory& part, uint32_t max_rungs) {
  const Layout L = p.layout();
  RegionPlan plan = plan_regions(p, L, max_rungs);
  std::vector<std::unique_ptr<Engine>> parts;
  for (const Region& r : plan.regions) parts.push_back(part(region_program(p, r)));
  return std::make_unique<ChangeDrivenEngine>(plan, L, std::move(parts));
}

bool looks_like_iec_il(const std::string& text) {
  size_t a = text.find_first_not_of(" \t\r\n");
  return a != std::string::npos && text.compare(a, 2, "(*") == 0;
}

Program compile_case(const std::string& text) {
  if (looks_like_ldc_il(text)) return parse_il_text(text, "prog.il");
  if (looks_like_iec_il(text)) return parse_iec_il(text, "prog.il");
  return lower_to_il(parse_ld(text, "prog.ld"));
}

// ------------------------------------------------------------------ naming bytes

Place describe(const Layout& l, uint32_t off) {
  Place p;
  for (int i = 0; i < kAreaCount; i++) {
    Area a = Area(i);
    uint32_t start = l.offset[i], end = start + l.count[i] * l.elem_size(a);
    if (off < start || off >= end) continue;
    p.area = a;
    p.index = (off - start) / l.elem_size(a);
    std::string n = std::to_string(p.index);
    switch (a) {
      case Area::Sys:
        p.name = "Sys+" + n + (p.index < 4 ? " (dt)" : p.index < 8 ? " (scans completed)" : " (reserved)");
        break;
      case Area::TQ: p.name = "T" + n + " done bit"; p.watch = ""; break;
      case Area::CQ: p.name = "C" + n + " done bit"; break;
      case Area::TI: p.name = "T" + n + " input memory (TI)"; break;
      case Area::TW: p.name = "T" + n + " elapsed ms"; p.watch = "T" + n; break;
      case Area::CW: p.name = "C" + n + " current value"; p.watch = "C" + n; break;
      case Area::E: p.name = "E" + n + " edge memory"; break;
      default: p.name = std::string(area_name(a)) + n; p.watch = p.name; break;
    }
    if (l.elem_size(a) == 4 && (off - start) % 4) p.name += " byte " + std::to_string((off - start) % 4);
    return p;
  }
  p.name = "padding at " + std::to_string(off);
  return p;
}

std::string value_at(const Layout& l, std::span<const uint8_t> img, uint32_t off) {
  Place p = describe(l, off);
  char buf[96];
  if (p.area == Area::Count || p.area == Area::Sys || area_is_bit(p.area)) {
    if (p.area == Area::Sys && p.index < 8) {
      uint32_t start = p.index / 4 * 4;
      int32_t v;
      std::memcpy(&v, img.data() + start, 4);
      std::snprintf(buf, sizeof buf, "%d", v);
    } else {
      std::snprintf(buf, sizeof buf, "%u (byte 0x%02x)", img[off], img[off]);
    }
    return buf;
  }
  uint32_t at = l.addr(p.area, p.index), u;
  std::memcpy(&u, img.data() + at, 4);
  if (area_is_real(p.area)) {
    float f;
    std::memcpy(&f, &u, 4);
    std::snprintf(buf, sizeof buf, "%.9g (0x%08x)", double(f), u);
  } else {
    std::snprintf(buf, sizeof buf, "%d (0x%08x)", int32_t(u), u);
  }
  return buf;
}

// ------------------------------------------------------------------ one run

namespace {

// As runtime/trace.cpp reads a cell: decimal, or hex with 0x; never octal.
long long cell_int(const std::string& v) {
  bool neg = !v.empty() && v[0] == '-';
  size_t at = (neg || (!v.empty() && v[0] == '+')) ? 1 : 0;
  if (v.size() > at + 2 && v[at] == '0' && (v[at + 1] == 'x' || v[at + 1] == 'X')) {
    long long x = std::strtoll(v.c_str() + at + 2, nullptr, 16);
    return neg ? -x : x;
  }
  return std::strtoll(v.c_str(), nullptr, 10);
}

// Writes trace row k (0-based) as run_trace does; dt keeps its last value.
void apply_row(const Trace& t, size_t k, Memory& mem, int32_t& dt, Engine* e = nullptr) {
  const auto& row = t.rows[k];
  for (size_t i = 0; i < row.size(); i++) {
    const std::string& v = row[i];
    if (v.empty()) continue;
    const Probe& p = t.columns[i];
    if (int(i) == t.dt_column) dt = int32_t(cell_int(v));
    else if (p.area == Area::F) mem.set_real(p.index, std::strtof(v.c_str(), nullptr));
    else if (area_is_bit(p.area)) mem.set_bit(p.area, p.index, cell_int(v) != 0);
    else mem.set_int(p.area, p.index, int32_t(cell_int(v)));
    if (e && int(i) != t.dt_column) e->written(mem.layout.addr(p.area, p.index), mem.layout.elem_size(p.area));
  }
}

}  // namespace

Outcome compare_run(const std::string& ld, const std::string& csv, const EngineFactory& ref, const EngineFactory& test) {
  Outcome o;
  Program prog;
  Trace trace;
  try {
    prog = compile_case(ld);
    trace = read_trace(csv, "trace.csv", prog.aliases);
  } catch (CompileError& e) {
    o.kind = Outcome::Kind::FrontEndError;
    o.message = format_error(looks_like_ldc_il(ld) || looks_like_iec_il(ld) ? "prog.il" : "prog.ld", ld, e.line, e.col, e.what());
    return o;
  } catch (std::exception& e) {
    o.kind = Outcome::Kind::FrontEndError;
    o.message = e.what();
    return o;
  }
  std::unique_ptr<Engine> a, b;
  try {
    a = ref(prog);
  } catch (std::exception& e) {
    o.kind = Outcome::Kind::FrontEndError;
    o.message = std::string("building the reference engine: ") + e.what();
    return o;
  }
  try {
    b = test(prog);
  } catch (std::exception& e) {
    o.kind = Outcome::Kind::TestError;
    o.message = std::string("building the engine under test: ") + e.what();
    return o;
  }
  Layout layout = prog.layout();
  Memory ma(layout), mb(layout);
  int32_t dt_a = 10, dt_b = 10;  // ldrun's default --period
  int scans = int(trace.rows.size());
  o.scans = scans;
  for (int k = 1; k <= scans; k++) {
    apply_row(trace, size_t(k - 1), ma, dt_a);
    apply_row(trace, size_t(k - 1), mb, dt_b, b.get());
    for (Memory* m : {&ma, &mb}) {
      std::memcpy(m->data() + kSysDt, m == &ma ? &dt_a : &dt_b, 4);
      m->set_bit(Area::S, kBitFirstScan, k == 1);
    }
    try {
      a->scan(ma.bytes);
    } catch (std::exception& e) {
      o.kind = Outcome::Kind::FrontEndError;
      o.message = std::string("the reference engine threw: ") + e.what();
      return o;
    }
    try {
      b->scan(mb.bytes);
    } catch (std::exception& e) {
      o.kind = Outcome::Kind::TestError;
      o.message = "scan " + std::to_string(k) + ": the engine under test threw: " + e.what();
      return o;
    }
    uint32_t n = uint32_t(k);
    std::memcpy(ma.data() + kSysScan, &n, 4);
    std::memcpy(mb.data() + kSysScan, &n, 4);
    if (ma.bytes == mb.bytes) continue;
    o.kind = Outcome::Kind::Differ;
    o.scan = k;
    bool first = true;
    std::set<std::pair<int, uint32_t>> seen;  // (area, index): one line per element
    for (uint32_t i = 0; i < layout.size; i++) {
      if (ma.bytes[i] == mb.bytes[i]) continue;
      Place p = describe(layout, i);
      if (first) {
        first = false;
        o.offset = i;
        o.place = p;
        o.ref_value = value_at(layout, ma.bytes, i);
        o.test_value = value_at(layout, mb.bytes, i);
        seen.insert({int(p.area), p.index});
      } else if (seen.insert({int(p.area), p.index}).second && o.also.size() < 12) {
        std::string name = p.area == Area::Count ? p.name : describe(layout, layout.addr(p.area, p.index)).name;
        o.also.push_back(name + ": " + value_at(layout, ma.bytes, i) + " vs " + value_at(layout, mb.bytes, i));
      }
    }
    return o;
  }
  return o;
}

// ------------------------------------------------------------------ in a child process

namespace {

void put(std::string& s, const std::string& v) { s += std::to_string(v.size()) + ":" + v; }
bool get(const std::string& s, size_t& at, std::string& v) {
  size_t c = s.find(':', at);
  if (c == std::string::npos) return false;
  size_t n = std::strtoul(s.c_str() + at, nullptr, 10);
  if (c + 1 + n > s.size()) return false;
  v = s.substr(c + 1, n);
  at = c + 1 + n;
  return true;
}

std::string encode(const Outcome& o) {
  std::string s;
  put(s, std::to_string(int(o.kind)));
  put(s, std::to_string(o.scans));
  put(s, std::to_string(o.scan));
  put(s, std::to_string(o.offset));
  put(s, std::to_string(int(o.place.area)));
  put(s, std::to_string(o.place.index));
  put(s, o.place.name);
  put(s, o.place.watch);
  put(s, o.ref_value);
  put(s, o.test_value);
  put(s, o.message);
  put(s, std::to_string(o.also.size()));
  for (const auto& a : o.also) put(s, a);
  return s;
}

bool decode(const std::string& s, Outcome& o) {
  size_t at = 0;
  std::string f[11];
  for (auto& x : f)
    if (!get(s, at, x)) return false;
  o.kind = Outcome::Kind(std::atoi(f[0].c_str()));
  o.scans = std::atoi(f[1].c_str());
  o.scan = std::atoi(f[2].c_str());
  o.offset = uint32_t(std::strtoul(f[3].c_str(), nullptr, 10));
  o.place.area = Area(std::atoi(f[4].c_str()));
  o.place.index = uint32_t(std::strtoul(f[5].c_str(), nullptr, 10));
  o.place.name = f[6];
  o.place.watch = f[7];
  o.ref_value = f[8];
  o.test_value = f[9];
  o.message = f[10];
  std::string n;
  if (!get(s, at, n)) return false;
  for (int i = 0, c = std::atoi(n.c_str()); i < c; i++) {
    std::string a;
    if (!get(s, at, a)) return false;
    o.also.push_back(a);
  }
  return true;
}

}  // namespace

Outcome compare_isolated(const std::string& ld, const std::string& csv, const EngineFactory& ref,
                         const EngineFactory& test, int time_limit_s) {
  const char* nofork = std::getenv("LDC_DIFF_NOFORK");
  if (nofork && *nofork && std::strcmp(nofork, "0") != 0) return compare_run(ld, csv, ref, test);
  int fds[2];
  if (pipe(fds) != 0) throw std::runtime_error(std::string("pipe: ") + std::strerror(errno));
  std::fflush(nullptr);
  pid_t pid = fork();
  if (pid < 0) throw std::runtime_error(std::string("fork: ") + std::strerror(errno));
  if (pid == 0) {
    close(fds[0]);
    alarm(unsigned(time_limit_s));
    std::string s;
    try {
      s = encode(compare_run(ld, csv, ref, test));
    } catch (std::exception& e) {
      Outcome o;
      o.kind = Outcome::Kind::FrontEndError;
      o.message = std::string("the harness threw: ") + e.what();
      s = encode(o);
    }
    size_t done = 0;
    while (done < s.size()) {
      ssize_t w = write(fds[1], s.data() + done, s.size() - done);
      if (w <= 0) break;
      done += size_t(w);
    }
    _exit(0);
  }
  close(fds[1]);
  std::string s;
  char buf[4096];
  for (;;) {
    ssize_t r = read(fds[0], buf, sizeof buf);
    if (r < 0 && errno == EINTR) continue;
    if (r <= 0) break;
    s.append(buf, size_t(r));
  }
  close(fds[0]);
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  Outcome o;
  if (WIFEXITED(status) && WEXITSTATUS(status) == 0 && decode(s, o)) return o;
  o = Outcome{};
  o.kind = Outcome::Kind::Crash;
  if (WIFSIGNALED(status))
    o.message = WTERMSIG(status) == SIGALRM ? "time limit of " + std::to_string(time_limit_s) + " s exceeded (a hang?)"
                                            : std::string("killed by signal ") + strsignal(WTERMSIG(status));
  else
    o.message = "the child exited with status " + std::to_string(WIFEXITED(status) ? WEXITSTATUS(status) : -1) +
                " (a sanitizer report above?)";
  return o;
}

// ------------------------------------------------------------------ minimizing

namespace {

struct Csv {
  std::string head;               // comments and the header line
  std::vector<std::string> rows;  // one per scan
  std::string text() const {
    std::string s = head;
    for (const auto& r : rows) s += r + "\n";
    return s;
  }
};

Csv split_csv(const std::string& csv) {
  Csv c;
  bool header = false;
  size_t pos = 0;
  while (pos < csv.size()) {
    size_t nl = csv.find('\n', pos);
    std::string l = csv.substr(pos, nl == std::string::npos ? std::string::npos : nl - pos);
    pos = nl == std::string::npos ? csv.size() : nl + 1;
    size_t a = l.find_first_not_of(" \t\r");
    if (a == std::string::npos || l[a] == '#') {  // blank or comment: kept above the header only
      if (!header) c.head += l + "\n";
      continue;
    }
    if (!header) {
      header = true;
      c.head += l + "\n";
      continue;
    }
    c.rows.push_back(l);
  }
  return c;
}

std::vector<std::string> cells(const std::string& line) {
  std::vector<std::string> v;
  size_t s = 0;
  while (true) {
    size_t c = line.find(',', s);
    v.push_back(line.substr(s, c == std::string::npos ? std::string::npos : c - s));
    if (c == std::string::npos) break;
    s = c + 1;
  }
  return v;
}

std::string join(const std::vector<std::string>& v) {
  std::string s;
  for (size_t i = 0; i < v.size(); i++) s += (i ? "," : "") + v[i];
  return s;
}

// The trace without column `col` (the header is the head's last line).
bool drop_column(const Csv& in, size_t col, Csv& out) {
  size_t end = in.head.size() - 1, start = in.head.rfind('\n', end - 1);
  start = start == std::string::npos ? 0 : start + 1;
  std::vector<std::string> h = cells(in.head.substr(start, end - start));
  if (col >= h.size() || h.size() == 1) return false;
  h.erase(h.begin() + long(col));
  out.head = in.head.substr(0, start) + join(h) + "\n";
  out.rows.clear();
  for (const auto& r : in.rows) {
    std::vector<std::string> c = cells(r);
    if (col < c.size()) c.erase(c.begin() + long(col));
    out.rows.push_back(join(c));
  }
  return true;
}

size_t column_count(const Csv& c) {
  size_t end = c.head.size() - 1, start = c.head.rfind('\n', end - 1);
  start = start == std::string::npos ? 0 : start + 1;
  return cells(c.head.substr(start, end - start)).size();
}

void drop_unused_labels(GenProgram& p) {
  std::set<std::string> used;
  for (const auto& it : p.items)
    for (const auto& j : it.jumps) used.insert(j);
  std::vector<GenItem> kept;
  for (auto& it : p.items)
    if (it.kind == GenItem::Kind::Rung || used.count(it.text)) kept.push_back(std::move(it));
  p.items = std::move(kept);
}

// An IL rung (a typed program's) without one of its instruction lines, for
// each line; one that unbalances the stack is refused and so never kept.
std::vector<std::string> il_line_reductions(const std::string& rung) {
  std::vector<std::string> lines, out;
  for (size_t at = 0; at < rung.size();) {
    size_t nl = rung.find('\n', at);
    nl = nl == std::string::npos ? rung.size() : nl + 1;
    lines.push_back(rung.substr(at, nl - at));
    at = nl;
  }
  for (size_t i = 1; i < lines.size(); i++) {
    std::string t;
    for (size_t j = 0; j < lines.size(); j++)
      if (j != i) t += lines[j];
    out.push_back(t);
  }
  return out;
}

// The smaller rungs one edit makes: an IL rung (a typed program's) without one
// of its lines, a grid rung without a group, a branch or a condition.
std::vector<GenItem> rung_item_reductions(const GenItem& rung, bool text) {
  std::vector<GenItem> out;
  if (text) {
    for (std::string& t : il_line_reductions(rung.text)) {
      out.push_back(rung);
      out.back().text = std::move(t);
    }
    return out;
  }
  for (GenNode& c : rung_reductions(rung.root)) {
    out.push_back(rung);
    out.back().root = std::move(c);
    update_rung(out.back());
  }
  return out;
}

}  // namespace

Reduced minimize(const GenProgram& prog, const std::string& csv, const Outcome& first, const Runner& run) {
  Reduced r;
  r.prog = prog;
  r.outcome = first;
  Csv trace = split_csv(csv);
  auto cut = [&](Csv& t, const Outcome& o) {
    if (o.kind == Outcome::Kind::Differ && o.scan > 0 && size_t(o.scan) < t.rows.size()) t.rows.resize(size_t(o.scan));
  };
  // Runs a smaller program; keeps it if it still fails the same way.
  auto try_program = [&](GenProgram& p) {
    r.runs++;
    Outcome o = run(render(p), trace.text());
    if (!o.failed() || o.kind != first.kind) return false;
    r.prog = std::move(p);
    r.outcome = o;
    cut(trace, o);
    return true;
  };
  cut(trace, r.outcome);
  for (bool changed = true; changed;) {
    changed = false;
    // Rungs, last to first, until no single rung can go.
    for (bool again = true; again;) {
      again = false;
      for (size_t i = r.prog.items.size(); i-- > 0;) {
        if (r.prog.items[i].kind != GenItem::Kind::Rung || r.prog.rungs() <= 1) continue;
        GenProgram p = r.prog;
        p.items.erase(p.items.begin() + long(i));
        if (try_program(p)) again = changed = true;
      }
    }
    // Inside each rung: leave out a group, a branch or a condition (an IL
    // rung: an instruction line) while it fails.
    for (size_t i = 0; i < r.prog.items.size(); i++) {
      if (r.prog.items[i].kind != GenItem::Kind::Rung) continue;
      for (bool again = true; again;) {
        again = false;
        for (GenItem& smaller : rung_item_reductions(r.prog.items[i], r.prog.il || r.prog.iec)) {
          GenProgram p = r.prog;
          p.items[i] = std::move(smaller);
          if (try_program(p)) {
            again = changed = true;
            break;
          }
        }
      }
    }
  }
  {
    GenProgram p = r.prog;
    drop_unused_labels(p);
    try_program(p);
  }
  // The trace: runs it with the program as it now is.
  auto attempt = [&](const Csv& t, Outcome& o) {
    r.runs++;
    o = run(render(r.prog), t.text());
    return o.failed() && o.kind == first.kind;
  };
  // Trailing scans: one at a time from the end while it still fails.
  while (trace.rows.size() > 1) {
    Csv t = trace;
    t.rows.pop_back();
    Outcome o;
    if (!attempt(t, o)) break;
    trace = std::move(t);
    r.outcome = o;
  }
  // Trace columns that do not matter (their devices then stay 0).
  for (size_t col = column_count(trace); col-- > 0;) {
    Csv t;
    if (!drop_column(trace, col, t)) continue;
    Outcome o;
    if (attempt(t, o)) {
      trace = std::move(t);
      r.outcome = o;
      cut(trace, o);
    }
  }
  if (r.outcome.kind == Outcome::Kind::Differ) r.outcome.scans = r.outcome.scan;  // what the cut trace runs
  std::string note = "minimized reproducer (" + std::to_string(r.prog.rungs()) + " of " + std::to_string(prog.rungs()) + " rungs)";
  r.prog.header = (prog.iec ? "(* " + note + " *)\n" : std::string(prog.il ? "; " : "# ") + note + "\n") + prog.header;
  r.csv = trace.text();
  return r;
}

// ------------------------------------------------------------------ a run over seeds

SeedTotals run_seeds(const SeedRun& run, const std::function<void(const std::string&)>& fail) {
  const std::string dir = output_dir();
  SeedTotals t;
  auto t0 = std::chrono::steady_clock::now();
  for (long i = run.first; i < run.count; i += run.step) {
    uint64_t seed = uint64_t(run.seed0 + i);
    GenOptions o = run.options(seed);
    GenProgram gp = generate_program(seed, o);
    const int scans = run.scans(seed);
    std::string text = render(gp), csv = generate_trace(seed, scans, o);
    if (run.trace_filter) csv = run.trace_filter(seed, csv);
    Outcome out = compare_isolated(text, csv, make_interp, run.test);
    t.programs++;
    t.rungs += gp.rungs();
    t.scans += out.scans;
    if (t.programs % 1000 == 0) {  // a long run says how far it is
      std::printf("%s: %ld programs, %ld failures, %.0f s\n", run.what.c_str(), t.programs, t.failures,
                  std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
      std::fflush(stdout);
    }
    if (out.kind == Outcome::Kind::FrontEndError) {
      fail("seed " + std::to_string(seed) + ": the generated case is refused (a generator bug): " + out.message);
      continue;
    }
    if (!out.failed()) continue;
    Reduced r = minimize(gp, csv, out, [&](const std::string& l, const std::string& c) {
      return compare_isolated(l, c, make_interp, run.test);
    });
    fail(reproducer(run.what + " differs from the interpreter: ldgen seed " + std::to_string(seed),
                    ldgen_command(seed, o, scans), gp, r, dir, run.stem + std::to_string(seed), "interp",
                    run.what.c_str(), run.engine));
    if (++t.failures >= run.max_failures) {
      fail("stopping after " + std::to_string(run.max_failures) + " failing seeds");
      break;
    }
  }
  t.secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return t;
}

// ------------------------------------------------------------------ reproducers

long env_long(const char* name, long def) {
  const char* v = std::getenv(name);
  if (!v || !*v) return def;
  char* end = nullptr;
  long x = std::strtol(v, &end, 10);
  return *end ? def : x;
}

std::string output_dir() {
  const char* d = std::getenv("LDC_DIFF_OUT");
  std::error_code ec;
  std::filesystem::path p = d && *d ? std::filesystem::path(d) : std::filesystem::current_path(ec);
  std::filesystem::create_directories(p, ec);
  return std::filesystem::absolute(p, ec).string();
}

std::string ldgen_command(uint64_t seed, const GenOptions& o, int scans) {
#ifdef LDC_LDGEN_PATH
  std::string ldgen = LDC_LDGEN_PATH;
#else
  std::string ldgen = "build/bench/ldgen";
#endif
  return ldgen + " " + ldgen_args(seed, o) + " -o prog." + (o.classes & (kGenTyped | kGenTPou) ? "il" : "ld") +
         " --trace trace.csv --scans " + std::to_string(scans);
}

namespace {

// Devices the program names, as --watch spellings (timers and counters as words).
std::vector<std::string> program_devices(const std::string& ld) {
  std::vector<std::string> out;
  try {
    Program p = compile_case(ld);
    std::set<std::string> seen;
    for (const Rung& r : p.rungs)
      for (const Instr& in : r.code)
        for (int i = 0; i < in.nopd(); i++) {
          const Operand& o = in.a[i];
          std::string n;
          if (o.kind == OpdKind::Timer) n = "T" + std::to_string(o.index);
          else if (o.kind == OpdKind::Counter) n = "C" + std::to_string(o.index);
          else if (o.kind == OpdKind::Bit || o.kind == OpdKind::Int || o.kind == OpdKind::Real) {
            Area a = o.area;
            if (a == Area::TQ || a == Area::TW) n = "T" + std::to_string(o.index);
            else if (a == Area::CQ || a == Area::CW) n = "C" + std::to_string(o.index);
            else n = std::string(area_name(a)) + std::to_string(o.index);
          }
          if (!n.empty() && seen.insert(n).second) out.push_back(n);
        }
  } catch (std::exception&) {
  }
  return out;
}

bool write_text(const std::string& path, const std::string& text) {
  std::ofstream f(path, std::ios::binary);
  f << text;
  return bool(f);
}

}  // namespace

std::string reproducer(const std::string& title, const std::string& origin, const GenProgram& original,
                       const Reduced& r, const std::string& dir, const std::string& stem, const char* ref_name,
                       const char* test_name, const std::string& test_engine) {
  const Outcome& o = r.outcome;
  std::string ld = render(r.prog);
  std::string ld_path = dir + "/" + stem + (r.prog.il || r.prog.iec ? ".il" : ".ld"), csv_path = dir + "/" + stem + ".csv";
  bool wrote = write_text(ld_path, ld) && write_text(csv_path, r.csv);
  std::string s = "==== " + title + "\n";
  s += "original: " + origin + "\n";
  s += "minimized from " + std::to_string(original.rungs()) + " rungs to " + std::to_string(r.prog.rungs()) +
       " rung(s) and " + std::to_string(o.scans) + " scan(s) in " + std::to_string(r.runs) + " runs\n";
  switch (o.kind) {
    case Outcome::Kind::Differ: {
      char off[32];
      std::snprintf(off, sizeof off, "0x%x", o.offset);
      s += "first differing scan: " + std::to_string(o.scan) + " (the trace's last row)\n";
      s += "first differing byte: offset " + std::to_string(o.offset) + " (" + off + ") = " + o.place.name + "\n";
      s += "  " + std::string(ref_name) + ": " + o.ref_value + "\n";
      s += "  " + std::string(test_name) + ": " + o.test_value + "\n";
      for (const auto& a : o.also) s += "  also differs: " + a + "\n";
      break;
    }
    default: s += "failure: " + o.message + "\n"; break;
  }
  s += "---- " + ld_path + "\n" + ld;
  s += "---- " + csv_path + "\n" + r.csv;
  std::vector<std::string> watch;
  if (!o.place.watch.empty()) watch.push_back(o.place.watch);
  for (const auto& d : program_devices(ld))
    if (std::find(watch.begin(), watch.end(), d) == watch.end() && watch.size() < 24) watch.push_back(d);
  std::string w;
  for (const auto& x : watch) w += (w.empty() ? "" : ",") + x;
  s += "---- reproduce (compare the last rows)\n";
  if (!wrote) s += "(could not write the files above; save them by hand)\n";
#ifdef LDC_LDRUN_PATH
  std::string ldrun = LDC_LDRUN_PATH;
#else
  std::string ldrun = "build/driver/ldrun";
#endif
  for (const std::string& e : {std::string("interp"), test_engine})
    s += ldrun + " " + ld_path + " --engine=" + e + " --trace " + csv_path + (w.empty() ? "" : " --watch " + w) + "\n";
  return s;
}

}  // namespace ldc::diff
