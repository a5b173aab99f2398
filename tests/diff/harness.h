// tests/diff/harness.h -- the differential test's machinery: run two engines
// side by side over one program and trace, compare their memory images after
// every scan, shrink a failing case and print a reproducer (docs/testing.md).
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "bench/ldgen.h"
#include "ir/ir.h"
#include "runtime/runtime.h"

namespace ldc::diff {

// Makes an engine for a compiled program (throws on failure).
using EngineFactory = std::function<std::unique_ptr<Engine>(const Program&)>;
std::unique_ptr<Engine> make_interp(const Program& p);  // encode_il + make_interp_engine
std::unique_ptr<Engine> make_native(const Program& p);     // build_x86 -O0 + make_native_engine
std::unique_ptr<Engine> make_native_o1(const Program& p);  // the same at -O1
std::unique_ptr<Engine> make_native_o2(const Program& p);  // the same at -O2
std::unique_ptr<Engine> make_fast_interp(const Program& p); // the fast interpreter (runtime/fastinterp.h)
std::unique_ptr<Engine> make_c_route(const Program& p);     // generate_c, the system cc -O2, dlopen
std::unique_ptr<Engine> make_c40sim(const Program& p);      // C40 code on the simulated board
std::unique_ptr<Engine> make_c40interp(const Program& p);   // the IL on the C40-hosted interpreter
// The change-driven scan (runtime/change_driven.h), each region (ir/regions.h,
// up to max_rungs rungs) on its own engine from `part`.
std::unique_ptr<Engine> make_change_driven(const Program& p, const EngineFactory& part, uint32_t max_rungs = 1);

// The program of a case's text: ldc IL text (a typed program, looks_like_ldc_il),
// IEC IL text (ldgen's tpou programs: it starts with a "(*" comment, parse_iec_il)
// or a .ld grid (parse_ld -> lower_to_il).  Throws CompileError.
Program compile_case(const std::string& text);
bool looks_like_iec_il(const std::string& text);

// A byte of the memory image, named for people.
struct Place {
  Area area = Area::Count;  // Area::Count: padding between areas
  uint32_t index = 0;
  std::string name;   // "D3", "T0 done bit", "E2 edge memory", "Sys+0 dt"
  std::string watch;  // a --watch spelling that shows it ("D3", "T0"), or ""
};
Place describe(const Layout& l, uint32_t offset);
// The value of the element holding `offset`, as "7 (0x00000007)" or "1.5 (0x3fc00000)".
std::string value_at(const Layout& l, std::span<const uint8_t> image, uint32_t offset);

struct Outcome {
  enum class Kind : uint8_t {
    Same,           // every image matched after every scan
    Differ,         // the images differ after `scan`
    TestError,      // the engine under test could not be built or threw
    Crash,          // the run died (signal, time limit) in its child process
    FrontEndError,  // the program or trace was refused: a generator bug, not an engine one
  } kind = Kind::Same;
  int scans = 0;        // scans run (the trace's rows)
  int scan = 0;         // Differ: first differing scan, 1-based
  uint32_t offset = 0;  // Differ: first differing byte
  Place place;
  std::string ref_value, test_value;
  std::vector<std::string> also;  // other differing devices in that scan (a few)
  std::string message;            // TestError / Crash / FrontEndError
  bool failed() const { return kind == Kind::Differ || kind == Kind::TestError || kind == Kind::Crash; }
};

// Compiles `ld` (compile_case: a grid, or IL text), reads `csv` and runs one scan per
// trace row on both engines, each on its own Memory, writing the row, dt and S1
// as ldrun's run_trace does; compares the images byte for byte after every scan.
Outcome compare_run(const std::string& ld, const std::string& csv, const EngineFactory& ref,
                    const EngineFactory& test);
// The same in a forked child, so a crash or a hang of native code becomes an
// Outcome (Crash) instead of killing the test.  LDC_DIFF_NOFORK=1 runs in process.
Outcome compare_isolated(const std::string& ld, const std::string& csv, const EngineFactory& ref,
                         const EngineFactory& test, int time_limit_s = 60);

using Runner = std::function<Outcome(const std::string& ld, const std::string& csv)>;

struct Reduced {
  GenProgram prog;
  std::string csv;
  Outcome outcome;  // of the reduced case
  int runs = 0;     // candidate runs tried
};
// Shrinks a failing case while it still fails the same way: cuts the trace
// after the first differing scan; drops rungs one at a time (labels stay in
// place, so every kept jump stays forward); inside the rungs left, leaves out
// groups of rows, fork and parallel branches and series conditions
// (rung_reductions); repeats both until nothing goes; drops the labels no kept
// jump names, trailing scans, and trace columns that do not matter.
Reduced minimize(const GenProgram& prog, const std::string& csv, const Outcome& first, const Runner& run);

// Where reproducers are written: $LDC_DIFF_OUT, else the current directory.
std::string output_dir();

// The report for a failing case: what differs, the minimal .ld and trace
// (also written to <dir>/<stem>.ld and .csv), and the ldrun commands.
// `origin` says how to make the original case again (an ldgen command line).
std::string reproducer(const std::string& title, const std::string& origin, const GenProgram& original,
                       const Reduced& r, const std::string& dir, const std::string& stem,
                       const char* ref_name = "interp", const char* test_name = "native",
                       const std::string& test_engine = "native");

// A run over seeds: seeds seed0 + i for i = first, first + step, ... < count,
// each program on the reference interpreter and the engine under test; a
// failing case is minimized and reported (through `fail`) as a reproducer
// <stem><seed>.il/.ld; the run stops after `max_failures` of them.  The
// ladder shards and the typed runs share it.
struct SeedRun {
  long seed0 = 1, first = 0, step = 1, count = 0;
  std::function<GenOptions(uint64_t)> options;
  std::function<int(uint64_t)> scans;
  EngineFactory test;
  // if set, makes each seed's trace from generate_trace's (the change-driven
  // runs thin it to an input activity)
  std::function<std::string(uint64_t, const std::string&)> trace_filter;
  std::string what;    // "native -O1", in the reports
  std::string engine;  // ldrun's --engine spelling, for the reproducer's commands
  std::string stem;    // "diff_seed": the reproducer is <dir>/<stem><seed>.ld
  int max_failures = 3;
};
struct SeedTotals {
  long programs = 0, rungs = 0, scans = 0, failures = 0;
  double secs = 0;
};
// `fail` gets each failure's text (a generator bug, a reproducer, the stop).
SeedTotals run_seeds(const SeedRun& run, const std::function<void(const std::string&)>& fail);

// The number in environment variable `name` (LDC_DIFF_SEEDS ...), or `def`
// if it is unset, empty or not a whole number.
long env_long(const char* name, long def);

// `ldgen ...` arguments that make this case again.
std::string ldgen_command(uint64_t seed, const GenOptions& opt, int scans);

}  // namespace ldc::diff
