// tests/diff/st_loops_diff_test.cpp -- random Structured Text programs with
// loops (docs/st.md, "Loops"; the IL's LOOP, docs/il.md) on every engine
// against the reference interpreter, memory images compared after every scan.
// Each program is drawn from a seed: FOR loops with constant, variable and
// negative steps (some unrolled, some looped, some whose body writes the
// control variable), WHILE and REPEAT with EXIT and CONTINUE under IFs, nested
// two deep, over DINT variables and an array indexed by expressions (an index
// outside it is the index fault), with divisions by values that may be 0.
// Some loops run to the scan's loop budget (the loop fault).  The programs
// evolve from scan to scan (no inputs).
//
//   LDC_DIFF_ST_SEEDS   programs per engine (default 24; the C route 6)
//   LDC_DIFF_ST_SEED0   first seed (default 1)
#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>
#include <string>

#include "bench/rng.h"
#include "frontend/frontend.h"
#include "tests/diff/harness.h"

namespace {

using namespace ldc;
using namespace ldc::diff;

long env_long(const char* name, long def) {
  const char* v = std::getenv(name);
  return v && *v ? std::strtol(v, nullptr, 10) : def;
}

class StGen {
 public:
  explicit StGen(uint64_t seed) : r_(seed * 0x2545F4914F6CDD1DULL + 7) {}

  std::string program() {
    std::string body;
    int n = 4 + r_.below(5);
    for (int k = 0; k < n; k++) body += statement(0, "  ");
    return "PROGRAM loops\nVAR\n  a : ARRAY[0..15] OF DINT := [1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16];\n"
           "  i, j, k, x, y, z, w0, w1, w2, r0, r1, r2 : DINT;\n  t : DINT := 3;\nEND_VAR\n" + body + "END_PROGRAM\n";
  }

 private:
  Rng r_;
  int loops_ = 0;  // loops open around the statement being drawn

