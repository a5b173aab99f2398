// tests/diff/typed_diff_test.cpp -- the differential test on typed programs:
// ldgen's typed classes (ldc IL text with typed arithmetic, compares feeding
// rungs, conversions, shifts, arrays with indices in and out of range, the
// 64-bit types) on every engine against the reference interpreter, memory
// images compared after every scan (docs/testing.md, "Typed programs").
//
//   LDC_DIFF_TYPED_SEEDS    programs per engine (default 12; the C route 4)
//   LDC_DIFF_TYPED_SEED0    first seed (default 1)
//   LDC_DIFF_TYPED_RUNGS    rungs per program (default 30)
//   LDC_DIFF_TYPED_CLASSES  typed classes, as ldgen --classes (default typed;
//                           the C40 engines always without t64)
//   LDC_DIFF_OUT, LDC_DIFF_NOFORK as for the ladder programs
#include <optional>
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iterator>
#include <set>

#include "frontend/frontend.h"
#include "ir/scanopt.h"
#include "ir/typed.h"
#include "tests/diff/harness.h"

namespace {

using namespace ldc;
using namespace ldc::diff;

GenOptions typed_options(uint64_t seed, bool narrow) {
  GenOptions o;
  o.rungs = int(env_long("LDC_DIFF_TYPED_RUNGS", 30));
  o.max_depth = int(seed % 4);
  o.classes = kGenTyped;
  if (const char* c = std::getenv("LDC_DIFF_TYPED_CLASSES"); c && *c) {
    std::string err;
    if (!parse_gen_classes(c, o.classes, err)) throw std::invalid_argument("LDC_DIFF_TYPED_CLASSES: " + err);
  }
  if (narrow) o.classes &= ~(kGenT64 | kGenTString);  // a 32-bit machine: the 64-bit types and STRING are refused by name
  if (!(o.classes & kGenTyped)) o.classes |= kGenTyped & ~(kGenT64 | kGenTString);
  return o;
}
int typed_scans(uint64_t s) { return 20 + int(s % 21); }

// ------------------------------------------------------------------ the generator

// The typed class names read and print back; `all` stays the ladder classes.

// A generated program's text compiled: the same seed gives the same text, and
// a refusal is a failure that shows the error at its place (nullopt then).
std::optional<Program> compile_generated(uint64_t seed, const GenOptions& o, const std::string& text, const char* what) {
  EXPECT_EQ(text, render(generate_program(seed, o))) << "the same seed, the same program";
  try {
    return compile_case(text);
  } catch (CompileError& e) {
    ADD_FAILURE() << "seed " << seed << ": a generated " << what << " program is refused:\n"
                  << format_error("prog.il", text, e.line, e.col, e.what()) << "\n" << text;
    return std::nullopt;
  }
}

TEST(TypedGenerator, ClassNames) {
  uint32_t m = 0;
  std::string err;
  ASSERT_TRUE(parse_gen_classes("typed", m, err)) << err;
  EXPECT_EQ(m, uint32_t(kGenTyped));
  EXPECT_EQ(gen_classes_text(m), "typed");
  ASSERT_TRUE(parse_gen_classes("tarith,t64", m, err)) << err;
  EXPECT_EQ(m, uint32_t(kGenTArith | kGenT64));
  EXPECT_EQ(gen_classes_text(m), "tarith,t64");
  ASSERT_TRUE(parse_gen_classes("all", m, err));
  EXPECT_EQ(m & kGenTyped, 0u);
  GenOptions o;
  o.classes = kGenTArray;
  EXPECT_NE(ldgen_args(3, o).find("--classes tarray"), std::string::npos) << ldgen_args(3, o);
  EXPECT_FALSE(generate_program(3, GenOptions{}).il);
}

// Every typed program is IL text the reader accepts and the validator passes,
// with the typed classes varied; its trace reads.
TEST(TypedGenerator, EveryProgramValidates) {
  const uint32_t subsets[] = {kGenTyped, kGenTArith, kGenTCompare | kGenTArith, kGenTConv | kGenT64, kGenTBits,
                              kGenTArray | kGenT64, kGenTArray, kGenTyped & ~kGenT64, kGenT64};
  for (uint64_t seed = 1; seed <= 180; seed++) {
    GenOptions o;
    o.rungs = 1 + int(seed * 7 % 40);
    o.max_depth = int(seed % 5);
    o.classes = subsets[seed % std::size(subsets)];
    GenProgram gp = generate_program(seed, o);
    ASSERT_TRUE(gp.il);
    std::string text = render(gp);
    std::optional<Program> compiled = compile_generated(seed, o, text, "typed");
    if (!compiled) continue;
    Program& p = *compiled;
    EXPECT_EQ(int(p.rungs.size()), o.rungs);
    EXPECT_EQ(validate_il(encode_il(p).code, p.layout()), "") << "seed " << seed << "\n" << text;
    bool wide = false;
    for (const Rung& r : p.rungs)
      for (const Instr& in : r.code)
        wide |= (in.ty != Ty::None && ty_info(in.ty).bits == 64) || (in.src != Ty::None && ty_info(in.src).bits == 64);
    if (!(o.classes & kGenT64)) {
      EXPECT_FALSE(wide) << "seed " << seed << ": a 64-bit type without t64\n" << text;
    }
    Trace t = read_trace(generate_trace(seed, 15, o), "trace.csv", p.aliases);
    EXPECT_EQ(t.rows.size(), 15u);
  }
}

// Does op take some type pair without STRING (the string functions do not)?
static bool op_takes_non_string(Op op) {
  for (int t = 0; t < kTyCount; t++)
    for (int u = 0; u <= kTyCount; u++) {
      Ty uu = op_info(op).typed == 2 ? Ty(u) : Ty::None;
      if ((op_info(op).typed == 2) == (u == kTyCount)) continue;
      if (op_takes(op, Ty(t), uu) && !typed::is_string_instr(op, Ty(t), uu)) return true;
    }
  return false;
}

// Over a few programs every typed instruction and every type is drawn.
TEST(TypedGenerator, DrawsEveryTypedMnemonicAndType) {
  std::set<Op> ops;
  std::set<Ty> tys;
  for (uint64_t seed = 1; seed <= 60; seed++) {
    Program p = compile_case(render(generate_program(seed, typed_options(seed, false))));
    for (const Rung& r : p.rungs)
      for (const Instr& in : r.code) {
        ops.insert(in.op);
        if (in.ty != Ty::None) tys.insert(in.ty);
      }
  }
  for (int i = 0; i < kOpCount; i++)
    if (op_info(Op(i)).klass == OpClass::Typed && op_takes_non_string(Op(i))) {
      EXPECT_TRUE(ops.count(Op(i))) << op_info(Op(i)).name << " never drawn";
    }
  for (int i = 0; i < kTyCount; i++)  // STRING runs on the interpreters only: never drawn for every engine
    if (Ty(i) != Ty::STRING) { EXPECT_TRUE(tys.count(Ty(i))) << ty_info(Ty(i)).name << " never drawn"; }
}

// Runs seed's program on the reference interpreter over its 20-scan trace and
// counts the scans and those that ended at an index fault (Sys+8), the first-
// scan bit S1 set on the first scan when `first_scan` says so.
void count_index_faults(uint64_t seed, const GenOptions& o, bool first_scan, int& scans, int& faults) {
  Program p = compile_case(render(generate_program(seed, o)));
  Trace t = read_trace(generate_trace(seed, 20, o), "trace.csv", p.aliases);
  auto e = make_interp(p);
  Memory m(p.layout());
  for (size_t k = 0; k < t.rows.size(); k++) {
    for (size_t i = 0; i < t.rows[k].size(); i++)
      if (!t.rows[k][i].empty() && int(i) != t.dt_column) put_trace_cell(m.data(), m.layout, t.columns[i], t.rows[k][i]);
    std::memset(m.data() + kSysFault, 0, 4);
    if (first_scan) m.set_bit(Area::S, kBitFirstScan, k == 0);
    e->scan(m.bytes);
    uint32_t kind;
    std::memcpy(&kind, m.data() + kSysFault, 4);
    scans++;
    faults += kind == kFaultIndex;
  }
}

// Indices go outside their bounds sometimes, not always: some scans end at an
// IDX and most do not (the interpreter's fault record says which).
TEST(TypedGenerator, IndicesFaultSometimes) {
  int scans = 0, faults = 0;
  for (uint64_t seed = 1; seed <= 30; seed++) {
    GenOptions o = typed_options(seed, false);
    o.classes = kGenTArray | kGenTArith | kGenT64;
    count_index_faults(seed, o, false, scans, faults);
  }
  std::printf("%d of %d scans ended at an index fault\n", faults, scans);
  EXPECT_GT(faults, scans / 50) << faults << " of " << scans << " scans faulted";
  EXPECT_LT(faults, scans / 2) << faults << " of " << scans << " scans faulted";
}

// ------------------------------------------------------------------ the harness on typed programs

// An engine wrong on one typed instruction (the interpreter with every ADD.T
// run as SUB.T) is caught, and the reproducer is a short IL program holding
// the ADD.
TEST(TypedHarness, CatchesAndShrinksAWrongTypedEngine) {
  EngineFactory bad = [](const Program& p) {
    Program q = p;
    for (Rung& r : q.rungs)
      for (Instr& in : r.code)
        if (in.op == Op::TADD) in.op = Op::TSUB;
    return make_interp(q);
  };
  int caught = 0;
  for (uint64_t seed = 1; seed <= 12 && caught < 1; seed++) {
    GenOptions o = typed_options(seed, false);
    GenProgram gp = generate_program(seed, o);
    std::string text = render(gp), csv = generate_trace(seed, typed_scans(seed), o);
    EXPECT_EQ(compare_isolated(text, csv, make_interp, make_interp).kind, Outcome::Kind::Same) << "seed " << seed;
    Outcome first = compare_isolated(text, csv, make_interp, bad);
    if (!first.failed()) continue;
    caught++;
    ASSERT_EQ(first.kind, Outcome::Kind::Differ) << first.message;
    Reduced r = minimize(gp, csv, first, [&](const std::string& l, const std::string& c) {
      return compare_isolated(l, c, make_interp, bad);
    });
    std::string min = render(r.prog);
    EXPECT_LE(r.prog.rungs(), 4) << min;
    EXPECT_NE(min.find("ADD."), std::string::npos) << min;
    EXPECT_EQ(compare_run(min, r.csv, make_interp, bad).kind, Outcome::Kind::Differ) << min;
    EXPECT_EQ(compare_run(min, r.csv, make_interp, make_interp).kind, Outcome::Kind::Same) << min;
    std::string dir = (std::filesystem::temp_directory_path() / "ldc_diff_minimizer").string();
    std::filesystem::create_directories(dir);
    std::string rep = reproducer("fake ADD engine, seed " + std::to_string(seed), ldgen_command(seed, o, typed_scans(seed)),
                                 gp, r, dir, "typed_add_" + std::to_string(seed), "interp", "fake", "fast");
    EXPECT_NE(rep.find(".il --engine=fast"), std::string::npos) << rep;
    EXPECT_NE(rep.find("-o prog.il"), std::string::npos) << rep;
    std::printf("%s", rep.c_str());
  }
  EXPECT_GT(caught, 0) << "no seed made the fake ADD engine differ";
}

// ------------------------------------------------------------------ every engine against the interpreter

// `engine`: ldrun's spelling ("native -O1"), for the reproducer's commands.
// `options`: the programs' options by seed (typed_options or pou_options).
void run_typed(const EngineFactory& test, const std::string& what, const std::string& engine, bool narrow, long def,
               GenOptions (*options)(uint64_t, bool) = typed_options, const char* kind = "typed") {
  std::string stem = engine;  // a file name: "native_O1"
  for (char& c : stem)
    if (c == ' ' || c == '-') c = '_';
  stem.erase(std::unique(stem.begin(), stem.end(), [](char a, char b) { return a == '_' && b == '_'; }), stem.end());
  SeedRun run;
  run.seed0 = env_long("LDC_DIFF_TYPED_SEED0", 1);
  run.count = env_long("LDC_DIFF_TYPED_SEEDS", def);
  run.options = [=](uint64_t seed) { return options(seed, narrow); };
  run.scans = typed_scans;
  run.test = test;
  run.what = what;
  run.engine = engine;
  run.stem = std::string(kind) + "_" + stem + "_seed";
  SeedTotals t = run_seeds(run, [](const std::string& m) { ADD_FAILURE() << m; });
  std::printf("%s, %s: %ld programs, %ld rungs, %ld scans compared in %.1f s\n", kind, what.c_str(), t.programs, t.rungs,
              t.scans, t.secs);
}

// The reference against itself on the program printed as IL text and read
// back (ldc --emit=il): typed mnemonics, types and constants survive the text
// form, and every generated program runs on the reference (an index fault
// included) the same way twice.  Runs today; the long run of docs/testing.md.
std::unique_ptr<Engine> make_interp_from_text(const Program& p) {
  return make_interp(parse_il_text(print_il_text(p), "printed.il"));
}
TEST(TypedDiff, ReferenceMatchesItsPrintedText) { run_typed(make_interp_from_text, "interp (printed IL)", "interp", false, 40); }

TEST(TypedDiff, FastMatchesInterpreter) { run_typed(make_fast_interp, "fast", "fast", false, 12); }
TEST(TypedDiff, NativeMatchesInterpreter) { run_typed(make_native, "native -O0", "native", false, 12); }
TEST(TypedDiff, NativeO1MatchesInterpreter) { run_typed(make_native_o1, "native -O1", "native -O1", false, 12); }
TEST(TypedDiff, NativeO2MatchesInterpreter) { run_typed(make_native_o2, "native -O2", "native -O2", false, 12); }
TEST(TypedDiff, CRouteMatchesInterpreter) { run_typed(make_c_route, "the C route", "c", false, 4); }
TEST(TypedDiff, C40SimMatchesInterpreter) { run_typed(make_c40sim, "c40sim", "c40sim", true, 6); }
// -O2 drops a typed instruction whose destination already holds its result
// (ir/scanopt.h, kHeld).  A generated program rarely repeats an instruction,
// so here each one runs twice in a scan: its rungs, then the same rungs again
// (programs with labels are left out: a second copy of a label is an
// error).  The second copy finds what the first stored, unless something
// wrote a source or the destination in between, a gated instruction, an STX,
// an IDX that ended the scan; native -O2 against the interpreter, every scan.
TEST(TypedDiff, NativeO2MatchesInterpreterOnRepeatedRungs) {
  const long total = env_long("LDC_DIFF_TYPED_SEEDS", 40);
  size_t held = 0, programs = 0;
  for (long seed = 1; seed <= total; seed++) {
    GenOptions o = typed_options(uint64_t(seed), false);
    const std::string text = render(generate_program(uint64_t(seed), o));
    if (text.find(".label") != std::string::npos) continue;
    const size_t body = text.find(".rung"), end = text.rfind(".end");
    ASSERT_NE(body, std::string::npos);
    ASSERT_NE(end, std::string::npos);
    const std::string rungs = text.substr(body, end - body);
    const std::string twice = text.substr(0, body) + rungs + rungs + text.substr(end);
    Program p = compile_case(twice);
    held += scan_facts(p, p.layout(), 3).count(kHeld);
    programs++;
    Outcome out = compare_isolated(twice, generate_trace(uint64_t(seed), typed_scans(uint64_t(seed)), o), make_interp, make_native_o2);
    EXPECT_FALSE(out.failed()) << "seed " << seed << ": " << out.message << "\n" << twice;
  }
  EXPECT_GT(programs, 0u);
  EXPECT_GT(held, 0u) << "no instruction of the second copies was held: the test tests nothing";
  std::printf("typed, repeated rungs: %zu programs, %zu instructions held\n", programs, held);
}

// The C40-hosted interpreter has no typed instructions: it refuses a typed
// program by name when it loads it (docs/c40.md), never runs it wrongly.
TEST(TypedDiff, C40InterpRefusesTypedPrograms) {
  for (uint64_t seed = 1; seed <= 3; seed++) {
    GenProgram gp = generate_program(seed, typed_options(seed, true));
    Program p = parse_il_text(render(gp), "typed.il");
    try {
      make_c40interp(p);
      ADD_FAILURE() << "seed " << seed << ": the C40-hosted interpreter took a typed program";
    } catch (const std::exception& e) {
      EXPECT_NE(std::string(e.what()).find("has no typed instructions"), std::string::npos) << e.what();
    }
  }
}

}  // namespace

