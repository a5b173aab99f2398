// driver/driver.cpp -- shared by the executables.
#include "driver/driver.h"

#include <dirent.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdlib>
#include <cstdio>
#include <cstring>
#include <memory>

#include "backend-c/backend_c.h"
#include "backend-c/c_shared.h"
#include "driver/project.h"
#include "driver/targets.h"
#include "frontend/frontend.h"

namespace ldc {

// In large pieces straight into the string, sized up front for a regular
// file (a stream copy, `ss << f.rdbuf()`, went through two buffers).
std::string read_file(const std::string& path) {
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!f) throw UserError(path + ": error: cannot open: " + std::strerror(errno));
  std::string text;
  struct stat st;
  if (fstat(fileno(f.get()), &st) == 0 && S_ISREG(st.st_mode)) text.reserve(size_t(st.st_size));
  char buf[1 << 16];
  for (size_t n; (n = std::fread(buf, 1, sizeof buf, f.get())) > 0;) text.append(buf, n);
  if (std::ferror(f.get())) throw UserError(path + ": error: cannot read");
  return text;
}

void write_file_atomic(const std::string& path, std::string_view data) {
  write_file_atomic(path, [&](std::FILE* f) { return std::fwrite(data.data(), 1, data.size(), f) == data.size(); });
}

// A device or a pipe (`-o /dev/null`, `/dev/stdout`, a FIFO) is written in
// place: a rename would replace it with a regular file (and, for root, /dev/null).
// The bytes go to an anonymous temporary file first (the image writer seeks
// back to its checksum, which a pipe cannot), then are copied.
static void write_in_place(const std::string& path, const std::function<bool(std::FILE*)>& write) {
  std::unique_ptr<FILE, int (*)(FILE*)> t(std::tmpfile(), &std::fclose);
  if (!t) throw UserError(path + ": error: cannot create a temporary file: " + std::strerror(errno));
  if (!write(t.get()) || std::ferror(t.get()) || std::fflush(t.get()) != 0)
    throw UserError(path + ": error: cannot write: " + std::strerror(errno));
  std::rewind(t.get());
  FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) throw UserError(path + ": error: cannot open: " + std::strerror(errno));
  char buf[1 << 16];
  bool ok = true;
  for (size_t n; ok && (n = std::fread(buf, 1, sizeof buf, t.get())) > 0;) ok = std::fwrite(buf, 1, n, f) == n;
  ok = ok && !std::ferror(t.get());
  ok &= std::fclose(f) == 0;
  if (!ok) throw UserError(path + ": error: cannot write: " + std::strerror(errno));
}

void write_file_atomic(const std::string& path, const std::function<bool(std::FILE*)>& write) {
  struct stat st;
  if (::stat(path.c_str(), &st) == 0 && !S_ISREG(st.st_mode) && !S_ISDIR(st.st_mode)) return write_in_place(path, write);
  std::string tmp = path + ".tmp." + std::to_string(getpid());
  FILE* f = std::fopen(tmp.c_str(), "wb");
  if (!f) throw UserError(path + ": error: cannot create: " + std::strerror(errno));
  bool ok;
  try {
    ok = write(f) && !std::ferror(f);
  } catch (...) {
    std::fclose(f);
    std::remove(tmp.c_str());
    throw;
  }
  ok &= std::fflush(f) == 0;
  ok &= std::fclose(f) == 0;
  if (!ok || std::rename(tmp.c_str(), path.c_str()) != 0) {
    int e = errno;
    std::remove(tmp.c_str());
    throw UserError(path + ": error: cannot write: " + std::strerror(e));
  }
}

static bool ends_with(const std::string& s, const std::string& suf) {
  return s.size() >= suf.size() && s.compare(s.size() - suf.size(), suf.size(), suf) == 0;
}

