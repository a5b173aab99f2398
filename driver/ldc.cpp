// ldc -- the ladder compiler.  The pipeline, one pass after another:
//   source --parse--> rung trees --lower--> IL --(backend, assembler, loader)--> image
#include <sys/stat.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "backend-c/backend_c.h"
#include "driver/driver.h"
#include "driver/project.h"
#include "driver/targets.h"
#include "driver/x86_target.h"
#include "frontend/frontend.h"
#include "ir/ladder.h"
#include "driver/version.h"

using namespace ldc;

static std::string usage() {
  std::string targets;
  for (const Target& t : ldc::targets()) targets += (targets.empty() ? "" : "|") + std::string(t.name);
  std::string warnings;
  for (const WarningInfo& w : warning_table())
    warnings += std::string("         -W") + w.name + (w.by_default ? " (on)" : " (-Wall)") + ": " + w.about + "\n";
  return "usage: ldc FILE [-o OUT] [--emit=tree|il|iec-il|ld|asm|listing|hex|c] [--target=" + targets + "] [-O0|-O1|-O2]\n"
         "       FILE: .ld (ladder grid, or LDmicro), .il (ldc IL, or IEC 61131-3 IL), .st (Structured Text), .xml (PLCopen TC6), .rtsp (the RTSP language of Y.-S. Kim), .sfc (SFC chart)\n"
         "       -O0 the macro templates of Kim, Chang and Kwon, -O1 peephole, -O2 bit stack in registers; for every target\n"
         "       --change-driven[=N]   x86-64: also regions of up to N rungs (default 8), each run only when what it\n"
         "                             reads or writes changed (docs/change-driven.md); recorded in the image\n"
         "       ldc --project PROJECT.ldp [-o DIR]   (check a project; with -o write DIR/TASK.bin and DIR/NAME.ldp)\n"
         "       ldc FILE.xml|FILE.st [-o DIR]   (a configuration of several tasks, PLCopen or ST, is a project, the same way)\n"
         "       ldc FILE.xml --task NAME ...   (one task's program of such a configuration)\n"
         "       ldc FILE   (no -o, no --emit: compile and check only; nothing is written, nothing said on success)\n"
         "       -o -   standard output (the image, or the --emit text; one program, not a project)\n"
         "       -fsyntax-only   read and check the source (errors and warnings), no code generated, nothing written\n"
         "       -Wall -Wname -Wno-name -Werror -Werror=name -w   warnings (docs/diagnostics.md):\n" + warnings +
         "       -fmax-errors=N   stop after N errors (default 20, 0: no limit)\n";
}

// ldc --project: compile every program of the project, run the configuration
// system of paper 002 (refusing write conflicts) and, with -o DIR, write one
// image per task with its 'config' section and the project file that runs them.
static int write_project(const Project& p, const std::string& outdir, Diagnostics& diag, bool syntax_only, bool task_option) {
  if (!outdir.empty() && !syntax_only) check_project_output(p, outdir, task_option);  // before any compiling
  std::vector<BuiltTask> built = build_project(p, &diag);
  std::fputs(diag.text().c_str(), stderr);  // the warnings (errors were thrown)
  if (syntax_only) return 0;
  if (outdir.empty()) {
    std::string t = print_configuration(p, built);
    std::fwrite(t.data(), 1, t.size(), stdout);
    return 0;
  }
  if (mkdir(outdir.c_str(), 0777) != 0 && errno != EEXIST)
    throw UserError("ldc: error: cannot create " + outdir + ": " + std::strerror(errno));
  std::vector<std::string> files;
  for (const BuiltTask& b : built) {
    std::vector<uint8_t> bin = write_image(b.image);
    files.push_back(b.spec.name + ".bin");
    write_file_atomic(outdir + "/" + files.back(), std::string_view(reinterpret_cast<const char*>(bin.data()), bin.size()));
  }
  write_file_atomic(outdir + "/" + p.name + ".ldp", print_project(p, files, outdir));
  return 0;
}

static int build_project_main(const std::string& project, const std::string& outdir, const DiagOptions& dopt,
                              bool syntax_only) {
  Diagnostics diag(dopt);
  return write_project(parse_project(project, diag), outdir, diag, syntax_only, false);
}

// n bytes on standard output (no -o, or -o -); a failed write is an error, not lost output
static int to_stdout(const void* p, size_t n, const std::string& what) {
  if (std::fwrite(p, 1, n, stdout) != n || std::fflush(stdout) != 0)
    throw UserError("ldc: error: cannot write " + what + " to standard output");
  return 0;
}

