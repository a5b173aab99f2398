// bench/ldgen_st.cpp -- random Structured Text programs (ldgen --st; the
// differential tests tests/diff/st_loops_diff_test.cpp; docs/testing.md).
// Each program is drawn from a seed: FOR loops with constant, variable and
// negative steps (some unrolled, some looped, some whose body writes the
// control variable), WHILE and REPEAT with EXIT and CONTINUE under IFs, nested
// two deep, over DINT variables and an array indexed by expressions (an index
// outside it is the index fault), divisions by values that may be 0; calls of
// a FUNCTION_BLOCK's instances (one chosen by a variable index in an array of
// them, one with an output by =>), of a FUNCTION with a default input, and an
// INT that wraps.  Some loops run to the scan's loop budget (the loop fault).
// The programs evolve from scan to scan (no inputs).
#include <string>

#include "bench/ldgen.h"
#include "bench/rng.h"

namespace ldc {
namespace {

// The POUs every program calls.  Acc's count stays small (MOD 97 past 1000);
// Mix divides by q, which a call may make 0 (MatIEC's C: the engines' rule
// for a division by 0, docs/il.md).
constexpr const char* kPous =
    "FUNCTION_BLOCK Acc\nVAR_INPUT k : DINT; END_VAR\nVAR_OUTPUT n : DINT; END_VAR\n"
    "n := n + k;\nIF n > 1000 OR n < -1000 THEN n := n MOD 97; END_IF;\nEND_FUNCTION_BLOCK\n"
    "FUNCTION Mix : DINT\nVAR_INPUT p : DINT; q : DINT := 3; END_VAR\nMix := p * q + p / q;\nEND_FUNCTION\n";

class StGen {
 public:
  explicit StGen(uint64_t seed) : r_(seed * 0x2545F4914F6CDD1DULL + 7) {}

  std::string program() {
    std::string body;
    int n = 4 + r_.below(5);
    for (int k = 0; k < n; k++) body += statement(0, "  ");
    return std::string(kPous) +
           "PROGRAM loops\nVAR\n  a : ARRAY[0..15] OF DINT := [1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16];\n"
           "  i, j, k, x, y, z, w0, w1, w2, r0, r1, r2 : DINT;\n  t : DINT := 3;\n"
           "  acc : ARRAY[0..3] OF Acc;\n  one : Acc;\n  s : INT;\nEND_VAR\n" + body + "END_PROGRAM\n";
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
    if (r_.pct(15)) return call(ind);
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
  // calls: an instance of Acc chosen by an index (mostly inside 0..3, the
  // index fault otherwise), one with an output by =>, the FUNCTION Mix with
  // its default or a divisor that may be 0, and an INT that wraps
  std::string call(const std::string& ind) {
    switch (r_.below(5)) {
      case 0: {
        std::string idx = r_.pct(90) ? "(" + var() + " MOD 4 + 4) MOD 4" : var() + " MOD 6";
        return ind + "acc[" + idx + "](k := " + expr(1) + ");\n";
      }
      case 1: return ind + "one(k := " + expr(1) + ", n => " + target() + ");\n";
      case 2: return ind + target() + " := Mix(p := " + expr(1) + (r_.pct(50) ? ", q := " + operand() : std::string()) + ");\n";
      case 3: return ind + target() + " := acc[" + std::to_string(r_.below(4)) + "].n + one.n;\n";
      default: return ind + "s := s + DINT_TO_INT(" + var() + ") * 1000;\n";
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

}  // namespace

std::string generate_st(uint64_t seed) { return StGen(seed).program(); }

}  // namespace ldc
