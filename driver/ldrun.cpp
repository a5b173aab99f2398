// ldrun -- run a program scan by scan over an input trace and print watched
// devices; with --io or --project, the soft-PLC runtime (docs/runtime.md):
// periodic scan tasks, I/O drivers, online download, retentive memory.
#include <algorithm>
#include <poll.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <string>
#include <thread>

#include "backend-c/backend_c.h"
#include "driver/driver.h"
#include "driver/project.h"
#include "driver/ldrun_io.h"
#include "driver/targets.h"
#include "runtime/failsafe.h"
#include "runtime/net/modbus.h"
#include "runtime/net/monitor.h"
#include "runtime/plc.h"
#include "runtime/runtime.h"
#include "runtime/sandbox.h"
#include "driver/version.h"

using namespace ldc;

namespace {

// The engines that run a program's IL, on any image or source.
const char* const kIlEngines[] = {"interp", "fast", "c"};

// Every engine: those of the targets that run here, the IL engines, then
// those of the simulated targets.
std::vector<std::string> all_engines() {
  std::vector<std::string> n = engine_names(true);
  n.insert(n.end(), std::begin(kIlEngines), std::end(kIlEngines));
  for (const std::string& e : engine_names(false)) n.push_back(e);
  return n;
}

std::string usage() {
  std::string engines;
  for (const std::string& e : all_engines()) engines += (engines.empty() ? "" : "|") + e;
  return
    "usage: ldrun FILE [--engine=" + engines + "] [-O0|-O1|-O2] [--trace in.csv] [--watch Y0,D3,...] [--scans N] [--period 10ms] [--cycles] [--sandbox] [--fault=stop|continue] [-W...]\n"
    "       ldrun FILE|--project P.ldp --io=stdio|shm[:/NAME]|trace|none [--period 1ms|500us] [--clock=real|virtual]\n"
    "             [--free-run] [--rt] [--watchdog 200ms] [--retain FILE] [--retain-every 1s] [--cold] [--stop]\n"
    "             [--control=stdin|none] [--reload] [--strict] [--load-budget 128M] [--stats] [--out FILE] [--block 16] [--scans N]\n"
    "             [--modbus [HOST:]PORT] [--modbus-connections 16]   a Modbus TCP server (127.0.0.1 unless HOST is given; also with --trace)\n"
    "             [--modbus-per-address 8] [--modbus-frame-timeout 2s] [--modbus-idle-timeout 60s]\n"
    "             [--modbus-write-timeout 1s] [--modbus-pending-writes 8192]   its limits (docs/faults.md)\n"
    "             [--modbus-map FILE]          named variables at coils and holding registers of their own\n"
    "             [--monitor HOST:PORT [--monitor-write] [--monitor-remote]]  (the live ladder view, docs/runtime.md)\n"
    "             [--monitor-host NAME[,NAME]] [--monitor-token TOKEN]  (names it is reached by; the write token)\n"
    "             [--monitor-connections 64] [--monitor-per-address 32] [--monitor-streams 32]  (docs/faults.md)\n"
    "       FILE: an image (.bin, .hex) or a source ldc reads (.ld, .il, .st, .xml, .rtsp, .sfc), compiled in memory\n"
    "             (native code at -O0 unless -O1 or -O2 is given; --engine=fast is the fast interpreter)\n"
    "       FILE.xml, FILE.st: a configuration of several tasks (PLCopen or ST) runs as a project (--io); --task NAME picks one task's program\n"
    "       --sandbox: run the scans in a child process that seccomp confines to its socket (native, interp, c)\n";
}

// Options of the soft-PLC runtime mode.
struct RtArgs {
  bool on = false;
  std::string project, io, control, clock, period, watchdog, retain, retain_every, out, block;
  std::string modbus, modbus_connections;  // --modbus [HOST:]PORT, --modbus-connections N
  std::string modbus_per_address, modbus_frame_timeout, modbus_idle_timeout, modbus_write_timeout, modbus_pending_writes;
  std::string modbus_map;  // --modbus-map FILE: named variables' coils and registers
  std::string load_budget;                 // --load-budget SIZE: the memory an online load may take
  bool free_run = false, rt = false, cold = false, stop = false, stats = false, reload = false;
  bool strict = false;   // --strict: an online download that would reset a variable is refused (docs/runtime.md)
  bool sandbox = false;  // also in trace mode: it does not select the runtime
  std::string monitor;   // --monitor HOST:PORT (runtime/net/monitor.h)
  bool monitor_write = false, monitor_remote = false;
  std::vector<std::string> monitor_hosts;  // --monitor-host, each a NAME or a comma list
  std::string monitor_token, monitor_connections, monitor_per_address, monitor_streams;
};

// --task NAME: one task's program of a PLCopen configuration of several tasks.
std::string g_task;

// An image for a task: an image file as it is, or a source compiled in memory.
Image load_program(const std::string& file) {
  if (is_image_file(file)) return load_image_file(file);
  Compiled c = compile_source(file, false, g_task);
  return target_image(host_target(), c.il, file, 0);
}

// Online load (`load`, --reload) into a running runtime: an image file is
// refused before it is read if loading it could take more than the budget.
// Loading holds the file, the image's copies of its code and IL and a few bits
// per byte of code, at most 3 times the file, and up to 40 MiB of rung titles
// and aliases (kImageMaxRungTitles, kImageMaxAliases; docs/runtime.md,
// "Online download").
constexpr uint64_t kDefaultLoadBudget = uint64_t(128) << 20, kLoadFixedCost = uint64_t(40) << 20;
Image load_program_online(const std::string& file, uint64_t budget, const std::string& budget_text) {
  if (!is_image_file(file)) return load_program(file);
  uint64_t max_file = budget > kLoadFixedCost ? (budget - kLoadFixedCost) / 3 : 0;
  try {
    return read_image_file(file, max_file, "that --load-budget " + budget_text + " lets one load read (a load holds up to 3 times the file, and 40 MiB)");
  } catch (const ImageError& e) {
    throw UserError(e.what());
  }
}

// "128M", "64MiB", "1G", "4096": bytes.
uint64_t size_arg(const std::string& v, const char* flag) {
  size_t digits = v.find_first_not_of("0123456789");
  std::string unit = digits == std::string::npos ? "" : v.substr(digits);
  int shift = unit.empty() ? 0 : unit == "K" || unit == "KiB" ? 10 : unit == "M" || unit == "MiB" ? 20 : unit == "G" || unit == "GiB" ? 30 : -1;
  if (v.empty() || digits == 0 || shift < 0 || v.size() - unit.size() > 12)
    throw UserError(std::string("ldrun: error: bad ") + flag + " '" + v + "' (bytes, or with K, M or G: 128M)");
  uint64_t n = std::stoull(v.substr(0, v.size() - unit.size()));
  if (n > (UINT64_MAX >> shift)) throw UserError(std::string("ldrun: error: ") + flag + " '" + v + "' is too large");
  return n << shift;
}

std::string stem(const std::string& path) {
  size_t slash = path.rfind('/');
  std::string b = slash == std::string::npos ? path : path.substr(slash + 1);
  std::string s = b.substr(0, b.find('.'));
  std::string n;
  for (char c : s) n += std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
  return n.empty() || std::isdigit(static_cast<unsigned char>(n[0])) ? "main" : n;
}

// Reads lines from fd 0 without blocking shutdown: poll with a timeout.
class LineReader {
 public:
  // 1: a line, 0: nothing yet, -1: end of input.
  int next(std::string& line, int timeout_ms) {
    while (true) {
      size_t nl = buf_.find('\n');
      if (nl != std::string::npos) {
        line = buf_.substr(0, nl);
        buf_.erase(0, nl + 1);
        if (!line.empty() && line.back() == '\r') line.pop_back();
        return 1;
      }
      if (eof_) {
        if (buf_.empty()) return -1;
        line.swap(buf_);
        buf_.clear();
        return 1;
      }
      pollfd p{0, POLLIN, 0};
      int r = poll(&p, 1, timeout_ms);
      if (r < 0 && errno == EINTR) continue;
      if (r <= 0) return 0;
      char tmp[4096];
      ssize_t n = read(0, tmp, sizeof tmp);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) eof_ = true;
      else buf_.append(tmp, size_t(n));
    }
  }