namespace {

// A PLCopen program: its rungs, then its chart (docs/plcopen.md, section 1b),
// q's edge slots after p's.
void append_il(Program& p, Program q) {
  if (!q.rungs.empty()) {
    auto& l = q.rungs[0].labels;
    l.insert(l.begin(), p.end_labels.begin(), p.end_labels.end());
    p.end_labels.clear();
  }
  append_rungs(p, q);
  p.end_labels.insert(p.end_labels.end(), q.end_labels.begin(), q.end_labels.end());
  for (const Alias& a : q.aliases) {
    bool dup = false;
    for (const Alias& b : p.aliases) dup |= same_name(a.name, b.name);
    if (!dup) p.aliases.push_back(a);
  }
}

Program plcopen_il(const TreeProgram& tree, const std::optional<PlcopenChart>& chart) {
  Program p = lower_to_il(tree);
  if (!chart) return p;
  if (chart->chart.edge_slots) throw std::logic_error("a PLCopen chart with edge slots");
  append_il(p, lower_chart(chart->chart));
  if (!chart->after.rungs.empty()) append_il(p, lower_to_il(chart->after));
  return p;
}

// A PLCopen configuration of several tasks as a project: each task's program
// compiled already, on the processor of its resource.
std::shared_ptr<Project> plcopen_project(PlcopenImport& im, const std::string& path, const std::string& text) {
  auto p = std::make_shared<Project>();
  p->path = path;
  p->text = text;
  size_t slash = path.rfind('/');
  p->dir = slash == std::string::npos ? "" : path.substr(0, slash);
  std::string base = slash == std::string::npos ? path : path.substr(slash + 1);
  p->name = is_project_name(im.configuration) ? im.configuration : "configuration";
  for (PlcopenTask& t : im.tasks) {
    auto fail = [&](const std::string& m) { return CompileError(t.line, t.col, m); };
    if (!is_project_name(t.name)) throw fail("task name '" + t.name + "' is not a name ldc's projects take (letters, digits and _)");
    if (!is_project_name(t.program)) throw fail("program name '" + t.program + "' is not a name ldc's projects take (letters, digits and _)");
    if (!is_project_name(t.resource)) throw fail("resource name '" + t.resource + "' is not a name ldc's projects take (letters, digits and _)");
    if (t.resource_index > 255) throw fail("more than 256 resources (ldc has processors 0..255)");
    for (const ProjectTask& o : p->tasks) {
      if (same_name(o.name, t.name)) throw fail("a second task named '" + t.name + "' (ldc's task names are unique in a project)");
      if (same_name(o.program, t.program)) throw fail("a second program named '" + t.program + "' (in task '" + o.name + "')");
    }
    ProjectTask pt;
    pt.name = t.name, pt.resource = t.resource, pt.processor = t.resource_index;
    pt.period_us = t.period_us, pt.priority = t.priority;
    pt.program = t.program, pt.path = path, pt.file = base;
    pt.line = t.line, pt.col = t.col;
    pt.il = std::make_shared<const Program>(plcopen_il(t.tree, t.chart));
    p->tasks.push_back(std::move(pt));
  }
  return p;
}

// A configuration of several tasks (PLCopen or ST): the project, or with
// --task one task's program.
void configuration(Compiled& c, PlcopenImport& im, const std::string& path, const std::string& text, bool allow_project, const std::string& task) {
  if (!task.empty()) {
    auto p = plcopen_project(im, path, text);
    std::string names;
    for (size_t i = 0; i < p->tasks.size(); i++) {
      names += (i ? ", " : "") + p->tasks[i].name;
      if (same_name(p->tasks[i].name, task)) {
        c.tree = std::move(im.tasks[i].tree);
        c.il = *p->tasks[i].il;
        return;
      }
    }
    throw UserError(path + ": error: no task '" + task + "' in the configuration (" + names + ")");
  }
  if (allow_project) {
    c.project = plcopen_project(im, path, text);
    return;
  }
  std::string names;
  for (const PlcopenTask& t : im.tasks) names += (names.empty() ? "" : ", ") + t.name;
  throw CompileError(im.tasks[0].line, im.tasks[0].col,
                     "the configuration has " + std::to_string(im.tasks.size()) + " tasks (" + names +
                         "), one program each: `ldc FILE -o DIR` writes their images and project, `ldrun FILE --io=...` runs them, "
                         "`ldc FILE --task NAME` compiles one");
}

}  // namespace

// Everything `d` reported since `from` (its text), as the UserError the tools print.
static UserError reported(const Diagnostics& d, size_t from) {
  std::string msg = d.text().substr(from);
  if (!msg.empty() && msg.back() == '\n') msg.pop_back();
  return UserError(msg);
}

