// tests/fuzz/limits_test.cpp -- the readers' resource limits (docs/fuzzing.md):
// oversized input is refused with a located error, never a crash; the deepest
// nesting each reader accepts is compiled on a thread whose stack is measured.
#include <pthread.h>
#include <sys/mman.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstring>
#include <functional>
#include <string>

#include "frontend/frontend.h"
#include "frontend/plcopen/xml.h"

static int failures = 0;

// The deepest input a reader accepts must leave a quarter of an 8 MiB stack
// free, under ASan too (whose frames are 4-10 times larger).
constexpr size_t kStackBudget = 6u << 20;

using Reader = ldc::TreeProgram (*)(std::string_view, const std::string&);

// Runs fn on a thread of its own with a painted stack of `bytes` (guard page
// below); returns how many bytes of that stack fn touched.
static size_t stack_used(size_t bytes, const std::function<void()>& fn) {
  const size_t page = size_t(sysconf(_SC_PAGESIZE));
  bytes = (bytes + page - 1) / page * page;
  void* map = mmap(nullptr, bytes + page, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  if (map == MAP_FAILED) { std::perror("mmap"); std::exit(2); }
  unsigned char* base = static_cast<unsigned char*>(map) + page;
  mprotect(map, page, PROT_NONE);
  std::memset(base, 0x5a, bytes);
  pthread_attr_t attr;
  pthread_attr_init(&attr);
  pthread_attr_setstack(&attr, base, bytes);
  pthread_t t;
  auto body = [](void* p) -> void* {
    (*static_cast<const std::function<void()>*>(p))();
    return nullptr;
  };
  if (pthread_create(&t, &attr, body, const_cast<std::function<void()>*>(&fn)) != 0) { std::perror("pthread_create"); std::exit(2); }
  pthread_join(t, nullptr);
  pthread_attr_destroy(&attr);
  size_t low = 0;
  while (low < bytes && base[low] == 0x5a) low++;
  munmap(map, bytes + page);
  return bytes - low;
}

static int tree_depth(const ldc::TreeNode& n) {
  int d = 0;
  for (const auto& k : n.kids) d = std::max(d, tree_depth(k));
  return d + 1;
}

// Reads, prints and lowers `text` on a measured 8 MiB stack; "" if accepted,
// else the error.
static std::string compile(Reader read, const std::string& text, int* depth = nullptr, size_t* stack = nullptr) {
  std::string err;
  auto t0 = std::chrono::steady_clock::now();
  size_t used = stack_used(8u << 20, [&] {
    try {
      ldc::TreeProgram t = read(text, "limits");
      (void)ldc::print_tree(t);
      (void)ldc::lower_to_il(t);
      if (depth) *depth = t.rungs.empty() ? 0 : tree_depth(t.rungs[0].root);
    } catch (const ldc::CompileError& e) {
      err = std::to_string(e.line) + ":" + std::to_string(e.col) + ": " + e.what();
    }
  });
  double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  if (stack) *stack = used;
  std::printf("     (%zu bytes in, %.0f ms, %zu bytes of stack)\n", text.size(), ms, used);
  return err;
}

static void expect_error(const std::string& what, Reader read, const std::string& text, const std::string& needle) {
  std::string err = compile(read, text);
  if (err.empty()) {
    std::printf("FAIL %s: accepted\n", what.c_str());
    failures++;
  } else if (err.find(needle) == std::string::npos) {
    std::printf("FAIL %s: wrong message: %s\n", what.c_str(), err.c_str());
    failures++;
  } else {
    std::printf("ok   %s: %s\n", what.c_str(), err.c_str());
  }
}

static void expect_ok(const std::string& what, Reader read, const std::string& text) {
  int depth = 0;
  size_t stack = 0;
  std::string err = compile(read, text, &depth, &stack);
  if (!err.empty()) {
    std::printf("FAIL %s: %s\n", what.c_str(), err.c_str());
    failures++;
  } else if (stack > kStackBudget) {
    std::printf("FAIL %s: %zu bytes of stack, more than %zu\n", what.c_str(), stack, kStackBudget);
    failures++;
  } else {
    std::printf("ok   %s: tree depth %d, %zu bytes of stack\n", what.c_str(), depth, stack);
  }
}

// ---------------------------------------------------------------- .ld grids

// ((((X0 | X1) X0 | X1) X0 | X1) ...) -> (Y0): n levels, 5 columns and one row each
static std::string ld_left_staircase(int n) {
  std::string row0 = "|[X0]";
  for (int k = 1; k < n; k++) row0 += "+[X0]";
  row0 += "+(Y0)\n";
  std::string s = row0;
  for (int k = 1; k <= n; k++) {  // branch k joins after element k-1, at column 5k
    std::string r = "|[X1]" + std::string(size_t(5 * k - 5), '-') + "+";
    for (int j = k + 1; j <= n; j++) r += "    |";
    s += r + "\n";
  }
  return s;
}

// X0 -> Y0 and (X0 -> Y1 and (X0 -> Y2 ...)): n levels of output branches
static std::string ld_right_staircase(int n) {
  std::string s;
  for (int k = 0; k < n; k++)
    s += (k == 0 ? "|" : "|" + std::string(size_t(5 * k - 1), ' ') + "+") + "[X0]+(Y" + std::to_string(k) + ")\n";
  return s;
}

// every row a wire from the rail to one column of junctions: the largest grid
static std::string ld_full_grid(int rows, int width) {
  std::string s = "|" + std::string(size_t(width - 6), '-') + "+(Y0)\n";
  for (int r = 1; r < rows; r++) s += "|" + std::string(size_t(width - 6), '-') + "+\n";
  return s;
}

// ---------------------------------------------------------------- LDmicro

// PARALLEL / SERIES alternately, n levels, a contact beside each level
static std::string ldmicro_nested(int n) {
  std::string open, close;
  for (int d = 1; d <= n; d++) {
    std::string ind(size_t(2 * d + 2), ' ');
    open += ind + (d % 2 ? "PARALLEL\n" : "SERIES\n");
    close = ind + "  CONTACTS X" + (d % 2 ? "c" : "b") + " 0\n" + ind + "END\n" + close;
  }
  return "LDmicro0.1\nCYCLE=10000\n\nPROGRAM\nRUNG\n" + open + std::string(size_t(2 * n + 4), ' ') + "CONTACTS Xa 0\n" + close +
         "    COIL Yout 0 0 0\nEND\n";
}

// ---------------------------------------------------------------- PLCopen

static std::string plcopen_project(const std::string& ld) {
  return "<?xml version=\"1.0\"?>\n<project xmlns=\"http://www.plcopen.org/xml/tc6_0201\"><types><pous>"
         "<pou name=\"P\" pouType=\"program\"><interface><localVars>"
         "<variable name=\"a\"><type><BOOL/></type></variable>"
         "<variable name=\"b\"><type><BOOL/></type></variable>"
         "<variable name=\"q\"><type><BOOL/></type></variable>"
         "<variable name=\"n\"><type><INT/></type></variable>"
         "</localVars></interface><body><LD>\n<leftPowerRail localId=\"1\"/>\n" + ld +
         "</LD></body></pou></pous></types></project>\n";
}
static std::string plcopen_contact(int id, std::initializer_list<int> from, const char* var) {
  std::string s = "<contact localId=\"" + std::to_string(id) + "\"><connectionPointIn>";
  for (int f : from) s += "<connection refLocalId=\"" + std::to_string(f) + "\"/>";
  return s + "</connectionPointIn><variable>" + var + "</variable></contact>\n";
}
// `levels` elements nested in <addData> (which the importer skips), around a one-contact rung
static std::string plcopen_deep_xml(int levels) {
  std::string open, close;
  for (int k = 0; k < levels; k++) open += "<a>", close += "</a>";
  std::string p = plcopen_project(plcopen_contact(2, {1}, "a") + "<coil localId=\"3\"><connectionPointIn><connection refLocalId=\"2\"/></connectionPointIn><variable>q</variable></coil>\n");
  return p.replace(p.find("<types>"), 7, "<addData>" + open + close + "</addData><types>");
}

static std::string plcopen_coil(int id, int from) {
  return "<coil localId=\"" + std::to_string(id) + "\"><connectionPointIn><connection refLocalId=\"" +
         std::to_string(from) + "\"/></connectionPointIn><variable>q</variable></coil>\n";
}

// a chain of n contacts, each also fed by a contact from the rail:
// ((((a | b) a | b) a | b) ...) -> q
static std::string plcopen_staircase(int n) {
  std::string ld;
  int prev = 1;
  for (int k = 0; k < n; k++) {
    int side = 2 + 2 * k, main = 3 + 2 * k;
    ld += plcopen_contact(side, {1}, "b");
    ld += k == 0 ? plcopen_contact(main, {1}, "a") : plcopen_contact(main, {prev, side}, "a");
    prev = main;
  }
  return plcopen_project(ld + plcopen_coil(2 * n + 2, prev));
}

// n blocks, each feeding input IN1 of the next: ADD (values) or AND (power flow)
static std::string plcopen_blocks(int n, bool values) {
  std::string ld = values ? "<inVariable localId=\"2\"><expression>n</expression></inVariable>\n"
                          : plcopen_contact(2, {1}, "a");
  auto in = [](const char* pin, int from, bool out) {
    return std::string("<variable formalParameter=\"") + pin + "\"><connectionPointIn><connection refLocalId=\"" +
           std::to_string(from) + "\"" + (out ? " formalParameter=\"OUT\"" : "") + "/></connectionPointIn></variable>";
  };
  for (int k = 0; k < n; k++)
    ld += "<block localId=\"" + std::to_string(10 + k) + "\" typeName=\"" + (values ? "ADD" : "AND") + "\"><inputVariables>" +
          in("IN1", k ? 9 + k : 2, k > 0) + in("IN2", 2, false) +
          "</inputVariables><outputVariables><variable formalParameter=\"OUT\"/></outputVariables></block>\n";
  std::string last = "<connection refLocalId=\"" + std::to_string(9 + n) + "\" formalParameter=\"OUT\"/>";
  ld += values ? "<outVariable localId=\"5\"><connectionPointIn>" + last + "</connectionPointIn><expression>n</expression></outVariable>\n"
               : "<coil localId=\"5\"><connectionPointIn>" + last + "</connectionPointIn><variable>q</variable></coil>\n";
  return plcopen_project(ld);
}

// IEC IL is read straight into IL (no tree): its own check
static void expect_iec_error(const std::string& what, const std::string& text, const std::string& needle) {
  try {
    (void)ldc::parse_iec_il(text, "limits.il");
    std::printf("FAIL %s: accepted\n", what.c_str());
    failures++;
  } catch (const ldc::CompileError& e) {
    bool ok = std::string(e.what()).find(needle) != std::string::npos;
    std::printf("%s %s: %d:%d: %s\n", ok ? "ok  " : "FAIL", what.c_str(), e.line, e.col, e.what());
    failures += !ok;
  }
}

// ---------------------------------------------------------------- SFC charts

// parse_sfc + lower_chart on a measured stack: refused with `needle`, within the budget.
static void expect_sfc_error(const std::string& what, const std::string& text, const std::string& needle) {
  std::string err;
  size_t used = stack_used(8u << 20, [&] {
    try {
      (void)ldc::lower_chart(ldc::parse_sfc(text, "limits.sfc"));
    } catch (const ldc::CompileError& e) {
      err = std::to_string(e.line) + ":" + std::to_string(e.col) + ": " + e.what();
    }
  });
  bool ok = err.find(needle) != std::string::npos && used <= kStackBudget;
  std::printf("%s %s: %s (%zu bytes of stack)\n", ok ? "ok  " : "FAIL", what.c_str(), err.empty() ? "accepted" : err.c_str(), used);
  failures += !ok;
}

int main() {
  std::setvbuf(stdout, nullptr, _IOLBF, 0);  // every line out before a crash
  std::string rungs;
  for (size_t i = 0; i <= ldc::kMaxRungs; i++) rungs += "|--[X0]--(Y0)\n\n";
  expect_error("rung count", ldc::parse_ld, rungs, "too many rungs");
  std::string tall;
  for (int i = 0; i <= ldc::kMaxRungRows; i++) tall += i == 0 ? "|--[X0]--+--(Y0)\n" : "|        |\n";
  expect_error("rung rows", ldc::parse_ld, tall, "rung too tall");
  expect_error("row width", ldc::parse_ld, "|--[X0]" + std::string(ldc::kMaxRowWidth, '-') + "(Y0)\n", "too wide");

  // The grid limits bound the nesting: a level costs one row and 5 columns.
  for (int n : {100, 818})
    expect_ok(".ld left staircase " + std::to_string(n), ldc::parse_ld, ld_left_staircase(n));
  expect_error(".ld left staircase 819", ldc::parse_ld, ld_left_staircase(819), "too wide");
  for (int n : {100, 817})
    expect_ok(".ld right staircase " + std::to_string(n), ldc::parse_ld, ld_right_staircase(n));
  expect_error(".ld right staircase 818", ldc::parse_ld, ld_right_staircase(818), "too wide");
  expect_ok(".ld full grid 4096 x 4096", ldc::parse_ld, ld_full_grid(ldc::kMaxRungRows, ldc::kMaxRowWidth));

  // LDmicro: the RUNG is the first level
  for (int n : {10, 99})
    expect_ok("LDmicro nesting " + std::to_string(n), ldc::parse_ldmicro, ldmicro_nested(n));
  expect_error("LDmicro nesting 100", ldc::parse_ldmicro, ldmicro_nested(100), "nested too deeply");

  for (int n : {10, 50})
    expect_ok("PLCopen ADD blocks " + std::to_string(n), ldc::parse_plcopen, plcopen_blocks(n, true));
  expect_error("PLCopen ADD blocks 51", ldc::parse_plcopen, plcopen_blocks(51, true), "too deeply");
  for (int n : {10, 30})
    expect_ok("PLCopen AND blocks " + std::to_string(n), ldc::parse_plcopen, plcopen_blocks(n, false));
  expect_error("PLCopen AND blocks 60", ldc::parse_plcopen, plcopen_blocks(60, false), "too deeply");
  for (int n : {10, 100, 499})
    expect_ok("PLCopen staircase " + std::to_string(n), ldc::parse_plcopen, plcopen_staircase(n));
  expect_error("PLCopen staircase 501", ldc::parse_plcopen, plcopen_staircase(501), "power flow too long");
  // XML: <project><addData> are 2 levels
  expect_ok("XML depth 512", ldc::parse_plcopen, plcopen_deep_xml(ldc::xml::kMaxDepth - 2));
  expect_error("XML depth 513", ldc::parse_plcopen, plcopen_deep_xml(ldc::xml::kMaxDepth - 1), "nested too deeply");

  // IL text is read line by line and lowered by nobody: a million instructions
  // in one rung cost no stack (the bit stack is 32 bits wide by definition, docs/il.md)
  std::string il = ".rung line 1\nLOAD X0\n";
  for (int i = 0; i < 1000000; i++) il += "LOAD X1\nORBLK\n";
  il += "OUT Y0\n.end\n";
  size_t il_stack = stack_used(8u << 20, [&] {
    try {
      ldc::Program p = ldc::parse_il_text(il, "limits.il");
      (void)ldc::print_il_text(p);
      (void)ldc::encode_il(p);
    } catch (const ldc::CompileError& e) {
      std::printf("FAIL IL text: %d:%d: %s\n", e.line, e.col, e.what());
      failures++;
    }
  });
  std::printf("ok   IL text, one rung of 2,000,003 instructions: %zu bytes of stack\n", il_stack);

  // IEC IL: rung count (every LD starts a rung), parenthesis depth
  std::string iec;
  for (size_t i = 0; i <= ldc::kMaxRungs; i++) iec += "LD %IX0.0\nST %QX0.0\n";
  expect_iec_error("IEC IL rung count", iec, "more than 65536 rungs");
  std::string deep = "LD %IX0.0\n";
  for (int i = 0; i < 1000; i++) deep += "AND( %IX0.1\n";
  expect_iec_error("IEC IL parentheses", deep, "parentheses nested deeper than 16");

  // RTSP: if statements and #if groups 64 deep; macro expansion bounded
  auto nested_ifs = [](int n) {
    std::string t;
    for (int i = 0; i < n; i++) t += "if IsGt(I0, " + std::to_string(i) + ") then\n";
    t += "Set(I1, 1);\n";
    for (int i = 0; i < n; i++) t += "fi\n";
    return t;
  };
  expect_ok("RTSP if nesting 64", ldc::parse_rtsp, nested_ifs(64));
  expect_error("RTSP if nesting 65", ldc::parse_rtsp, nested_ifs(65), "nested deeper than 64");
  std::string groups;
  for (int i = 0; i < 65; i++) groups += "#if 1\n";
  expect_error("RTSP #if nesting 65", ldc::parse_rtsp, groups, "#if groups nested deeper than 64");
  std::string bomb = "#define M0 I0\n";  // each macro twice the one before: 2^40 tokens
  for (int i = 1; i <= 40; i++) bomb += "#define M" + std::to_string(i) + " M" + std::to_string(i - 1) + " M" + std::to_string(i - 1) + "\n";
  bomb += "Set(M40, 1);\n";
  expect_error("RTSP macro expansion", ldc::parse_rtsp, bomb, "too large after macro expansion");
  expect_error("RTSP expression depth", ldc::parse_rtsp, "Set(I0, " + std::string(1000, '(') + "1" + std::string(1000, ')') + ");\n",
               "nested deeper than 64");
  // SFC (docs/sfc.md): step count, nesting of selections and simultaneous sequences, condition depth
  std::string steps = "flags M0\ninitial step Step0\n";
  for (size_t i = 1; i <= ldc::kMaxSfcSteps; i++) steps += "transition X0\nstep Step" + std::to_string(i) + "\n";
  expect_sfc_error("sfc steps", steps, "too many steps");
  std::string nest = "initial step A\ntransition X0\n", tail;
  for (int i = 0; i <= ldc::kMaxSfcNesting; i++) {
    nest += "parallel\nbranch\n  step P" + std::to_string(i) + "\nbranch\n";
    tail = "end\n" + tail;
  }
  expect_sfc_error("sfc nesting", nest + "  step Z\n" + tail, "nested too deeply");
  expect_sfc_error("sfc condition depth",
                   "initial step A\ntransition " + std::string(100, '(') + "X0" + std::string(100, ')') + "\nstep B\n",
                   "nested too deeply");
  return failures ? 1 : 0;
}
