// driver/project.h -- the project file (docs/runtime.md): an IEC 61131-3
// configuration of resources (processors), tasks (period, priority) and
// programs bound to them; reading and printing it, building its images with
// the configuration system of paper 002, and the system-level table.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "frontend/diag.h"
#include "ir/ir.h"
#include "loader/loader.h"

namespace ldc {

// "500us", "10ms", "10" (ms), "2s" -> microseconds; nullopt if malformed
// or above 2^31 us.
std::optional<int64_t> parse_duration_us(const std::string& s);
// A duration as it is best written: "50us", "10ms", "2s".
std::string duration_text(int64_t us);
// Why `s` is not a duration of at least `min_us`, or "" if it is one: "'10us'
// is below the minimum of 50us", or "'5q' is not a duration (e.g. 500us, 10ms, 1s)".
std::string duration_problem(const std::string& s, int64_t min_us);

// Names of configurations, resources, tasks and programs: letters, digits and
// _, not starting with a digit; compared without case (same_name).
bool is_project_name(const std::string& s);
bool same_name(const std::string& a, const std::string& b);

struct ProjectTask {
  std::string name;                // task name
  std::string resource;            // resource name
  uint32_t processor = 0;          // the resource's processor number
  uint32_t period_us = 0;
  uint32_t priority = 0;           // 0 highest
  uint32_t watchdog_us = 0;        // 0: the runtime's default
  bool exclusive = false;          // no other task may write its I/O blocks
  std::string program;             // program name
  std::string file;                // program file as written in the project
  std::string path;                // ... resolved against the project's directory
  int line = 0, col = 0;           // where the program is bound (for messages)
  std::shared_ptr<const Program> il;  // compiled already (a PLCopen task), else compile `path`
};
struct Project {
  std::string path, dir, name;     // project file, its directory ("" = cwd), configuration name
  std::string text;                // the project file, for messages
  uint32_t block_size = 16;        // points per I/O block
  std::string retain_file;         // resolved against dir; "" if none
  std::string retain_file_as_written;
  int64_t retain_every_us = 1000000;
  std::vector<ProjectTask> tasks;
};
// Reads a project file; errors are UserError "file:line:col: error: ..." with a caret.
Project parse_project(const std::string& path);
// ... with error recovery (docs/diagnostics.md): every wrong line is reported
// to `diag` and the next one read; a project with errors is a UserError with
// every error `diag` reported (up to -fmax-errors).
Project parse_project(const std::string& path, Diagnostics& diag);
// The project file text for a project (canonical form; programs as given in `files`, one per task),
// to be written into the folder `outdir` ("" = the current one): its `retain` line names the
// project's retentive file as seen from there, so the written project keeps the same retentive
// memory (an absolute path stays as written).
std::string print_project(const Project& p, const std::vector<std::string>& files, const std::string& outdir = "");

struct BuiltTask {
  ProjectTask spec;
  Image image;  // an image of the host target (x86-64) with its 'config' section
};
// Compiles (sources) or loads (images) every program, runs the configuration
// system of paper 002 and attaches each image's 'config' section.  A write
// conflict is a UserError listing every conflict: the project line, then every
// writing element as "file:line:col: error: ..." with its source line and a caret.
// With `diag`, the project's warnings (-Wshared-output, docs/diagnostics.md)
// go there; one made an error by -Werror is thrown as a UserError with them.
std::vector<BuiltTask> build_project(const Project& p, Diagnostics* diag = nullptr);
// `ldc ... -o DIR` for a project writes a folder: DIR/TASK.bin per task and
// DIR/NAME.ldp.  A DIR that names an image (ends in .bin or .hex) or an existing
// file that is not a folder is refused with a UserError saying what -o takes
// (and, with `task_option`, that --task NAME compiles one task's image).
void check_project_output(const Project& p, const std::string& outdir, bool task_option);
// The system-level table as text (ldc --project without -o).
std::string print_configuration(const Project& p, const std::vector<BuiltTask>& built);

}  // namespace ldc
