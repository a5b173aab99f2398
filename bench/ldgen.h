// bench/ldgen.h -- a seeded random ladder program generator (docs/testing.md).
//
// The generator draws a random series/parallel tree per rung and renders it as
// a text grid, so the programs it makes go through the whole front end: the
// grid reader, the series/parallel reduction and the lowering to IL.  The same
// seed and options always give the same text, on every platform (the random
// numbers come from a fixed generator, not from <random>'s distributions).
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace ldc {

// Element classes the generator may draw from (GenOptions::classes).
enum GenClass : uint32_t {
  kGenContacts = 1u << 0,   // [X1] [/X1] on every bit kind (also used when no input class is on)
  kGenEdges = 1u << 1,      // [P X1] [N X1]
  kGenCompares = 1u << 2,   // [a op b], INT32, REAL and mixed
  kGenCoils = 1u << 3,      // (Y1) (/Y1) (also used when no output class is on)
  kGenSetReset = 1u << 4,   // (S Y1) (R Y1) (RST Y1) ...
  kGenTimers = 1u << 5,     // TON TOF TP, (RST T0)
  kGenCounters = 1u << 6,   // CTU CTD, (RST C0)
  kGenMove = 1u << 7,       // MOV
  kGenArith = 1u << 8,      // ADD SUB MUL DIV MOD
  kGenLogic = 1u << 9,      // AND OR XOR NOT SHL SHR
  kGenRealFn = 1u << 10,    // SIN COS TAN SQRT EXP LN ABS
  kGenJumps = 1u << 11,     // (JMP L) with a later `label L`
  kGenEnd = 1u << 12,       // a rare conditional (END)
  kGenAll = (1u << 13) - 1,  // "all": the ladder classes
  // Typed classes (ldgen_typed.cpp): with any of them on, the program is ldc IL
  // text of typed rungs (the grid has no typed elements), and the ladder classes
  // are not drawn.  `typed` names them all; an engine that cannot hold 64-bit
  // types (the C40) runs them without t64.
  kGenTArith = 1u << 13,    // MOVE ADD SUB MUL DIV MOD MIN MAX NEG ABS EXPT, the REAL functions
  kGenTCompare = 1u << 14,  // EQ NE LT LE GT GE in the rungs' conditions
  kGenTConv = 1u << 15,     // CONV TRUNC between the types
  kGenTBits = 1u << 16,     // AND OR XOR NOT SHL SHR ROL ROR
  kGenTArray = 1u << 17,    // IDX + LDX/STX over arrays (of structures too), indices in and out of range
  kGenT64 = 1u << 18,       // the 64-bit types: LINT ULINT LWORD LREAL TIME LTIME DATE TOD DT
  // STRING and its functions (MOVE, CONV both ways, LEN LEFT RIGHT CONCAT FIND,
  // ARGS + MID DELETE INSERT REPLACE, compares); drawn only with t64 (the C40,
  // which runs typed programs without t64, has neither)
  kGenTString = 1u << 20,
  kGenTyped = kGenTArith | kGenTCompare | kGenTConv | kGenTBits | kGenTArray | kGenT64 | kGenTString,
  // IEC IL text (ldgen_iec.cpp) with the project's own FUNCTION_BLOCKs and
  // FUNCTIONs, nested instances, instances in arrays and structures, arrays
  // and nested structures, read by the typed IEC IL reader; with t64 the
  // 64-bit types too.  Not part of `typed` (which is ldc IL text).
  kGenTPou = 1u << 19,
};

struct GenOptions {
  int rungs = 50;
  int max_depth = 4;  // nesting of a rung's condition tree, 0..6 (drawn per rung)
  uint32_t classes = kGenAll;
  // Device ranges: indices 0..n-1 are used (X0..X7, ...).  Small sets make
  // rungs read what other rungs write.
  int x = 8, y = 8, m = 8, k = 4, d = 8, f = 4, t = 4, c = 4, wx = 4, wy = 2;
};

// A rung as drawn: the tree the grid is rendered from.  Conditions are Elem
// "[...]", Series and Parallel; actions are Elem "(...)", Fork, and a Series
// whose last kid is an action (a condition, then what it drives).
struct GenNode {
  enum class Kind : uint8_t {
    Elem,      // text: "[X1]", "(Y0)"
    Series,    // kids side by side; wires[i]: dashes between kid i and i+1
    Parallel,  // kids stacked; wires: {dashes after the left '+', dashes before the right '+'}
    Fork,      // actions stacked, left '+' column only; wires: {dashes after the '+'}
    Rail,      // the rung: groups of rows from the left rail; wires[i]: dashes after the rail (0: none)
  } kind = Kind::Elem;
  std::string text;
  std::vector<GenNode> kids;
  std::vector<int> wires;
};

// A generated program as a list of items, so that a minimizer can drop rungs
// and keep every label in place (a jump stays forward when rungs go away).
struct GenItem {
  enum class Kind : uint8_t { Rung, Label } kind = Kind::Rung;
  std::string text;   // Rung: its lines (title and rows), each ending in '\n'; Label: the name
  int number = 0;     // Rung: its index in the generated program, 0-based (also its title)
  GenNode root;       // Rung: kind Rail
  int outputs = 0;    // Rung: output elements (...) drawn
  int inputs = 0;     // Rung: input elements [...] drawn
  std::vector<std::string> jumps;  // Rung: the labels its (JMP L) outputs name
};
// Renders a rung's root again and recounts its elements (after an edit of root).
void update_rung(GenItem& rung);

// Every smaller rung that one edit of the tree makes: a group, a fork branch,
// a parallel branch or a series condition left out.  Each is still a valid
// grid (a minimizer tries them in order).
std::vector<GenNode> rung_reductions(const GenNode& root);

struct GenProgram {
  std::string header;  // comment lines, each ending in '\n'
  std::vector<GenItem> items;
  bool il = false;     // ldc IL text (a typed program): labels are `.label`, the text ends with `.end`
  bool iec = false;    // IEC IL text (class tpou): the header declares the POUs, the items are the
                       // PROGRAM body's statements, the footer ends it
  std::string footer;
  int rungs() const;
  int outputs() const;
  int inputs() const;
};

// Checks the options (ranges, depth); "" if they are usable, else the reason.
std::string check_options(const GenOptions& opt);

GenProgram generate_program(uint64_t seed, const GenOptions& opt = {});
std::string render(const GenProgram& p);  // the .ld text
std::string generate_ld(uint64_t seed, const GenOptions& opt = {});  // render(generate_program(..))

// An input trace for `scans` scans (CSV, docs/format.md section 5): random X
// bits, WX words, D and F cells (on the first row, rarely later), sometimes
// empty cells, and a dt column of 0..60 ms.  Uses the options' device ranges.
std::string generate_trace(uint64_t seed, int scans, const GenOptions& opt = {});

// A typed program (opt.classes has typed classes; generate_program calls it):
// ldc IL rungs with typed actions, and its trace (X bits, D words of every
// pattern, index words, the arrays' words on the first row).
GenProgram generate_typed_program(uint64_t seed, const GenOptions& opt);
std::string generate_typed_trace(uint64_t seed, int scans, const GenOptions& opt);

// A typed IEC IL program with POUs, arrays and structures (class tpou), and its
// trace (bit inputs, index inputs mostly inside their bounds, word inputs).
GenProgram generate_iec_program(uint64_t seed, const GenOptions& opt);
std::string generate_iec_trace(uint64_t seed, int scans, const GenOptions& opt);

// A Structured Text program (bench/ldgen_st.cpp, `ldgen --st`): loops of every
// form with EXIT and CONTINUE, an array indexed by expressions, calls of a
// FUNCTION_BLOCK's instances (one chosen by a variable index) and of a
// FUNCTION; index and loop-budget faults happen.  No inputs.
std::string generate_st(uint64_t seed);

// "timers,arith" -> mask; false and `err` on an unknown name.  Names: contacts
// edges compares coils setreset timers counters move arith logic realfn jumps end all,
// and the typed ones: tarith tcompare tconv tbits tarray t64 typed, and tpou.
bool parse_gen_classes(std::string_view list, uint32_t& mask, std::string& err);
std::string gen_classes_text(uint32_t mask);  // the inverse: "timers,arith"

// The ldgen arguments that make this program again: "--seed 7 --rungs 50 --depth 4 ..."
// (options left at their defaults are left out).
std::string ldgen_args(uint64_t seed, const GenOptions& opt);

}  // namespace ldc
