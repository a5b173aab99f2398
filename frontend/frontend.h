// frontend/frontend.h -- the .ld ladder grid reader (docs/format.md).
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "ir/ir.h"

namespace ldc {

class Diagnostics;

// Parses a ladder source file into one series/parallel tree per rung, with every
// device resolved and type-checked.  Throws CompileError (line, col, message).
TreeProgram parse_ld(std::string_view text, const std::string& filename);
// lower_to_il(parse_ld(text, filename)) in one pass: each rung is lowered as it
// is read and its tree freed, so the whole tree never lives at once (what an
// image needs; the IL is the same).
Program parse_ld_to_il(std::string_view text, const std::string& filename);
// The same with error recovery: every error goes to `diag` (with -Wunused's
// warnings), the reader goes on with the next declaration or rung, and a
// program with errors ends with ErrorsReported (frontend/diag.h).
TreeProgram parse_ld(std::string_view text, const std::string& filename, Diagnostics& diag);
Program parse_ld_to_il(std::string_view text, const std::string& filename, Diagnostics& diag);
// The warnings of a ladder program's IL (-Wdouble-coil, -Wshared-timer,
// -Wundriven, -Wunreachable; docs/diagnostics.md), at the places its
// instructions came from in `p.source`.  `named_only`: a double coil only of
// a device the program names (an importer's own relays, such as LDmicro's
// master control relay, are driven in several places by design).
void warn_ladder(const Program& p, Diagnostics& diag, bool named_only = false);
// ... with names known beforehand (an SFC's aliases and steps); the file may
// not redefine them.
TreeProgram parse_ld(std::string_view text, const std::string& filename, const std::vector<Alias>& predefined);

// "file:line:col: error: message", the source line and a caret under the column.
std::string format_error(const std::string& file, std::string_view text, int line, int col,
                         const std::string& message);

// Limits that keep hostile input from exhausting the compiler.
constexpr size_t kMaxSourceBytes = 64u << 20;
constexpr int kMaxRungRows = 4096;
constexpr int kMaxRowWidth = 4096;
constexpr size_t kMaxRungs = 65536;  // rungs in one program (every reader)

// Imports an LDmicro program (a file whose first line starts with "LDmicro"):
// its rungs become trees over ldc devices, its names aliases (docs/ldmicro.md).
// Throws CompileError (line, col, message).
TreeProgram parse_ldmicro(std::string_view text, const std::string& filename);
// The same with error recovery (docs/diagnostics.md): an error in a setting or
// I/O-list line, or in a rung, goes to `diag` and the import goes on with the
// next line or rung; a program with errors ends with ErrorsReported.
TreeProgram parse_ldmicro(std::string_view text, const std::string& filename, Diagnostics& diag);

// Imports the LD bodies of a PLCopen TC6 XML project (docs/plcopen.md).
// Throws CompileError (line, col, message naming the XML element path).
TreeProgram parse_plcopen(std::string_view text, const std::string& filename);
// A configuration of several tasks (docs/plcopen.md, "Configurations of
// several tasks"): one program per task, over one allocation of devices, so a
// BOOL global is the same relay in every program.
struct PlcopenChart {
  Chart chart;          // steps and transitions (ir/sfc.cpp)
  TreeProgram after;    // its actions, run after the steps have moved
};
struct PlcopenTask {
  std::string name, resource, program;  // task, its resource, the program's name
  uint32_t resource_index = 0;          // the resource's place in the file: its processor
  uint32_t period_us = 0, priority = 0;
  int line = 0, col = 0;                // the task element
  TreeProgram tree;
  std::optional<PlcopenChart> chart;    // an SFC program's chart, run after the tree's rungs
};
struct PlcopenImport {
  std::string configuration;            // the configuration's name
  std::vector<PlcopenTask> tasks;       // empty: one program, `single`
  TreeProgram single;
  std::optional<PlcopenChart> single_chart;
};
// A program's IL is lower_to_il(tree), then lower_chart(chart) appended
// (then the actions' rungs).  At most one task: `single` is parse_plcopen's program.  Several tasks: one
// program per task.  Throws CompileError.
PlcopenImport import_plcopen(std::string_view text, const std::string& filename);
// The same with error recovery (docs/diagnostics.md): the errors of each
// variable, interface section, body statement and POU body go to `diag`, the
// import goes on with the next, and one with errors ends with ErrorsReported.
// The XML itself, the data types and the configuration stop at their first
// error, thrown as a CompileError as above.
PlcopenImport import_plcopen(std::string_view text, const std::string& filename, Diagnostics& diag);
TreeProgram parse_plcopen(std::string_view text, const std::string& filename, Diagnostics& diag);
// A Structured Text file (docs/st.md) as a PLCopen import is: one program
// (`single`, as raw rungs), or a CONFIGURATION of several tasks, one program
// instance each, compiled one by one over the same layout of the globals.
// Throws CompileError.
PlcopenImport import_st(std::string_view text, const std::string& filename);
// The same with error recovery (docs/diagnostics.md): each statement, each
// declaration, each IL line the statements become is reported on its own and
// the reader goes on; one with errors ends with ErrorsReported.  The lexer
// and the file's structure (its POUs and blocks, the CONFIGURATION) stop at
// their first error, thrown as a CompileError as above.
PlcopenImport import_st(std::string_view text, const std::string& filename, Diagnostics& diag);

// IEC 61131-3 Instruction List (docs/iec-il.md).  A `.il` file is ldc's own IL
// text when its first character other than blanks and `;` comment lines is
// '.', and IEC IL otherwise.
bool looks_like_ldc_il(std::string_view text);
// Reads IEC IL straight into ldc IL.  Throws CompileError (line, col, message).
Program parse_iec_il(std::string_view text, const std::string& filename);
// The same with error recovery: each line of the body and each declaration
// is reported on its own and the reader goes on (a line that goes on with
// the value of a refused one is passed over with it); one with errors ends
// with ErrorsReported.  The lexer and the file's structure stop at their
// first error, thrown as a CompileError.
Program parse_iec_il(std::string_view text, const std::string& filename, Diagnostics& diag);
// Prints any program as IEC IL that parse_iec_il reads back to the same
// behaviour (`ldc --emit=iec-il`).  Throws std::runtime_error naming the rung
// and the instruction when the program has no IEC IL form.
std::string print_iec_il(const Program& p);

// Reads IEC 61131-3 Structured Text (docs/st.md) through the typed IEC IL
// reader.  Throws CompileError.
Program parse_st(std::string_view text, const std::string& filename);
Program parse_st(std::string_view text, const std::string& filename, Diagnostics& diag);  // as import_st's recovery

// The RTSP language of paper 000 (`.rtsp`, docs/rtsp.md): its preprocessor,
// statements and data groups, as rung trees over ldc devices.
// Throws CompileError (line, col, message).
TreeProgram parse_rtsp(std::string_view text, const std::string& filename);
// The same with error recovery (docs/diagnostics.md, docs/rtsp.md): an error in
// a line, a directive, a statement or an argument goes to `diag` and the reader
// goes on with the next one; a program with errors ends with ErrorsReported.
TreeProgram parse_rtsp(std::string_view text, const std::string& filename, Diagnostics& diag);

// Reads a sequential function chart (docs/sfc.md): steps, transitions,
// selections, simultaneous sequences, jumps, and actions in ladder or IL text.
// Throws CompileError (line, col, message); errors inside an action point into
// the .sfc file.
constexpr size_t kMaxSfcSteps = 1024;  // steps and simultaneous sequences
constexpr int kMaxSfcNesting = 32;     // select/parallel inside each other
Chart parse_sfc(std::string_view text, const std::string& filename);
// The same with error recovery (docs/diagnostics.md, docs/sfc.md): a wrong
// declaration, step, transition, action, jump, condition or body goes to `diag`
// and the reader goes on; a chart with errors ends with ErrorsReported.
Chart parse_sfc(std::string_view text, const std::string& filename, Diagnostics& diag);

}  // namespace ldc