 private:
  std::string buf_;
  bool eof_ = false;
};

namespace soft_plc {

using namespace ldc::plc;

// "--period 10ms" and the like: microseconds, at least `min`.
int64_t duration_arg(const std::string& v, const char* what, int64_t min) {
  std::string why = duration_problem(v, min);
  if (!why.empty()) throw UserError(std::string("ldrun: error: bad ") + what + ": " + why);
  return *parse_duration_us(v);
}

// interp, or the engine of the code of a target that runs here (native)
FoundEngine runtime_engine(const std::string& engine) {
  const FoundEngine code = find_engine(engine);
  if (engine != "interp" && !(code.engine && code.engine->runs_code && code.target->host)) {
    std::vector<std::string> ok;
    for (const std::string& e : engine_names(true)) ok.push_back("--engine=" + e);
    ok.push_back("--engine=interp");
    throw UserError("ldrun: error: the runtime runs " + or_list(ok) + ", not '" + engine + "'");
  }
  return code;
}

TaskSpec task_of(BuiltTask& b) {
  TaskSpec s;
  s.name = b.spec.name, s.program = b.spec.program, s.resource = b.spec.resource;
  s.processor = b.spec.processor, s.period_us = b.spec.period_us, s.priority = b.spec.priority;
  s.watchdog_us = b.spec.watchdog_us, s.exclusive = b.spec.exclusive, s.file = b.spec.path;
  s.image = std::move(b.image);
  return s;
}

// One run of the soft PLC (ldrun --io or --project), step by step: the
// options, the tasks, the I/O driver (with Modbus and the monitor around it),
// the runtime and the threads that serve signals, the line protocol and --reload.
class SoftPlcRun {
 public:
  SoftPlcRun(const std::string& input, const std::string& trace_file, const std::string& watch, const RtArgs& a)
      : input_(input), trace_file_(trace_file), watch_(watch), a_(a) {}
  ~SoftPlcRun() {
    rt_.reset();
    monitor_.reset();
    if (out_ && out_ != stdout) std::fclose(out_);
  }

  int run(const std::string& engine, int scans) {
    code_ = runtime_engine(engine);
    if (!a_.project.empty() && !input_.empty()) throw UserError("ldrun: error: give a program or --project, not both");
    if (a_.project.empty() && input_.empty()) throw UserError("ldrun: error: no program\n" + usage());
    install_failsafe();
    read_options(scans);
    read_tasks();
    apply_task_options();
    open_io();
    std::optional<modbus::ServerOptions> mb = modbus_options();
    check_open_files(mb);
    if (mb) add_modbus(*mb);
    add_monitor();
    start();
    try {
      return finish();
    } catch (const std::exception& e) {  // the run cannot end in order: end it on the fatal path
      char what[300];
      std::snprintf(what, sizeof what, "an unexpected error (%s) on the main thread", e.what());
      failsafe::fatal(what);
    }
  }

 private:
  const std::string& input_;
  const std::string& trace_file_;
  const std::string& watch_;
  const RtArgs& a_;
  FoundEngine code_;
  Options opt_;
  int64_t period_us_ = 10000;
  std::vector<TaskSpec> specs_;
  bool control_ = false;
  Trace trace_;
  FILE* out_ = nullptr;
  std::unique_ptr<IoDriver> driver_;
  std::unique_ptr<Monitor> monitor_;
  std::string monitor_host_, monitor_token_;
  bool print_token_ = false;  // a token ldrun made: the user learns it here
  std::string io_name_;         // the --io driver, for the banner
  std::string task_lines_;      // the tasks, for the banner
  std::string modbus_address_;  // where the Modbus server listens, for the banner
  uint64_t load_budget_ = kDefaultLoadBudget;  // --load-budget
  std::string load_budget_text_ = "128M";
  sigset_t sigs_;
  std::unique_ptr<Runtime> rt_;
  std::atomic<bool> done_{false};
  std::thread sig_thread_, ctl_thread_, reload_thread_;

  // Whatever ends the run from here on drives the outputs safe first
  // (runtime/failsafe.h, docs/faults.md): fatal signals, std::terminate.
  void install_failsafe() {
    try {
      failsafe::install();
    } catch (const std::exception& e) { throw UserError(std::string("ldrun: error: ") + e.what()); }
  }

  void read_options(int scans) {
    opt_.log = [](const std::string& m) { std::fprintf(stderr, "%s\n", m.c_str()); };
    if (!a_.period.empty()) period_us_ = duration_arg(a_.period, "--period", 50);
    if (!a_.watchdog.empty())
      opt_.watchdog_us = uint32_t(std::min<int64_t>(duration_arg(a_.watchdog, "--watchdog", 0), UINT32_MAX));
    if (a_.clock == "virtual") opt_.clock = Options::Clock::Virtual;
    else if (!a_.clock.empty() && a_.clock != "real") throw UserError("ldrun: error: --clock is real or virtual, not '" + a_.clock + "'");
    opt_.free_run = a_.free_run;
    opt_.rt = a_.rt;
    if (a_.rt && a_.free_run) throw UserError("ldrun: error: --rt with --free-run would keep a CPU busy forever; choose one");
    opt_.start_stopped = a_.stop;
    opt_.cold = a_.cold;
    opt_.scans = scans;
    if (!a_.load_budget.empty()) load_budget_ = size_arg(a_.load_budget, "--load-budget"), load_budget_text_ = a_.load_budget;
  }

