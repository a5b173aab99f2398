// frontend/iecil/iecil.h -- what the two readers of IEC 61131-3 IL share
// (docs/iec-il.md): the lexer, and the typed reader that takes a program
// with typed declarations (typed.cpp).
#pragma once

#include <set>
#include <string>
#include <utility>
#include <string_view>
#include <vector>

#include "ir/ir.h"

namespace ldc {
class Diagnostics;
}

namespace ldc::iecil {

// Error recovery of the IEC IL and ST readers (docs/diagnostics.md, "Errors:
// every independent one"): with a Diagnostics, a reader reports an error and
// goes on with its next line, declaration or statement.  An error that
// follows from one reported already is thrown as a Quiet one and not
// reported; nor is a second error at the place of one reported (a function
// block's body is read again at each of its calls, an ST file once per task,
// and a block that lacks its END_ word is refused by each block around it).
struct Quiet : CompileError {
  using CompileError::CompileError;
};
class Recovery {
 public:
  Recovery(Diagnostics& d, std::string file) : diag_(d), file_(std::move(file)) {}
  // Reports `e` (its notes too) unless it is Quiet or reported already;
  // throws ErrorsReported at -fmax-errors.
  void report(const CompileError& e);
  // Has anything been reported (errors of this run only)?
  bool failed() const { return reported_ > 0; }
  // Throws ErrorsReported if anything was reported.
  void check() const;

 private:
  Diagnostics& diag_;
  std::string file_;
  std::set<std::pair<int, int>> seen_;  // the places reported (line, col)
  int reported_ = 0;
};

struct Tok {
  enum Kind { Word, Punct, Eol, End } kind = End;
  std::string text;
  int line = 0, col = 0;
  bool statement = false;  // an Eol after which frontend/st writes an ST statement (error recovery starts there)
};
std::string upper(std::string_view s);
// Words (names, numbers, literals, %addresses), punctuation ( ) [ ] : , ;
// := => .., one Eol per line end, and End.  Throws CompileError.
std::vector<Tok> lex(std::string_view s);
// Is `head` (a word up to its '#', e.g. "DT#2024") a date literal's, whose '-'
// and ':' before a digit belong to the word (DATE#2024-01-31, TOD#12:30:00)?
bool date_literal_head(std::string_view head);
// A direct address (%IX0.4, %QW2 ...); without the size letter (%I0.4, %Q0.0,
// %M1.2) a bit, as IEC 61131-3 has it.  nullopt and `why` if it is none.
std::optional<DeviceRef> iec_address(const std::string& text, std::string& why);

// Does the program need the typed reader: a TYPE, FUNCTION_BLOCK or FUNCTION,
// VAR_IN_OUT/VAR_TEMP/VAR_EXTERNAL, a CONSTANT or RETAIN block, or a declared
// type outside the classic subset (docs/iec-il.md, "Two readers")?
bool needs_typed_reader(const std::vector<Tok>& t);
// The typed reader: the program through the typed program model (ir/model.h)
// to typed IL.  `from_st`: the tokens are Structured Text written as IL
// (frontend/st), whose temporaries __Tn/__Sn take the type of the value
// stored into them.  Throws CompileError.
Program parse_typed_il(const std::vector<Tok>& t, const std::string& filename, bool from_st = false);
// The same with error recovery: each declaration and each line of a POU's
// body is reported on its own (in `from_st` text, each ST statement: the
// lines after an Eol token marked `statement`); the file's
// structure (its TYPEs and POUs) and the layout stop at their first error.
// A program with errors ends with ErrorsReported.
Program parse_typed_il(const std::vector<Tok>& t, const std::string& filename, bool from_st, Recovery& rec);
// A program of a configuration of several tasks (frontend/st): the relays of
// its own variables (all but VAR_GLOBAL) lie at M `own_m` or later, because
// the tasks of a project share every relay (docs/st.md).  rec may be null.
Program parse_typed_il(const std::vector<Tok>& t, const std::string& filename, bool from_st, Recovery* rec, uint32_t own_m);

// A POU body compiled for another reader (the PLCopen reader's calls of ST and
// IL POUs, docs/plcopen.md "ST and IL POUs"): a program whose variable area
// and timers start at `base` (the caller keeps the devices below), whose REAL
// variables lie in D cells like every other word, and whose located variables
// named in `callers` get no initial value (they are the caller's).
struct UnitBase {
  uint32_t m = 0, d = 0, t = 0;  // the first M bit, D cell and timer it may take
  std::set<std::string> callers;  // upper-case names of located variables that are the caller's: no initial value here
};
struct Unit {
  Program prog;           // rungs [0, init_rungs) run once per scan, first; the others at the call
  size_t init_rungs = 0;  // the initial values (first scan) and RTC's clock
  UnitBase end;           // the first M, D and T after what it took
};
Unit parse_typed_unit(const std::vector<Tok>& t, const std::string& filename, UnitBase base);

}  // namespace ldc::iecil
