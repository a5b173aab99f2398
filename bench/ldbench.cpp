// ldbench -- paper 003's evaluation, measured on this machine, side by side:
// the classic reference interpreter (ir/interp.cpp), the fast interpreter
// (runtime/fastinterp.h), native x86-64 code (build_x86) and the C route
// (ldc --emit=c through cc -O2), on the same programs and the same input
// traces; the simulated TMS320C40 (its native code and its C40-hosted
// interpreter, in cycles); plus code size, compile speed and compile memory.
// Writes CSV files, SVG plots and tables.md into --out (docs/BENCHMARKS.md
// presents one run).
//
//   ldbench --out docs/bench            the full run (several minutes)
//   ldbench --smoke --out DIR           tiny sizes, a few seconds (the test suite)
//
// Timing: every engine runs the program on its own memory image over the same
// input trace (one row written before each scan).  After a warm-up that also
// sizes a batch (enough scans for ~25 us, at least one), the engines take
// turns, one batch each, in an order that rotates every round, until each has
// --samples batches.  A sample is a batch's time / its scans
// (std::chrono::steady_clock).  The same loop with an engine that does nothing
// measures the cost of writing the inputs and calling through Engine; its
// median is subtracted.  Reported: median and p99 of the samples.
#include <dirent.h>
#include <fcntl.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/utsname.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <fstream>
#include <functional>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "backend-c/backend_c.h"
#include "backend-c/c_shared.h"
#include "backend-x86/backend_x86.h"
#include "bench/ldgen.h"
#include "bench/rng.h"
#include "bench/svgplot.h"
#include "bench/synth.h"
#include "driver/driver.h"
#include "driver/targets.h"
#include "driver/x86_target.h"
#include "frontend/frontend.h"
#include "loader/loader.h"
#include "runtime/fastinterp.h"
#include "runtime/runtime.h"
#include "driver/version.h"

#ifndef LDC_SOURCE_DIR
#define LDC_SOURCE_DIR "."
#endif
#ifndef LDC_BUILD_TYPE
#define LDC_BUILD_TYPE "?"
#endif

extern "C" char** environ;

using namespace ldc;

namespace {

using Clock = std::chrono::steady_clock;

// native is ldc's -O0 (paper 003's pure macro expansion); native-O1 and
// native-O2 the optimizing levels of docs/x86.md.
// native-cd is the change-driven scan (issue 28, docs/change-driven.md):
// regions of up to kChangeRungs rungs compiled at -O2, each run only when
// what it reads or writes changed (8 ran faster than 1 on every program of
// the first measurement, docs/BENCHMARKS.md "Issue 28").
enum EngineKind { kClassic, kFast, kNative, kNativeO1, kNativeO2, kC, kChange, kEngines };
const char* const kEngineName[] = {"classic", "fast", "native", "native-O1", "native-O2", "c", "native-cd"};
const char* const kEngineTitle[] = {"classic interpreter", "fast interpreter", "native x86-64 -O0",
                                    "native x86-64 -O1",   "native x86-64 -O2", "C route (cc -O2)",
                                    "native change-driven"};
constexpr int kLevels = 3;
constexpr uint32_t kChangeRungs = 8;
constexpr EngineKind kNativeAt[kLevels] = {kNative, kNativeO1, kNativeO2};

struct Options {
  std::string out = "bench-out";
  bool smoke = false;
  int samples = 1001;
  double batch_us = 25;
  bool c_route = true;
  long c_max_il = 70000;
  bool c40 = true;
  std::string source_dir = LDC_SOURCE_DIR;
  std::string only;  // experiments to run, comma separated; "" = all
  std::vector<std::string> files;  // `ldbench FILE...`: only these programs, every engine
  std::string doc;   // a Markdown file whose generated region gets tables.md
  std::string command;
  bool want(const std::string& e) const {
    if (only.empty()) return true;
    std::string s = "," + only + ",";
    return s.find("," + e + ",") != std::string::npos;
  }
};

void say(const char* fmt, ...) __attribute__((format(printf, 1, 2)));
void say(const char* fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  std::vfprintf(stderr, fmt, ap);
  va_end(ap);
  std::fflush(stderr);
}

double secs_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// ------------------------------------------------------------------ statistics

double quantile(std::vector<double> v, double q) {  // nearest rank
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  size_t k = size_t(std::ceil(q * double(v.size())));
  k = std::clamp<size_t>(k, 1, v.size());
  return v[k - 1];
}
double median(std::vector<double> v) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  size_t n = v.size();
  return n % 2 ? v[n / 2] : (v[n / 2 - 1] + v[n / 2]) / 2;
}

// Least squares y = slope x + intercept, its R^2, and the slope of y = a x.
struct Fit {
  double slope = NAN, intercept = NAN, r2 = NAN, slope0 = NAN;
  int n = 0;
};
Fit fit(const std::vector<double>& x, const std::vector<double>& y) {
  Fit f;
  size_t n = std::min(x.size(), y.size());
  f.n = int(n);
  if (n < 2) return f;
  double sx = 0, sy = 0, sxx = 0, sxy = 0, syy = 0;
  for (size_t i = 0; i < n; i++) {
    sx += x[i]; sy += y[i]; sxx += x[i] * x[i]; sxy += x[i] * y[i]; syy += y[i] * y[i];
  }
  double d = n * sxx - sx * sx;
  if (d == 0) return f;
  f.slope = (n * sxy - sx * sy) / d;
  f.intercept = (sy - f.slope * sx) / n;
  double ss_tot = syy - sy * sy / n, ss_res = 0;
  for (size_t i = 0; i < n; i++) {
    double e = y[i] - (f.slope * x[i] + f.intercept);
    ss_res += e * e;
  }
  f.r2 = ss_tot > 0 ? 1 - ss_res / ss_tot : 1;
  f.slope0 = sxx > 0 ? sxy / sxx : NAN;
  return f;
}

std::string fmt(double v, int prec = 3) {
  if (!std::isfinite(v)) return "";
  char b[64];
  std::snprintf(b, sizeof b, "%.*g", prec, v);
  return b;
}
std::string fixed(double v, int decimals) {
  if (!std::isfinite(v)) return "–";
  char b[64];
  std::snprintf(b, sizeof b, "%.*f", decimals, v);
  return b;
}
std::string human_ns(double ns) {  // for tables: 850 ns, 12.3 us, 4.56 ms
  if (!std::isfinite(ns)) return "–";
  char b[64];
  if (ns < 1e3) std::snprintf(b, sizeof b, "%.3g ns", ns);
  else if (ns < 1e6) std::snprintf(b, sizeof b, "%.3g µs", ns / 1e3);
  else std::snprintf(b, sizeof b, "%.3g ms", ns / 1e6);
  return b;
}
std::string mp(double median, double p99) {  // "1.2 µs / 1.5 µs"
  return std::isfinite(median) ? human_ns(median) + " / " + human_ns(p99) : "–";
}
std::string ratio(double a, double b) { return std::isfinite(a) && std::isfinite(b) && b > 0 ? fixed(a / b, 1) + "×" : "–"; }

// ------------------------------------------------------------------ CSV

class Csv {
 public:
  explicit Csv(std::vector<std::string> header) : cols_(header.size()) { row(header); }
  void row(const std::vector<std::string>& cells) {
    if (cells.size() != cols_) throw std::logic_error("csv: wrong number of cells");
    for (size_t i = 0; i < cells.size(); i++) {
      const std::string& c = cells[i];
      bool quote = c.find_first_of(",\"\n") != std::string::npos;
      if (i) text_ += ',';
      if (!quote) { text_ += c; continue; }
      text_ += '"';
      for (char ch : c) text_ += ch == '"' ? std::string("\"\"") : std::string(1, ch);
      text_ += '"';
    }
    text_ += '\n';
  }
  const std::string& text() const { return text_; }

 private:
  size_t cols_;
  std::string text_;
};

// ------------------------------------------------------------------ input traces

// A trace as raw byte writes into the memory image, one list per scan.
struct RawTrace {
  struct Write { uint32_t off, len, pos; };
  std::vector<std::vector<Write>> rows;
  std::vector<uint8_t> pool;
  void add(size_t row, uint32_t off, const void* p, uint32_t len) {
    rows[row].push_back({off, len, uint32_t(pool.size())});
    const uint8_t* b = static_cast<const uint8_t*>(p);
    pool.insert(pool.end(), b, b + len);
  }
  void apply(uint8_t* mem, size_t row) const {
    for (const Write& w : rows[row]) std::memcpy(mem + w.off, pool.data() + w.pos, w.len);
  }
  // The same, each write announced to the engine (Engine::written: the
  // change-driven scan compares the inputs it reads itself and runs what
  // reads or writes any other cell written).
  void apply(uint8_t* mem, size_t row, Engine& e) const {
    for (const Write& w : rows[row]) {
      std::memcpy(mem + w.off, pool.data() + w.pos, w.len);
      e.written(w.off, w.len);
    }
  }
  size_t size() const { return rows.size(); }
};