  // The tasks: a project's (a PLCopen configuration of several tasks is a
  // project too), or one task "main" running the program.
  void read_tasks() {
    std::shared_ptr<Project> proj;
    std::optional<Image> single;
    if (!a_.project.empty()) {
      Diagnostics pd;  // every wrong line of the project, as ldc --project reports them
      proj = std::make_shared<Project>(parse_project(a_.project, pd));
    } else if (!input_.empty() && !is_image_file(input_)) {
      Compiled c = compile_source(input_, g_task.empty(), g_task);
      if (c.project) proj = c.project;
      else single = target_image(host_target(), c.il, input_, 0);
    }
    if (proj) {
      opt_.block_size = proj->block_size;
      opt_.retain_file = proj->retain_file;
      opt_.retain_every_us = proj->retain_every_us;
      for (BuiltTask& b : build_project(*proj)) specs_.push_back(task_of(b));
      if (!a_.period.empty()) throw UserError("ldrun: error: --period is for one program; a project gives each task its period");
      return;
    }
    TaskSpec s;
    s.name = "main";
    s.program = stem(input_);
    s.resource = "cpu0";
    s.period_us = uint32_t(period_us_);
    s.file = input_;
    s.image = single ? std::move(*single) : load_program(input_);
    if (s.image.config) {
      s.processor = s.image.config->processor;
      opt_.block_size = s.image.config->block_size;
    }
    specs_.push_back(std::move(s));
  }

  // --block, --retain, --retain-every over the tasks' own; the engine's image kind.
  void apply_task_options() {
    if (!a_.block.empty()) {
      const std::string& b = a_.block;
      if (b.find_first_not_of("0123456789") != std::string::npos || b.size() > 5 || std::stoul(b) < 16 ||
          std::stoul(b) % 16 || std::stoul(b) > kMaxBlockSize)
        throw UserError("ldrun: error: bad --block '" + b + "' (a multiple of 16 in 16..8192)");
      opt_.block_size = uint32_t(std::stoul(b));
    }
    if (!a_.retain.empty()) opt_.retain_file = a_.retain;
    if (!a_.retain_every.empty()) opt_.retain_every_us = duration_arg(a_.retain_every, "--retain-every", 1000);
    for (const TaskSpec& s : specs_)
      if (code_.engine && s.image.target != code_.target->image_kind)
        throw UserError("ldrun: error: " + s.file + " is not " + std::string(code_.target->an_image) + "; use --engine=interp");
  }

  // The I/O driver (--io), and whether the line protocol reads stdin (--control).
  void open_io() {
    std::string io = a_.io.empty() ? (trace_file_.empty() ? "none" : "trace") : a_.io;
    io_name_ = io;
    control_ = a_.control.empty() ? io == "stdio" : a_.control == "stdin";
    if (!a_.control.empty() && a_.control != "stdin" && a_.control != "none")
      throw UserError("ldrun: error: --control is stdin or none, not '" + a_.control + "'");
    if (io == "trace") open_trace();
    else if (io == "shm" || io.rfind("shm:", 0) == 0) driver_ = make_shm_driver(io.size() > 4 ? io.substr(4) : "/ldc");
    else if (io == "stdio" || io == "none") driver_ = make_null_driver();
    else throw UserError("ldrun: error: unknown --io '" + io + "' (stdio, shm[:/NAME], trace or none)");
  }

  void open_trace() {
    if (specs_.size() != 1) throw UserError("ldrun: error: the trace driver drives one task; the project has " + std::to_string(specs_.size()));
    std::vector<Probe> probes = parse_watch(watch_, specs_[0].image.aliases);
    if (!trace_file_.empty()) {
      trace_ = load_trace(trace_file_, specs_[0].image.aliases);
      if (opt_.scans < 0) opt_.scans = int64_t(trace_.rows.size());
    }
    if (a_.out.empty()) {
      if (control_) throw UserError("ldrun: error: the trace CSV and the line protocol both want stdout: give --out FILE");
      out_ = stdout;
    } else if (!(out_ = std::fopen(a_.out.c_str(), "w"))) {
      throw UserError("ldrun: error: cannot create " + a_.out + ": " + std::strerror(errno));
    }
    driver_ = make_trace_driver(trace_file_.empty() ? nullptr : &trace_, probes, nullptr, out_);
  }

  // "--modbus-connections 16" and the like: an integer in lo..hi.
  static size_t count_arg(const std::string& v, const char* what, size_t lo, size_t hi) {
    if (v.empty() || v.size() > 6 || v.find_first_not_of("0123456789") != std::string::npos || std::stoul(v) < lo ||
        std::stoul(v) > hi)
      throw UserError("ldrun: error: bad " + std::string(what) + " '" + v + "' (" + std::to_string(lo) + ".." +
                      std::to_string(hi) + ")");
    return std::stoul(v);
  }
  // "--modbus-frame-timeout 2s" and the like: milliseconds in 10 ms..1 h.
  static int ms_arg(const std::string& v, const char* what) {
    int64_t us = duration_arg(v, what, 10000);
    if (us > 3600 * int64_t(1000000)) throw UserError(std::string("ldrun: error: bad ") + what + " '" + v + "' (at most 1h)");
    return int(us / 1000);
  }

