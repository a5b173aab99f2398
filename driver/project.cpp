// driver/project.cpp -- the project file language (driver/project.h).
#include "driver/project.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <cstring>
#include <filesystem>
#include <functional>
#include <sys/stat.h>

#include "driver/driver.h"
#include "driver/targets.h"
#include "frontend/frontend.h"
#include "loader/config.h"

namespace ldc {

std::optional<int64_t> parse_duration_us(const std::string& s) {
  char* end = nullptr;
  errno = 0;
  long long v = std::strtoll(s.c_str(), &end, 10);
  if (end == s.c_str() || errno || v < 0 || !std::isdigit(static_cast<unsigned char>(s[0]))) return std::nullopt;
  std::string unit = end;
  long long mul = unit.empty() || unit == "ms" ? 1000 : unit == "us" ? 1 : unit == "s" ? 1000000 : -1;
  if (mul < 0 || v > (int64_t(1) << 31) / mul) return std::nullopt;
  return int64_t(v) * mul;
}

std::string duration_text(int64_t us) {
  if (us % 1000000 == 0 && us) return std::to_string(us / 1000000) + "s";
  if (us % 1000 == 0) return std::to_string(us / 1000) + "ms";
  return std::to_string(us) + "us";
}

std::string duration_problem(const std::string& s, int64_t min_us) {
  auto d = parse_duration_us(s);
  if (!d) return "'" + s + "' is not a duration (e.g. 500us, 10ms, 1s)";
  if (*d < min_us) return "'" + s + "' is below the minimum of " + duration_text(min_us);
  return "";
}

bool is_project_name(const std::string& s) {
  if (s.empty() || std::isdigit(static_cast<unsigned char>(s[0]))) return false;
  for (char c : s)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_') return false;
  return true;
}

namespace {

std::string lower(std::string s) {
  for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

}  // namespace

bool same_name(const std::string& a, const std::string& b) { return lower(a) == lower(b); }

// ---------------------------------------------------------------- reading

namespace {

struct Token {
  std::string text;
  int col;
};

std::vector<Token> split_words(std::string_view line) {
  std::vector<Token> t;
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r')) i++;
    if (i >= line.size() || line[i] == '#') break;
    size_t s = i;
    while (i < line.size() && line[i] != ' ' && line[i] != '\t' && line[i] != '\r') i++;
    t.push_back(Token{std::string(line.substr(s, i - s)), int(s) + 1});
  }
  return t;
}

std::string us_text(int64_t us) { return duration_text(us); }

// Reads a project file line by line: one member function per keyword, each
// reading the words `w` of the current line into the project `p`.
struct ProjectReader {
  Project& p;
  int line = 0;
  std::vector<Token> w;                // the current line's words
  std::string resource;                // the current resource
  uint32_t processor = 0;              // ... its processor
  std::vector<std::pair<uint32_t, std::string>> processors;
  bool in_task = false, task_has_program = false;
  int task_line = 0, task_col = 0;
  // Error recovery (docs/diagnostics.md): with `diag`, a wrong line is
  // reported and the next one read.  What follows from a refused line says
  // nothing: the tasks of a refused resource, the program of a refused task,
  // "no program" of a task whose program line was refused, "no task" when a
  // task line was refused.
  Diagnostics* diag = nullptr;
  bool resource_refused = false, task_refused = false;
  int task_lines = 0;                  // task lines read, refused ones too
  int program_lines = 0;               // ... program lines of the current task
  bool after_unknown = false;          // the line above had an unknown keyword (a lost resource or task line?)
  struct Quiet : CompileError {        // follows from an error reported: said nothing
    Quiet() : CompileError(0, 0, "follows from an error reported") {}
  };

  // Reading one line goes on past an error with `diag`; without, the first
  // error is thrown.
  void recover(const std::function<void()>& read) {
    if (!diag) return read();
    try {
      read();
    } catch (const Quiet&) {
    } catch (const CompileError& e) {
      diag->error(p.path, e);
    }
  }