// ------------------------------------------------------------------ typed programs with POUs (class tpou)

namespace {

// IEC IL with the project's own FBs and FUNCTIONs, arrays and structures
// (bench/ldgen_iec.cpp); LDC_DIFF_TYPED_RUNGS statements; the C40 without t64.
GenOptions pou_options(uint64_t, bool narrow) {
  GenOptions o;
  o.rungs = int(env_long("LDC_DIFF_TYPED_RUNGS", 30));
  o.max_depth = 0;
  o.classes = kGenTPou | (narrow ? 0u : uint32_t(kGenT64));
  return o;
}

bool has_wide(const Program& p) {
  for (const Rung& r : p.rungs)
    for (const Instr& in : r.code)
      if ((in.ty != Ty::None && ty_info(in.ty).bits == 64) || (in.src != Ty::None && ty_info(in.src).bits == 64)) return true;
  return false;
}

// Every POU program is IEC IL the typed reader takes and the validator
// passes; without t64 no 64-bit type appears; each body item stands alone
// (the minimizer drops any of them); the trace reads.
TEST(TypedPouGenerator, EveryProgramCompiles) {
  for (uint64_t seed = 1; seed <= 120; seed++) {
    GenOptions o = pou_options(seed, seed % 3 == 0);
    o.rungs = 1 + int(seed * 7 % 40);
    GenProgram gp = generate_program(seed, o);
    ASSERT_TRUE(gp.iec);
    std::string text = render(gp);
    std::optional<Program> compiled = compile_generated(seed, o, text, "POU");
    if (!compiled) continue;
    Program& p = *compiled;
    EXPECT_EQ(validate_il(encode_il(p).code, p.layout()), "") << "seed " << seed << "\n" << text;
    if (!(o.classes & kGenT64)) {
      EXPECT_FALSE(has_wide(p)) << "seed " << seed << ": a 64-bit type without t64\n" << text;
    }
    Trace t = read_trace(generate_trace(seed, 15, o), "trace.csv", p.aliases);
    EXPECT_EQ(t.rows.size(), 15u);
    if (seed % 10 == 0)
      for (const GenItem& it : gp.items) {
        GenProgram one = gp;
        one.items = {it};
        EXPECT_NO_THROW(compile_case(render(one))) << "seed " << seed << ": item alone\n" << it.text;
      }
  }
}

// Over a few programs every elementary type is computed with, and every
// construct the issue names is drawn: FB instances alone, nested, in arrays
// and in structures, FUNCTIONs called both ways, VAR_IN_OUT, VAR_EXTERNAL,
// EN/ENO, CALC, variable indices (in the program and inside an FB), nested
// structures copied whole.
TEST(TypedPouGenerator, DrawsEveryTypeAndConstruct) {
  std::set<Ty> tys;
  std::string all;
  for (uint64_t seed = 1; seed <= 60; seed++) {
    GenOptions o = pou_options(seed, false);
    std::string text = render(generate_program(seed, o));
    all += text;
    Program p = compile_case(text);
    for (const Rung& r : p.rungs)
      for (const Instr& in : r.code)
        if (in.ty != Ty::None) tys.insert(in.ty);
  }
  for (int i = 0; i < kTyCount; i++)  // STRING runs on the interpreters and the C route only: not drawn
    if (Ty(i) != Ty::STRING) { EXPECT_TRUE(tys.count(Ty(i))) << ty_info(Ty(i)).name << " never drawn"; }
  for (const char* c : {"CAL fa(", "CAL fb(", "CAL fbs[", "CAL s.fa(", "CAL subs[", "CAL a(", "CAL fc(", "VAR_IN_OUT",
                        "VAR_EXTERNAL", "ENO =>", "CALC ", "CALCN ", "hist[i]", "[k0", "[k1]", "[k2]", "inner : S0",
                        "F0(x :=", "F1 ", "LD s\n", "RETCN", "JMPCN", "_TO_", "SHL", "ROR", ".inner.m3"})
    EXPECT_NE(all.find(c), std::string::npos) << "'" << c << "' never drawn";
  for (const char* c : {"SQRT", "LTIME#", "DT#", "TOD#", "DATE#", "LREAL#", "ULINT#", "LWORD#16#"})
    EXPECT_NE(all.find(c), std::string::npos) << "'" << c << "' never drawn";
}

// Indices go outside their bounds sometimes, not always, in the program and
// inside the FB's body.
TEST(TypedPouGenerator, IndicesFaultSometimes) {
  int scans = 0, faults = 0;
  for (uint64_t seed = 1; seed <= 30; seed++) {
    GenOptions o = pou_options(seed, false);
    count_index_faults(seed, o, true, scans, faults);
  }
  std::printf("%d of %d scans ended at an index fault\n", faults, scans);
  EXPECT_GT(faults, scans / 50) << faults << " of " << scans << " scans faulted";
  EXPECT_LT(faults, scans / 2) << faults << " of " << scans << " scans faulted";
}

void run_pou(const EngineFactory& test, const std::string& what, const std::string& engine, bool narrow, long def) {
  run_typed(test, what, engine, narrow, def, pou_options, "pou");
}

TEST(PouDiff, ReferenceMatchesItsPrintedText) { run_pou(make_interp_from_text, "interp (printed IL)", "interp", false, 10); }
TEST(PouDiff, FastMatchesInterpreter) { run_pou(make_fast_interp, "fast", "fast", false, 6); }
TEST(PouDiff, NativeMatchesInterpreter) { run_pou(make_native, "native -O0", "native", false, 6); }
TEST(PouDiff, NativeO1MatchesInterpreter) { run_pou(make_native_o1, "native -O1", "native -O1", false, 6); }
TEST(PouDiff, NativeO2MatchesInterpreter) { run_pou(make_native_o2, "native -O2", "native -O2", false, 6); }
TEST(PouDiff, CRouteMatchesInterpreter) { run_pou(make_c_route, "the C route", "c", false, 2); }
TEST(PouDiff, C40SimMatchesInterpreter) { run_pou(make_c40sim, "c40sim", "c40sim", true, 4); }

}  // namespace