  // The Modbus server's options and limits (docs/faults.md, "Modbus TCP"), if --modbus.
  std::optional<modbus::ServerOptions> modbus_options() {
    std::pair<const char*, const std::string*> limits[] = {
        {"--modbus-connections", &a_.modbus_connections},     {"--modbus-per-address", &a_.modbus_per_address},
        {"--modbus-frame-timeout", &a_.modbus_frame_timeout}, {"--modbus-idle-timeout", &a_.modbus_idle_timeout},
        {"--modbus-write-timeout", &a_.modbus_write_timeout}, {"--modbus-pending-writes", &a_.modbus_pending_writes},
        {"--modbus-map", &a_.modbus_map}};
    if (a_.modbus.empty()) {
      for (auto& [name, v] : limits)
        if (!v->empty()) throw UserError("ldrun: error: " + std::string(name) + " needs --modbus");
      return std::nullopt;
    }
    modbus::ServerOptions mo;
    mo.tasks = specs_.size();
    mo.log = opt_.log;
    mo.listening = [this](const std::string& address) { modbus_address_ = address; };
    if (!a_.modbus_connections.empty()) mo.max_connections = count_arg(a_.modbus_connections, "--modbus-connections", 1, 1000);
    if (!a_.modbus_per_address.empty()) mo.max_per_address = count_arg(a_.modbus_per_address, "--modbus-per-address", 1, 1000);
    mo.max_per_address = std::min(mo.max_per_address, mo.max_connections);
    if (!a_.modbus_frame_timeout.empty()) mo.frame_timeout_ms = ms_arg(a_.modbus_frame_timeout, "--modbus-frame-timeout");
    if (!a_.modbus_idle_timeout.empty()) mo.idle_timeout_ms = ms_arg(a_.modbus_idle_timeout, "--modbus-idle-timeout");
    // a write waits for its task's next scan: by default 1 s, or two periods of the slowest task
    uint32_t slowest_us = 0;
    for (const TaskSpec& t : specs_) slowest_us = std::max(slowest_us, t.period_us);
    mo.write_timeout_ms = int(std::max<int64_t>(1000, 2 * int64_t(slowest_us) / 1000));
    if (!a_.modbus_write_timeout.empty()) mo.write_timeout_ms = ms_arg(a_.modbus_write_timeout, "--modbus-write-timeout");
    // one request writes 1968 coils at most; the map has 34,816 writable elements
    if (!a_.modbus_pending_writes.empty())
      mo.pending_writes = count_arg(a_.modbus_pending_writes, "--modbus-pending-writes", 1968, 34816);
    if (!a_.modbus_map.empty()) {  // names of the first task's program (units 0, 1, 255)
      try {
        mo.named = modbus::read_map(read_file(a_.modbus_map), a_.modbus_map, specs_[0].image.aliases);
      } catch (UserError&) { throw; } catch (std::exception& e) { throw UserError(e.what()); }
    }
    return mo;
  }

  void add_modbus(modbus::ServerOptions mo) {
    try {
      modbus::parse_address(a_.modbus, mo);
      driver_ = modbus::make_modbus_driver(std::move(driver_), mo);
    } catch (std::runtime_error& e) { throw UserError(std::string("ldrun: error: ") + e.what()); }
  }

  // A --monitor-... count: 1..1000, `def` if not given.
  static size_t monitor_count(const std::string& v, const char* flag, size_t def) {
    if (v.empty()) return def;
    if (v.size() > 4 || v.find_first_not_of("0123456789") != std::string::npos || std::stoul(v) < 1 || std::stoul(v) > 1000)
      throw UserError(std::string("ldrun: error: bad ") + flag + " '" + v + "' (1..1000)");
    return std::stoul(v);
  }

  // The source text the monitor shows for an ST or IL program
  // (docs/runtime.md, "The monitor"): the file the image names, read here --
  // a source this ldrun compiled as it is, an image's source only if it still
  // compiles to the image's IL and line map (a source edited since would put
  // values on the wrong lines); else `note` says why and the rungs are drawn.
  // `file` is where the image came from ("" when not known: the source is
  // then always compiled and compared).
  static void monitor_source(const Image& image, const std::string& file, const std::string& task, std::string& text,
                             std::string& note) {
    const std::string& path = image.source;
    auto ends = [&](const char* e) { size_t n = std::strlen(e); return path.size() >= n && path.compare(path.size() - n, n, e) == 0; };
    if (!ends(".st") && !ends(".il")) return;
    constexpr off_t kMax = off_t(4) << 20;  // as the monitor's bound (runtime/net/monitor.cpp)
    struct stat st;
    if (::stat(path.c_str(), &st) != 0 || !S_ISREG(st.st_mode)) {
      note = "the source " + path + " is not available here: the rungs of its code are shown instead";
      return;
    }
    if (st.st_size > kMax) {
      note = "the source " + path + " is larger than 4 MiB: the rungs of its code are shown instead";
      return;
    }
    try {
      std::string t = read_file(path);
      if (file == path && !is_image_file(path)) {  // compiled from it just now, in this process
        text = std::move(t);
        return;
      }
      Compiled c;
      try {
        c = compile_source(path, false, g_task);
      } catch (const UserError&) {  // one task of a configuration
        c = compile_source(path, false, task);
      }
      if (!same_code(c.il, image)) {
        note = "the source " + path + " has changed since this program was compiled: the rungs of its code are shown instead";
        return;
      }
      text = std::move(t);
    } catch (const std::exception&) {
      note = "the source " + path + " does not compile as it did: the rungs of its code are shown instead";
    }
  }
  // Does `p` encode to the image's IL, each instruction on the same line?
  static bool same_code(const Program& p, const Image& img) {
    BinaryIl b = encode_il(p);
    if (b.code != img.il || b.instr_offset.size() != img.lines.size()) return false;
    size_t k = 0;
    for (const Rung& r : p.rungs)
      for (const Instr& in : r.code)
        if (img.lines[k++].line != (in.loc.line ? in.loc.line : r.line)) return false;
    return true;
  }

  // The monitor wraps the driver: snapshots after scans, writes before them.
  void add_monitor() {
    if (a_.monitor.empty()) {
      if (a_.monitor_write || a_.monitor_remote || !a_.monitor_hosts.empty() || !a_.monitor_token.empty() ||
          !a_.monitor_connections.empty() || !a_.monitor_per_address.empty() || !a_.monitor_streams.empty())
        throw UserError("ldrun: error: the --monitor-... options need --monitor HOST:PORT");
      return;
    }
    MonitorOptions mo;
    try {
      std::tie(mo.host, mo.port) = parse_monitor_address(a_.monitor, a_.monitor_remote);
      for (const std::string& h : a_.monitor_hosts) parse_monitor_hosts(h, mo.hosts);
      if (!a_.monitor_token.empty()) {
        if (!a_.monitor_write) throw std::runtime_error("--monitor-token guards writes: it needs --monitor-write");
        check_monitor_token(a_.monitor_token);
        mo.token = a_.monitor_token;
      } else if (a_.monitor_remote && a_.monitor_write) {
        mo.token = make_monitor_token();  // printed at start
        print_token_ = true;
      }
    } catch (std::exception& e) { throw UserError(std::string("ldrun: error: ") + e.what()); }
    mo.max_connections = monitor_count(a_.monitor_connections, "--monitor-connections", mo.max_connections);
    mo.max_per_address = monitor_count(a_.monitor_per_address, "--monitor-per-address", mo.max_per_address);
    mo.max_streams = monitor_count(a_.monitor_streams, "--monitor-streams", mo.max_streams);
    mo.log = opt_.log;
    mo.write = a_.monitor_write;
    monitor_host_ = mo.host;
    monitor_token_ = mo.token;
    std::vector<MonitorTask> mts;
    for (const TaskSpec& s : specs_) {
      mts.push_back({s.name, s.period_us, s.image, "", ""});
      monitor_source(s.image, s.file, s.name, mts.back().source_text, mts.back().source_note);
    }
    // after an online download: the new image's source, if it still compiles to it
    std::vector<std::string> names;
    for (const TaskSpec& s : specs_) names.push_back(s.name);
    mo.source_of = [names](size_t task, const Image& img, std::string& text, std::string& note) {
      monitor_source(img, "", task < names.size() ? names[task] : "", text, note);
    };
    monitor_ = std::make_unique<Monitor>(std::move(mts), mo);
    driver_ = monitor_->wrap(std::move(driver_));
  }

