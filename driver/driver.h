// driver/driver.h -- what the ldc, ldrun and ldobjdump executables share:
// reading inputs, turning any accepted source into IL, and writing outputs
// without leaving a half-written file behind.
#pragma once

#include <cstdio>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "frontend/diag.h"
#include "ir/ir.h"
#include "loader/loader.h"

namespace ldc {

// Thrown for user errors; the message is printed as is, exit status 1.
struct UserError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// A tool's main: runs `work`; a UserError prints as it is, any other
// exception as "TOOL: error: ...", and either gives exit status 1.
int run_tool(const char* tool, const std::function<int()>& work);

std::string read_file(const std::string& path);  // throws UserError
// Writes to path.tmp.PID, then renames, so no half-written output is left.
void write_file_atomic(const std::string& path, std::string_view data);  // throws UserError
// The same, the bytes written by `write` (false: it could not write them);
// what it throws is thrown on, the file removed.
void write_file_atomic(const std::string& path, const std::function<bool(std::FILE*)>& write);

struct Project;
struct Compiled {
  TreeProgram tree;  // empty for IL input
  Program il;
  bool from_ld = false;
  std::optional<Chart> chart;  // a .sfc source (docs/sfc.md)
  std::shared_ptr<Project> project;  // a PLCopen configuration of several tasks
};
// .ld (grid) or .il (IL text): parse and lower.  Errors are formatted
// "file:line:col: error: ..." with the source line and a caret.
// A PLCopen configuration of several tasks is a project (one program per
// task, `project`) when allow_project is set, and an error otherwise.
// `task` picks one task's program of such a configuration (`--task NAME`).
// Without `keep_tree`, a .ld grid is lowered rung by rung as it is read
// (parse_ld_to_il) and `tree` stays empty: the whole tree never lives at once.
// With `diag`, the .ld reader reports every independent error (up to
// -fmax-errors) and a ladder program gets its warnings (docs/diagnostics.md):
// they stay in diag.text() for the caller to print; errors are thrown as a
// UserError holding everything reported.  Without, errors are reported the
// same way and no warnings are made.
Compiled compile_source(const std::string& path, bool allow_project = false, const std::string& task = "",
                        bool keep_tree = false, Diagnostics* diag = nullptr);

// read_image_file (loader.h) with its errors as UserError.
Image load_image_file(const std::string& path);

// `ldc --emit=c` of a source: the SFC switch form for a chart, else the C route.
std::string c_source(const Compiled& c);  // what the C route refuses: "file:line:col: error: ..."
// The C route's shared object of a compiled source (backend-c/c_shared.h:
// DIR/prog.c compiled into DIR/prog.so; returns its path), errors as UserError.
std::string build_c_shared_object(const Compiled& c, const std::string& dir);

// A fresh private directory under $TMPDIR (or /tmp), removed with remove_tree.
std::string make_temp_dir();
void remove_tree(const std::string& dir);

// "10ms", "10", "2s" -> ms; nullopt if malformed or not whole ms
// (parse_duration_us of driver/project.h reads it).
std::optional<int32_t> parse_period(const std::string& s);

}  // namespace ldc