uint64_t splitmix(uint64_t& s) {
  uint64_t z = (s += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

// The synthetic programs' inputs (synth::SynthDevices): X0..X63, WX0..WX15
// (a random walk), F0..F3 in [0.1, 8], F4..F7 in [-8, 8], dt 5..15 ms.  Each
// input changes with probability change_permille / 1000 per scan (an X bit
// flips, a WX word takes a step, an F word is drawn again); the default 20% a
// scan is far livelier than a plant, whose inputs change every few hundred
// scans, so it is the hard case for branch prediction.  Three block copies and
// dt a scan.
RawTrace synth_trace(const Layout& L, int rows, uint64_t seed, int change_permille = 200) {
  using D = synth::SynthDevices;
  RawTrace t;
  t.rows.resize(size_t(rows));
  uint64_t s = seed * 7919 + 17;
  uint8_t x[D::kInX] = {};
  int32_t wx[D::kInWX] = {};
  float f[D::kInF];
  auto draw_f = [&](int i) {
    double u = double(splitmix(s) % 1000000) / 1e6;
    f[i] = i < D::kInFPos ? float(0.1 + 7.9 * u) : float(-8 + 16 * u);
  };
  for (int i = 0; i < D::kInF; i++) draw_f(i);
  auto change = [&] { return int(splitmix(s) % 1000) < change_permille; };
  for (int r = 0; r < rows; r++) {
    for (auto& b : x)
      if (change()) b ^= 1;
    for (auto& w : wx)
      if (change()) w = std::clamp<int32_t>(w + int32_t(splitmix(s) % 101) - 50, -2000, 2000);
    for (int i = 0; i < D::kInF; i++)
      if (change()) draw_f(i);
    int32_t dt = 5 + int32_t(splitmix(s) % 11);
    t.add(size_t(r), L.addr(Area::X, 0), x, sizeof x);
    t.add(size_t(r), L.addr(Area::WX, 0), wx, sizeof wx);
    t.add(size_t(r), L.addr(Area::F, 0), f, sizeof f);
    t.add(size_t(r), kSysDt, &dt, 4);
  }
  return t;
}

// A CSV input trace (docs/format.md section 5) as raw writes, as run_trace
// would write it; dt is written every scan.
RawTrace raw_from_trace(const Trace& tr, const Layout& L, int32_t period) {
  RawTrace t;
  t.rows.resize(std::max<size_t>(1, tr.rows.size()));
  int32_t dt = period;
  for (size_t r = 0; r < tr.rows.size(); r++) {
    const auto& row = tr.rows[r];
    for (size_t i = 0; i < row.size(); i++) {
      const std::string& v = row[i];
      if (v.empty()) continue;
      const Probe& p = tr.columns[i];
      if (int(i) == tr.dt_column) { dt = int32_t(std::strtoll(v.c_str(), nullptr, 0)); continue; }
      if (p.area == Area::F) {
        float f = std::strtof(v.c_str(), nullptr);
        t.add(r, L.addr(Area::F, p.index), &f, 4);
      } else if (area_is_bit(p.area)) {
        uint8_t b = std::strtoll(v.c_str(), nullptr, 0) != 0;
        t.add(r, L.addr(p.area, p.index), &b, 1);
      } else {
        int32_t x = int32_t(std::strtoll(v.c_str(), nullptr, 0));
        t.add(r, L.addr(p.area, p.index), &x, 4);
      }
    }
    t.add(r, kSysDt, &dt, 4);
  }
  if (tr.rows.empty()) t.add(0, kSysDt, &dt, 4);
  return t;
}

// ------------------------------------------------------------------ ELF symbol sizes

// Size of a symbol (st_size) in an ELF64 little-endian file's .symtab or
// .dynsym; if `sym` ends in '*', the sum over every symbol containing the rest
// and `also` (when given).  0 when not found.
size_t elf_symbol_size(const std::string& path, const std::string& sym, const std::string& also = "") {
  std::string data;
  try { data = read_file(path); } catch (...) { return 0; }
  auto u16 = [&](size_t o) -> uint64_t { return o + 2 <= data.size() ? uint8_t(data[o]) | uint8_t(data[o + 1]) << 8 : 0; };
  auto u32 = [&](size_t o) -> uint64_t { return o + 4 <= data.size() ? u16(o) | u16(o + 2) << 16 : 0; };
  auto u64 = [&](size_t o) -> uint64_t { return o + 8 <= data.size() ? u32(o) | u32(o + 4) << 32 : 0; };
  if (data.size() < 64 || data.compare(0, 4, "\x7f" "ELF") != 0 || data[4] != 2 || data[5] != 1) return 0;
  uint64_t shoff = u64(0x28), shentsize = u16(0x3A), shnum = u16(0x3C);
  bool prefix = !sym.empty() && sym.back() == '*';
  std::string want = prefix ? sym.substr(0, sym.size() - 1) : sym;
  size_t total = 0;
  bool found = false;
  for (int pass = 0; pass < 2 && !found; pass++) {  // .symtab (type 2) first, then .dynsym (11)
    uint64_t type_wanted = pass == 0 ? 2 : 11;
    for (uint64_t i = 0; i < shnum; i++) {
      size_t sh = size_t(shoff + i * shentsize);
      if (u32(sh + 4) != type_wanted) continue;
      uint64_t off = u64(sh + 0x18), size = u64(sh + 0x20), link = u32(sh + 0x28), entsize = u64(sh + 0x38);
      size_t strsh = size_t(shoff + link * shentsize);
      uint64_t stroff = u64(strsh + 0x18), strsize = u64(strsh + 0x20);
      if (!entsize || off + size > data.size() || stroff + strsize > data.size()) continue;
      for (uint64_t k = 0; k < size / entsize; k++) {
        size_t e = size_t(off + k * entsize);
        uint64_t name = u32(e);
        if (name >= strsize) continue;
        const char* n = data.c_str() + stroff + name;
        std::string_view nv(n, strnlen(n, size_t(strsize - name)));
        bool match = prefix ? (nv.find(want) != std::string_view::npos && (also.empty() || nv.find(also) != std::string_view::npos))
                            : nv == want;
        if (!match) continue;
        found = true;
        total += size_t(u64(e + 16));
        if (!prefix) return total;
      }
    }
  }
  return total;
}

// ------------------------------------------------------------------ subjects

class NullEngine : public Engine {
 public:
  void scan(ImageBytes&) override {}
};

struct Timing {
  bool ok = false;
  double median = NAN, p99 = NAN;          // per scan, the loop overhead subtracted (ns)
  double raw_median = NAN, raw_p99 = NAN;  // as measured (ns)
  int batch = 0, samples = 0;
};

struct Subject {
  std::string experiment, name;
  Program prog;
  RawTrace trace;
  int n = 0;  // IL instructions
  synth::ClassCounts counts;
  std::unique_ptr<Engine> eng[kEngines];
  std::string status[kEngines];  // "" = usable, else why not
  Timing t[kEngines];
  double overhead_ns = NAN;
  size_t il_bytes = 0, fast_bytes = 0, native_bytes = 0, image_bytes = 0, c_bytes = 0;
  double native_build_s = NAN, c_build_s = NAN;
  size_t native_bytes_at[kLevels] = {};                 // code bytes at -O0, -O1, -O2
  double native_build_at[kLevels] = {NAN, NAN, NAN};  // build_x86 seconds (generate + assemble)
  double c40_cycles = NAN, c40_interp_cycles = NAN;  // simulated cycles per scan (median)
  size_t c40_bytes = 0;
  double c40_cycles_at[kLevels] = {NAN, NAN, NAN};  // C40 native code at -O0, -O1, -O2
  size_t c40_bytes_at[kLevels] = {};
  std::string c40_status;
  double p_target = NAN;  // the synth's p_basic, for grouping
  int n_target = 0;
  std::string klass;  // class programs: the class name; "" otherwise
  bool powered = true;
  int activity = -1;  // the "activity" experiment: inputs changing per scan, per mille
};

void prepare(Subject& s, const Options& o) {
  Layout L = s.prog.layout();
  s.counts = synth::count_classes(s.prog);
  s.n = s.counts.total();
  BinaryIl bin = encode_il(s.prog);
  if (std::string why = validate_il(bin.code, L); !why.empty()) throw std::runtime_error(s.name + ": invalid IL: " + why);
  s.il_bytes = bin.code.size();
  s.eng[kClassic] = make_interp_engine(bin.code, L);
  {
    auto fast = std::make_unique<FastInterpreter>(bin.code, L);
    s.fast_bytes = fast->decoded_bytes();
    s.eng[kFast] = std::move(fast);
  }
  auto t0 = Clock::now();
  const Target& x86 = *find_target("x86-64");
  for (int lvl = 0; lvl < kLevels; lvl++) {
    t0 = Clock::now();
    TargetCode tc;
    try {
      tc = x86.generate(s.prog, s.name, lvl, /*notes=*/false);
    } catch (const CompileError& e) {  // what native code refuses by name (STRING: docs/il.md)
      s.status[kNativeAt[lvl]] = std::string("refused: ") + e.what();
      continue;
    }
    s.native_build_at[lvl] = secs_since(t0);
    s.native_bytes_at[lvl] = tc.assembled.code.size();
    Image img = make_image(x86.image_kind, s.prog, tc.assembled.code, tc.line_offsets);
    if (lvl == 0) s.image_bytes = write_image(img).size();
    s.eng[kNativeAt[lvl]] = find_engine("native").engine->make(img);
  }
  s.native_build_s = s.native_build_at[0];
  s.native_bytes = s.native_bytes_at[0];
  try {
    s.eng[kChange] = make_change_driven_native(s.prog, 2, kChangeRungs);
  } catch (const std::exception& e) {
    s.status[kChange] = std::string("refused: ") + e.what();
  }
  if (!o.c_route) {
    s.status[kC] = "off (--no-c)";
  } else if (s.n > o.c_max_il) {
    s.status[kC] = "skipped (more than --c-max-il " + std::to_string(o.c_max_il) + " instructions)";
  } else {
    std::string dir = make_temp_dir();
    try {
      t0 = Clock::now();
      std::string so = build_c_shared_object(s.prog, dir);
      s.c_build_s = secs_since(t0);
      s.c_bytes = elf_symbol_size(so, kCScanSymbol);
      s.eng[kC] = make_shared_object_engine(so, kCScanSymbol);
    } catch (std::exception& e) {
      s.status[kC] = std::string("failed: ") + e.what();
    }
    remove_tree(dir);  // a loaded shared object stays mapped
  }
}

// ------------------------------------------------------------------ the TMS320C40
//
// Simulated cycles per scan of the C40 native code (the table's "c40" target) and of the
// C40-hosted interpreter running the same IL, on the board of docs/c40.md
// (backend-c40sim: code in zero-wait SRAM, the memory image in SRAM with one
// wait state, 50 ns per cycle on a TMS320C40-40, cache off as in paper 003).
// The simulator is deterministic: the median over a few scans of the trace
// (the first, with S1 set, left out).  REAL arithmetic on the C40 uses its own
// float format, so C40 images are not compared with the classic interpreter's
// here; tests/backend-c40sim/gen holds them to the C40 semantic model.
void measure_c40(Subject& s, const Options& o) {
  if (!o.c40) {
    s.c40_status = "off (--no-c40)";
    return;
  }
  Layout L = s.prog.layout();
  int scans = o.smoke ? 3 : s.n > 30000 ? 5 : 17;
  auto run = [&](Engine& e) {
    Memory m(L);
    std::vector<double> cyc;
    for (int k = 0; k < scans; k++) {
      s.trace.apply(m.data(), size_t(k) % s.trace.size());
      m.set_bit(Area::S, kBitFirstScan, k == 0);
      e.scan(m.bytes);
      if (k > 0) cyc.push_back(double(e.last_cost()->cycles));
    }
    return median(cyc);
  };
  try {
    const Target& c40 = *find_target("c40");
    Image img;
    for (int lvl = 0; lvl < kLevels; lvl++) {
      img = target_image(c40, s.prog, s.name, lvl);
      s.c40_bytes_at[lvl] = img.code.size();
      s.c40_cycles_at[lvl] = run(*find_engine("c40sim").engine->make(img));
    }
    s.c40_bytes = s.c40_bytes_at[0];
    s.c40_cycles = s.c40_cycles_at[0];
    s.c40_interp_cycles = run(*find_engine("c40interp").engine->make(img));  // the image's IL
  } catch (const CompileError& e) {  // what the C40 refuses by name (64-bit types, REAL functions)
    s.c40_status = std::string("refused: ") + e.what();
  } catch (std::exception& e) {
    s.c40_status = std::string("failed: ") + e.what();
  }
}
constexpr double kC40NsPerCycle = 50.0;  // TMS320C40-40

std::string cycles_text(double c) {  // "617 µs (12.3k cyc)"
  if (!std::isfinite(c)) return "–";
  char b[32];
  if (c >= 1e6) std::snprintf(b, sizeof b, "%.3gM", c / 1e6);
  else if (c >= 1e3) std::snprintf(b, sizeof b, "%.3gk", c / 1e3);
  else std::snprintf(b, sizeof b, "%.0f", c);
  return human_ns(c * kC40NsPerCycle) + " (" + b + " cyc)";
}

// Every engine from a zero image over the first scans of the trace, images
// compared with the classic interpreter's after every scan.  An engine that
// differs is not timed.
void check_agreement(Subject& s, int scans) {
  Layout L = s.prog.layout();
  std::vector<Memory> mem;
  for (int e = 0; e < kEngines; e++) {
    mem.emplace_back(L);
  }
  for (int k = 1; k <= scans; k++) {
    for (int e = 0; e < kEngines; e++) {
      if (!s.eng[e] || !s.status[e].empty()) continue;
      if (e == kChange) s.trace.apply(mem[e].data(), size_t(k - 1) % s.trace.size(), *s.eng[e]);
      else s.trace.apply(mem[e].data(), size_t(k - 1) % s.trace.size());
      mem[e].set_bit(Area::S, kBitFirstScan, k == 1);
      s.eng[e]->scan(mem[e].bytes);
      uint32_t n = uint32_t(k);
      std::memcpy(mem[e].data() + kSysScan, &n, 4);
      if (e != kClassic && mem[e].bytes != mem[kClassic].bytes) {
        size_t off = 0;
        while (mem[e].bytes[off] == mem[kClassic].bytes[off]) off++;
        s.status[e] = "DIFFERS from the classic interpreter after scan " + std::to_string(k) + " at byte " +
                      std::to_string(off);
        say("  %s: %s: %s\n", s.name.c_str(), kEngineName[e], s.status[e].c_str());
      }
    }
  }
}

void measure(Subject& s, const Options& o) {
  Layout L = s.prog.layout();
  NullEngine null_engine;
  std::vector<Engine*> engines;
  std::vector<int> which;  // engine kind, or kEngines for the null engine
  for (int e = 0; e < kEngines; e++)
    if (s.eng[e] && s.status[e].empty()) { engines.push_back(s.eng[e].get()); which.push_back(e); }
  engines.push_back(&null_engine);
  which.push_back(kEngines);
  size_t ne = engines.size();
  std::vector<Memory> mem;
  std::vector<size_t> row(ne, 0);
  std::vector<int> batch(ne, 1);
  for (size_t i = 0; i < ne; i++) {
    mem.emplace_back(L);
  }
  auto run = [&](size_t i, int scans) {
    Engine* e = engines[i];
    uint8_t* m = mem[i].data();
    size_t r = row[i], rows = s.trace.size();
    auto t0 = Clock::now();
    if (which[i] == kChange) {
      for (int k = 0; k < scans; k++) {
        s.trace.apply(m, r, *e);
        if (++r == rows) r = 0;
        e->scan(mem[i].bytes);
      }
    } else {
      for (int k = 0; k < scans; k++) {
        s.trace.apply(m, r);
        if (++r == rows) r = 0;
        e->scan(mem[i].bytes);
      }
    }
    auto t1 = Clock::now();
    row[i] = r;
    return double(std::chrono::duration_cast<std::chrono::nanoseconds>(t1 - t0).count());
  };
  // The first scan, S1 set, as a PLC's: it writes the programs' initial values
  // (docs/iec-il.md), without which a typed program's loops would run over zeros.
  for (size_t i = 0; i < ne; i++) {
    mem[i].set_bit(Area::S, kBitFirstScan, true);
    s.trace.apply(mem[i].data(), 0);
    row[i] = 1 % s.trace.size();
    engines[i]->scan(mem[i].bytes);
    mem[i].set_bit(Area::S, kBitFirstScan, false);
  }
  // Warm-up and batch size: double the scans until a chunk takes >= 2 ms.
  const double target_ns = o.batch_us * 1e3, warm_ns = o.smoke ? 2e5 : 2e6;
  for (size_t i = 0; i < ne; i++) {
    int k = 1;
    double ns = run(i, k);
    while (ns < warm_ns && k < (1 << 24)) {
      k *= 2;
      ns = run(i, k);
    }
    double per = ns / k;
    batch[i] = int(std::clamp(std::ceil(target_ns / std::max(per, 0.01)), 1.0, double(1 << 22)));
  }
  std::vector<std::vector<double>> samples(ne);
  for (int round = 0; round < o.samples; round++) {
    for (size_t j = 0; j < ne; j++) {
      size_t i = (j + size_t(round)) % ne;
      samples[i].push_back(run(i, batch[i]) / batch[i]);
    }
  }
  s.overhead_ns = median(samples[ne - 1]);
  for (size_t i = 0; i + 1 < ne; i++) {
    Timing& t = s.t[which[i]];
    t.ok = true;
    t.batch = batch[i];
    t.samples = int(samples[i].size());
    t.raw_median = median(samples[i]);
    t.raw_p99 = quantile(samples[i], 0.99);
    t.median = std::max(0.0, t.raw_median - s.overhead_ns);
    t.p99 = std::max(0.0, t.raw_p99 - s.overhead_ns);
  }
}

// The progress line's time of an engine: "-" when it was not timed (skipped
// or refused); when the scan took no longer than the timing loop's own
// overhead, which is subtracted, that is said (a median of 0 would read as free).
std::string progress_ns(const Timing& t) {
  if (!t.ok || !std::isfinite(t.median)) return "-";
  if (t.median <= 0) return "~0 (within the loop overhead)";
  return human_ns(t.median);
}
// Simulated cycles, or "-" when the C40 was not run (--no-c40, or refused).
std::string progress_cycles(double c) {
  if (!std::isfinite(c)) return "-";
  char b[32];
  std::snprintf(b, sizeof b, "%.0f", c);
  return b;
}

// ------------------------------------------------------------------ the run

struct Run {
  Options o;
  std::vector<std::unique_ptr<Subject>> subjects;
  std::string tables;  // tables.md
  Clock::time_point start = Clock::now();
  Csv timings{{"experiment", "program", "n_exe", "p_basic", "engine", "median_ns", "p99_ns", "raw_median_ns",
               "raw_p99_ns", "overhead_ns", "ns_per_il", "batch", "samples", "status"}};

  Subject& add(std::unique_ptr<Subject> s, int agree_scans = 64) {
    auto t0 = Clock::now();
    prepare(*s, o);
    say("  %-24s %7d IL  built %5.1fs", s->name.c_str(), s->n, secs_since(t0));
    check_agreement(*s, o.smoke ? 8 : agree_scans);
    measure(*s, o);
    auto tc = Clock::now();
    measure_c40(*s, o);
    double c40_s = secs_since(tc);
    auto t = [&](int e) { return progress_ns(s->t[e]); };
    say("  timed %.1fs: classic %s, fast %s, native %s / %s / %s / cd %s, C %s; C40 %s / %s cycles (%.1fs)\n", secs_since(t0),
        t(kClassic).c_str(), t(kFast).c_str(), t(kNative).c_str(), t(kNativeO1).c_str(), t(kNativeO2).c_str(),
        t(kChange).c_str(), t(kC).c_str(), progress_cycles(s->c40_interp_cycles).c_str(), progress_cycles(s->c40_cycles).c_str(), c40_s);
    if (!s->c40_status.empty() && o.c40) say("  C40: %s\n", s->c40_status.c_str());
    for (int e = 0; e < kEngines; e++) {
      const Timing& t = s->t[e];
      timings.row({s->experiment, s->name, std::to_string(s->n), fmt(s->counts.p_basic(), 4), kEngineName[e],
                   fmt(t.median, 6), fmt(t.p99, 6), fmt(t.raw_median, 6), fmt(t.raw_p99, 6), fmt(s->overhead_ns, 4),
                   fmt(t.median / s->n, 4), std::to_string(t.batch), std::to_string(t.samples),
                   t.ok ? "ok" : s->status[e]});
    }
    // the simulated C40: time = cycles x 50 ns
    const char* c40_names[2] = {"c40", "c40interp"};
    double c40_cyc[2] = {s->c40_cycles, s->c40_interp_cycles};
    for (int k = 0; k < 2; k++)
      timings.row({s->experiment, s->name, std::to_string(s->n), fmt(s->counts.p_basic(), 4), c40_names[k],
                   fmt(c40_cyc[k] * kC40NsPerCycle, 6), "", "", "", "", fmt(c40_cyc[k] * kC40NsPerCycle / s->n, 4), "", "",
                   std::isfinite(c40_cyc[k]) ? "simulated: " + fmt(c40_cyc[k], 10) + " cycles x 50 ns"
                                             : (s->c40_status.empty() ? "not measured" : s->c40_status)});
    // the engines (the C route's shared object, native code) are not needed any more
    for (auto& e : s->eng) e.reset();
    subjects.push_back(std::move(s));
    return *subjects.back();
  }
  std::vector<Subject*> of(const std::string& experiment) {
    std::vector<Subject*> v;
    for (auto& s : subjects)
      if (s->experiment == experiment) v.push_back(s.get());
    return v;
  }
  void write(const std::string& name, const std::string& text) {
    write_file_atomic(o.out + "/" + name, text);
  }
};

std::unique_ptr<Subject> synth_subject(const std::string& experiment, int n, double p, uint64_t seed) {
  auto s = std::make_unique<Subject>();
  s->experiment = experiment;
  char name[64];
  std::snprintf(name, sizeof name, "synth n=%d p=%.3g", n, p);
  s->name = name;
  synth::SynthOptions so;
  so.n_exe = n;
  so.p_basic = p;
  so.seed = seed;
  s->prog = parse_il_text(synth::synth_il(so), s->name);
  s->trace = synth_trace(s->prog.layout(), 1024, seed);
  s->p_target = p;
  s->n_target = n;
  return s;
}

// ------------------------------------------------------------------ experiments

const OpClass kClasses[] = {OpClass::Basic, OpClass::Compare, OpClass::Move, OpClass::Arith,
                            OpClass::Logic, OpClass::Special, OpClass::Timer, OpClass::Counter};

void run_examples(Run& R) {
  std::string dir = R.o.source_dir + "/examples";
  std::vector<std::string> names;
  if (DIR* d = opendir(dir.c_str())) {
    while (dirent* e = readdir(d)) {
      std::string n = e->d_name;
      if (n.size() > 3 && n.compare(n.size() - 3, 3, ".ld") == 0) names.push_back(n.substr(0, n.size() - 3));
    }
    closedir(d);
  }
  std::sort(names.begin(), names.end());
  if (R.o.smoke && names.size() > 2) names.resize(2);
  say("examples (%zu) from %s\n", names.size(), dir.c_str());
  for (const std::string& n : names) {
    auto s = std::make_unique<Subject>();
    s->experiment = "examples";
    s->name = n;
    s->prog = compile_source(dir + "/" + n + ".ld").il;
    std::string csv = dir + "/" + n + ".csv";
    struct stat st;
    if (stat(csv.c_str(), &st) == 0) {
      Trace tr = read_trace(read_file(csv), csv, s->prog.aliases);
      s->trace = raw_from_trace(tr, s->prog.layout(), 10);
    } else {
      s->trace = synth_trace(s->prog.layout(), 256, 1);
    }
    R.add(std::move(s));
  }
}

// `ldbench FILE...`: each program (any source ldc reads) on every engine, with
// the trace FILE.csv beside it if there is one, else random inputs.
void run_files(Run& R) {
  say("programs from the command line (%zu)\n", R.o.files.size());
  for (const std::string& f : R.o.files) {
    auto s = std::make_unique<Subject>();
    s->experiment = "files";
    s->name = f;
    s->prog = compile_source(f).il;
    size_t dot = f.rfind('.');
    std::string csv = (dot == std::string::npos ? f : f.substr(0, dot)) + ".csv";
    struct stat st;
    if (stat(csv.c_str(), &st) == 0) {
      Trace tr = read_trace(read_file(csv), csv, s->prog.aliases);
      s->trace = raw_from_trace(tr, s->prog.layout(), 10);
    } else {
      s->trace = synth_trace(s->prog.layout(), 256, 1);
    }
    R.add(std::move(s));
  }
}

void run_classes(Run& R) {
  int n = R.o.smoke ? 60 : 3000;
  say("one-class programs (%d instructions each)\n", n);
  for (OpClass c : kClasses) {
    for (bool powered : {true, false}) {
      if (!powered && (c == OpClass::Basic || c == OpClass::Compare)) continue;  // no power to switch off
      auto s = std::make_unique<Subject>();
      s->experiment = "classes";
      s->klass = op_class_name(c);
      s->powered = powered;
      s->name = std::string("class ") + op_class_name(c) + (powered ? "" : " (off)");
      s->prog = parse_il_text(synth::synth_class_il(c, n, 11, powered), s->name);
      s->trace = synth_trace(s->prog.layout(), 1024, 3);
      R.add(std::move(s));
    }
  }
}

std::vector<double> fig10_p() { return {0.5, 0.6, 0.689, 0.8, 0.9, 0.95}; }

void run_fig10(Run& R) {
  std::vector<int> ns;
  for (int n = 300; n <= 3000; n += 300) ns.push_back(n);
  std::vector<double> ps = fig10_p();
  if (R.o.smoke) { ns = {30, 60}; ps = {0.5, 0.689}; }
  say("time vs N_exe and P_basic (%zu x %zu programs)\n", ns.size(), ps.size());
  bool c = R.o.c_route;
  for (double p : ps)
    for (int n : ns) {
      if (R.o.smoke) R.o.c_route = c && n == ns[0] && p == ps[0];  // one C build in the smoke run
      R.add(synth_subject("fig10", n, p, uint64_t(n * 1000 + int(p * 1000))));
    }
  R.o.c_route = c;
}

void run_scaling(Run& R) {
  std::vector<int> ns = {300, 1000, 3000, 10000, 30000, 100000};
  if (R.o.smoke) ns = {100, 300};
  say("scaling, typical mix (p_basic %.3f)\n", synth::kTypicalPBasic);
  bool c = R.o.c_route;
  if (R.o.smoke) R.o.c_route = false;
  for (int n : ns) R.add(synth_subject("scaling", n, synth::kTypicalPBasic, uint64_t(n) + 77));
  // issue 28: the same programs from 3,000 instructions on, inputs 2% a scan
  for (int n : ns) {
    if (n <= (R.o.smoke ? 300 : 3000)) continue;  // 3,000's row is below
    auto s = synth_subject("inputs", n, synth::kTypicalPBasic, uint64_t(n) + 77);
    s->name += " (inputs 2% a scan)";
    s->trace = synth_trace(s->prog.layout(), 1024, uint64_t(n) + 77, 20);
    R.add(std::move(s));
  }
  // The same program as the scaling one of 3000 instructions, its inputs
  // changing 10 times less often, and never: data-dependent branches become
  // predictable.
  int n = R.o.smoke ? 300 : 3000;
  auto slow = synth_subject("inputs", n, synth::kTypicalPBasic, uint64_t(n) + 77);
  slow->name += " (inputs 2% a scan)";
  slow->trace = synth_trace(slow->prog.layout(), 1024, uint64_t(n) + 77, 20);
  R.add(std::move(slow));
  auto s = synth_subject("inputs", n, synth::kTypicalPBasic, uint64_t(n) + 77);
  s->name += " (inputs constant)";
  s->trace.rows.resize(1);
  R.add(std::move(s));
  R.o.c_route = c;
}

// The plant of `rungs` rungs as IL.  The .ld reader refuses more than
// kMaxRungs (65,536) rungs, so a larger plant is cut into pieces at rung
// boundaries (its rungs share no labels), each read and lowered, and the
// pieces joined with their edge slots renumbered.
Program plant_program(int rungs) {
  std::string text = synth::synth_plant_ld(rungs, 1);
  const int piece = 50000;
  if (rungs <= piece) return lower_to_il(parse_ld(text, "plant.ld"));
  Program all;
  all.source = "plant.ld";
  size_t pos = text.find("rung \"");
  while (pos != std::string::npos) {
    size_t end = pos;
    for (int k = 0; k < piece && end != std::string::npos; k++) end = text.find("\nrung \"", end + 1);
    std::string part = text.substr(pos, end == std::string::npos ? std::string::npos : end + 1 - pos);
    Program p = lower_to_il(parse_ld(part, "plant.ld"));
    append_rungs(all, p);
    pos = end == std::string::npos ? end : end + 1;
  }
  return all;
}

// Issue 25: typed programs (INT, DINT, LREAL arithmetic, arrays through IDX
// and LDX / STX, function block instances expanded inline), on every engine.
void run_typed(Run& R) {
  say("typed programs\n");
  for (int k : R.o.smoke ? std::vector<int>{4} : std::vector<int>{20, 200}) {
    auto s = std::make_unique<Subject>();
    s->experiment = "typed";
    s->name = "typed, " + std::to_string(k) + " FB instances";
    s->prog = parse_il_text(synth::synth_typed_il(k), "typed.il");
    s->trace = synth_trace(s->prog.layout(), 1024, uint64_t(k) + 25);
    R.add(std::move(s));
  }
}

// Issue 28: scan time against the share of inputs changing each scan, on the
// plant: the full scan, the change-driven scan and the fast interpreter.
void run_activity(Run& R) {
  const int rungs = R.o.smoke ? 40 : 20000;
  say("scan time against input activity\n");
  const Program prog = lower_to_il(parse_ld(synth::synth_plant_ld(rungs, 1), "plant.ld"));
  bool c = R.o.c_route;
  R.o.c_route = false;  // the C route is the levels table's
  for (int pm : {0, 10, 20, 50, 100, 200, 500, 1000}) {
    auto s = std::make_unique<Subject>();
    s->experiment = "activity";
    s->name = "plant " + std::to_string(rungs) + " rungs (inputs " + fixed(pm / 10.0, 0) + "% a scan)";
    s->prog = prog;
    s->trace = synth_trace(s->prog.layout(), 1024, 5, pm);
    s->activity = pm;
    R.add(std::move(s), 16);
  }
  R.o.c_route = c;
}

void run_large(Run& R) {
  int plant = R.o.smoke ? 40 : 20000, gen = R.o.smoke ? 20 : 2000;
  say("large programs\n");
  bool c = R.o.c_route;
  if (R.o.smoke) R.o.c_route = false;
  {
    auto s = std::make_unique<Subject>();
    s->experiment = "large";
    s->name = "plant " + std::to_string(plant) + " rungs";
    std::string text = synth::synth_plant_ld(plant, 1);
    s->prog = lower_to_il(parse_ld(text, "plant.ld"));
    s->trace = synth_trace(s->prog.layout(), 1024, 5);
    // The same rungs in a random order (seeded): the groups of a plant no
    // longer repeat in the code, so neighbouring branches and stores do not
    // either (what a real program's layout looks like to the predictors).
    auto sh = std::make_unique<Subject>();
    sh->experiment = "large";
    sh->name = s->name + " (shuffled)";
    sh->prog = s->prog;
    Rng rng(12345);
    for (size_t i = sh->prog.rungs.size(); i > 1; i--) std::swap(sh->prog.rungs[i - 1], sh->prog.rungs[size_t(rng.below(int(i)))]);
    sh->trace = s->trace;
    // the same plant with its inputs changing 10 times less often (issue 28)
    auto slow = std::make_unique<Subject>();
    slow->experiment = "large";
    slow->name = s->name + " (inputs 2% a scan)";
    slow->prog = s->prog;
    slow->trace = synth_trace(slow->prog.layout(), 1024, 5, 20);
    R.add(std::move(s), 16);
    R.add(std::move(sh), 16);
    R.add(std::move(slow), 16);
  }
  {
    auto s = std::make_unique<Subject>();
    s->experiment = "large";
    s->name = "ldgen " + std::to_string(gen) + " rungs";
    GenOptions go;
    go.rungs = gen;
    go.classes &= ~uint32_t(kGenEnd);  // an END would cut the scan short
    s->prog = lower_to_il(parse_ld(generate_ld(7, go), "ldgen.ld"));
    Trace tr = read_trace(generate_trace(7, 512, go), "ldgen.csv", s->prog.aliases);
    s->trace = raw_from_trace(tr, s->prog.layout(), 10);
    R.add(std::move(s), 16);
  }
  R.o.c_route = c;
}

// ---- compile speed: ldc's own pipeline, phase by phase

// CPU time of each phase (CLOCK_PROCESS_CPUTIME_ID: page faults included, time
// lost to other processes on a busy machine not), and the wall time of all.
struct Phases {
  double parse = 0, lower = 0, generate = 0, assemble = 0, image = 0, wall = 0;
  size_t il = 0, rungs = 0, code = 0, image_bytes = 0;
  double total() const { return parse + lower + generate + assemble + image; }
};

Phases compile_once(const std::string& text, bool is_ld, int opt = 0) {
  Phases ph;
  auto cpu_now = [] {
    timespec ts{};
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return double(ts.tv_sec) + ts.tv_nsec * 1e-9;
  };
  auto wall0 = Clock::now();
  double t = cpu_now();
  auto lap = [&] {
    double now = cpu_now(), d = now - t;
    t = now;
    return d;
  };
  Program p;
  if (is_ld) {
    TreeProgram tp = parse_ld(text, "bench.ld");
    ph.parse = lap();
    p = lower_to_il(tp);
    ph.lower = lap();
  } else {
    p = parse_il_text(text, "bench.il");
    ph.parse = lap();
  }
  // As ldc builds an image (build_x86 without notes): every block is assembled as
  // soon as it is generated.  The assembler's share is timed around each block with
  // the steady clock (the process CPU clock is a system call, too slow to read
  // 40,000 times); the generator gets the rest of the CPU time of the two.
  NativeBuild nb;
  double asm_s = 0;
  {
    nb.gen.program.globals = x86_globals(p);
    using Asm = as::Assembler<as::x86::Instruction>;
    Asm a(as::x86::target(), nb.gen.program.globals, Asm::Items::LastOnly);
    std::vector<std::vector<uint32_t>> il_items;
    size_t blocks = 0;
    generate_x86_blocks(p, p.layout(), opt, false, [&](as::Block<as::x86::Instruction>& b) {
      auto t0 = Clock::now();
      a.add(b);
      if (!il_items.empty() && X86Code::rung_block(il_items.size() - 1) == blocks) {  // as build_x86
        append_line_offsets(nb.line_offsets, a.last_items(), a.code_size(), il_items.back());
        il_items.back().clear();  // read: the generator reuses its storage
      }
      blocks++;
      asm_s += secs_since(t0);
    }, il_items);
    auto t0 = Clock::now();
    nb.asm_result = a.finish();
    asm_s += secs_since(t0);
  }
  double both = lap();
  ph.assemble = std::min(asm_s, both);
  ph.generate = both - ph.assemble;
  if (!nb.asm_result.ok()) throw std::runtime_error("assembly failed: " + nb.asm_result.errors[0].message);
  std::vector<uint8_t> img = write_image(make_x86_image(p, nb));
  ph.image = lap();
  ph.wall = secs_since(wall0);
  for (const Rung& r : p.rungs) ph.il += r.code.size();
  ph.rungs = p.rungs.size();
  ph.code = nb.asm_result.code.size();
  ph.image_bytes = img.size();
  return ph;
}

struct CompileRow {
  std::string source;
  int opt = 0;          // -O level
  bool levels = false;  // one of the per-level rows (not in the size fit)
  Phases ph;  // the median of the repeats, phase by phase
  int repeats = 0;
};

std::vector<CompileRow> run_compile(Run& R) {
  std::vector<CompileRow> rows;
  std::vector<int> plant = {1000, 3000, 10000, 30000, 60000}, il = {3000, 30000, 100000, 300000};
  int big_plant = 100000;  // more than the .ld reader takes: compiled from its IL text
  if (R.o.smoke) { plant = {20, 60}; il = {60}; big_plant = 100; }
  int repeats = R.o.smoke ? 1 : 3;
  say("compile speed\n");
  auto one = [&](const std::string& source, const std::string& text, bool is_ld, int opt = 0, bool levels = false) {
    std::vector<Phases> v;
    for (int k = 0; k < repeats; k++) v.push_back(compile_once(text, is_ld, opt));
    CompileRow row;
    row.source = source;
    row.opt = opt;
    row.levels = levels;
    row.repeats = repeats;
    row.ph = v[0];
    auto med = [&](double Phases::*m) {
      std::vector<double> x;
      for (auto& p : v) x.push_back(p.*m);
      return median(x);
    };
    row.ph.parse = med(&Phases::parse);
    row.ph.lower = med(&Phases::lower);
    row.ph.generate = med(&Phases::generate);
    row.ph.assemble = med(&Phases::assemble);
    row.ph.image = med(&Phases::image);
    row.ph.wall = med(&Phases::wall);
    say("  %-26s -O%d %8zu IL  %.3f s CPU, %.3f s wall  (%.2f M IL/s)\n", source.c_str(), opt, row.ph.il,
        row.ph.total(), row.ph.wall, row.ph.il / row.ph.total() / 1e6);
    rows.push_back(row);
  };
  for (int n : plant) one("plant .ld " + std::to_string(n) + " rungs", synth::synth_plant_ld(n, 1), true);
  one("plant .il " + std::to_string(big_plant) + " rungs", print_il_text(plant_program(big_plant)), false);
  for (int n : il) {
    synth::SynthOptions so;
    so.n_exe = n;
    so.seed = 5;
    one("synth .il n=" + std::to_string(n), synth::synth_il(so), false);
  }
  // The cost of each optimization level (issue 8): the 20,000-rung plant and
  // the typical mix of 30,000 instructions at -O1 and -O2.
  {
    int pr = R.o.smoke ? 40 : 20000, sn = R.o.smoke ? 60 : 30000;
    std::string ptext = synth::synth_plant_ld(pr, 1);
    synth::SynthOptions so;
    so.n_exe = sn;
    so.seed = 5;
    std::string stext = synth::synth_il(so);
    for (int opt = 0; opt < kLevels; opt++) {
      one("plant .ld " + std::to_string(pr) + " rungs", ptext, true, opt, true);
      one("synth .il n=" + std::to_string(sn), stext, false, opt, true);
    }
  }
  return rows;
}

// ---- peak memory of a compile, in a child process

// VmRSS and VmHWM of this process (KiB), from /proc/self/status.  (getrusage's
// ru_maxrss is no use in a child made by posix_spawn: Linux carries the
// parent's high-water mark across the exec.)
std::pair<long, long> rss_hwm_kb() {
  long rss = 0, hwm = 0;
  std::ifstream st("/proc/self/status");
  for (std::string l; std::getline(st, l);) {
    if (l.rfind("VmRSS:", 0) == 0) rss = std::atol(l.c_str() + 6);
    if (l.rfind("VmHWM:", 0) == 0) hwm = std::atol(l.c_str() + 6);
  }
  return {rss, hwm};
}

// `ldbench --compile-child FILE`: compiles FILE (.ld or .il) through every phase, as
// the ldc driver does for an image (a .ld lowered rung by rung as it is read,
// parse_ld_to_il; the IL, the code and the image alive at the end, the image
// written to FILE.bin), and prints "rss_before_kb hwm_parse hwm_lower hwm_generate
// hwm_assemble hwm_image il code_bytes image_bytes seconds".
int compile_child(const std::string& file) {
  std::string text = read_file(file);
  long before = rss_hwm_kb().first;
  long hwm[5];
  auto t0 = Clock::now();
  bool il_text = file.size() > 3 && file.compare(file.size() - 3, 3, ".il") == 0;
  // as ldc does for an image: a .ld is lowered rung by rung as it is read, so
  // parse and lower share one high-water mark
  Program p = il_text ? parse_il_text(text, file) : parse_ld_to_il(text, file);
  hwm[0] = hwm[1] = rss_hwm_kb().second;
  // as ldc does (no listing notes): generation and assembly interleave, block by
  // block, so they share one high-water mark
  NativeBuild nb = build_x86(p, file, as::Mode::Blockwise, 0, false);
  hwm[2] = hwm[3] = rss_hwm_kb().second;
  size_t code_bytes = nb.asm_result.code.size();
  // as ldc does (target_image): the image takes the code over, the rest of the build is dropped
  Image im = make_image(ImageTarget::X86_64, p, std::move(nb.asm_result.code), nb.line_offsets);
  nb = {};
  size_t image_bytes = 0;  // as ldc does: written straight into the file (FILE.bin, beside the source)
  write_file_atomic(file + ".bin", [&](std::FILE* f) { return (image_bytes = write_image_file(im, f)) != 0; });
  hwm[4] = rss_hwm_kb().second;
  double s = secs_since(t0);
  size_t il = 0;
  for (const Rung& r : p.rungs) il += r.code.size();
  std::printf("%ld %ld %ld %ld %ld %ld %zu %zu %zu %.3f\n", before, hwm[0], hwm[1], hwm[2], hwm[3], hwm[4], il,
              code_bytes, image_bytes, s);
  return 0;
}

struct MemRow {
  int rungs = 0;
  std::string source;  // ".ld" or ".il"
  long before_kb = 0, hwm_kb[5] = {};
  size_t il = 0, code = 0, image = 0, source_bytes = 0;
  double seconds = NAN;
  std::string error;
  long peak_kb() const { return hwm_kb[4]; }
};

MemRow run_memory_one(int rungs, bool il_text) {
  MemRow m;
  m.rungs = rungs;
  m.source = il_text ? ".il" : ".ld";
  std::string dir = make_temp_dir(), ld = dir + "/plant" + m.source, out = dir + "/out.txt";
  std::string text = il_text ? print_il_text(plant_program(rungs)) : synth::synth_plant_ld(rungs, 1);
  m.source_bytes = text.size();
  write_file_atomic(ld, text);
  std::string self = "/proc/self/exe";
  std::vector<std::string> args = {"ldbench", "--compile-child", ld};
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 1, out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  pid_t pid;
  int rc = posix_spawn(&pid, self.c_str(), &fa, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&fa);
  if (rc != 0) {
    m.error = std::string("cannot run ") + self + ": " + std::strerror(rc);
  } else {
    int status = 0;
    while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {}
    std::istringstream in(read_file(out));
    in >> m.before_kb;
    for (long& h : m.hwm_kb) in >> h;
    in >> m.il >> m.code >> m.image >> m.seconds;
    if (!(WIFEXITED(status) && WEXITSTATUS(status) == 0) || !in) m.error = "the child failed";
  }
  remove_tree(dir);
  return m;
}

// ------------------------------------------------------------------ machine

std::string first_line_of(const std::string& cmd) {
  FILE* p = popen(cmd.c_str(), "r");
  if (!p) return "";
  char b[512] = {};
  if (!std::fgets(b, sizeof b, p)) b[0] = 0;
  pclose(p);
  std::string s = b;
  while (!s.empty() && (s.back() == '\n' || s.back() == '\r')) s.pop_back();
  return s;
}

// Where sysfs has no cache directory (some virtual machines): the sizes the C
// library reads from CPUID (sysconf's _SC_LEVEL*, a glibc extension), said so,
// or "unknown".
std::string cache_sizes_cpuid() {
  std::string out;
#if defined(_SC_LEVEL1_DCACHE_SIZE) && defined(_SC_LEVEL1_ICACHE_SIZE) && defined(_SC_LEVEL2_CACHE_SIZE) && \
    defined(_SC_LEVEL3_CACHE_SIZE)
  const std::pair<const char*, int> levels[] = {{"L1d", _SC_LEVEL1_DCACHE_SIZE},
                                                {"L1i", _SC_LEVEL1_ICACHE_SIZE},
                                                {"L2", _SC_LEVEL2_CACHE_SIZE},
                                                {"L3", _SC_LEVEL3_CACHE_SIZE}};
  for (const auto& [name, key] : levels) {
    const long b = sysconf(key);
    if (b > 0) out += (out.empty() ? "" : ", ") + std::string(name) + " " + std::to_string(b / 1024) + "K";
  }
#endif
  return out.empty() ? "unknown" : out + " (CPUID, as the C library reads it: no sysfs cache directory)";
}

// CPU 0's caches from sysfs, as "L1d 48K, L1i 64K, L2 2048K, L3 ..." (the
// sizes that decide when code falls out of a cache, issue 28), else from CPUID.
std::string cache_sizes() {
  std::string out;
  for (int i = 0; i < 8; i++) {
    const std::string dir = "/sys/devices/system/cpu/cpu0/cache/index" + std::to_string(i) + "/";
    std::ifstream lv(dir + "level"), ty(dir + "type"), sz(dir + "size");
    std::string level, type, size;
    if (!std::getline(lv, level) || !std::getline(ty, type) || !std::getline(sz, size)) break;
    const char* kind = type == "Data" ? "d" : type == "Instruction" ? "i" : "";
    out += (out.empty() ? "" : ", ") + std::string("L") + level + kind + " " + size;
  }
  return out.empty() ? cache_sizes_cpuid() : out;
}

std::map<std::string, std::string> machine_info() {
  std::map<std::string, std::string> m;
  std::ifstream cpu("/proc/cpuinfo");
  int procs = 0;
  for (std::string l; std::getline(cpu, l);) {
    if (l.rfind("processor", 0) == 0) procs++;
    if (l.rfind("model name", 0) == 0 && !m.count("cpu")) m["cpu"] = l.substr(l.find(':') + 2);
    if (l.rfind("cpu MHz", 0) == 0 && !m.count("cpu_mhz")) m["cpu_mhz"] = l.substr(l.find(':') + 2);
    if (l.rfind("cache size", 0) == 0 && !m.count("cache")) m["cache"] = l.substr(l.find(':') + 2);
  }
  m["logical_cpus"] = std::to_string(procs);
  m["caches"] = cache_sizes();
  m["online_cpus"] = std::to_string(sysconf(_SC_NPROCESSORS_ONLN));
  utsname u{};
  if (uname(&u) == 0) m["kernel"] = std::string(u.sysname) + " " + u.release + " " + u.machine;
  m["compiler"] = std::string("g++/clang ") + __VERSION__;
  m["build_type"] = LDC_BUILD_TYPE;
  m["cc"] = first_line_of("${CC:-cc} --version 2>/dev/null");
  std::ifstream la("/proc/loadavg");
  std::string l;
  std::getline(la, l);
  m["loadavg_start"] = l;
  std::time_t now = std::time(nullptr);
  char b[64];
  std::strftime(b, sizeof b, "%Y-%m-%d %H:%M:%S UTC", std::gmtime(&now));
  m["date"] = b;
  return m;
}

// ------------------------------------------------------------------ reports

std::string md_row(const std::vector<std::string>& cells) {
  std::string s = "|";
  for (auto& c : cells) s += " " + c + " |";
  return s + "\n";
}
std::string md_head(const std::vector<std::string>& cells) {
  std::string s = md_row(cells) + "|";
  for (size_t i = 0; i < cells.size(); i++) s += i ? "---:|" : "---|";
  return s + "\n";
}

// Per-instruction time of a class program (ns), for engine e.
double class_ns(Run& R, const std::string& klass, bool powered, int e) {
  for (Subject* s : R.of("classes"))
    if (s->klass == klass && s->powered == powered) return s->t[e].median / s->n;
  return NAN;
}

// The report in named steps: each writes its CSV files and plots and appends
// its section to the tables (R.tables); run() puts them in order.
struct Report {
  Run& R;
  const std::vector<CompileRow>& compile;
  const std::vector<MemRow>& memrows;
  const std::map<std::string, std::string>& machine;
  const Options& o = R.o;
  std::string& md = R.tables;
  std::string note = info("cpu") + ", " + info("date");

  std::string info(const char* k) const {
    auto it = machine.find(k);
    return it == machine.end() ? std::string("?") : it->second;
  }
  static std::string cell(const Timing& t) { return t.ok ? mp(t.median, t.p99) : std::string("–"); }
  std::vector<Subject*> headline_subjects() const {
    std::vector<Subject*> head;
    for (const char* e : {"scaling", "inputs", "repeat", "large", "typed"})
      for (Subject* s : R.of(e)) head.push_back(s);
    return head;
  }

  void run() {
    R.write("timings.csv", R.timings.text());
    targets();
    headline();
    levels();
    scaling();
    activity();
    classes();
    fig10();
    code_size();
    examples();
    compile_speed();
    memory();
    machine_csv();
    this_run();
    put_in_doc();
  }

  // the targets of the issues, where this run stands
  void targets() {
    Subject* mix = nullptr;  // the headline program: the typical mix of 3,000 instructions
    Subject* plant = nullptr;
    for (Subject* s : R.of("scaling"))
      if (s->n_target == (o.smoke ? 300 : 3000)) mix = s;
    for (Subject* s : R.of("large"))
      if (!plant && s->name.rfind("plant", 0) == 0) plant = s;
    auto range = [&](int num, int den) {  // "min–max" of t[num]/t[den] over the scaling programs
      double lo = INFINITY, hi = -INFINITY;
      for (Subject* s : R.of("scaling")) {
        double r = s->t[num].median / s->t[den].median;
        if (std::isfinite(r)) lo = std::min(lo, r), hi = std::max(hi, r);
      }
      return std::isfinite(lo) ? fixed(lo, 1) + "–" + fixed(hi, 1) + "×" : std::string("–");
    };
    auto verdict = [](double measured, double goal, bool at_least) {
      if (!std::isfinite(measured)) return std::string("not measured");
      bool met = at_least ? measured >= goal : measured <= goal;
      return met ? std::string("met") : "missed by " + fixed(at_least ? goal / measured : measured / goal, 1) + "×";
    };
    auto bytes_fit = [&](int lvl) {
      std::vector<double> x, y;
      for (Subject* s : R.of("scaling")) x.push_back(s->n), y.push_back(double(s->native_bytes_at[lvl]));
      return fit(x, y).slope;
    };
    md += "## Where this run stands against the targets\n\n";
    md += md_head({"target", "goal", "measured (-O0)", "measured (-O2)", "verdict (-O0 · -O2)", "over all typical-mix sizes (-O0 · -O2)"});
    auto row = [&](const std::string& what, const std::string& goal, double m0, double m2, double g, bool at_least,
                   int decimals, const std::string& unit, const std::string& spread) {
      auto num = [&](double v) { return std::isfinite(v) ? fixed(v, decimals) + unit : std::string("–"); };
      md += md_row({what, goal, num(m0), num(m2),
                    verdict(m0, g, at_least) + " · " + verdict(m2, g, at_least), spread});
    };
    if (mix) {
      const Timing* t = mix->t;
      row("native vs the fast interpreter, typical mix", "≥ 20×", t[kFast].median / t[kNative].median,
          t[kFast].median / t[kNativeO2].median, 20, true, 1, "×",
          range(kFast, kNative) + " · " + range(kFast, kNativeO2));
      row("native vs the classic interpreter, typical mix", "≥ 50×", t[kClassic].median / t[kNative].median,
          t[kClassic].median / t[kNativeO2].median, 50, true, 1, "×",
          range(kClassic, kNative) + " · " + range(kClassic, kNativeO2));
      row("native no slower than the C route (C time / native time)", "≥ 1.0×", t[kC].median / t[kNative].median,
          t[kC].median / t[kNativeO2].median, 1, true, 2, "×", range(kC, kNative) + " · " + range(kC, kNativeO2));
    }
    if (plant)
      row("the same on the " + plant->name, "≥ 1.0×", plant->t[kC].median / plant->t[kNative].median,
          plant->t[kC].median / plant->t[kNativeO2].median, 1, true, 2, "×", "");
    double b0 = class_ns(R, op_class_name(OpClass::Basic), true, kNative);
    double b2 = class_ns(R, op_class_name(OpClass::Basic), true, kNativeO2);
    row("ns per basic IL instruction (issue 5)", "≤ 1 ns", b0, b2, 1, false, 3, " ns", "");
    row("ns per basic IL instruction (issue 8)", "≤ 0.5 ns", b0, b2, 0.5, false, 3, " ns", "");
    row("code bytes per IL instruction, typical mix (issue 5: paper's 9.79)", "≤ 9.79", bytes_fit(0), bytes_fit(2),
        9.79, false, 2, "", "");
    row("code bytes per IL instruction, typical mix (issue 8)", "≤ 8", bytes_fit(0), bytes_fit(2), 8, false, 2, "", "");
    double best_il_s = NAN, worst_il_s = NAN, best2 = NAN;
    for (const CompileRow& r : compile) {
      double v = r.ph.il / r.ph.total() / 1e6;
      if (r.opt == 0) {
        best_il_s = std::isfinite(best_il_s) ? std::max(best_il_s, v) : v;
        worst_il_s = std::isfinite(worst_il_s) ? std::min(worst_il_s, v) : v;
      } else if (r.opt == 2) {
        best2 = std::isfinite(best2) ? std::max(best2, v) : v;
      }
    }
    row("IL instructions compiled per second (best source)", "≥ 1 M/s", best_il_s, best2, 1, true, 2, " M/s",
        "worst -O0 source: " + fixed(worst_il_s, 2) + " M/s");
    // issue 15: native code that wins on real programs
    for (Subject* s : R.of("scaling"))
      if (s->n_target == 30000 || s->n_target == 100000)
        row("issue 15: native vs the fast interpreter, typical mix of " + std::to_string(s->n_target), "≥ 10×",
            s->t[kFast].median / s->t[kNative].median, s->t[kFast].median / s->t[kNativeO2].median, 10, true, 1, "×", "");
    for (Subject* s : R.of("large"))
      if (s->name.rfind("plant", 0) == 0) {
        row("issue 15: native vs the fast interpreter, " + s->name, "≥ 4×", s->t[kFast].median / s->t[kNative].median,
            s->t[kFast].median / s->t[kNativeO2].median, 4, true, 2, "×", "");
        row("issue 15: C time / native time, " + s->name, "≥ 1.25×", s->t[kC].median / s->t[kNative].median,
            s->t[kC].median / s->t[kNativeO2].median, 1.25, true, 2, "×", "");
        row("issue 15: code bytes per IL instruction, " + s->name, "≤ 12", double(s->native_bytes_at[0]) / s->n,
            double(s->native_bytes_at[2]) / s->n, 12, false, 2, "", "");
      }
    for (Subject* s : R.of("typed")) {
      row("issue 25: native vs the fast interpreter, " + s->name, "≥ 10×", s->t[kFast].median / s->t[kNative].median,
          s->t[kFast].median / s->t[kNativeO2].median, 10, true, 1, "×", "");
      row("issue 25: C time / native time, " + s->name, "≥ 1.25×", s->t[kC].median / s->t[kNative].median,
          s->t[kC].median / s->t[kNativeO2].median, 1.25, true, 2, "×", "");
    }
    if (mix)
      row("issue 15: C time / native time, typical mix", "≥ 1.25×", mix->t[kC].median / mix->t[kNative].median,
          mix->t[kC].median / mix->t[kNativeO2].median, 1.25, true, 2, "×", "");
    row("issue 15: ns per basic IL instruction", "≤ 0.1 ns", b0, b2, 0.1, false, 3, " ns", "");
    row("issue 15: IL instructions compiled per second at -O2 (best source)", "≥ 2 M/s", best_il_s, best2, 2, true, 2,
        " M/s", "");
    const MemRow* big = nullptr;  // the largest .ld plant of the memory table
    for (const MemRow& m : memrows)
      if (m.source == ".ld" && m.il && m.error.empty() && (!big || m.il > big->il)) big = &m;
    if (big)
      row("issue 15: ldc peak memory per IL instruction, plant of " + std::to_string(big->rungs) + " rungs (-O0)",
          "≤ 200 B", (big->peak_kb() - big->before_kb) * 1024.0 / double(big->il), NAN, 200, false, 0, " B", "");
    // no class slower than its C route: C/-O2 of the powered one-class programs
    // (compares left out: gcc deletes those whose result nobody reads)
    double worst = INFINITY;
    std::string worst_class, each;
    for (Subject* s : R.of("classes")) {
      if (!s->powered || s->klass == op_class_name(OpClass::Compare)) continue;
      double r = s->t[kC].median / s->t[kNativeO2].median;
      if (!std::isfinite(r)) continue;
      each += (each.empty() ? "" : ", ") + s->klass + " " + fixed(r, 2) + "×";
      if (r < worst) worst = r, worst_class = s->klass;
    }
    if (std::isfinite(worst))
      row("issue 15: slowest class against its C route (C time / native time): " + worst_class, "≥ 1.0×", NAN, worst, 1,
          true, 2, "×", each);
    md += "\nThe typical mix is the 3,000-instruction program of P_basic = 0.689 (the paper's Fig. 10 range ends "
          "at 3,000); the last column gives the spread over the typical-mix programs of 300 to 100,000 instructions. "
          "Basic: the one-class program of 3,000 basic instructions.  Bytes: the least-squares slope over the "
          "typical-mix programs.  Compile speed: CPU time of every phase, the table below.\n\n";
  }

  // headline: the typical mix
  void headline() {
    md += "## Headline: the typical mix (P_basic = 0.689)\n\n";
    md += md_head({"program", "N_exe", "P_basic", "classic", "fast", "native", "C -O2", "classic/native", "fast/native",
                   "C/native", "native ns/IL", "C40 interp", "C40 native", "C40 interp/native"});
    for (Subject* s : headline_subjects()) {
      md += md_row({s->name, std::to_string(s->n), fixed(s->counts.p_basic(), 3), cell(s->t[kClassic]),
                    cell(s->t[kFast]), cell(s->t[kNative]), cell(s->t[kC]),
                    ratio(s->t[kClassic].median, s->t[kNative].median), ratio(s->t[kFast].median, s->t[kNative].median),
                    ratio(s->t[kC].median, s->t[kNative].median), fixed(s->t[kNative].median / s->n, 3),
                    cycles_text(s->c40_interp_cycles), cycles_text(s->c40_cycles), ratio(s->c40_interp_cycles, s->c40_cycles)});
    }
    md += "\nMedian / p99 time per scan on this machine (the input-writing overhead subtracted; a sample is one batch "
          "of scans, so p99 is over batch means, and on a shared machine it mostly shows the scheduler); C40: the "
          "simulated TMS320C40-40 (50 ns per cycle), median cycles per scan of its native code and of the C40-hosted "
          "interpreter.\n\n";
  }

  // optimization levels (issue 8)
  void levels() {
    Csv c({"program", "n_exe", "p_basic", "o0_ns", "o1_ns", "o2_ns", "c_ns", "o0_p99_ns", "o1_p99_ns", "o2_p99_ns",
           "c_p99_ns", "o0_bytes", "o1_bytes", "o2_bytes", "o0_build_s", "o1_build_s", "o2_build_s", "c_build_s",
           "c40_o0_cycles", "c40_o1_cycles", "c40_o2_cycles", "c40_o0_bytes", "c40_o1_bytes", "c40_o2_bytes", "cd_ns",
           "cd_p99_ns"});
    md += "## Optimization levels: -O0, -O1, -O2 against the C route\n\n";
    md += md_head({"program", "N_exe", "-O0", "-O1", "-O2", "change-driven", "C -O2", "C/-O2", "-O0/-O2", "-O2 ns/IL",
                   "bytes/IL -O0 · -O1 · -O2", "build ms -O0 · -O1 · -O2", "cc -O2 build"});
    std::vector<Subject*> lv = headline_subjects();
    for (Subject* s : R.of("files")) lv.push_back(s);  // `ldbench FILE...`: their code sizes per level
    for (Subject* s : R.of("classes"))
      if (s->powered) lv.push_back(s);
    for (Subject* s : lv) {
      auto per = [&](const size_t* b) {
        return fixed(double(b[0]) / s->n, 1) + " · " + fixed(double(b[1]) / s->n, 1) + " · " + fixed(double(b[2]) / s->n, 1);
      };
      const double* bt = s->native_build_at;
      c.row({s->name, std::to_string(s->n), fmt(s->counts.p_basic(), 4), fmt(s->t[kNative].median, 6),
             fmt(s->t[kNativeO1].median, 6), fmt(s->t[kNativeO2].median, 6), fmt(s->t[kC].median, 6),
             fmt(s->t[kNative].p99, 6), fmt(s->t[kNativeO1].p99, 6), fmt(s->t[kNativeO2].p99, 6), fmt(s->t[kC].p99, 6),
             std::to_string(s->native_bytes_at[0]), std::to_string(s->native_bytes_at[1]),
             std::to_string(s->native_bytes_at[2]), fmt(bt[0], 4), fmt(bt[1], 4), fmt(bt[2], 4), fmt(s->c_build_s, 4),
             fmt(s->c40_cycles_at[0], 10), fmt(s->c40_cycles_at[1], 10), fmt(s->c40_cycles_at[2], 10),
             std::to_string(s->c40_bytes_at[0]), std::to_string(s->c40_bytes_at[1]), std::to_string(s->c40_bytes_at[2]),
             fmt(s->t[kChange].median, 6), fmt(s->t[kChange].p99, 6)});
      md += md_row({s->name, std::to_string(s->n), cell(s->t[kNative]), cell(s->t[kNativeO1]), cell(s->t[kNativeO2]),
                    cell(s->t[kChange]), cell(s->t[kC]), ratio(s->t[kC].median, s->t[kNativeO2].median),
                    ratio(s->t[kNative].median, s->t[kNativeO2].median), fixed(s->t[kNativeO2].median / s->n, 3),
                    per(s->native_bytes_at),
                    fixed(bt[0] * 1e3, 1) + " · " + fixed(bt[1] * 1e3, 1) + " · " + fixed(bt[2] * 1e3, 1),
                    std::isfinite(s->c_build_s) ? fixed(s->c_build_s * 1e3, 0) + " ms" : "–"});
    }
    md += "\nMedian / p99 per scan as above; change-driven: the image of `ldc --change-driven -O2` (regions of up to "
          "8 rungs, adaptive: docs/change-driven.md); C/-O2 above 1.0× means -O2 is faster than the C route.  bytes/IL: "
          "machine code bytes per IL instruction.  build: `build_x86` (generate and assemble, no listing notes) at "
          "each level, one run; cc -O2 build: `ldc --emit=c` and the system C compiler making the shared object.  "
          "The one-class programs (the last rows) are powered; their C cells are subject to the note under the "
          "per-class table.\n\n";
    // code bytes per IL on the typical mix, per level: least squares over the scaling programs
    md += md_head({"level", "code bytes per IL (fit over the typical-mix programs)", "R²", "basic class ns/IL"});
    for (int lvl = 0; lvl < kLevels; lvl++) {
      std::vector<double> x, y;
      for (Subject* s : R.of("scaling")) {
        x.push_back(s->n);
        y.push_back(double(s->native_bytes_at[lvl]));
      }
      Fit f = fit(x, y);
      md += md_row({"-O" + std::to_string(lvl), fixed(f.slope, 2), fixed(f.r2, 4),
                    fixed(class_ns(R, op_class_name(OpClass::Basic), true, kNativeAt[lvl]), 3)});
    }
    md += "\n";
    // the same levels on the simulated C40 (docs/c40.md, "Optimization levels")
    md += "On the simulated TMS320C40 (cycles per scan of its native code, 50 ns each; words: 32-bit code "
          "words per IL instruction):\n\n";
    md += md_head({"program", "N_exe", "C40 -O0", "C40 -O1", "C40 -O2", "-O0/-O2", "words/IL -O0 · -O1 · -O2",
                   "C40 interp/-O2"});
    for (Subject* s : lv) {
      const size_t* w = s->c40_bytes_at;
      md += md_row({s->name, std::to_string(s->n), cycles_text(s->c40_cycles_at[0]), cycles_text(s->c40_cycles_at[1]),
                    cycles_text(s->c40_cycles_at[2]), ratio(s->c40_cycles_at[0], s->c40_cycles_at[2]),
                    fixed(w[0] / 4.0 / s->n, 2) + " · " + fixed(w[1] / 4.0 / s->n, 2) + " · " + fixed(w[2] / 4.0 / s->n, 2),
                    ratio(s->c40_interp_cycles, s->c40_cycles_at[2])});
    }
    md += "\n";
    R.write("levels.csv", c.text());
  }

  // scaling.csv and plot
  // scan time against input activity (issue 28)
  void activity() {
    std::vector<Subject*> v = R.of("activity");
    if (v.empty()) return;
    Csv c({"inputs_changing_permille", "fast_ns", "native_o2_ns", "native_cd_ns", "fast_p99_ns", "native_o2_p99_ns",
           "native_cd_p99_ns"});
    plot::LinePlot lp;
    lp.title = "Time per scan vs inputs changing per scan (" + v.front()->name.substr(0, v.front()->name.find(" (")) + ")";
    lp.xlabel = "inputs changing per scan (%)";
    lp.ylabel = "median time per scan (ns)";
    lp.logy = true;
    lp.note = note;
    const int show[] = {kFast, kNativeO2, kChange};
    std::vector<plot::Series> ser;
    for (int e : show) ser.push_back(plot::Series{kEngineTitle[e], {}, {}, "", false, true, true});
    md += "## Scan time against input activity (issue 28)\n\n";
    md += md_head({"program", "fast interpreter", "native -O2 (full)", "native change-driven", "change-driven / full"});
    for (Subject* s : v) {
      c.row({std::to_string(s->activity), fmt(s->t[kFast].median, 6), fmt(s->t[kNativeO2].median, 6),
             fmt(s->t[kChange].median, 6), fmt(s->t[kFast].p99, 6), fmt(s->t[kNativeO2].p99, 6), fmt(s->t[kChange].p99, 6)});
      md += md_row({s->name, cell(s->t[kFast]), cell(s->t[kNativeO2]), cell(s->t[kChange]),
                    fixed(s->t[kChange].median / s->t[kNativeO2].median, 2) + "×"});
      for (size_t k = 0; k < ser.size(); k++) {
        ser[k].x.push_back(s->activity / 10.0);
        ser[k].y.push_back(s->t[show[k]].ok ? s->t[show[k]].median : NAN);
      }
    }
    md += "\nThe plant's inputs (X, WX, F) each change with the given probability per scan (synth_trace); the "
          "change-driven scan is the adaptive engine of docs/change-driven.md.  Plot: activity.svg.\n\n";
    lp.series = ser;
    R.write("activity.csv", c.text());
    R.write("activity.svg", plot::render(lp));
  }

  void scaling() {
    Csv c({"n_exe", "p_basic", "classic_ns", "fast_ns", "native_ns", "c_ns", "classic_p99_ns", "fast_p99_ns",
           "native_p99_ns", "c_p99_ns", "c40_cycles", "c40_interp_cycles", "classic_over_native", "fast_over_native",
           "c_over_native", "c40_interp_over_native"});
    plot::LinePlot lp;
    lp.title = "Time per scan vs program size (typical mix, P_basic = 0.689)";
    lp.xlabel = "N_exe (IL instructions)";
    lp.ylabel = "median time per scan (ns)";
    lp.logx = lp.logy = true;
    lp.note = note;
    std::vector<plot::Series> ser(kEngines);
    for (int e = 0; e < kEngines; e++) ser[e].name = kEngineTitle[e];
    for (Subject* s : R.of("scaling")) {
      c.row({std::to_string(s->n), fmt(s->counts.p_basic(), 4), fmt(s->t[kClassic].median, 6), fmt(s->t[kFast].median, 6),
             fmt(s->t[kNative].median, 6), fmt(s->t[kC].median, 6), fmt(s->t[kClassic].p99, 6), fmt(s->t[kFast].p99, 6),
             fmt(s->t[kNative].p99, 6), fmt(s->t[kC].p99, 6), fmt(s->c40_cycles, 10), fmt(s->c40_interp_cycles, 10),
             fmt(s->t[kClassic].median / s->t[kNative].median, 4), fmt(s->t[kFast].median / s->t[kNative].median, 4),
             fmt(s->t[kC].median / s->t[kNative].median, 4), fmt(s->c40_interp_cycles / s->c40_cycles, 4)});
      for (int e = 0; e < kEngines; e++) {
        ser[e].x.push_back(s->n);
        ser[e].y.push_back(s->t[e].ok ? s->t[e].median : NAN);
      }
    }
    lp.series = ser;
    R.write("scaling.csv", c.text());
    R.write("scaling.svg", plot::render(lp));
    plot::LinePlot pi = lp;
    pi.title = "Time per IL instruction vs program size (typical mix)";
    pi.ylabel = "ns per IL instruction (median scan / N_exe)";
    for (auto& q : pi.series)
      for (size_t i = 0; i < q.y.size(); i++) q.y[i] /= q.x[i];
    R.write("ns_per_il.svg", plot::render(pi));
    // speed-up vs size
    plot::LinePlot sp;
    sp.title = "Speed-up of native code vs program size (typical mix)";
    sp.xlabel = "N_exe (IL instructions)";
    sp.ylabel = "time of engine / time of native";
    sp.logx = sp.logy = true;
    sp.note = note;
    for (int e : {kClassic, kFast, kC}) {
      plot::Series q;
      q.name = std::string(kEngineTitle[e]) + " / native";
      q.color = plot::palette()[e];
      for (Subject* s : R.of("scaling")) {
        q.x.push_back(s->n);
        q.y.push_back(s->t[e].ok ? s->t[e].median / s->t[kNative].median : NAN);
      }
      sp.series.push_back(q);
    }
    {
      plot::Series q;
      q.name = "C40: interpreter / native";
      q.color = plot::palette()[4];
      q.dashed = true;
      for (Subject* s : R.of("scaling")) {
        q.x.push_back(s->n);
        q.y.push_back(s->c40_interp_cycles / s->c40_cycles);
      }
      sp.series.push_back(q);
    }
    R.write("speedup.svg", plot::render(sp));
  }

  // classes (Fig. 8)
  void classes() {
    Csv c({"class", "powered", "n", "classic_ns_per_instr", "fast_ns_per_instr", "native_ns_per_instr", "c_ns_per_instr",
           "c40_cycles_per_instr", "c40_interp_cycles_per_instr", "classic_over_native", "fast_over_native",
           "c_over_native", "c40_interp_over_native", "native_code_bytes_per_instr", "c40_code_bytes_per_instr",
           "native_o1_ns_per_instr", "native_o2_ns_per_instr", "native_o2_code_bytes_per_instr"});
    md += "## Per class (Kim, Chang and Kwon, Fig. 8): time per instruction\n\n";
    md += "One-class programs of " + std::to_string(o.smoke ? 60 : 3000) +
          " instructions; *off*: the same with no power (application instructions skipped).\n\n";
    md += md_head({"class", "classic ns", "fast ns", "native ns", "-O2 ns", "C ns", "classic/native", "fast/native",
                   "C/native", "C/-O2", "native bytes/instr", "-O2 bytes/instr", "C40 interp cyc", "C40 native cyc",
                   "C40 interp/native"});
    plot::BarPlot bp;
    bp.title = "Time per instruction by class (one-class programs, powered)";
    bp.ylabel = "ns per IL instruction";
    bp.logy = true;
    bp.note = note;
    std::vector<plot::Series> ser(kEngines);
    for (int e = 0; e < kEngines; e++) ser[e].name = kEngineTitle[e];
    for (Subject* s : R.of("classes")) {
      double v[kEngines];
      for (int e = 0; e < kEngines; e++) v[e] = s->t[e].median / s->n;
      double cb = double(s->native_bytes) / s->n;
      double ci = s->c40_interp_cycles / s->n, cn = s->c40_cycles / s->n;
      double cb2 = double(s->native_bytes_at[2]) / s->n;
      c.row({s->klass, s->powered ? "1" : "0", std::to_string(s->n), fmt(v[kClassic], 5), fmt(v[kFast], 5),
             fmt(v[kNative], 5), fmt(v[kC], 5), fmt(cn, 5), fmt(ci, 5), fmt(v[kClassic] / v[kNative], 4),
             fmt(v[kFast] / v[kNative], 4), fmt(v[kC] / v[kNative], 4), fmt(ci / cn, 4), fmt(cb, 4),
             fmt(double(s->c40_bytes) / s->n, 4), fmt(v[kNativeO1], 5), fmt(v[kNativeO2], 5), fmt(cb2, 4)});
      // cc -O2 drops compares nobody reads and tests the power of a run of
      // instructions under one condition once: those C cells measure the optimizer.
      bool c_optimized = s->klass == op_class_name(OpClass::Compare) || !s->powered;
      std::string star = c_optimized ? " *" : "";
      md += md_row({s->klass + (s->powered ? "" : " (off)"), fixed(v[kClassic], 2), fixed(v[kFast], 2),
                    fixed(v[kNative], 3), fixed(v[kNativeO2], 3), s->t[kC].ok ? fixed(v[kC], 3) + star : "–",
                    ratio(v[kClassic], v[kNative]), ratio(v[kFast], v[kNative]),
                    s->t[kC].ok ? ratio(v[kC], v[kNative]) + star : "–",
                    s->t[kC].ok ? ratio(v[kC], v[kNativeO2]) + star : "–", fixed(cb, 1), fixed(cb2, 1), fixed(ci, 1),
                    fixed(cn, 1), ratio(ci, cn)});
      if (s->powered) {
        bp.categories.push_back(s->klass);
        for (int e = 0; e < kEngines; e++) ser[e].y.push_back(s->t[e].ok && !(e == kC && c_optimized) ? v[e] : NAN);
      }
    }
    bp.series = ser;
    md += "\n\\* The C compiler removes compares whose results no instruction reads, and tests the power of a run of "
          "instructions under one condition once: these C figures show the optimizer at work, not the instruction's "
          "cost (left out of the plot).  C40: simulated cycles per instruction.\n\n";
    R.write("classes.csv", c.text());
    R.write("classes.svg", plot::render(bp));
    plot::BarPlot cp;
    cp.title = "Simulated TMS320C40: cycles per instruction by class (powered)";
    cp.ylabel = "cycles per IL instruction";
    cp.logy = true;
    cp.note = "backend-c40sim cycle model (docs/c40.md); 50 ns per cycle on a TMS320C40-40";
    plot::Series ci, cn;
    ci.name = "C40-hosted interpreter";
    cn.name = "C40 native code";
    ci.color = plot::palette()[0];
    cn.color = plot::palette()[2];
    for (Subject* s : R.of("classes")) {
      if (!s->powered) continue;
      cp.categories.push_back(s->klass);
      ci.y.push_back(s->c40_interp_cycles / s->n);
      cn.y.push_back(s->c40_cycles / s->n);
    }
    cp.series = {ci, cn};
    R.write("classes_c40.svg", plot::render(cp));
  }

  // Fig. 10 and eq. (2)
  void fig10() {
    // eq. (2): T = N [P T_basic + (1-P) sum_c w_c T_c], T_c the mean of the
    // powered and unpowered one-class programs (a mix rung has power about half the time).
    synth::AppMix mix = synth::typical_app_mix();
    auto predict = [&](int e, int n, double p) {
      if (e == kC) return double(NAN);  // the C class programs are optimized away (see above)
      double tb = class_ns(R, op_class_name(OpClass::Basic), true, e), app = 0, wsum = 0;
      for (OpClass c : kClasses) {
        if (c == OpClass::Basic) continue;
        double on = class_ns(R, op_class_name(c), true, e), off = class_ns(R, op_class_name(c), false, e);
        double tc = std::isfinite(off) ? (on + off) / 2 : on;
        app += mix[int(c)] * tc;
        wsum += mix[int(c)];
      }
      return n * (p * tb + (1 - p) * app / wsum);
    };
    Csv c({"n_exe", "p_basic_target", "p_basic", "classic_ns", "fast_ns", "native_ns", "c_ns", "c40_cycles",
           "c40_interp_cycles", "classic_eq2_ns", "fast_eq2_ns", "native_eq2_ns", "native_code_bytes", "image_bytes",
           "il_bytes", "fast_decoded_bytes", "c_scan_bytes", "c40_code_bytes"});
    std::vector<double> ps;
    for (Subject* s : R.of("fig10"))
      if (std::find(ps.begin(), ps.end(), s->p_target) == ps.end()) ps.push_back(s->p_target);
    for (int e = 0; e < kEngines; e++) {
      plot::LinePlot lp;
      lp.title = std::string("Fig. 10: ") + kEngineTitle[e] + ", time per scan vs N_exe";
      lp.xlabel = "N_exe (IL instructions)";
      lp.ylabel = "median time per scan (µs)";
      lp.note = note + "; dashed: eq. (2) from the per-class times";
      for (size_t k = 0; k < ps.size(); k++) {
        plot::Series m, q;
        char nm[64];
        std::snprintf(nm, sizeof nm, "P_basic %.3g", ps[k]);
        m.name = nm;
        q.name = std::string(nm) + " eq. (2)";
        m.color = q.color = plot::palette()[k % plot::palette().size()];
        q.dashed = true;
        q.markers = false;
        for (Subject* s : R.of("fig10")) {
          if (s->p_target != ps[k]) continue;
          m.x.push_back(s->n);
          m.y.push_back(s->t[e].ok ? s->t[e].median / 1e3 : NAN);
          q.x.push_back(s->n);
          q.y.push_back(predict(e, s->n, s->counts.p_basic()) / 1e3);
        }
        lp.series.push_back(m);
        if (k == 0 || k + 1 == ps.size()) lp.series.push_back(q);
      }
      bool any = false;
      for (auto& ss : lp.series)
        for (double y : ss.y) any |= std::isfinite(y);
      if (any || e != kC) R.write(std::string("fig10_") + kEngineName[e] + ".svg", plot::render(lp));
    }
    for (Subject* s : R.of("fig10")) {
      double p = s->counts.p_basic();
      c.row({std::to_string(s->n), fmt(s->p_target, 4), fmt(p, 4), fmt(s->t[kClassic].median, 6), fmt(s->t[kFast].median, 6),
             fmt(s->t[kNative].median, 6), fmt(s->t[kC].median, 6), fmt(s->c40_cycles, 10), fmt(s->c40_interp_cycles, 10),
             fmt(predict(kClassic, s->n, p), 6), fmt(predict(kFast, s->n, p), 6), fmt(predict(kNative, s->n, p), 6),
             std::to_string(s->native_bytes), std::to_string(s->image_bytes), std::to_string(s->il_bytes),
             std::to_string(s->fast_bytes), s->c_bytes ? std::to_string(s->c_bytes) : "",
             s->c40_bytes ? std::to_string(s->c40_bytes) : ""});
    }
    R.write("fig10.csv", c.text());
    {  // the simulated C40, as paper 003 measured it: its interpreter and its native code
      plot::LinePlot lp;
      lp.title = "Fig. 10 on the simulated TMS320C40: time per scan vs N_exe";
      lp.xlabel = "N_exe (IL instructions)";
      lp.ylabel = "simulated time per scan (µs, 50 ns per cycle)";
      lp.logy = true;
      lp.note = "backend-c40sim cycle model; solid: C40 native code, dashed: C40-hosted interpreter";
      for (size_t k = 0; k < ps.size(); k++) {
        plot::Series nat, itp;
        char nm[64];
        std::snprintf(nm, sizeof nm, "P_basic %.3g", ps[k]);
        nat.name = std::string(nm) + " native";
        itp.name = std::string(nm) + " interp";
        nat.color = itp.color = plot::palette()[k % plot::palette().size()];
        itp.dashed = true;
        for (Subject* s : R.of("fig10")) {
          if (s->p_target != ps[k]) continue;
          nat.x.push_back(s->n);
          nat.y.push_back(s->c40_cycles * kC40NsPerCycle / 1e3);
          itp.x.push_back(s->n);
          itp.y.push_back(s->c40_interp_cycles * kC40NsPerCycle / 1e3);
        }
        lp.series.push_back(nat);
        lp.series.push_back(itp);
      }
      R.write("fig10_c40.svg", plot::render(lp));
    }

    // time per instruction vs P_basic at the largest N of the grid
    int nmax = 0;
    for (Subject* s : R.of("fig10")) nmax = std::max(nmax, s->n_target);
    plot::LinePlot pp;
    pp.title = "Time per IL instruction vs P_basic (N_exe = " + std::to_string(nmax) + ")";
    pp.xlabel = "P_basic (share of basic bit instructions)";
    pp.ylabel = "ns per IL instruction";
    pp.logy = true;
    pp.note = note;
    md += "## Time vs P_basic (Kim, Chang and Kwon, Fig. 10) at N_exe = " + std::to_string(nmax) + "\n\n";
    md += md_head({"P_basic", "classic", "fast", "native", "C -O2", "classic/native", "fast/native", "C/native",
                   "native eq. (2)", "native ns/IL", "C40 interp", "C40 native", "C40 interp/native"});
    for (int e = 0; e < kEngines; e++) {
      plot::Series q;
      q.name = kEngineTitle[e];
      for (Subject* s : R.of("fig10")) {
        if (s->n_target != nmax) continue;
        q.x.push_back(s->counts.p_basic());
        q.y.push_back(s->t[e].ok ? s->t[e].median / s->n : NAN);
      }
      pp.series.push_back(q);
    }
    for (Subject* s : R.of("fig10")) {
      if (s->n_target != nmax) continue;
      md += md_row({fixed(s->counts.p_basic(), 3), human_ns(s->t[kClassic].median), human_ns(s->t[kFast].median),
                    human_ns(s->t[kNative].median), s->t[kC].ok ? human_ns(s->t[kC].median) : "–",
                    ratio(s->t[kClassic].median, s->t[kNative].median), ratio(s->t[kFast].median, s->t[kNative].median),
                    ratio(s->t[kC].median, s->t[kNative].median),
                    human_ns(predict(kNative, s->n, s->counts.p_basic())), fixed(s->t[kNative].median / s->n, 3),
                    cycles_text(s->c40_interp_cycles), cycles_text(s->c40_cycles),
                    ratio(s->c40_interp_cycles, s->c40_cycles)});
    }
    md += "\n";
    R.write("pbasic.svg", plot::render(pp));

    // how well eq. (2) predicts, over the whole grid
    md += "Eq. (2) from the per-class times against the measured grid (" + std::to_string(R.of("fig10").size()) +
          " programs): median |error| ";
    for (int e = 0; e < kC; e++) {
      std::vector<double> err;
      for (Subject* s : R.of("fig10"))
        if (s->t[e].ok) err.push_back(std::fabs(predict(e, s->n, s->counts.p_basic()) / s->t[e].median - 1));
      md += std::string(e ? ", " : "") + kEngineName[e] + " " + (err.empty() ? "–" : fixed(100 * median(err), 0) + "%");
    }
    md += ".\n\n";
  }

  // code size (eq. 3, 4)
  void code_size() {
    if (!R.of("fig10").empty() || !R.of("scaling").empty()) {
      std::vector<double> x, native, image, il, fast, cx, cb, kx, kb;
      std::vector<Subject*> typical;
      for (Subject* s : R.of("fig10"))
        if (std::fabs(s->p_target - synth::kTypicalPBasic) <= 1e-9) typical.push_back(s);
      for (Subject* s : R.of("scaling")) typical.push_back(s);
      for (Subject* s : typical) {
        x.push_back(s->n);
        native.push_back(double(s->native_bytes));
        image.push_back(double(s->image_bytes));
        il.push_back(double(s->il_bytes));
        fast.push_back(double(s->fast_bytes));
        if (s->c_bytes) { cx.push_back(s->n); cb.push_back(double(s->c_bytes)); }
        if (s->c40_bytes) { kx.push_back(s->n); kb.push_back(double(s->c40_bytes)); }
      }
      Csv c({"quantity", "slope_bytes_per_il", "intercept_bytes", "r2", "slope_through_origin", "points"});
      md += "## Memory: bytes vs N_exe (Kim, Chang and Kwon, eq. 3 and 4)\n\n";
      md += "Least squares over the typical-mix programs (P_basic = 0.689: the Fig. 10 row and the scaling programs, "
            "N_exe 300 to 100,000); per P_basic below.  Bytes, except where words are said.\n\n";
      md += md_head({"quantity", "fit (bytes)", "R²", "through 0", "paper"});
      auto line = [&](const std::string& q, const std::vector<double>& xs, const std::vector<double>& ys,
                      const std::string& paper) {
        Fit f = fit(xs, ys);
        c.row({q, fmt(f.slope, 6), fmt(f.intercept, 6), fmt(f.r2, 6), fmt(f.slope0, 6), std::to_string(f.n)});
        md += md_row({q, fixed(f.slope, 3) + " N_exe " + (f.intercept < 0 ? "− " : "+ ") + fixed(std::fabs(f.intercept), 0),
                      fixed(f.r2, 4), fixed(f.slope0, 3) + " N_exe", paper});
        return f;
      };
      Fit fn = line("native x86-64 code", x, native, "M = 9.790 N_exe (C40)");
      if (!kx.empty()) line("native C40 code (4 bytes a word)", kx, kb, "M = 9.790 N_exe");
      Fit fi = line("image file", x, image, "");
      line("binary IL (classic interpreter's program)", x, il, "M' = 2.114 N_exe + 18.973 N_PLC + 183");
      line("fast interpreter's decoded program", x, fast, "");
      if (!cx.empty()) line("C route: ldc_scan function (cc -O2)", cx, cb, "");
      // the interpreters' own code, from this executable's symbol table
      size_t classic_code = elf_symbol_size("/proc/self/exe", "_GLOBAL__N_1*", "3Ctx") +
                            elf_symbol_size("/proc/self/exe", "_ZNK3ldc11Interpreter4scanEPh");
      size_t fast_code = elf_symbol_size("/proc/self/exe", "_ZN3ldc15FastInterpreter4scanEPh") +
                         elf_symbol_size("/proc/self/exe", "_GLOBAL__N_1*", "7genericEPhRKNS_15FastInterpreter3InsEj") +
                         elf_symbol_size("/proc/self/exe", "_GLOBAL__N_1*", "12compare_real");
      c.row({"classic interpreter code (N_PLC term)", "", fmt(double(classic_code), 6), "", "", "0"});
      c.row({"fast interpreter code", "", fmt(double(fast_code), 6), "", "", "0"});
      md += "\nThe interpreters' own machine code (this executable's symbol table; the N_PLC term of eq. 3, " +
            std::to_string(kOpCount) + " mnemonics): classic " + std::to_string(classic_code) + " bytes, fast " +
            std::to_string(fast_code) + " bytes.\n\n";
      R.write("codesize_fits.csv", c.text());
      plot::LinePlot lp;
      lp.title = "Memory vs N_exe (typical mix, P_basic = 0.689)";
      lp.xlabel = "N_exe (IL instructions)";
      lp.ylabel = "bytes";
      lp.logx = lp.logy = true;
      lp.note = note;
      auto pts = [&](const std::string& n, const std::vector<double>& xs, const std::vector<double>& ys, int color) {
        plot::Series s;
        s.name = n;
        s.x = xs;
        s.y = ys;
        s.line = false;
        s.color = plot::palette()[color];
        lp.series.push_back(s);
      };
      auto fitline = [&](const std::string& n, const Fit& f, int color, bool dashed) {
        plot::Series s;
        s.name = n;
        s.markers = false;
        s.dashed = dashed;
        s.color = plot::palette()[color];
        double lo = *std::min_element(x.begin(), x.end()), hi = *std::max_element(x.begin(), x.end());
        for (double v = lo; v <= hi * 1.0001; v *= 1.25) {
          s.x.push_back(v);
          s.y.push_back(f.slope * v + f.intercept);
        }
        lp.series.push_back(s);
      };
      pts("native x86-64 code", x, native, 2);
      if (!kx.empty()) pts("native C40 code", kx, kb, 5);
      fitline("native fit", fn, 2, false);
      pts("image file", x, image, 4);
      fitline("image fit", fi, 4, false);
      pts("binary IL", x, il, 0);
      pts("fast decoded", x, fast, 1);
      if (!cx.empty()) pts("C ldc_scan", cx, cb, 3);
      Fit paper;
      paper.slope = 9.790;
      paper.intercept = 0;
      fitline("paper eq. 4 (bytes)", paper, 7, true);
      paper.slope = 4 * 9.790;
      fitline("paper eq. 4 (C40 words)", paper, 8, true);
      R.write("codesize.svg", plot::render(lp));
      // per-subject sizes
      Csv all({"experiment", "program", "n_exe", "p_basic", "il_bytes", "fast_decoded_bytes", "native_code_bytes",
               "image_bytes", "c_scan_bytes", "c40_code_bytes", "native_bytes_per_il", "native_build_s", "c_build_s"});
      for (auto& s : R.subjects)
        all.row({s->experiment, s->name, std::to_string(s->n), fmt(s->counts.p_basic(), 4), std::to_string(s->il_bytes),
                 std::to_string(s->fast_bytes), std::to_string(s->native_bytes), std::to_string(s->image_bytes),
                 s->c_bytes ? std::to_string(s->c_bytes) : "", s->c40_bytes ? std::to_string(s->c40_bytes) : "",
                 fmt(double(s->native_bytes) / s->n, 5),
                 fmt(s->native_build_s, 4), fmt(s->c_build_s, 4)});
      R.write("codesize.csv", all.text());
      // bytes per instruction by P_basic
      md += md_head({"P_basic", "x86-64 bytes/IL (fit over N)", "R²", "C40 bytes/IL (fit over N)", "R²"});
      std::map<double, std::array<std::vector<double>, 3>> byp;
      for (Subject* s : R.of("fig10")) {
        byp[s->p_target][0].push_back(s->n);
        byp[s->p_target][1].push_back(double(s->native_bytes));
        byp[s->p_target][2].push_back(double(s->c40_bytes));
      }
      for (auto& [p, v] : byp) {
        Fit f = fit(v[0], v[1]), g = fit(v[0], v[2]);
        md += md_row({fixed(p, 3), fixed(f.slope, 2), fixed(f.r2, 4), fixed(g.slope, 2), fixed(g.r2, 4)});
      }
      md += "\n";
    }
  }

  // examples
  void examples() {
    Csv c({"example", "n_exe", "p_basic", "classic_ns", "fast_ns", "native_ns", "c_ns", "classic_p99_ns", "fast_p99_ns",
           "native_p99_ns", "c_p99_ns", "c40_cycles", "c40_interp_cycles", "native_code_bytes"});
    md += "## Shipped examples (their own input traces, cycled)\n\n";
    md += md_head({"example", "N_exe", "P_basic", "classic", "fast", "native", "C -O2", "classic/native", "fast/native",
                   "C/native", "code bytes", "C40 interp/native"});
    for (Subject* s : R.of("examples")) {
      c.row({s->name, std::to_string(s->n), fmt(s->counts.p_basic(), 4), fmt(s->t[kClassic].median, 6),
             fmt(s->t[kFast].median, 6), fmt(s->t[kNative].median, 6), fmt(s->t[kC].median, 6), fmt(s->t[kClassic].p99, 6),
             fmt(s->t[kFast].p99, 6), fmt(s->t[kNative].p99, 6), fmt(s->t[kC].p99, 6), fmt(s->c40_cycles, 10),
             fmt(s->c40_interp_cycles, 10), std::to_string(s->native_bytes)});
      auto cell = [](const Timing& t) { return t.ok ? mp(t.median, t.p99) : std::string("–"); };
      md += md_row({s->name, std::to_string(s->n), fixed(s->counts.p_basic(), 2), cell(s->t[kClassic]),
                    cell(s->t[kFast]), cell(s->t[kNative]), cell(s->t[kC]), ratio(s->t[kClassic].median, s->t[kNative].median),
                    ratio(s->t[kFast].median, s->t[kNative].median), ratio(s->t[kC].median, s->t[kNative].median),
                    std::to_string(s->native_bytes), ratio(s->c40_interp_cycles, s->c40_cycles)});
    }
    md += "\nMedian per scan; the input-writing overhead (" +
          (R.of("examples").empty() ? std::string("–") : human_ns(R.of("examples")[0]->overhead_ns)) +
          " for the first example) is subtracted, so tiny programs are near the clock's resolution.\n\n";
    R.write("examples.csv", c.text());
  }

  // compile speed
  void compile_speed() {
    if (!compile.empty()) {
      Csv c({"source", "opt", "rungs", "il", "parse_s", "lower_s", "generate_s", "assemble_s", "image_s", "total_s",
             "il_per_s", "wall_s", "code_bytes", "image_bytes", "repeats"});
      md += "## Compile speed (ldc's own pipeline, CPU time, median of " + std::to_string(compile[0].repeats) + ")\n\n";
      md += md_head({"source", "level", "IL", "parse", "lower", "generate", "assemble", "image", "total", "IL/s", "wall",
                     "code bytes/IL"});
      plot::LinePlot lp;
      lp.title = "Compile time vs program size (plant .ld, all phases)";
      lp.xlabel = "IL instructions";
      lp.ylabel = "CPU seconds";
      lp.logx = lp.logy = true;
      lp.note = note;
      std::vector<plot::Series> ser(6);
      const char* names[] = {"parse (.ld grid)", "lower to IL", "generate x86", "assemble", "image", "total"};
      for (int k = 0; k < 6; k++) ser[k].name = names[k];
      std::vector<double> fx, fy;
      for (const CompileRow& r : compile) {
        const Phases& p = r.ph;
        c.row({r.source, std::to_string(r.opt), std::to_string(p.rungs), std::to_string(p.il), fmt(p.parse, 5), fmt(p.lower, 5),
               fmt(p.generate, 5), fmt(p.assemble, 5), fmt(p.image, 5), fmt(p.total(), 5), fmt(p.il / p.total(), 5),
               fmt(p.wall, 5), std::to_string(p.code), std::to_string(p.image_bytes), std::to_string(r.repeats)});
        md += md_row({r.source, "-O" + std::to_string(r.opt), std::to_string(p.il), fixed(p.parse * 1e3, 1) + " ms",
                      fixed(p.lower * 1e3, 1) + " ms", fixed(p.generate * 1e3, 1) + " ms",
                      fixed(p.assemble * 1e3, 1) + " ms", fixed(p.image * 1e3, 1) + " ms",
                      fixed(p.total() * 1e3, 1) + " ms", fixed(p.il / p.total() / 1e6, 2) + " M",
                      fixed(p.wall * 1e3, 1) + " ms", fixed(double(p.code) / double(p.il), 2)});
        if (r.source.rfind("plant .ld", 0) == 0 && !r.levels) {
          double v[6] = {p.parse, p.lower, p.generate, p.assemble, p.image, p.total()};
          for (int k = 0; k < 6; k++) {
            ser[k].x.push_back(double(p.il));
            ser[k].y.push_back(v[k]);
          }
          fx.push_back(double(p.il));
          fy.push_back(p.total());
        }
      }
      ser[5].color = "#000000";
      lp.series = ser;
      Fit f = fit(fx, fy);
      md += "\nPlant programs: total = " + fmt(f.slope * 1e9, 4) + " ns × IL " + (f.intercept < 0 ? "− " : "+ ") +
            fmt(std::fabs(f.intercept) * 1e3, 3) + " ms (R² " + fixed(f.r2, 4) + "); per IL instruction " +
            fixed(compile.front().ph.total() / compile.front().ph.il * 1e9, 0) + " ns at the smallest, " +
            fixed(fy.empty() ? NAN : fy.back() / fx.back() * 1e9, 0) + " ns at the largest plant.\n\n";
      R.write("compile.csv", c.text());
      R.write("compile.svg", plot::render(lp));
    }
  }

  // memory
  void memory() {
    if (!memrows.empty()) {
      Csv c({"rungs", "source", "source_bytes", "il", "code_bytes", "image_bytes", "rss_before_kb", "hwm_after_parse_kb",
             "hwm_after_lower_kb", "hwm_after_generate_kb", "hwm_after_assemble_kb", "hwm_after_image_kb", "seconds",
             "error"});
      md += "## Peak memory of compiling (child process, VmHWM)\n\n";
      md += "Peak resident memory (VmHWM) after each phase; the source text is already in memory; generation and assembly "
            "interleave block by block, as in ldc, so they share one figure; a .ld is lowered rung by rung as it is read (parse_ld_to_il, as in ldc), so parse and lower share one figure too and the whole tree never lives at once.  The .ld reader "
            "refuses more than 65,536 rungs (frontend kMaxRungs), so the 100,000-rung plant is compiled from its IL text "
            "(no grid to read, no lowering).\n\n";
      md += md_head({"plant rungs", "IL", "source file", "image", "RSS before", "after parse", "after lower",
                     "after generate", "after assemble", "after image (peak)", "peak bytes per IL", "time"});
      auto mib = [](long kb) { return fixed(kb / 1024.0, 1) + " MiB"; };
      for (const MemRow& m : memrows) {
        c.row({std::to_string(m.rungs), m.source, std::to_string(m.source_bytes), std::to_string(m.il), std::to_string(m.code),
               std::to_string(m.image), std::to_string(m.before_kb), std::to_string(m.hwm_kb[0]), std::to_string(m.hwm_kb[1]),
               std::to_string(m.hwm_kb[2]), std::to_string(m.hwm_kb[3]), std::to_string(m.hwm_kb[4]), fmt(m.seconds, 4),
               m.error});
        md += md_row({std::to_string(m.rungs), std::to_string(m.il),
                      m.source + " " + fixed(m.source_bytes / 1048576.0, 1) + " MiB",
                      fixed(m.image / 1048576.0, 1) + " MiB", mib(m.before_kb), mib(m.hwm_kb[0]), mib(m.hwm_kb[1]),
                      mib(m.hwm_kb[2]), mib(m.hwm_kb[3]), mib(m.hwm_kb[4]),
                      m.il ? fixed((m.peak_kb() - m.before_kb) * 1024.0 / double(m.il), 0) : "–",
                      fixed(m.seconds, 2) + " s" + (m.error.empty() ? "" : " (" + m.error + ")")});
      }
      md += "\n";
      R.write("memory.csv", c.text());
    }
  }

  // machine.csv
  void machine_csv() {
    Csv c({"key", "value"});
    for (auto& [k, v] : machine) c.row({k, v});
    std::ifstream la("/proc/loadavg");
    std::string l;
    std::getline(la, l);
    c.row({"loadavg_end", l});
    c.row({"command", o.command});
    c.row({"samples", std::to_string(o.samples)});
    c.row({"batch_us", fmt(o.batch_us)});
    c.row({"c40", o.c40 ? "simulated TMS320C40-40 (backend-c40sim, docs/c40.md), 50 ns per cycle" : "off (--no-c40)"});
    R.write("machine.csv", c.text());
  }

  // "This run" heads the tables; tables.md
  void this_run() {
    std::string run = "## This run\n\n" + md_head({"what", "value"});
    std::ifstream la("/proc/loadavg");
    std::string load_end;
    std::getline(la, load_end);
    for (const char* k : {"date", "cpu", "logical_cpus", "kernel", "compiler", "cc", "build_type"})
      run += md_row({k, info(k)});
    run += md_row({"load average (1, 5, 15 min) at start · end", info("loadavg_start").substr(0, 14) + " · " + load_end.substr(0, 14)});
    run += md_row({"duration", fixed(secs_since(R.start), 0) + " s"});
    run += md_row({"command", "`" + o.command + "`"});
    run += "\n";
    md = run + md;
    R.write("tables.md", "<!-- generated by ldbench; " + o.command + " -->\n\n" + md);
  }

  // --doc FILE: between FILE's markers, this run's tables with headings one
  // level down; the rest of the document untouched.
  void put_in_doc() {
    if (o.doc.empty()) return;
    const std::string begin = "<!-- ldbench tables: begin -->", end = "<!-- ldbench tables: end -->";
    std::string text = read_file(o.doc);
    size_t b = text.find(begin), e = text.find(end);
    if (b == std::string::npos || e == std::string::npos || e < b)
      throw std::runtime_error(o.doc + ": no '" + begin + "' ... '" + end + "' region");
    std::string body;
    std::istringstream in(md);
    for (std::string l; std::getline(in, l);) body += (l.rfind("## ", 0) == 0 ? "#" + l : l) + "\n";
    text = text.substr(0, b + begin.size()) + "\n<!-- generated by " + o.command + "; do not edit -->\n\n" + body +
           text.substr(e);
    write_file_atomic(o.doc, text);
  }
};

void report(Run& R, const std::vector<CompileRow>& compile, const std::vector<MemRow>& memrows,
            const std::map<std::string, std::string>& machine) {
  Report{R, compile, memrows, machine}.run();
}

const char kUsage[] =
    "usage: ldbench [--out DIR] [--smoke] [--samples N] [--batch-us US] [--no-c] [--c-max-il N]\n"
    "               [--only examples,classes,fig10,scaling,large,activity,typed,compile,memory] [--c40|--no-c40] [--source DIR]\n"
    "               [--doc FILE.md]   (also put the tables between FILE.md's generated-region markers)\n"
    "       ldbench --synth N_EXE P_BASIC [SEED]   (a synthetic program's IL text, to stdout)\n"
    "       ldbench --plant RUNGS                  (the synthetic plant's .ld text, to stdout)\n"
    "       ldbench --typed INSTANCES              (the typed benchmark's IL text, to stdout)\n"
    "       ldbench [options] FILE...              (every engine on these programs only; FILE.csv beside\n"
    "                                               a program is its trace, else random inputs)\n";

int usage() {
  std::fputs(kUsage, stderr);
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc == 2 && (std::string(argv[1]) == "--help" || std::string(argv[1]) == "-h")) return std::fputs(kUsage, stdout), 0;
  if (argc == 2 && std::string(argv[1]) == "--version") return print_version("ldbench");
  // The benchmark programs themselves, for a look with ldc --emit=listing.
  if ((argc == 4 || argc == 5) && std::string(argv[1]) == "--synth") {
    synth::SynthOptions so;
    so.n_exe = std::atoi(argv[2]);
    so.p_basic = std::atof(argv[3]);
    so.seed = argc == 5 ? std::strtoull(argv[4], nullptr, 10) : uint64_t(so.n_exe) + 77;
    if (so.n_exe < 1 || so.n_exe > 10000000 || !(so.p_basic >= 0 && so.p_basic <= 1)) return usage();
    std::fputs(synth::synth_il(so).c_str(), stdout);
    return 0;
  }
  if (argc == 3 && std::string(argv[1]) == "--plant") {
    int rungs = std::atoi(argv[2]);
    if (rungs < 1 || rungs > int(kMaxRungs)) return usage();
    std::fputs(synth::synth_plant_ld(rungs, 1).c_str(), stdout);
    return 0;
  }
  if (argc == 3 && std::string(argv[1]) == "--typed") {
    int k = std::atoi(argv[2]);
    if (k < 1 || k > synth::kTypedMaxInstances) return usage();
    std::fputs(synth::synth_typed_il(k).c_str(), stdout);
    return 0;
  }
  if (argc == 3 && std::string(argv[1]) == "--compile-child") {
    try {
      return compile_child(argv[2]);
    } catch (std::exception& e) {
      std::fprintf(stderr, "ldbench --compile-child: %s\n", e.what());
      return 1;
    }
  }
  Run R;
  Options& o = R.o;
  bool samples_given = false;
  for (int i = 1; i < argc; i++) {
    std::string a = argv[i];
    auto val = [&]() -> std::string {
      if (i + 1 >= argc) { usage(); std::exit(2); }
      return argv[++i];
    };
    if (a == "--out") o.out = val();
    else if (a == "--smoke") o.smoke = true;
    else if (a == "--samples") { o.samples = std::max(1, std::atoi(val().c_str())); samples_given = true; }
    else if (a == "--batch-us") o.batch_us = std::atof(val().c_str());
    else if (a == "--no-c") o.c_route = false;
    else if (a == "--c-max-il") o.c_max_il = std::atol(val().c_str());
    else if (a == "--only") o.only = val();
    else if (a == "--c40") o.c40 = true;
    else if (a == "--no-c40") o.c40 = false;
    else if (a == "--source") o.source_dir = val();
    else if (a == "--doc") o.doc = val();
    else if (!a.empty() && a[0] != '-') o.files.push_back(a);
    else return usage();
  }
  if (o.smoke && !samples_given) o.samples = 15;
  if (o.smoke) o.batch_us = 5;
  o.command = "ldbench";
  for (int i = 1; i < argc; i++) o.command += std::string(" ") + argv[i];
  try {
    mkdir(o.out.c_str(), 0755);
    struct stat st;
    if (stat(o.out.c_str(), &st) != 0 || !S_ISDIR(st.st_mode)) throw std::runtime_error("cannot create " + o.out);
    auto machine = machine_info();
    say("ldbench: %s, %s cpus, %s; caches per core: %s\n", machine["cpu"].c_str(), machine["logical_cpus"].c_str(),
        machine["date"].c_str(), machine["caches"].c_str());
    auto t0 = Clock::now();
    // the one-class programs first: eq. (2) needs them
    if (!o.files.empty()) {  // only the given programs
      o.only = "files";
      run_files(R);
    }
    if (o.want("classes")) run_classes(R);
    if (o.want("fig10")) run_fig10(R);
    if (o.want("scaling")) run_scaling(R);
    if (o.want("large")) run_large(R);
    if (o.want("activity")) run_activity(R);
    if (o.want("typed")) run_typed(R);
    if (o.want("examples")) run_examples(R);
    if (o.want("scaling")) {  // the same program as at the start of the scaling run: the drift over the run
      say("repeat, to see the drift\n");
      int n = o.smoke ? 300 : 3000;
      auto s = synth_subject("repeat", n, synth::kTypicalPBasic, uint64_t(n) + 77);
      s->name += " (again, at the end)";
      bool c = o.c_route;
      if (o.smoke) o.c_route = false;
      R.add(std::move(s));
      o.c_route = c;
    }
    std::vector<CompileRow> compile;
    if (o.want("compile")) compile = run_compile(R);
    std::vector<MemRow> mem;
    if (o.want("memory")) {
      say("peak memory of compiling\n");
      std::vector<std::pair<int, bool>> sizes = {{10000, false}, {60000, false}, {100000, true}};
      if (o.smoke) sizes = {{200, false}, {200, true}};
      for (auto [n, il_text] : sizes) {
        mem.push_back(run_memory_one(n, il_text));
        say("  plant %d rungs%s: peak %ld KiB (%ld KiB before compiling)%s\n", n, il_text ? " (IL text)" : "",
            mem.back().peak_kb(),
            mem.back().before_kb, mem.back().error.empty() ? "" : (" " + mem.back().error).c_str());
      }
    }
    report(R, compile, mem, machine);
    say("ldbench: done in %.0f s; results in %s\n", secs_since(t0), o.out.c_str());
  } catch (std::exception& e) {
    std::fprintf(stderr, "ldbench: %s\n", e.what());
    return 1;
  }
  return 0;
}
