// driver/driver.h -- what the ldc, ldrun and ldobjdump executables share:
// reading inputs, turning any accepted source into IL, and writing outputs
// without leaving a half-written file behind.
#pragma once

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "backend-x86/backend_x86.h"
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
void write_file_atomic(const std::string& path, const std::string& data);  // throws UserError

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
Compiled compile_source(const std::string& path, bool allow_project = false, const std::string& task = "");

// The x86-64 route: macro compiler then the blockwise assembler.  Assembly
// errors become UserError with the rung's source line.  Without notes (an
// image) in Mode::Blockwise the blocks are streamed: each is assembled as soon
// as it is generated and dropped (as::Assembler), so gen.program holds only the
// global names; with notes (listings, --emit=asm) it holds every block.
struct NativeBuild {
  X86Code gen;
  as::Result asm_result;
};
NativeBuild build_x86(const Program& p, const std::string& source_name, as::Mode mode = as::Mode::Blockwise,
                      int opt_level = 0, bool notes = true);

// The image ldc writes for the x86-64 target: code, binary IL, line map, names.
Image make_x86_image(const Program& p, const NativeBuild& nb);
// An image's retentive ranges for p: the K area, then p's .retain words
// (docs/image-format.md, section 6), adjacent words joined into one range.

// Reads an image file (binary, or Intel HEX by its first character) and checks
// it fully; errors are UserError naming the file and the place.
Image load_image_file(const std::string& path);
// True for files ldrun treats as an image: *.bin, *.hex, or the image magic.
bool is_image_file(const std::string& path);

// The C route: writes `ldc --emit=c` to DIR/prog.c and compiles it with the
// system C compiler (${CC:-cc} -O2 -shared -fPIC) into DIR/prog.so; returns its path.
std::string build_c_shared_object(const Program& p, const std::string& dir);
// `ldc --emit=c` of a source: the SFC switch form for a chart, else the C route.
std::string c_source(const Compiled& c);
// ... of a compiled source (a chart as its switch form).
std::string build_c_shared_object(const Compiled& c, const std::string& dir);

// A fresh private directory under $TMPDIR (or /tmp), removed with remove_tree.
std::string make_temp_dir();
void remove_tree(const std::string& dir);

// "10ms", "10", "2s" -> ms; nullopt if malformed or not whole ms
// (parse_duration_us, below, reads it).
std::optional<int32_t> parse_period(const std::string& s);


// ---------------------------------------------------------------- projects
// The project file (docs/runtime.md): an IEC 61131-3 configuration of
// resources (processors), tasks (period, priority) and programs bound to them.

// "500us", "10ms", "10" (ms), "2s" -> microseconds; nullopt if malformed
// or above 2^31 us.
std::optional<int64_t> parse_duration_us(const std::string& s);

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
// The project file text for a project (canonical form; programs as given in `files`, one per task).
std::string print_project(const Project& p, const std::vector<std::string>& files);

struct BuiltTask {
  ProjectTask spec;
  Image image;  // x86-64 image with its 'config' section
};
// Compiles (sources) or loads (images) every program, runs the configuration
// system of paper 002 and attaches each image's 'config' section.  A write
// conflict is a UserError listing every conflict: the project line, then every
// writing element as "file:line:col: error: ..." with its source line and a caret.
std::vector<BuiltTask> build_project(const Project& p);
// The system-level table as text (ldc --project without -o).
std::string print_configuration(const Project& p, const std::vector<BuiltTask>& built);

}  // namespace ldc