  std::string resolve(const std::string& f) const {
    return f.empty() || f[0] == '/' || p.dir.empty() ? f : p.dir + "/" + f;
  }
  CompileError fail(int col, const std::string& msg) const { return CompileError(line, col, msg); }
  void need(size_t n, const char* form) const {
    if (w.size() < n) throw fail(w.back().col + int(w.back().text.size()), std::string("expected '") + form + "'");
  }
  void nothing_after(size_t n) const {
    if (w.size() > n) throw fail(w[n].col, "unexpected '" + w[n].text + "'");
  }
  std::string name_at(size_t i, const char* what) const {
    if (!is_project_name(w[i].text)) throw fail(w[i].col, std::string("bad ") + what + " name '" + w[i].text + "' (letters, digits and _)");
    return w[i].text;
  }
  uint32_t number_at(size_t i, const char* what, uint32_t max) const {
    const std::string& s = w[i].text;
    if (s.empty() || s.find_first_not_of("0123456789") != std::string::npos || s.size() > 9 || std::stoul(s) > max)
      throw fail(w[i].col, std::string("bad ") + what + " '" + s + "' (0.." + std::to_string(max) + ")");
    return uint32_t(std::stoul(s));
  }
  int64_t duration_at(size_t i, const char* what, int64_t min) const {
    std::string why = duration_problem(w[i].text, min);
    if (!why.empty()) throw fail(w[i].col, std::string("bad ") + what + ": " + why);
    return *parse_duration_us(w[i].text);
  }
  void end_task() {
    if (in_task && !task_has_program && program_lines == 0 && !task_refused)
      throw CompileError(task_line, task_col, "task '" + p.tasks.back().name + "' has no program (a task runs one program)");
  }