Compiled compile_source(const std::string& path, bool allow_project, const std::string& task, bool keep_tree,
                        Diagnostics* diag) {
  if (!task.empty() && !ends_with(path, ".xml") && !ends_with(path, ".st"))
    throw UserError(path + ": error: --task is for a configuration of several tasks (PLCopen XML or ST)");
  std::string text = read_file(path);
  DiagOptions quiet;
  quiet.silent = true;
  Diagnostics local(quiet);
  Diagnostics& d = diag ? *diag : local;
  d.source(path, text);
  struct Forget {  // `text` dies with this call: d must not quote it later
    Diagnostics& d;
    const std::string& path;
    ~Forget() { d.forget(path); }
  } forget{d, path};
  size_t from = d.text().size();
  int errors0 = d.errors();
  bool ladder = false;  // a ladder program: the ladder warnings apply
  bool ldmicro = false;
  bool named_only = false;  // the ladder warnings of the devices the file names only (an importer's own relays are not)
  Compiled c;
  try {
    if (ends_with(path, ".il")) {
      if (looks_like_ldc_il(text)) {
        c.il = parse_il_text(text, path, [&](const CompileError& e) { d.error(path, e); });
        if (d.errors() > errors0) throw ErrorsReported();  // errors were reported: the program read is not one
      } else {
        c.il = parse_iec_il(text, path, d);
      }
    } else if (ends_with(path, ".st")) {
      PlcopenImport im = import_st(text, path, d);
      if (im.tasks.empty() && !task.empty()) throw UserError(path + ": error: --task " + task + ": the file has one program, not a configuration of several tasks");
      if (im.tasks.empty()) c.il = lower_to_il(im.single);
      else configuration(c, im, path, text, allow_project, task);
    } else if (ends_with(path, ".sfc")) {
      c.chart = parse_sfc(text, path, d);
      c.il = lower_chart(*c.chart);
    } else if (text.compare(text.compare(0, 3, "\xEF\xBB\xBF") ? 0 : 3, 7, "LDmicro") == 0) {
      c.from_ld = ladder = ldmicro = true;
      c.tree = parse_ldmicro(text, path, d);
      c.il = lower_to_il(c.tree);
    } else if (ends_with(path, ".rtsp")) {
      c.from_ld = true;
      c.tree = parse_rtsp(text, path, d);
      c.il = lower_to_il(c.tree);
    } else if (ends_with(path, ".xml")) {
      c.from_ld = true;
      PlcopenImport im = import_plcopen(text, path, d);
      if (im.tasks.empty() && !task.empty()) throw UserError(path + ": error: --task " + task + ": the file has one program, not a configuration of several tasks");
      if (im.tasks.empty()) {
        ladder = named_only = !im.single_chart;  // LD and FBD bodies: a chart's actions drive their variables from several steps
        c.tree = std::move(im.single);
        c.il = plcopen_il(c.tree, im.single_chart);
      } else {
        configuration(c, im, path, text, allow_project, task);
      }
    } else {
      c.from_ld = ladder = true;
      if (keep_tree) {
        c.tree = parse_ld(text, path, d);
        c.il = lower_to_il(c.tree);
      } else {
        c.il = parse_ld_to_il(text, path, d);
      }
    }
    if (ladder && !c.project) warn_ladder(c.il, d, ldmicro || named_only);
  } catch (CompileError& e) {
    try {
      d.error(path, e);
    } catch (ErrorsReported&) {  // -fmax-errors reached
    }
    throw reported(d, from);
  } catch (ErrorsReported&) {
    throw reported(d, from);
  }
  if (d.errors() > errors0) throw reported(d, from);  // a warning made an error by -Werror
  return c;
}

Image load_image_file(const std::string& path) {
  try {
    return read_image_file(path);
  } catch (const ImageError& e) {
    throw UserError(e.what());
  }
}

std::string make_temp_dir() {
  const char* t = std::getenv("TMPDIR");
  std::string tmpl = std::string(t && *t ? t : "/tmp") + "/ldc.XXXXXX";
  if (!mkdtemp(tmpl.data())) throw UserError(std::string("error: cannot create a temporary directory: ") + std::strerror(errno));
  return tmpl;
}

void remove_tree(const std::string& dir) {
  if (DIR* d = opendir(dir.c_str())) {
    while (dirent* e = readdir(d)) {
      std::string n = e->d_name;
      if (n != "." && n != "..") std::remove((dir + "/" + n).c_str());
    }
    closedir(d);
  }
  rmdir(dir.c_str());
}

std::string c_source(const Compiled& c) {
  try {
    return c.chart ? generate_sfc_c(*c.chart, c.il.layout()) : generate_c(c.il, c.il.layout());
  } catch (CompileError& e) {  // what the C route refuses, at its place in the source
    std::string msg = format_error(c.il.source, read_file(c.il.source), e.line, e.col, e.what());
    if (!msg.empty() && msg.back() == '\n') msg.pop_back();
    throw UserError(msg);
  }
}

std::string build_c_shared_object(const Compiled& c, const std::string& dir) {
  try {
    return build_c_text(c_source(c), dir);
  } catch (const CBuildError& e) {
    throw UserError(e.what());
  }
}

int run_tool(const char* tool, const std::function<int()>& work) {
  try {
    return work();
  } catch (const UserError& e) {
    std::fprintf(stderr, "%s\n", e.what());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: error: %s\n", tool, e.what());
  }
  return 1;
}

std::optional<int32_t> parse_period(const std::string& s) {
  std::optional<int64_t> us = parse_duration_us(s);
  if (!us || *us % 1000) return std::nullopt;  // whole milliseconds
  return int32_t(*us / 1000);
}

}  // namespace ldc