  // The open-file limit against what the caps let the runtime hold at once:
  // the servers' connections (a client that takes every descriptor would
  // make the retentive save fail), the sandbox's sockets, and the files of
  // the runtime itself.  The soft limit is raised as far as needed if the
  // hard one allows; else the run is refused, saying what to change.
  void check_open_files(const std::optional<modbus::ServerOptions>& mb) {
    // stdin/out/err, the retentive file and its directory, the shared
    // memory object, the trace and --out files, an image being loaded, and
    // a margin for the C library (and the C route's shared object)
    const size_t own = 32;
    const size_t sandbox = a_.sandbox ? 2 * specs_.size() : 0;
    const size_t modbus_conns = mb ? mb->max_connections : 0;
    const size_t modbus_files = mb ? modbus::descriptors_needed(*mb) : 0;
    // the monitor's connections, a newcomer told 503, its listener and wake-up pipe
    const size_t monitor_conns =
        a_.monitor.empty() ? 0 : monitor_count(a_.monitor_connections, "--monitor-connections", MonitorOptions{}.max_connections);
    const size_t monitor_files = monitor_conns ? monitor_conns + 4 : 0;
    const size_t need = own + sandbox + modbus_files + monitor_files;
    rlimit rl{};
    if (getrlimit(RLIMIT_NOFILE, &rl) != 0 || rl.rlim_cur == RLIM_INFINITY || rl.rlim_cur >= need) return;
    if (rl.rlim_max == RLIM_INFINITY || rl.rlim_max >= need) {
      rlimit raised{rlim_t(need), rl.rlim_max};
      if (setrlimit(RLIMIT_NOFILE, &raised) == 0) {
        opt_.log("ldrun: raised the open-file limit from " + std::to_string(rl.rlim_cur) + " to " + std::to_string(need) +
                 " (what the connection caps need)");
        return;
      }
    }
    std::string what = std::to_string(own) + " for the runtime";
    if (sandbox) what += ", " + std::to_string(sandbox) + " for --sandbox";
    if (modbus_files)
      what += ", " + std::to_string(modbus_files) + " for --modbus-connections " + std::to_string(modbus_conns);
    if (monitor_files)
      what += ", " + std::to_string(monitor_files) + " for --monitor-connections " + std::to_string(monitor_conns);
    // what can be had: the hard limit, or the soft one if raising it failed
    const size_t limit = rl.rlim_max != RLIM_INFINITY && rl.rlim_max < need ? rl.rlim_max : rl.rlim_cur;
    std::string fix = "raise the limit (ulimit -n " + std::to_string(need) + ")";
    if (need - limit < monitor_conns)
      fix = "lower --monitor-connections to " + std::to_string(monitor_conns - (need - limit)) + " or " + fix;
    if (need - limit < modbus_conns)
      fix = "lower --modbus-connections to " + std::to_string(modbus_conns - (need - limit)) + " or " + fix;
    throw UserError("ldrun: error: the open-file limit is " + std::to_string(limit) + " but the connection caps need " +
                    std::to_string(need) + " descriptors (" + what + "): " + fix);
  }

  EngineFactory engines() const {
    return [code = code_, sandbox = a_.sandbox](const Image& img) -> std::unique_ptr<Engine> {
      std::unique_ptr<Engine> e;
      if (!code.engine) e = make_interp_engine(img.il, img.layout);
      else if (img.target != code.target->image_kind) throw std::runtime_error("not " + std::string(code.target->an_image));
      else e = code.engine->make(img);
      return sandbox ? make_sandboxed_engine(std::move(e), img.layout) : std::move(e);
    };
  }

  // SIGINT and SIGTERM end the run in order (outputs safe, retentive memory
  // saved): blocked here, so every thread inherits the mask, and taken by sigtimedwait.
  void start() {
    sigemptyset(&sigs_);
    sigaddset(&sigs_, SIGINT);
    sigaddset(&sigs_, SIGTERM);
    pthread_sigmask(SIG_BLOCK, &sigs_, nullptr);
    for (const TaskSpec& t : specs_)
      task_lines_ += "ldrun:   task " + t.name + ": program " + t.program + " (" + t.file + "), period " +
                     duration_text(t.period_us) + ", priority " + std::to_string(t.priority) + ", processor " +
                     std::to_string(t.processor) + "\n";
    try {
      rt_ = std::make_unique<Runtime>(std::move(specs_), opt_, engines(), std::move(driver_));
    } catch (UserError&) { throw; } catch (std::exception& e) {
      std::string m = e.what();
      throw UserError(m.find("error:") == std::string::npos ? "ldrun: error: " + m : m);
    }
    std::string banner = monitor_ ? start_monitor() : "";
    rt_->start();
    sig_thread_ = std::thread([this] { serve_signals(); });
    if (control_) ctl_thread_ = std::thread([this] { serve_control(); });
    if (a_.reload) reload_thread_ = std::thread([this] { serve_reload(); });
    // Announced once every thread runs: a client (or a test lowering the
    // descriptor limit) that acts on the banner meets a started ldrun.
    if (runs_until_stopped()) banner = startup_banner(banner);
    if (!banner.empty()) std::fprintf(stderr, "%s\n", banner.c_str());
  }

  // Runs until SIGINT, SIGTERM or quit: no --scans, and not the trace driver
  // (a trace run ends with its rows; its CSV is the output a user reads).
  bool runs_until_stopped() const { return opt_.scans < 0 && io_name_ != "trace"; }