  void read_configuration() {
    need(2, "configuration NAME");
    if (!p.tasks.empty() || !resource.empty()) throw fail(w[0].col, "'configuration' comes before the first resource");
    p.name = name_at(1, "configuration");
    nothing_after(2);
  }
  void read_block() {
    need(2, "block N");
    if (!resource.empty()) throw fail(w[0].col, "'block' comes before the first resource");
    uint32_t b = number_at(1, "block size", kMaxBlockSize);
    if (b < 16 || b % 16) throw fail(w[1].col, "the block size is a multiple of 16 (16.." + std::to_string(kMaxBlockSize) + ")");
    p.block_size = b;
    nothing_after(2);
  }
  void read_retain() {
    need(2, "retain FILE [every DURATION]");
    p.retain_file_as_written = w[1].text;
    p.retain_file = resolve(w[1].text);
    if (w.size() > 2) {
      if (lower(w[2].text) != "every") throw fail(w[2].col, "expected 'every DURATION' after the file");
      need(4, "every DURATION");
      p.retain_every_us = duration_at(3, "save interval", 1000);
      nothing_after(4);
    }
  }
  void read_resource() {
    recover([&] { end_task(); });  // the task above's mistake, not this line's
    in_task = false;
    resource_refused = true;  // until the line is read
    resource = "?";           // its tasks do not ask for a resource
    need(4, "resource NAME processor N");
    resource = name_at(1, "resource");
    if (lower(w[2].text) != "processor") throw fail(w[2].col, "expected 'processor N'");
    processor = number_at(3, "processor number", 255);
    for (auto& [n, r] : processors) {
      if (r == resource) throw fail(w[1].col, "second resource named '" + resource + "'");
      if (n == processor) throw fail(w[3].col, "processor " + std::to_string(n) + " already belongs to resource '" + r + "'");
    }
    processors.emplace_back(processor, resource);
    resource_refused = false;
    nothing_after(4);
  }
  // period, priority, watchdog and exclusive after "task NAME"
  void task_attributes(ProjectTask& t) {
    bool have_period = false;
    for (size_t i = 2; i < w.size(); i++) {
      std::string k = lower(w[i].text);
      if (k == "exclusive") { t.exclusive = true; continue; }
      if (k != "period" && k != "priority" && k != "watchdog")
        throw fail(w[i].col, "unknown task attribute '" + w[i].text + "' (period, priority, watchdog, exclusive)");
      if (i + 1 >= w.size()) throw fail(w[i].col + int(w[i].text.size()), "'" + k + "' needs a value");
      if (k == "period") t.period_us = uint32_t(duration_at(i + 1, "period", 50)), have_period = true;
      else if (k == "priority") t.priority = number_at(i + 1, "priority", 99);
      else t.watchdog_us = uint32_t(duration_at(i + 1, "watchdog", 1));
      i++;
    }
    if (!have_period) throw fail(w[0].col, "task '" + t.name + "' needs 'period DURATION' (e.g. period 10ms)");
    if (t.period_us > 10000000) throw fail(w[0].col, "task period above 10 s");
  }
  void read_task() {
    recover([&] { end_task(); });
    task_lines++;
    in_task = true, task_refused = true, task_has_program = false, program_lines = 0;  // until the line is read
    if (resource.empty()) {
      resource = "?", resource_refused = true;  // said once: the next tasks are refused quietly
      if (after_unknown && diag) throw Quiet();  // the unknown line was the resource, most likely
      throw fail(w[0].col, "a task belongs to a resource: 'resource NAME processor N' first");
    }
    need(4, "task NAME period DURATION");
    ProjectTask t;
    t.name = name_at(1, "task");
    for (const ProjectTask& o : p.tasks)
      if (same_name(o.name, t.name)) throw fail(w[1].col, "second task named '" + t.name + "'");
    t.resource = resource;
    t.processor = processor;
    task_attributes(t);
    if (resource_refused) return;  // its resource was refused: so is the task, quietly
    p.tasks.push_back(t);
    task_refused = false, task_line = line, task_col = w[1].col;
  }
  void read_program() {
    if (!in_task && after_unknown && diag) {  // the unknown line was its task, most likely
      in_task = true, task_refused = true, task_lines++, program_lines = 1;
      throw Quiet();
    }
    if (!in_task) throw fail(w[0].col, "a program is bound to a task: 'task NAME period DURATION' first");
    program_lines++;  // a wrong program line is its task's program line still
    need(3, "program NAME FILE");
    if (task_has_program)
      throw fail(w[0].col, "task '" + p.tasks.back().name + "' already runs program '" + p.tasks.back().program +
                               "' (one program, one image per task)");
    if (task_refused) {  // the program of a refused task: its own mistakes only
      name_at(1, "program");
      nothing_after(3);
      return;
    }
    ProjectTask& t = p.tasks.back();
    t.program = name_at(1, "program");
    for (const ProjectTask& o : p.tasks)
      if (&o != &t && same_name(o.program, t.program)) throw fail(w[1].col, "second program named '" + t.program + "'");
    t.file = w[2].text;
    t.path = resolve(w[2].text);
    t.line = line, t.col = w[1].col;
    task_has_program = true;
    nothing_after(3);
  }

