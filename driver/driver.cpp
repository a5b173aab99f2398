// driver/driver.cpp -- shared by the executables.
#include "driver/driver.h"

#include <dirent.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdlib>
#include <fcntl.h>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>

#include "backend-c/backend_c.h"
#include "frontend/frontend.h"

namespace ldc {

std::string read_file(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw UserError(path + ": error: cannot open: " + std::strerror(errno));
  std::ostringstream ss;
  ss << f.rdbuf();
  if (f.bad()) throw UserError(path + ": error: cannot read");
  return ss.str();
}

void write_file_atomic(const std::string& path, const std::string& data) {
  std::string tmp = path + ".tmp." + std::to_string(getpid());
  FILE* f = std::fopen(tmp.c_str(), "wb");
  if (!f) throw UserError(path + ": error: cannot create: " + std::strerror(errno));
  bool ok = std::fwrite(data.data(), 1, data.size(), f) == data.size();
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

bool is_name(const std::string& s) {
  if (s.empty() || std::isdigit(static_cast<unsigned char>(s[0]))) return false;
  for (char c : s)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_') return false;
  return true;
}

std::string lower(std::string s) {
  for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
}


// A PLCopen program: its rungs, then its chart (docs/plcopen.md, section 1b).
void append_il(Program& p, Program q) {
  if (!q.rungs.empty()) {
    auto& l = q.rungs[0].labels;
    l.insert(l.begin(), p.end_labels.begin(), p.end_labels.end());
    p.end_labels.clear();
  }
  for (Rung& r : q.rungs) p.rungs.push_back(std::move(r));
  p.end_labels.insert(p.end_labels.end(), q.end_labels.begin(), q.end_labels.end());
  for (const Alias& a : q.aliases) {
    bool dup = false;
    for (const Alias& b : p.aliases) dup |= lower(a.name) == lower(b.name);
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
  p->name = is_name(im.configuration) ? im.configuration : "configuration";
  for (PlcopenTask& t : im.tasks) {
    auto fail = [&](const std::string& m) { return CompileError(t.line, t.col, m); };
    if (!is_name(t.name)) throw fail("task name '" + t.name + "' is not a name ldc's projects take (letters, digits and _)");
    if (!is_name(t.program)) throw fail("program name '" + t.program + "' is not a name ldc's projects take (letters, digits and _)");
    if (!is_name(t.resource)) throw fail("resource name '" + t.resource + "' is not a name ldc's projects take (letters, digits and _)");
    if (t.resource_index > 255) throw fail("more than 256 resources (ldc has processors 0..255)");
    for (const ProjectTask& o : p->tasks) {
      if (lower(o.name) == lower(t.name)) throw fail("a second task named '" + t.name + "' (ldc's task names are unique in a project)");
      if (lower(o.program) == lower(t.program)) throw fail("a second program named '" + t.program + "' (in task '" + o.name + "')");
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

}  // namespace

Compiled compile_source(const std::string& path, bool allow_project, const std::string& task) {
  if (!task.empty() && !ends_with(path, ".xml")) throw UserError(path + ": error: --task is for a PLCopen configuration of several tasks");
  std::string text = read_file(path);
  Compiled c;
  try {
    if (ends_with(path, ".il")) {
      c.il = looks_like_ldc_il(text) ? parse_il_text(text, path) : parse_iec_il(text, path);
    } else if (ends_with(path, ".sfc")) {
      c.chart = parse_sfc(text, path);
      c.il = lower_chart(*c.chart);
    } else if (text.compare(text.compare(0, 3, "\xEF\xBB\xBF") ? 0 : 3, 7, "LDmicro") == 0) {
      c.from_ld = true;
      c.tree = parse_ldmicro(text, path);
      c.il = lower_to_il(c.tree);
    } else if (ends_with(path, ".rtsp")) {
      c.from_ld = true;
      c.tree = parse_rtsp(text, path);
      c.il = lower_to_il(c.tree);
    } else if (ends_with(path, ".xml")) {
      c.from_ld = true;
      PlcopenImport im = import_plcopen(text, path);
      if (!task.empty()) {
        if (im.tasks.empty()) throw UserError(path + ": error: --task " + task + ": the file has one program, not a configuration of several tasks");
        auto p = plcopen_project(im, path, text);
        std::string names;
        for (size_t i = 0; i < p->tasks.size(); i++) {
          names += (i ? ", " : "") + p->tasks[i].name;
          if (lower(p->tasks[i].name) == lower(task)) {
            c.tree = std::move(im.tasks[i].tree);
            c.il = *p->tasks[i].il;
            return c;
          }
        }
        throw UserError(path + ": error: no task '" + task + "' in the configuration (" + names + ")");
      } else if (im.tasks.empty()) {
        c.tree = std::move(im.single);
        c.il = plcopen_il(c.tree, im.single_chart);
      } else if (allow_project) {
        c.project = plcopen_project(im, path, text);
      } else {
        std::string names;
        for (const PlcopenTask& t : im.tasks) names += (names.empty() ? "" : ", ") + t.name;
        throw CompileError(im.tasks[0].line, im.tasks[0].col,
                           "the configuration has " + std::to_string(im.tasks.size()) + " tasks (" + names +
                               "), one program each: `ldc FILE -o DIR` writes their images and project, `ldrun FILE --io=...` runs them, "
                               "`ldc FILE --task NAME` compiles one");
      }
    } else {
      c.from_ld = true;
      c.tree = parse_ld(text, path);
      c.il = lower_to_il(c.tree);
    }
  } catch (CompileError& e) {
    std::string msg = format_error(path, text, e.line, e.col, e.what());
    if (!msg.empty() && msg.back() == '\n') msg.pop_back();
    throw UserError(msg);
  }
  return c;
}

NativeBuild build_x86(const Program& p, const std::string& source_name, as::Mode mode, int opt_level, bool notes) {
  NativeBuild b;
  if (mode == as::Mode::Blockwise && !notes) {  // an image: each block assembled as it is made, then dropped
    b.gen.program.globals = x86_globals(p);
    as::Assembler<as::x86::Instruction> a(as::x86::target(), b.gen.program.globals);
    b.gen.il_items = generate_x86_blocks(p, p.layout(), opt_level, false,
                                         [&](as::Block<as::x86::Instruction>& blk) { a.add(blk); });
    b.asm_result = a.finish();
  } else {
    b.gen = generate_x86(p, p.layout(), opt_level, notes);
    b.asm_result = as::assemble(as::x86::target(), b.gen.program, mode);
  }
  if (!b.asm_result.ok()) {
    std::string msg;
    for (const auto& e : b.asm_result.errors)
      msg += (msg.empty() ? "" : "\n") + source_name + ":" + std::to_string(e.line) + ":1: error: " + e.message;
    throw UserError(msg);
  }
  return b;
}

Image make_x86_image(const Program& p, const NativeBuild& nb) {
  return make_image(ImageTarget::X86_64, p, nb.asm_result, nb.gen.il_items);
}

bool is_image_file(const std::string& path) {
  if (ends_with(path, ".bin") || ends_with(path, ".hex")) return true;
  std::ifstream f(path, std::ios::binary);
  char magic[6] = {};
  f.read(magic, 6);
  return f.gcount() == 6 && std::string(magic, 6) == "LDCIMG";
}

Image load_image_file(const std::string& path) {
  std::string data = read_file(path);
  std::span<const uint8_t> bytes(reinterpret_cast<const uint8_t*>(data.data()), data.size());
  try {
    if (looks_like_intel_hex(bytes)) {
      std::vector<uint8_t> raw = read_intel_hex(data, path);
      return read_image(raw, path);
    }
    return read_image(bytes, path);
  } catch (ImageError& e) {
    std::string m = e.what();  // "prog.bin: section ...": make it "prog.bin: error: section ..."
    if (m.find(" error: ") == std::string::npos && m.rfind(path + ": ", 0) == 0)
      m = path + ": error: " + m.substr(path.size() + 2);
    throw UserError(m);
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

extern "C" char** environ;

std::string c_source(const Compiled& c) {
  return c.chart ? generate_sfc_c(*c.chart, c.il.layout()) : generate_c(c.il, c.il.layout());
}

static std::string build_c_text(const std::string& text, const std::string& dir);

std::string build_c_shared_object(const Program& p, const std::string& dir) {
  return build_c_text(generate_c(p, p.layout()), dir);
}

std::string build_c_shared_object(const Compiled& c, const std::string& dir) { return build_c_text(c_source(c), dir); }

static std::string build_c_text(const std::string& text, const std::string& dir) {
  std::string c = dir + "/prog.c", so = dir + "/prog.so", log = dir + "/cc.log";
  write_file_atomic(c, text);
  const char* cc_env = std::getenv("CC");
  std::string cc = cc_env && *cc_env ? cc_env : "cc";
  std::vector<std::string> args = {cc, "-O2", "-shared", "-fPIC", "-ffp-contract=off", "-o", so, c, "-lm"};
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&fa, 1, 2);
  pid_t pid;
  int rc = posix_spawnp(&pid, cc.c_str(), &fa, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&fa);
  if (rc != 0) throw UserError("error: cannot run the C compiler '" + cc + "': " + std::strerror(rc));
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {}
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    std::string out;
    try { out = read_file(log); } catch (...) {}
    throw UserError("error: the C compiler failed on the generated C (" + c + "):\n" + out);
  }
  return so;
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

// ---------------------------------------------------------------- projects

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

std::string us_text(int64_t us) {
  if (us % 1000000 == 0 && us) return std::to_string(us / 1000000) + "s";
  if (us % 1000 == 0) return std::to_string(us / 1000) + "ms";
  return std::to_string(us) + "us";
}

}  // namespace

Project parse_project(const std::string& path) {
  Project p;
  p.path = path;
  p.text = read_file(path);
  size_t slash = path.rfind('/');
  p.dir = slash == std::string::npos ? "" : path.substr(0, slash);
  std::string base = slash == std::string::npos ? path : path.substr(slash + 1);
  p.name = base.substr(0, base.rfind('.'));
  auto resolve = [&](const std::string& f) { return f.empty() || f[0] == '/' || p.dir.empty() ? f : p.dir + "/" + f; };
  int line = 0;
  auto fail = [&](int col, const std::string& msg) -> UserError {
    std::string m = format_error(path, p.text, line, col, msg);
    if (!m.empty() && m.back() == '\n') m.pop_back();
    return UserError(m);
  };
  std::string resource;
  uint32_t processor = 0;
  std::vector<std::pair<uint32_t, std::string>> processors;
  bool in_task = false, task_has_program = false;
  int task_line = 0, task_col = 0;
  std::string_view text = p.text;
  size_t pos = 0;
  auto end_task = [&]() {
    if (in_task && !task_has_program) {
      line = task_line;
      throw fail(task_col, "task '" + p.tasks.back().name + "' has no program (a task runs one program)");
    }
  };
  ProjectTask pending;
  while (pos < text.size()) {
    size_t nl = text.find('\n', pos);
    std::string_view l = text.substr(pos, nl == std::string_view::npos ? std::string_view::npos : nl - pos);
    pos = nl == std::string_view::npos ? text.size() : nl + 1;
    line++;
    std::vector<Token> w = split_words(l);
    if (w.empty()) continue;
    std::string kw = lower(w[0].text);
    auto need = [&](size_t n, const char* form) {
      if (w.size() < n) throw fail(w.back().col + int(w.back().text.size()), std::string("expected '") + form + "'");
    };
    auto name_at = [&](size_t i, const char* what) {
      if (!is_name(w[i].text)) throw fail(w[i].col, std::string("bad ") + what + " name '" + w[i].text + "' (letters, digits and _)");
      return w[i].text;
    };
    auto number_at = [&](size_t i, const char* what, uint32_t max) {
      const std::string& s = w[i].text;
      if (s.empty() || s.find_first_not_of("0123456789") != std::string::npos || s.size() > 9 || std::stoul(s) > max)
        throw fail(w[i].col, std::string("bad ") + what + " '" + s + "' (0.." + std::to_string(max) + ")");
      return uint32_t(std::stoul(s));
    };
    auto duration_at = [&](size_t i, const char* what, int64_t min) {
      auto d = parse_duration_us(w[i].text);
      if (!d || *d < min) throw fail(w[i].col, std::string("bad ") + what + " '" + w[i].text + "' (e.g. 500us, 10ms, 1s)");
      return *d;
    };
    if (kw == "configuration") {
      need(2, "configuration NAME");
      if (!p.tasks.empty() || !resource.empty()) throw fail(w[0].col, "'configuration' comes before the first resource");
      p.name = name_at(1, "configuration");
      if (w.size() > 2) throw fail(w[2].col, "unexpected '" + w[2].text + "'");
    } else if (kw == "block") {
      need(2, "block N");
      if (!resource.empty()) throw fail(w[0].col, "'block' comes before the first resource");
      uint32_t b = number_at(1, "block size", kMaxBlockSize);
      if (b < 16 || b % 16) throw fail(w[1].col, "the block size is a multiple of 16 (16.." + std::to_string(kMaxBlockSize) + ")");
      p.block_size = b;
      if (w.size() > 2) throw fail(w[2].col, "unexpected '" + w[2].text + "'");
    } else if (kw == "retain") {
      need(2, "retain FILE [every DURATION]");
      p.retain_file_as_written = w[1].text;
      p.retain_file = resolve(w[1].text);
      if (w.size() > 2) {
        if (lower(w[2].text) != "every") throw fail(w[2].col, "expected 'every DURATION' after the file");
        need(4, "every DURATION");
        p.retain_every_us = duration_at(3, "save interval", 1000);
        if (w.size() > 4) throw fail(w[4].col, "unexpected '" + w[4].text + "'");
      }
    } else if (kw == "resource") {
      end_task();
      in_task = false;
      need(4, "resource NAME processor N");
      resource = name_at(1, "resource");
      if (lower(w[2].text) != "processor") throw fail(w[2].col, "expected 'processor N'");
      processor = number_at(3, "processor number", 255);
      for (auto& [n, r] : processors) {
        if (r == resource) throw fail(w[1].col, "second resource named '" + resource + "'");
        if (n == processor) throw fail(w[3].col, "processor " + std::to_string(n) + " already belongs to resource '" + r + "'");
      }
      processors.emplace_back(processor, resource);
      if (w.size() > 4) throw fail(w[4].col, "unexpected '" + w[4].text + "'");
    } else if (kw == "task") {
      end_task();
      if (resource.empty()) throw fail(w[0].col, "a task belongs to a resource: 'resource NAME processor N' first");
      need(4, "task NAME period DURATION");
      ProjectTask t;
      t.name = name_at(1, "task");
      for (const ProjectTask& o : p.tasks)
        if (lower(o.name) == lower(t.name)) throw fail(w[1].col, "second task named '" + t.name + "'");
      t.resource = resource;
      t.processor = processor;
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
      p.tasks.push_back(t);
      in_task = true, task_has_program = false, task_line = line, task_col = w[1].col;
    } else if (kw == "program") {
      if (!in_task) throw fail(w[0].col, "a program is bound to a task: 'task NAME period DURATION' first");
      need(3, "program NAME FILE");
      if (task_has_program)
        throw fail(w[0].col, "task '" + p.tasks.back().name + "' already runs program '" + p.tasks.back().program +
                                 "' (one program, one image per task)");
      ProjectTask& t = p.tasks.back();
      t.program = name_at(1, "program");
      for (const ProjectTask& o : p.tasks)
        if (&o != &t && lower(o.program) == lower(t.program)) throw fail(w[1].col, "second program named '" + t.program + "'");
      t.file = w[2].text;
      t.path = resolve(w[2].text);
      t.line = line, t.col = w[1].col;
      task_has_program = true;
      if (w.size() > 3) throw fail(w[3].col, "unexpected '" + w[3].text + "'");
    } else {
      throw fail(w[0].col, "unknown keyword '" + w[0].text + "' (configuration, block, retain, resource, task, program)");
    }
  }
  end_task();
  if (p.tasks.empty()) {
    line = std::max(line, 1);
    throw fail(1, "the project has no task");
  }
  return p;
}

std::string print_project(const Project& p, const std::vector<std::string>& files) {
  std::string s = "# " + p.name + ": written by ldc --project from " + p.path + "\nconfiguration " + p.name + "\nblock " +
                  std::to_string(p.block_size) + "\n";
  if (!p.retain_file_as_written.empty())
    s += "retain " + p.retain_file_as_written + " every " + us_text(p.retain_every_us) + "\n";
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
    auto it = std::lower_bound(instr_offset.begin(), instr_offset.end(), il_offset);
    SrcLoc loc = it != instr_offset.end() && *it == il_offset ? instr_loc[it - instr_offset.begin()] : SrcLoc{};
    return format_error(file, text, loc.line, loc.col ? loc.col : 1, msg);
  }
};

}  // namespace

std::vector<BuiltTask> build_project(const Project& p) {
  std::vector<BuiltTask> built;
  std::vector<ProgramSource> srcs;
  std::vector<ConfigTask> cts;
  for (const ProjectTask& t : p.tasks) {
    BuiltTask b{t, {}};
    ProgramSource ps;
    ps.file = t.path;
    if (t.il) {  // a PLCopen task, compiled with its configuration
      b.image = make_x86_image(*t.il, build_x86(*t.il, t.path));
      ps.text = p.text;
      BinaryIl bin = encode_il(*t.il);
      ps.instr_offset = bin.instr_offset;
      for (const Rung& r : t.il->rungs)
        for (const Instr& in : r.code) ps.instr_loc.push_back(in.loc.line ? in.loc : SrcLoc{r.line, 1});
    } else if (is_image_file(t.path)) {
      b.image = load_image_file(t.path);
      if (b.image.target != ImageTarget::X86_64) throw UserError(t.path + ": error: not an x86-64 image");
      b.image.config.reset();  // recomputed for this project
      ps.image = true;
      ps.lines = b.image.lines;
    } else {
      Compiled c = compile_source(t.path);
      b.image = make_x86_image(c.il, build_x86(c.il, t.path));
      ps.text = read_file(t.path);
      BinaryIl bin = encode_il(c.il);
      ps.instr_offset = bin.instr_offset;
      for (const Rung& r : c.il.rungs)
        for (const Instr& in : r.code) ps.instr_loc.push_back(in.loc.line ? in.loc : SrcLoc{r.line, 1});
    }
    ConfigTask ct;
    ct.program = t.program, ct.task = t.name, ct.resource = t.resource;
    ct.processor = t.processor, ct.period_us = t.period_us, ct.priority = t.priority, ct.exclusive = t.exclusive;
    ct.accesses = io_accesses(b.image.il);
    cts.push_back(std::move(ct));
    srcs.push_back(std::move(ps));
    built.push_back(std::move(b));
  }
  SystemConfig sc = configure(cts, p.block_size);
  if (!sc.conflicts.empty()) {
    std::string msg;
    constexpr size_t kMaxListed = 8;
    for (const WriteConflict& c : sc.conflicts) {
      const ProjectTask &a = p.tasks[c.first], &b = p.tasks[c.second];
      std::string block = block_name(c.area, c.block, p.block_size);
      auto who = [](const ProjectTask& t) {
        return "program '" + t.program + "' (task " + t.name + ", processor " + std::to_string(t.processor) + ")";
      };
      std::string why = a.processor != b.processor ? "a block is written by one processor only"
                        : a.exclusive ? "task '" + a.name + "' is exclusive: no other task may write its blocks"
                                      : "task '" + b.name + "' is exclusive: no other task may write its blocks";
      msg += format_error(p.path, p.text, b.line, b.col,
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
    }
    msg += p.path + ": error: " + std::to_string(sc.conflicts.size()) + " I/O write conflict" +
           (sc.conflicts.size() == 1 ? "" : "s") + "; the project is refused";
    throw UserError(msg);
  }
  for (size_t i = 0; i < built.size(); i++) built[i].image.config = sc.per_task[i];
  return built;
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