  // What runs, its tasks, the servers and how to stop (stderr; stdout is the
  // line protocol's). `monitor_line` is the monitor's own line, or "".
  std::string startup_banner(const std::string& monitor_line) const {
    const size_t n = rt_->task_count();
    std::string what = !a_.project.empty() ? a_.project : input_;
    std::string engine = code_.engine ? "native code" : "the reference interpreter";
    std::string b = "ldrun: running " + what + ": " + std::to_string(n) + " task" + (n == 1 ? "" : "s") + ", " + engine +
                    ", I/O " + io_name_ + (a_.stop ? ", started in STOP" : "") + "\n";
    b += task_lines_;
    if (!modbus_address_.empty()) b += "ldrun: Modbus TCP on " + modbus_address_ + "\n";
    if (!monitor_line.empty()) b += monitor_line + "\n";
    if (!opt_.retain_file.empty()) b += "ldrun: retentive memory in " + opt_.retain_file + "\n";
    return b + "ldrun: Ctrl-C to stop" + (control_ ? " (or quit on stdin)" : "");
  }

  // Starts the monitor's server; returns its banner line.
  std::string start_monitor() {
    monitor_->attach(rt_.get());
    try {
      monitor_->start();
    } catch (std::exception& e) { throw UserError(std::string("ldrun: error: ") + e.what()); }
    std::string host = monitor_host_.find(':') != std::string::npos ? "[" + monitor_host_ + "]" : monitor_host_;
    std::string url = "http://" + host + ":" + std::to_string(monitor_->port()) + "/";
    std::string note = !a_.monitor_write      ? ""
                       : monitor_token_.empty() ? " (writes allowed)"
                       : print_token_           ? " (writes allowed with the token: open " + url + "?token=" + monitor_token_ + " once)"
                                                : " (writes allowed with the token of --monitor-token: open " + url + "?token=TOKEN once)";
    return "ldrun: monitor on " + url + note;
  }

  void serve_signals() {
    timespec ts{0, 100000000};
    while (!done_.load()) {
      int s = sigtimedwait(&sigs_, nullptr, &ts);
      if (s == SIGINT || s == SIGTERM) {
        std::fprintf(stderr, "ldrun: %s: stopping\n", s == SIGINT ? "SIGINT" : "SIGTERM");
        rt_->request_quit();
      }
    }
  }

  // The line protocol on stdin (docs/runtime.md), replies on stdout.
  void serve_control() {
    Control c{*rt_, [this](const std::string& f) { return load_program_online(f, load_budget_, load_budget_text_); }, a_.strict};
    LineReader in;
    std::string line;
    while (!done_.load()) {
      int r = in.next(line, 100);
      if (r == 0) continue;
      if (r < 0) {
        rt_->request_quit();
        break;
      }
      bool quit = false;
      std::string reply;
      try {
        reply = c.execute(line, quit);
      } catch (std::exception& e) { reply = std::string("error: ") + e.what(); }
      if (!reply.empty()) {
        std::fprintf(stdout, "%s\n", reply.c_str());
        std::fflush(stdout);
      }
      if (quit) {
        rt_->request_quit();
        break;
      }
    }
  }

  // The files --reload watches: each task's image (or source).
  std::vector<std::string> watched_files() const {
    std::vector<std::string> files;
    for (size_t i = 0; i < rt_->task_count(); i++) files.push_back(!a_.project.empty() ? "" : input_);
    if (!a_.project.empty()) {
      Project p = parse_project(a_.project);
      for (size_t i = 0; i < p.tasks.size(); i++) files[i] = p.tasks[i].path;
    }
    return files;
  }

  // A watched file that changes is loaded and switched in, like `load`.
  void serve_reload() {
    struct Seen { std::string file; int64_t mtime_ns = 0, size = -1; };
    auto stat_of = [](const std::string& f, int64_t& mt, int64_t& sz) {
      struct stat st;
      if (::stat(f.c_str(), &st) != 0) return false;
      mt = int64_t(st.st_mtim.tv_sec) * 1000000000 + st.st_mtim.tv_nsec, sz = st.st_size;
      return true;
    };
    std::vector<Seen> seen;
    for (auto& f : watched_files()) {
      Seen s{f};
      stat_of(f, s.mtime_ns, s.size);
      seen.push_back(s);
    }
    while (!done_.load()) {
      std::this_thread::sleep_for(std::chrono::milliseconds(250));
      for (size_t i = 0; i < seen.size(); i++) {
        int64_t mt, sz;
        if (!stat_of(seen[i].file, mt, sz) || (mt == seen[i].mtime_ns && sz == seen[i].size)) continue;
        seen[i].mtime_ns = mt, seen[i].size = sz;
        try {
          SwapReport r = rt_->replace(rt_->task_name(i), load_program_online(seen[i].file, load_budget_, load_budget_text_), seen[i].file,
                                     5000, a_.strict);
          std::fprintf(stderr, "ldrun: reloaded %s: %s\n", seen[i].file.c_str(), r.text().c_str());
        } catch (std::exception& e) {
          std::fprintf(stderr, "ldrun: reload of %s refused: %s\n", seen[i].file.c_str(), e.what());
        }
      }
    }
  }

  // With the line protocol a fault leaves the runtime up (status, run, quit);
  // without it, a fault ends the run (exit status 2).
  int finish() {
    rt_->wait_finished(-1, !control_);
    // The monitor keeps showing the last state until SIGINT/SIGTERM (or quit).
    while (monitor_ && !rt_->quit_requested()) std::this_thread::sleep_for(std::chrono::milliseconds(50));
    if (monitor_) monitor_->stop();
    bool faulted = rt_->faulted();
    done_.store(true);
    sig_thread_.join();
    if (ctl_thread_.joinable()) ctl_thread_.join();
    if (reload_thread_.joinable()) reload_thread_.join();
    rt_->shutdown();
    if (a_.stats) {
      std::string s = Runtime::format_stats(rt_->stats());
      std::fputs(s.c_str(), stderr);
    }
    return faulted && !control_ ? 2 : 0;
  }
};

}  // namespace soft_plc

int run_runtime(const std::string& input, const std::string& engine, const std::string& trace_file,
                const std::string& watch, int scans, const RtArgs& a) {
  return soft_plc::SoftPlcRun(input, trace_file, watch, a).run(engine, scans);
}

}  // namespace

namespace {

// ---------------------------------------------------------------- trace mode

struct TraceArgs {
  std::string input, engine, trace_file, watch;
  int opt_level;  // -1: none given
  bool cycles, sandbox;
};

// Keeps the cost of every scan of the engine it wraps (--cycles).
class Recorder : public Engine {
 public:
  explicit Recorder(Engine& e) : e_(e) {}
  void scan(ImageBytes& mem_bytes) override {
    e_.scan(mem_bytes);
    costs.push_back(e_.last_cost().value_or(ScanCost{}));
  }
  std::vector<ScanCost> costs;