static int ldc_main(int argc, char** argv) {
  std::string input, output, emit, target(targets().front().name), project, task;
  int opt = 0;
  uint32_t change_rungs = 0;  // --change-driven: regions of up to this many rungs
  bool syntax_only = false;
  DiagOptions dopt;
  for (int i = 1; i < argc; i++) {
    std::string a = argv[i];
    if (auto why = dopt.parse(a)) {
      if (!why->empty()) { std::fprintf(stderr, "ldc: error: %s\n", why->c_str()); return 1; }
      continue;
    }
    if (a == "-fsyntax-only") syntax_only = true;
    else if (a == "-o" && i + 1 < argc) output = argv[++i];
    else if (a.rfind("--emit=", 0) == 0) emit = a.substr(7);
    else if (a.rfind("--target=", 0) == 0) target = a.substr(9);
    else if (a == "--project" && i + 1 < argc) project = argv[++i];
    else if (a.rfind("--project=", 0) == 0) project = a.substr(10);
    else if (a == "--task" && i + 1 < argc) task = argv[++i];
    else if (a.rfind("--task=", 0) == 0) task = a.substr(7);
    else if (a == "-O0" || a == "-O1" || a == "-O2") opt = a[2] - '0';
    else if (a == "--change-driven") change_rungs = 8;
    else if (a.rfind("--change-driven=", 0) == 0) {
      char* end = nullptr;
      const long n = std::strtol(a.c_str() + 16, &end, 10);
      if (*end || end == a.c_str() + 16 || n < 1 || n > 65536) {
        std::fprintf(stderr, "ldc: error: --change-driven=N takes a number of rungs from 1 to 65536, not '%s'\n", a.c_str() + 16);
        return 1;
      }
      change_rungs = uint32_t(n);
    }
    else if (a == "-h" || a == "--help") { std::fputs(usage().c_str(), stdout); return 0; }
    else if (a == "--version") return print_version("ldc");
    else if (!a.empty() && a[0] == '-') { std::fprintf(stderr, "ldc: error: unknown option '%s'\n%s", a.c_str(), usage().c_str()); return 1; }
    else if (input.empty()) input = a;
    else { std::fprintf(stderr, "ldc: error: more than one input file\n%s", usage().c_str()); return 1; }
  }
  if (change_rungs && (!project.empty() || (!emit.empty() && emit != "hex"))) {
    std::fprintf(stderr, "ldc: error: --change-driven makes an image: it goes with -o FILE.bin or --emit=hex, not with %s\n",
                 project.empty() ? ("--emit=" + emit).c_str() : "--project");
    return 1;
  }
  if (!project.empty()) {
    if (!input.empty() || !emit.empty() || !task.empty()) { std::fprintf(stderr, "ldc: error: --project takes no input file, --emit or --task\n%s", usage().c_str()); return 1; }
    return build_project_main(project, output, dopt, syntax_only);
  }
  if (input.empty()) { std::fprintf(stderr, "ldc: error: no input file\n%s", usage().c_str()); return 1; }
  const Target* t = find_target(target);
  if (!t) throw UserError("ldc: error: unknown target '" + target + "' (" + target_names() + ")");
  Diagnostics diag(dopt);
  Compiled c = compile_source(input, emit.empty() && t->host, task, emit == "tree", &diag);  // parse + lower
  if (c.project && output == "-")
    throw UserError("ldc: error: -o - (standard output) takes one program, but " + input + " is a project of " +
                    std::to_string(c.project->tasks.size()) + " tasks: give -o a folder, or --task NAME");
  if (c.project) {  // a PLCopen configuration of several tasks
    Diagnostics pdiag(dopt);  // the reader's warnings are printed with the project's
    std::fputs(diag.text().c_str(), stderr);
    return write_project(*c.project, output, pdiag, syntax_only, true);
  }
  std::fputs(diag.text().c_str(), stderr);  // the warnings (errors were thrown)
  if (syntax_only) return 0;
  if (emit.empty() || emit == "hex") c.tree = {};  // an image needs only the IL: free the tree before code generation
  std::string text;
  // a CompileError of a stage after the reader, shown at its place in the source
  auto at_source = [&](auto make) -> std::string {
    try {
      return make();
    } catch (CompileError& e) {
      std::string msg = format_error(input, read_file(input), e.line, e.col, e.what());
      if (!msg.empty() && msg.back() == '\n') msg.pop_back();
      throw UserError(msg);
    }
  };
  if (emit == "tree") {
    if (!c.from_ld) throw UserError("ldc: error: --emit=tree needs a .ld source");
    text = print_tree(c.tree);
  } else if (emit == "il") {
    text = print_il_text(c.il);
  } else if (emit == "ld") {                               // the ladder grid (docs/format.md)
    text = at_source([&] { return print_ladder(draw_ladder(raise_to_tree(c.il)), input); });
  } else if (emit == "iec-il") {                           // IEC 61131-3 IL
    text = print_iec_il(c.il);
  } else if (emit == "c") {                                   // the C route
    text = c_source(c);
  } else if (emit == "asm") {                              // macro compiler
    text = at_source([&] { return t->gnu_as(c.il, input, opt); });
  } else if (emit == "listing") {                          // + blockwise assembler
    text = at_source([&] { return t->listing(c.il, input, opt); });
  } else if (emit.empty() || emit == "hex") {              // + loader
    Image image;  // a backend's refusal (the C40's of a 64-bit type) at its place in the source
    at_source([&] { image = target_image(*t, c.il, input, opt); return std::string(); });
    if (change_rungs) {
      if (std::string(t->name) != "x86-64") throw UserError("ldc: error: --change-driven is for the x86-64 target, not " + std::string(t->name));
      image.regions = x86_region_table(c.il, change_rungs, opt);
    }
    if (emit == "hex") text = write_intel_hex(write_image(image));
    else {
      if (output.empty()) return 0;  // `ldc FILE`: compiled and checked, nothing written (docs/diagnostics.md)
      if (output == "-") {  // -o -: the image on standard output (made in memory: its checksum is not patched in place)
        const std::vector<uint8_t> bytes = write_image(image);
        return to_stdout(bytes.data(), bytes.size(), "the image");
      }
      // straight into the file: no copy of the image in memory
      write_file_atomic(output, [&](std::FILE* f) { return write_image_file(image, f) != 0; });
      return 0;
    }
  } else {
    throw UserError("ldc: error: " + (emit.empty() ? std::string("image output (-o FILE.bin)") : "--emit=" + emit) +
                    " is not available in this build (for this target)");
  }
  if (output.empty() || output == "-") return to_stdout(text.data(), text.size(), "the --emit=" + emit + " text");
  write_file_atomic(output, text);
  return 0;
}

int main(int argc, char** argv) {
  return run_tool("ldc", [&] { return ldc_main(argc, argv); });
}
