// frontend/diag.h -- diagnostics as gcc and clang print them (docs/diagnostics.md):
// `file:line:col: error|warning|note: message`, the source line and a caret,
// warnings by name (-Wname, -Wno-name, -Wall, -Werror, -w), and a limit on
// the errors of one run (-fmax-errors=N).  Every reader and the project
// language report through it; a reader that recovers from an error goes on
// and reports the next one.
#pragma once

#include <functional>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "ir/ir.h"

namespace ldc {

enum class Severity { Note, Warning, Error };

// A warning ldc knows: its -W name, whether it is on without -Wall, and
// what it is about (ldc --help and docs/diagnostics.md list them).
struct WarningInfo {
  const char* name;
  bool by_default;
  const char* about;
};
const std::vector<WarningInfo>& warning_table();

// The options that choose what is reported (the command line's -W..., -w,
// -fmax-errors=N).
struct DiagOptions {
  bool all = false;     // -Wall
  bool werror = false;  // -Werror: every warning is an error
  bool silent = false;  // -w: no warnings at all
  int max_errors = 20;  // -fmax-errors=N; 0: no limit
  std::map<std::string, bool> chosen;        // -Wname / -Wno-name, by name
  std::map<std::string, bool> chosen_error;  // -Werror=name / -Wno-error=name
  bool enabled(std::string_view name) const;
  bool is_error(std::string_view name) const;  // reported as an error (-Werror)
  // One command-line argument: nullopt if it is not a diagnostics option,
  // "" if it was taken, else why it is wrong ("unknown warning option ...").
  std::optional<std::string> parse(std::string_view arg);
};

// The other place an error or warning is about (clang's `note:`).
struct DiagNote {
  int line = 0, col = 0;
  std::string message;
};

// A CompileError that points at a second place too: a reader throws it
// where the message alone would leave the user looking for the other end.
struct NotedError : CompileError {
  std::vector<DiagNote> notes;
  NotedError(int l, int c, const std::string& m, std::vector<DiagNote> n)
      : CompileError(l, c, m), notes(std::move(n)) {}
};

// Thrown once the errors of a run are reported (they are in
// Diagnostics::text()): a reader that went on past its first error ends
// with it, and so does the run that reached -fmax-errors.
struct ErrorsReported : std::runtime_error {
  ErrorsReported() : std::runtime_error("errors reported") {}
};

class Diagnostics {
 public:
  explicit Diagnostics(DiagOptions o = {}) : opt_(std::move(o)) {}
  const DiagOptions& options() const { return opt_; }
  // The text of `file` that its diagnostics quote (kept by the caller).
  void source(const std::string& file, std::string_view text) { texts_[file] = text; }
  // ... no longer kept (its diagnostics from here on quote no source line).
  void forget(const std::string& file) { texts_.erase(file); }

  // An error; throws ErrorsReported when it is the -fmax-errors'th.
  void error(const std::string& file, int line, int col, const std::string& msg);
  // A reader's CompileError (with its notes, if it is a NotedError).
  void error(const std::string& file, const CompileError& e);
  // Warning `name` if it is enabled (false if not: its notes are then
  // dropped too); with -Werror it is an error.
  bool warning(const char* name, const std::string& file, int line, int col, const std::string& msg);
  bool wants(const char* name) const { return opt_.enabled(name); }
  // A note on the last error or warning (dropped with it).
  void note(const std::string& file, int line, int col, const std::string& msg);

  int errors() const { return errors_; }
  int warnings() const { return warnings_; }
  // Everything reported so far, formatted.
  const std::string& text() const { return out_; }
  // Throws ErrorsReported if an error was reported.
  void check() const {
    if (errors_) throw ErrorsReported();
  }

 private:
  DiagOptions opt_;
  std::map<std::string, std::string_view> texts_;
  std::string out_;
  int errors_ = 0, warnings_ = 0;
  bool dropping_ = false;  // the last warning was not reported: nor are its notes
  void emit(Severity s, const std::string& file, int line, int col, const std::string& msg);
  void count_error();
};

// Error recovery's two exceptions (docs/diagnostics.md, "Errors"): a
// Cascade follows from an error already reported -- its unit is refused and
// nothing more is said (only recovery reaches one: without it the first error
// ends the reading); a Stop is an error after which nothing more can be read
// (a limit of the whole program) -- it ends the reading with recovery too.
struct Cascade : CompileError {
  Cascade() : CompileError(0, 0, "follows from an error reported") {}
};
struct Stop : CompileError {
  using CompileError::CompileError;
};

// Reads one unit (a line, a declaration, a statement, a rung) of a reader
// that recovers: without `diag` its error is thrown as before; with it an
// error is reported to `diag` as `file`'s and false returned, a Cascade
// returns false unreported, and a Stop goes on up.  `quiet`, if given, says
// after an error whether it follows from one reported already (not reported).
bool recover_unit(Diagnostics* diag, const std::string& file, const std::function<void()>& read,
                  const std::function<bool()>& quiet = nullptr);

// "file:line:col: KIND: message", the source line (from `text`) and a caret
// under the column; only the first line when the line is not in the text.
std::string format_diagnostic(const std::string& file, std::string_view text, int line, int col, Severity s,
                              const std::string& message);

// Damerau-Levenshtein distance (adjacent transpositions count 1), ASCII
// case-insensitive.
size_t edit_distance(std::string_view a, std::string_view b);
// The name of `names` nearest to `word` within an edit distance of 2 (1 for
// names of up to 3 characters; the first of equals wins), "" for none; a name
// equal to `word` apart from case is not a suggestion.
std::string closest_name(std::string_view word, const std::vector<std::string>& names);
// "; did you mean 'NAME'?" for closest_name, else "".
std::string did_you_mean(std::string_view word, const std::vector<std::string>& names);

}  // namespace ldc