 private:
  Engine& e_;
};

// --cycles: two more columns, the scan's cycles and microseconds.
std::string with_cycles(const std::string& out, const std::vector<ScanCost>& costs) {
  std::string with;
  size_t pos = 0, row = 0;
  while (pos < out.size()) {
    size_t nl = out.find('\n', pos);
    std::string line = out.substr(pos, nl - pos);
    pos = nl + 1;
    if (row == 0) line += ",cycles,us";
    else if (row - 1 < costs.size()) {
      char buf[64];
      std::snprintf(buf, sizeof buf, ",%llu,%.2f", (unsigned long long)costs[row - 1].cycles, costs[row - 1].us());
      line += buf;
    }
    with += line + "\n";
    row++;
  }
  return with;
}

// "a, b, c"
std::string comma_list(const std::vector<std::string>& names) {
  std::string s;
  for (const std::string& n : names) s += (s.empty() ? "" : ", ") + n;
  return s;
}

// The engines of target t that run its code (code) or its images' IL.
std::vector<std::string> engines_of(const Target& t, bool code) {
  std::vector<std::string> n;
  for (const TargetEngine& e : t.engines)
    if (e.runs_code == code) n.emplace_back(e.name);
  return n;
}

// Refusals before anything is read or compiled: the engine's name, the
// options it takes, and the target of an image input (`image`, or nullptr).
void check_trace_args(const TraceArgs& a, const FoundEngine& fe, const Target* image) {
  bool il_engine = std::find(std::begin(kIlEngines), std::end(kIlEngines), a.engine) != std::end(kIlEngines);
  const Target* simulated = fe.target && !fe.target->host ? fe.target
                            : image && !image->host && (!fe.engine || fe.engine->runs_code) ? image : nullptr;
  if (a.sandbox && simulated) {
    std::vector<std::string> here = engine_names(true);
    here.insert(here.end(), {"interp", "c"});
    throw UserError("ldrun: error: --sandbox is for the engines that run on this machine (" + comma_list(here) + "); the " +
                    std::string(simulated->title) + " engines are simulated");
  }
  if (!g_task.empty() && simulated && !il_engine)
    throw UserError("ldrun: error: --task is not taken by the " + std::string(simulated->title) +
                    " engines: compile the task's image first (ldc FILE --task NAME --target=" + std::string(simulated->name) +
                    " -o F.bin)");
  if (a.cycles && !(fe.target && !fe.target->host)) {
    std::vector<std::string> sim;
    for (const std::string& e : engine_names(false)) sim.push_back("--engine=" + e);
    throw UserError("ldrun: error: --cycles needs " + or_list(sim));
  }
  if (!fe.engine && !il_engine)
    throw UserError("ldrun: error: unknown engine '" + a.engine + "' (" + or_list(all_engines()) + ")");
  if (a.opt_level >= 0 && (!fe.engine || !fe.engine->runs_code || is_image_file(a.input))) {
    std::vector<std::string> code;
    for (const Target& t : targets())
      for (const std::string& e : engines_of(t, true)) code.push_back(e);
    const std::string why = is_image_file(a.input) ? "an image is already compiled"
                            : a.engine == "c"      ? "the C route is compiled by the system C compiler at -O2"
                                                   : "the " + a.engine + " engine interprets the IL";
    throw UserError("ldrun: error: -O" + std::to_string(a.opt_level) + " is for a source compiled to native code (--engine=" +
                    or_list(code) + "); " + why);
  }
}

// An image for an engine on another target's code: where to go instead.
std::string wrong_image(const TraceArgs& a, const FoundEngine& fe, const Target& image) {
  if (fe.target->host) {  // the default engine on a simulated target's image
    std::vector<std::string> other = engines_of(image, false);
    other.push_back("interp");
    return "ldrun: error: " + a.input + " is " + std::string(image.an_image) + "; use --engine=" +
           or_list(engines_of(image, true)) + " (or " + comma_list(other) + ")";
  }
  std::vector<std::string> il = engines_of(*fe.target, false);
  return "ldrun: error: " + a.input + " is not " + std::string(fe.target->an_image) + "; compile it with ldc --target=" +
         std::string(fe.target->name) + ", or use --engine=" + or_list(il.empty() ? std::vector<std::string>{"interp"} : il);
}

// ldrun FILE --engine=E [--trace ...]: the program over the trace, scan by scan.
int run_trace_mode(const TraceArgs& a, RunOptions opt) {
  const FoundEngine fe = find_engine(a.engine);
  const Target* image_target = image_file_target(a.input);
  check_trace_args(a, fe, image_target);
  // The program: an image (checked in full before anything runs), or a
  // source file compiled in memory.
  Image img;
  std::string tmpdir, so_path;
  struct Cleanup {
    std::string& dir;
    ~Cleanup() { if (!dir.empty()) remove_tree(dir); }
  } cleanup{tmpdir};
  bool code = fe.engine && fe.engine->runs_code;
  if (is_image_file(a.input)) {
    img = load_image_file(a.input);
    if (a.engine == "c") throw UserError("ldrun: error: --engine=c needs the program's source (.ld or .il), not an image");
    if (code && img.target != fe.target->image_kind) throw UserError(wrong_image(a, fe, target_of(img.target)));
  } else if (a.engine == "c") {
    Compiled c = compile_source(a.input, false, g_task);
    img = il_image(c.il);  // the IL and its line map name a scan fault's place
    tmpdir = make_temp_dir();
    so_path = build_c_shared_object(c, tmpdir);
  } else {
    Compiled c = compile_source(a.input, false, g_task);
    img = code ? target_image(*fe.target, c.il, a.input, std::max(a.opt_level, 0)) : il_image(c.il);
  }
  const Layout& layout = img.layout;
  std::unique_ptr<Engine> eng = fe.engine           ? fe.engine->make(img)
                                : a.engine == "interp" ? make_interp_engine(img.il, layout)
                                : a.engine == "fast"   ? make_fast_interp_engine(img.il, layout)
                                                       : make_shared_object_engine(so_path, kCScanSymbol);
  if (a.sandbox) eng = make_sandboxed_engine(std::move(eng), layout);
  for (Probe& p : parse_watch(a.watch, img.aliases)) opt.watch.push_back(p);
  Trace trace;
  if (!a.trace_file.empty()) trace = load_trace(a.trace_file, img.aliases);
  std::string out;
  std::vector<ScanFault> faults;
  if (a.cycles) {
    Recorder rec(*eng);
    faults = run_trace(rec, layout, a.trace_file.empty() ? nullptr : &trace, a.trace_file, opt, out);
    out = with_cycles(out, rec.costs);
  } else {
    faults = run_trace(*eng, layout, a.trace_file.empty() ? nullptr : &trace, a.trace_file, opt, out);
  }
  std::fwrite(out.data(), 1, out.size(), stdout);
  std::fflush(stdout);
  for (const ScanFault& f : faults)
    std::fprintf(stderr, "ldrun: scan %d: %s; %s\n", f.scan, describe_scan_fault(f, &img).c_str(),
                 opt.continue_after_fault ? "the next scan runs (--fault=continue)"
                                          : "the program stops (a PLC would drive its outputs to the safe state)");
  return faults.empty() || opt.continue_after_fault ? 0 : 1;
}

int ldrun_main(int argc, char** argv) {
  std::string input, engine(host_target().engines.front().name), trace_file, watch;
  bool cycles = false;
  int opt_level = -1;  // -O<n> for a source compiled to native code
  RunOptions opt;
  RtArgs rta;
  std::string period_text;
  DiagOptions warnings;
  for (int i = 1; i < argc; i++) {
    std::string a = argv[i];
    auto value = [&](const std::string& name) -> std::string {
      if (a.rfind(name + "=", 0) == 0) return a.substr(name.size() + 1);
      if (a == name && i + 1 < argc) return argv[++i];
      throw UserError("ldrun: error: " + name + " needs a value");
    };
    auto flag = [&](const char* name, bool& f) {
      if (a != name) return false;
      f = true, rta.on = true;
      return true;
    };
    auto opt_value = [&](const char* name, std::string& v) {
      if (a != name && a.rfind(std::string(name) + "=", 0) != 0) return false;
      v = value(name), rta.on = true;
      return true;
    };
    if (flag("--free-run", rta.free_run) || flag("--rt", rta.rt) || flag("--cold", rta.cold) || flag("--stop", rta.stop) ||
        flag("--stats", rta.stats) || flag("--reload", rta.reload) || flag("--strict", rta.strict) || opt_value("--project", rta.project) ||
        opt_value("--io", rta.io) || opt_value("--control", rta.control) || opt_value("--clock", rta.clock) ||
        opt_value("--watchdog", rta.watchdog) || opt_value("--retain-every", rta.retain_every) ||
        opt_value("--retain", rta.retain) || opt_value("--out", rta.out) || opt_value("--block", rta.block) ||
        opt_value("--modbus-map", rta.modbus_map) ||
        opt_value("--modbus-connections", rta.modbus_connections) || opt_value("--modbus", rta.modbus) ||
        opt_value("--modbus-per-address", rta.modbus_per_address) ||
        opt_value("--modbus-frame-timeout", rta.modbus_frame_timeout) ||
        opt_value("--modbus-idle-timeout", rta.modbus_idle_timeout) ||
        opt_value("--modbus-write-timeout", rta.modbus_write_timeout) ||
        opt_value("--modbus-pending-writes", rta.modbus_pending_writes) ||
        opt_value("--monitor-token", rta.monitor_token) || opt_value("--monitor-connections", rta.monitor_connections) ||
        opt_value("--monitor-per-address", rta.monitor_per_address) || opt_value("--monitor-streams", rta.monitor_streams) ||
        opt_value("--monitor", rta.monitor) || flag("--monitor-write", rta.monitor_write) ||
        opt_value("--load-budget", rta.load_budget) ||
        flag("--monitor-remote", rta.monitor_remote)) {
    } else if (a == "--monitor-host" || a.rfind("--monitor-host=", 0) == 0) {
      rta.monitor_hosts.push_back(value("--monitor-host"));
      rta.on = true;
    } else if (a.rfind("--engine", 0) == 0) engine = value("--engine");
    else if (a.rfind("--task", 0) == 0) g_task = value("--task");
    else if (a == "--cycles") cycles = true;  // simulated engines: cycles and us per scan
    else if (a == "--fault=continue") opt.continue_after_fault = true;  // trace mode: run on after a scan fault
    else if (a == "--fault=stop") opt.continue_after_fault = false;
    else if (a == "-O0" || a == "-O1" || a == "-O2") opt_level = a[2] - '0';
    else if (a == "--sandbox") rta.sandbox = true;
    else if (a.rfind("--trace", 0) == 0) trace_file = value("--trace");
    else if (a.rfind("--watch", 0) == 0) watch = value("--watch");
    else if (a.rfind("--scans", 0) == 0) {
      std::string v = value("--scans");
      if (v.empty() || v.size() > 9 || v.find_first_not_of("0123456789") != std::string::npos)
        throw UserError("ldrun: error: bad --scans '" + v + "'");
      opt.scans = std::stoi(v);
    } else if (a.rfind("--period", 0) == 0) {
      period_text = value("--period");
    } else if (a == "-h" || a == "--help") { std::fputs(usage().c_str(), stdout); return 0; }
    else if (a == "--version") return print_version("ldrun");
    else if (auto why = warnings.parse(a)) {  // -W..., -w, as ldc's (docs/diagnostics.md)
      if (!why->empty()) throw UserError("ldrun: error: " + *why);
    } else if (!a.empty() && a[0] == '-') throw UserError("ldrun: error: unknown option '" + a + "'\n" + usage());
    else if (input.empty()) input = a;
    else throw UserError("ldrun: error: more than one program");
  }
  set_ldrun_warnings(warnings);
  if (rta.on) {
    rta.period = period_text;
    return run_runtime(input, engine, trace_file, watch, opt.scans, rta);
  }
  if (!period_text.empty()) {
    auto p = parse_period(period_text);
    if (!p) {  // the trace runner's dt is whole milliseconds (docs/format.md, "Traces")
      std::string why = duration_problem(period_text, 0);
      throw UserError("ldrun: error: bad --period: " +
                      (why.empty() ? "'" + period_text + "' is not whole milliseconds: the trace runner's dt is (e.g. 1ms, 10ms, 1s); "
                                     "the runtime (--io, --project) takes periods from 50us"
                                   : why));
    }
    opt.period_ms = *p;
    if (*p == 0) ldrun_option_warning("period", "--period " + period_text + ": dt is 0 in every scan, so no timer advances");
  }
  if (input.empty()) throw UserError("ldrun: error: no program\n" + usage());
  return run_trace_mode({input, engine, trace_file, watch, opt_level, cycles, rta.sandbox}, opt);
}

}  // namespace

int main(int argc, char** argv) {
  return run_tool("ldrun", [&] { return ldrun_main(argc, argv); });
}