  void read_line(std::string_view l) {
    line++;
    w = split_words(l);
    if (w.empty()) return;
    recover([&] { read_words(); });
  }
  void read_words() {
    std::string kw = lower(w[0].text);
    bool unknown = kw != "configuration" && kw != "block" && kw != "retain" && kw != "resource" && kw != "task" && kw != "program";
    struct Note {  // after this line: whether its keyword was unknown
      bool& to;
      bool v;
      ~Note() { to = v; }
    } note{after_unknown, unknown};
    if (kw == "configuration") read_configuration();
    else if (kw == "block") read_block();
    else if (kw == "retain") read_retain();
    else if (kw == "resource") read_resource();
    else if (kw == "task") read_task();
    else if (kw == "program") read_program();
    else {
      if (in_task) program_lines++;  // in a task: its misspelled program line, most likely ("no program" is not said)
      throw fail(w[0].col, "unknown keyword '" + w[0].text + "' (configuration, block, retain, resource, task, program)");
    }
  }
  void read_all() {
    std::string_view text = p.text;
    size_t pos = 0;
    while (pos < text.size()) {
      size_t nl = text.find('\n', pos);
      read_line(text.substr(pos, nl == std::string_view::npos ? std::string_view::npos : nl - pos));
      pos = nl == std::string_view::npos ? text.size() : nl + 1;
    }
    recover([&] { end_task(); });
    if (task_lines == 0) {
      line = std::max(line, 1);
      recover([&] { throw fail(1, "the project has no task"); });
    }
  }
};

}  // namespace

static Project read_project(const std::string& path, Diagnostics* diag) {
  Project p;
  p.path = path;
  p.text = read_file(path);
  size_t slash = path.rfind('/');
  p.dir = slash == std::string::npos ? "" : path.substr(0, slash);
  std::string base = slash == std::string::npos ? path : path.substr(slash + 1);
  p.name = base.substr(0, base.rfind('.'));
  ProjectReader r{p};
  r.diag = diag;
  r.read_all();
  return p;
}

Project parse_project(const std::string& path) {
  try {
    return read_project(path, nullptr);
  } catch (const CompileError& e) {  // the first error, as "file:line:col: error: ..." with its line and a caret
    std::string text = read_file(path);
    std::string m = format_error(path, text, e.line, e.col, e.what());
    if (!m.empty() && m.back() == '\n') m.pop_back();
    throw UserError(m);
  }
}

Project parse_project(const std::string& path, Diagnostics& diag) {
  size_t from = diag.text().size();
  int errors0 = diag.errors();
  std::optional<Project> p;
  std::string text = read_file(path);
  diag.source(path, text);
  try {
    p = read_project(path, &diag);
  } catch (const ErrorsReported&) {  // -fmax-errors reached
  }
  diag.forget(path);
  if (diag.errors() > errors0) {
    std::string m = diag.text().substr(from);
    if (!m.empty() && m.back() == '\n') m.pop_back();
    throw UserError(m);
  }
  return std::move(*p);
}

namespace {

// The project's retentive file as a path from `outdir`: the same file the
// project's own `retain` line names (relative to the project's folder).
std::string retain_path_from(const Project& p, const std::string& outdir) {
  namespace fs = std::filesystem;
  const std::string& written = p.retain_file_as_written;
  if (written.empty() || written[0] == '/') return written;
  fs::path file = fs::absolute(p.retain_file).lexically_normal();
  fs::path rel = file.lexically_relative(fs::absolute(outdir.empty() ? "." : outdir).lexically_normal());
  std::string r = rel.empty() ? file.string() : rel.string();
  if (r.find_first_of(" \t#") != std::string::npos)
    throw UserError(p.path + ": error: the retentive file " + written + ", named from the output folder " + outdir + ", is " +
                    r + ", which a project line cannot hold (blanks or '#'); give 'retain' an absolute path without them");
  return r;
}

}  // namespace

std::string print_project(const Project& p, const std::vector<std::string>& files, const std::string& outdir) {
  std::string s = "# " + p.name + ": written by ldc --project from " + p.path + "\nconfiguration " + p.name + "\nblock " +
                  std::to_string(p.block_size) + "\n";
  if (!p.retain_file_as_written.empty()) {
    std::string r = retain_path_from(p, outdir);
    if (r != p.retain_file_as_written)
      s += "# the retentive file of " + p.path + " ('retain " + p.retain_file_as_written + "'), named from this folder\n";
    s += "retain " + r + " every " + us_text(p.retain_every_us) + "\n";
  }
  std::string res;
  for (size_t i = 0; i < p.tasks.size(); i++) {
    const ProjectTask& t = p.tasks[i];
    if (t.resource != res) s += "resource " + t.resource + " processor " + std::to_string(t.processor) + "\n", res = t.resource;
    s += "  task " + t.name + " period " + us_text(t.period_us) + " priority " + std::to_string(t.priority);
    if (t.watchdog_us) s += " watchdog " + us_text(t.watchdog_us);
    if (t.exclusive) s += " exclusive";
    s += "\n    program " + t.program + " " + files[i] + "\n";
  }
  return s;
}

namespace {

// Where each program's IL instructions come from, for messages.
struct ProgramSource {
  std::string file, text;           // source file and its text ("" for an image)
  std::vector<uint32_t> instr_offset;
  std::vector<SrcLoc> instr_loc;
  std::vector<LineEntry> lines;      // images: the line map
  bool image = false;
  std::string located(uint32_t il_offset, const std::string& msg) const {
    if (image) {
      int line = 0;
      for (const LineEntry& e : lines)
        if (e.il_offset == il_offset) line = e.line;
      return file + ": error: " + msg + " (IL offset " + std::to_string(il_offset) +
             (line ? ", source line " + std::to_string(line) : std::string()) + ")\n";
    }
    SrcLoc loc = where(il_offset);
    return format_error(file, text, loc.line, loc.col ? loc.col : 1, msg);
  }
  SrcLoc where(uint32_t il_offset) const {
    auto it = std::lower_bound(instr_offset.begin(), instr_offset.end(), il_offset);
    return it != instr_offset.end() && *it == il_offset ? instr_loc[it - instr_offset.begin()] : SrcLoc{};
  }
};

// A task's image (compiled, loaded or PLCopen's) and where its IL comes from.
BuiltTask build_task(const Project& p, const ProjectTask& t, ProgramSource& ps, Diagnostics* diag) {
  const Target& host = host_target();  // the soft PLC runs the tasks on this machine
  BuiltTask b{t, {}};
  ps.file = t.path;
  auto source_of = [&](const Program& il, std::string text) {
    ps.text = std::move(text);
    BinaryIl bin = encode_il(il);
    ps.instr_offset = bin.instr_offset;
    for (const Rung& r : il.rungs)
      for (const Instr& in : r.code) ps.instr_loc.push_back(in.loc.line ? in.loc : SrcLoc{r.line, 1});
  };
  if (t.il) {  // a PLCopen task, compiled with its configuration
    b.image = target_image(host, *t.il, t.path, 0);
    source_of(*t.il, p.text);
  } else if (is_image_file(t.path)) {
    b.image = load_image_file(t.path);
    if (b.image.target != host.image_kind) throw UserError(t.path + ": error: not " + std::string(host.an_image));
    b.image.config.reset();  // recomputed for this project
    ps.image = true;
    ps.lines = b.image.lines;
  } else {
    Compiled c = compile_source(t.path, false, "", false, diag);  // with diag: each program's own warnings
    b.image = target_image(host, c.il, t.path, 0);
    source_of(c.il, read_file(t.path));
  }
  return b;
}

ConfigTask config_task(const ProjectTask& t, const Image& image) {
  ConfigTask ct;
  ct.program = t.program, ct.task = t.name, ct.resource = t.resource;
  ct.processor = t.processor, ct.period_us = t.period_us, ct.priority = t.priority, ct.exclusive = t.exclusive;
  ct.accesses = io_accesses(image.il);
  return ct;
}

// One write conflict: the project line, then the writes of both programs.
std::string conflict_text(const Project& p, const WriteConflict& c, const std::vector<ProgramSource>& srcs) {
  constexpr size_t kMaxListed = 8;
  const ProjectTask &a = p.tasks[c.first], &b = p.tasks[c.second];
  std::string block = block_name(c.area, c.block, p.block_size);
  auto who = [](const ProjectTask& t) {
    return "program '" + t.program + "' (task " + t.name + ", processor " + std::to_string(t.processor) + ")";
  };
  std::string why = a.processor != b.processor ? "a block is written by one processor only"
                    : a.exclusive ? "task '" + a.name + "' is exclusive: no other task may write its blocks"
                                  : "task '" + b.name + "' is exclusive: no other task may write its blocks";
  std::string msg = format_error(p.path, p.text, b.line, b.col,
                                 "I/O block " + block + " is written by " + who(a) + " and by " + who(b) + "; " + why);
  for (int side = 0; side < 2; side++) {
    const ProjectTask& t = side ? b : a;
    const ProjectTask& other = side ? a : b;
    const auto& ws = side ? c.second_writes : c.first_writes;
    for (size_t i = 0; i < ws.size() && i < kMaxListed; i++)
      msg += srcs[side ? c.second : c.first].located(
          ws[i].il_offset, "'" + t.program + "' writes " + point_name(ws[i].area, ws[i].index) + " (block " + block +
                               ", also written by '" + other.program + "')");
    if (ws.size() > kMaxListed)
      msg += srcs[side ? c.second : c.first].file + ": note: and " + std::to_string(ws.size() - kMaxListed) +
             " more writes of '" + t.program + "' in block " + block + "\n";
  }
  return msg;
}

// -Wshared-output: a point of the shared image (Y M K WY) written by two
// programs of one processor.  The write-conflict check of paper 002 allows
// it (one processor writes the block), but the task that runs last in a
// cycle decides the point, so one program's write is lost.  At most
// kMaxListed points per pair of programs.
void warn_shared_outputs(const Project& p, const std::vector<ConfigTask>& cts, const std::vector<ProgramSource>& srcs,
                         Diagnostics& d) {
  constexpr int kMaxListed = 8;
  if (!d.wants("shared-output")) return;
  for (size_t i = 0; i < cts.size(); i++) {
    std::map<std::pair<Area, uint32_t>, uint32_t> first;  // point -> its first write's IL offset in task i
    for (const IoAccess& a : cts[i].accesses)
      if (a.write) first.emplace(std::make_pair(a.area, a.index), a.il_offset);
    for (size_t j = i + 1; j < cts.size(); j++) {
      if (cts[j].processor != cts[i].processor || srcs[i].image || srcs[j].image) continue;
      std::map<std::pair<Area, uint32_t>, bool> told;
      int listed = 0;
      for (const IoAccess& a : cts[j].accesses) {
        auto it = first.find({a.area, a.index});
        if (!a.write || it == first.end() || told[it->first] || listed >= kMaxListed) continue;
        told[it->first] = true;
        listed++;
        const ProjectTask &ta = p.tasks[i], &tb = p.tasks[j];
        SrcLoc at = srcs[j].where(a.il_offset), before = srcs[i].where(it->second);
        d.source(srcs[j].file, srcs[j].text);
        d.source(srcs[i].file, srcs[i].text);
        if (d.warning("shared-output", srcs[j].file, at.line, at.col ? at.col : 1,
                      "'" + tb.program + "' (task " + tb.name + ") writes " + point_name(a.area, a.index) + ", which '" +
                          ta.program + "' (task " + ta.name + ") writes too, on the same processor " +
                          std::to_string(ta.processor) + ": the task that runs last decides it"))
          d.note(srcs[i].file, before.line, before.col ? before.col : 1, "'" + ta.program + "' writes it here");
      }
    }
  }
  for (const ProgramSource& ps : srcs) d.forget(ps.file);
}

}  // namespace

std::vector<BuiltTask> build_project(const Project& p, Diagnostics* diag) {
  std::vector<BuiltTask> built;
  std::vector<ProgramSource> srcs;
  std::vector<ConfigTask> cts;
  for (const ProjectTask& t : p.tasks) {
    ProgramSource ps;
    built.push_back(build_task(p, t, ps, diag));
    cts.push_back(config_task(t, built.back().image));
    srcs.push_back(std::move(ps));
  }
  SystemConfig sc = configure(cts, p.block_size);
  if (!sc.conflicts.empty()) {
    std::string msg;
    for (const WriteConflict& c : sc.conflicts) msg += conflict_text(p, c, srcs);
    msg += p.path + ": error: " + std::to_string(sc.conflicts.size()) + " I/O write conflict" +
           (sc.conflicts.size() == 1 ? "" : "s") + "; the project is refused";
    throw UserError(msg);
  }
  if (diag) {
    warn_shared_outputs(p, cts, srcs, *diag);
    if (diag->errors()) throw UserError(diag->text().substr(0, diag->text().size() - 1));  // -Werror
  }
  for (size_t i = 0; i < built.size(); i++) built[i].image.config = sc.per_task[i];
  return built;
}

void check_project_output(const Project& p, const std::string& outdir, bool task_option) {
  auto ends = [&](const char* e) {
    size_t n = std::strlen(e);
    return outdir.size() >= n && same_name(outdir.substr(outdir.size() - n), e);
  };
  // DIR/NAME.ldp must not be the project file being read (ldc --project p.ldp -o .)
  std::error_code ec;
  const std::filesystem::path written = std::filesystem::path(outdir) / (p.name + ".ldp");
  if (std::filesystem::equivalent(written, p.path, ec))
    throw UserError("ldc: error: -o " + outdir + " would write " + written.string() + " over the project file " + p.path +
                    " itself: give -o another folder (-o build/" + p.name + ")");
  struct stat st;
  bool not_folder = ::stat(outdir.c_str(), &st) == 0 && !S_ISDIR(st.st_mode);
  if (!ends(".bin") && !ends(".hex") && !not_folder) return;
  std::string tasks = std::to_string(p.tasks.size()) + " task" + (p.tasks.size() == 1 ? "" : "s");
  throw UserError("ldc: error: -o " + outdir + (not_folder ? " is a file" : " names an image") + ", but " + p.path +
                  " is a project of " + tasks + ", written as a folder (DIR/TASK.bin for each task and DIR/" + p.name +
                  ".ldp): give -o a folder (-o build/" + p.name + ")" +
                  (task_option ? ", or --task NAME -o " + outdir + " for one task's image" : ""));
}

std::string print_configuration(const Project& p, const std::vector<BuiltTask>& built) {
  std::string s = "configuration " + p.name + ": " + std::to_string(built.size()) + " task" +
                  (built.size() == 1 ? "" : "s") + ", I/O blocks of " + std::to_string(p.block_size) + " points\n";
  auto flags_text = [](uint8_t f) {
    std::string t;
    if (f & kBlockRead) t += " read";
    if (f & kBlockWrite) t += " write";
    return t;
  };
  for (const BuiltTask& b : built) {
    const IoConfig& c = *b.image.config;
    s += "task " + c.task + " (resource " + c.resource + ", processor " + std::to_string(c.processor) + ", period " +
         us_text(c.period_us) + ", priority " + std::to_string(c.priority) + "): program " + c.program + "\n";
    for (const ConfigRow& r : c.rows)
      if (r.flags & (kBlockRead | kBlockWrite)) s += "  " + block_name(r.area, r.block, c.block_size) + flags_text(r.flags) + "\n";
  }
  s += "system table (block, writing processor, refresh period, users):\n";
  const IoConfig& c0 = *built.front().image.config;
  for (size_t i = 0; i < c0.rows.size(); i++) {
    const ConfigRow& r = c0.rows[i];
    std::string users;
    for (const BuiltTask& b : built)
      if (b.image.config->rows[i].flags & (kBlockRead | kBlockWrite))
        users += " " + b.spec.name + (b.image.config->rows[i].flags & kBlockWrite ? "(w)" : "");
    char line[160];
    std::snprintf(line, sizeof line, "  %-16s %-6s %-8s", block_name(r.area, r.block, c0.block_size).c_str(),
                  r.writer == kNoProcessor ? "-" : std::to_string(r.writer).c_str(), us_text(r.period_us).c_str());
    s += line + users + "\n";
  }
  return s;
}

}  // namespace ldc