  std::string var() {  // read anywhere
    static const char* v[] = {"x", "y", "z", "t", "i", "j", "k", "w0"};
    return v[r_.below(8)];
  }
  std::string target() {  // written by assignments: no loop's counter
    static const char* v[] = {"x", "y", "z", "t"};
    return v[r_.below(4)];
  }
  std::string operand() {
    switch (r_.below(4)) {
      case 0: return std::to_string(r_.below(9) - 2);
      case 1: return "a[" + index() + "]";
      default: return var();
    }
  }
  // mostly inside 0..15; sometimes outside (the index fault)
  std::string index() {
    if (r_.pct(90)) return "(" + var() + " MOD 16 + 16) MOD 16";
    return var() + " MOD 20";
  }
  std::string expr(int depth = 0) {
    if (depth > 2 || r_.pct(35)) return operand();
    static const char* ops[] = {" + ", " - ", " * ", " / ", " MOD "};
    return "(" + expr(depth + 1) + ops[r_.below(5)] + expr(depth + 1) + ")";
  }
  std::string cond() {
    static const char* rel[] = {" < ", " > ", " <= ", " >= ", " = ", " <> "};
    std::string c = expr(1) + rel[r_.below(6)] + expr(1);
    if (r_.pct(25)) c = "(" + c + ") AND (" + var() + rel[r_.below(6)] + operand() + ")";
    return c;
  }
  std::string block(int depth, const std::string& ind) {
    std::string b;
    int n = 1 + r_.below(3);
    for (int k = 0; k < n; k++) b += statement(depth + 1, ind + "  ");
    return b;
  }
  std::string statement(int depth, const std::string& ind) {
    int kind = r_.below(depth >= 2 ? 3 : 8);
    switch (kind) {
      case 0:
      case 1: return ind + target() + " := " + expr() + ";\n";
      case 2:
        if (loops_ > 0 && r_.pct(30))
          return ind + "IF " + cond() + " THEN " + (r_.pct(50) ? "EXIT" : "CONTINUE") + "; END_IF;\n";
        return ind + "a[" + index() + "] := " + expr() + ";\n";
      case 3: return ind + "IF " + cond() + " THEN\n" + block(depth, ind) + ind + "ELSE\n" + block(depth, ind) + ind + "END_IF;\n";
      case 4: case 5: return for_loop(depth, ind);
      case 6: return while_loop(depth, ind);
      default: return repeat_loop(depth, ind);
    }
  }
  std::string in_loop(int depth, const std::string& ind) {
    loops_++;
    std::string b = block(depth, ind);
    loops_--;
    return b;
  }
  std::string for_loop(int depth, const std::string& ind) {
    std::string v = depth == 0 ? "i" : depth == 1 ? "j" : "k";
    std::string from = std::to_string(r_.below(6) - 1), to, by;
    switch (r_.below(4)) {
      case 0: to = std::to_string(r_.below(30)); break;               // constant: unrolled up to 16
      case 1: to = "(" + var() + " MOD 40)"; break;                   // a variable bound
      case 2: to = std::to_string(r_.below(10)), by = " BY " + std::to_string(r_.below(3) + 2); break;
      default: from = std::to_string(r_.below(20)), to = "-3", by = " BY -" + std::to_string(r_.below(3) + 1); break;
    }
    std::string b = in_loop(depth, ind);
    if (r_.pct(15)) b += ind + "  " + v + " := " + v + " + 1;\n";  // the body writes the control variable
    return ind + "FOR " + v + " := " + from + " TO " + to + by + " DO\n" + b + ind + "END_FOR;\n";
  }
  // a counter that moves toward its bound, or (rarely) one that never gets
  // there: the loop runs to the budget
  std::string while_loop(int depth, const std::string& ind) {
    std::string c = "w" + std::to_string(depth);
    bool endless = r_.pct(4);
    std::string init = ind + c + " := 0;\n";
    std::string step = ind + "  " + c + " := " + c + (endless ? " * 1;\n" : " + 1;\n");
    return init + ind + "WHILE " + c + " < " + std::to_string(1 + r_.below(12)) + " DO\n" + step + in_loop(depth, ind) + ind +
           "END_WHILE;\n";
  }
  std::string repeat_loop(int depth, const std::string& ind) {
    std::string c = "r" + std::to_string(depth);
    return ind + c + " := 0;\n" + ind + "REPEAT\n" + ind + "  " + c + " := " + c + " + 1;\n" + in_loop(depth, ind) + ind +
           "UNTIL " + c + " >= " + std::to_string(1 + r_.below(8)) + " END_REPEAT;\n";
  }
};

// Runs `p` for `scans` scans on the reference and on `test`: the memory images
// after each scan must be equal.  The fault record is cleared before a scan,
// as the runtime does.  Returns "" or what differs.
std::string compare(const Program& p, const EngineFactory& test, int scans) {
  std::unique_ptr<Engine> ref = make_interp(p), other = test(p);
  const Layout L = p.layout();
  ImageBytes a(L.size), b(L.size);
  for (int s = 1; s <= scans; s++) {
    std::memset(a.data() + kSysFault, 0, 4);
    std::memset(b.data() + kSysFault, 0, 4);
    ref->scan(a);
    other->scan(b);
    for (uint32_t k = 0; k < L.size; k++)
      if (a.data()[k] != b.data()[k])
        return "scan " + std::to_string(s) + ": image byte " + std::to_string(k) + " is " + std::to_string(b.data()[k]) +
               ", the reference's " + std::to_string(a.data()[k]);
  }
  return "";
}

void run(const EngineFactory& test, const char* what, long def) {
  long seed0 = env_long("LDC_DIFF_ST_SEED0", 1), seeds = env_long("LDC_DIFF_ST_SEEDS", def);
  int loops = 0, faults = 0;
  for (long seed = seed0; seed < seed0 + seeds; seed++) {
    std::string text = StGen(uint64_t(seed)).program();
    Program p;
    try {
      p = parse_st(text, "random.st");
    } catch (const CompileError& e) {
      ADD_FAILURE() << "seed " << seed << ": " << e.line << ":" << e.col << ": " << e.what() << "\n" << text;
      continue;
    }
    loops += has_loop(p);
    std::string why = compare(p, test, 5);
    EXPECT_EQ(why, "") << what << ", seed " << seed << " (LDC_DIFF_ST_SEED0=" << seed << " LDC_DIFF_ST_SEEDS=1):\n" << text;
    ImageBytes m(p.layout().size);
    make_interp(p)->scan(m);
    uint32_t kind;
    std::memcpy(&kind, m.data() + kSysFault, 4);
    faults += kind != kFaultNone;
  }
  std::printf("st loops, %s: %ld programs (%d with a LOOP, %d faulting in scan 1)\n", what, seeds, loops, faults);
  if (seeds >= 12) EXPECT_GT(loops, int(seeds) / 2) << "too few programs with a LOOP";
}

// The generator's programs compile, most have a LOOP, and its faults occur.
TEST(StLoops, ProgramsHaveLoopsAndSomeFault) {
  int loops = 0, loop_faults = 0, index_faults = 0;
  for (uint64_t seed = 1; seed <= 60; seed++) {
    Program p = parse_st(StGen(seed).program(), "random.st");
    loops += has_loop(p);
    ImageBytes m(p.layout().size);
    std::unique_ptr<Engine> e = make_interp(p);
    for (int s = 0; s < 3; s++) {
      std::memset(m.data() + kSysFault, 0, 4);
      e->scan(m);
      uint32_t kind;
      std::memcpy(&kind, m.data() + kSysFault, 4);
      loop_faults += kind == kFaultLoop, index_faults += kind == kFaultIndex;
    }
  }
  std::printf("60 programs: %d with a LOOP, %d loop faults, %d index faults in 180 scans\n", loops, loop_faults, index_faults);
  EXPECT_GT(loops, 40);
  EXPECT_GT(loop_faults, 0);
  EXPECT_GT(index_faults, 0);
}

TEST(StLoops, FastMatchesInterpreter) { run(make_fast_interp, "fast", 24); }
TEST(StLoops, NativeMatchesInterpreter) { run(make_native, "native -O0", 24); }
TEST(StLoops, NativeO1MatchesInterpreter) { run(make_native_o1, "native -O1", 24); }
TEST(StLoops, NativeO2MatchesInterpreter) { run(make_native_o2, "native -O2", 24); }
TEST(StLoops, CRouteMatchesInterpreter) { run(make_c_route, "the C route", 6); }

}  // namespace
