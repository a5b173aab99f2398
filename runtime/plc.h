// runtime/plc.h -- the soft-PLC runtime behind `ldrun --io=...` and
// `ldrun --project` (docs/runtime.md): periodic scan tasks (paper 000, Fig. 4)
// with RUN/STOP/FAULT states, several tasks and programs sharing one I/O
// image refreshed block by block from the configuration table (paper 002),
// online download of one task's image at its scan boundary (paper 004),
// retentive memory saved crash-safely, I/O drivers behind one interface.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "loader/loader.h"
#include "runtime/online_carry.h"
#include "runtime/runtime.h"

namespace ldc::plc {

// A program bound to a task, ready to be run (from a project, or one image).
struct TaskSpec {
  std::string name;            // task name
  std::string program;         // program name
  std::string resource;
  uint32_t processor = 0;
  uint32_t period_us = 10000;
  uint32_t priority = 0;       // 0 highest
  uint32_t watchdog_us = 0;    // 0: Options::watchdog_us
  bool exclusive = false;
  std::string file;            // where the image came from
  Image image;
};

enum class State : uint32_t { Stop = 0, Run = 1, Fault = 2 };
const char* state_name(State s);

// A byte range of the memory image (same offsets in every image: the
// layout is standard up to the edge area).
struct Run {
  uint32_t offset, size;
};

// What an I/O driver sees of a scan.
struct ScanContext {
  size_t task;         // task index
  uint64_t scan;       // scans of this task since the last (re)start, this one included
  std::span<const Run> runs;  // read_inputs: the task's X/WX runs; write_outputs: its Y/WY runs
  // before_scan: the task's engine, told of every write a driver makes to
  // the task's memory (Engine::written: the change-driven scan runs what
  // depends on it; docs/change-driven.md)
  Engine* engine = nullptr;
  void written(const Layout& L, Area a, uint32_t index) const {
    if (engine) engine->written(L.addr(a, index), L.elem_size(a));
  }
};

// An I/O driver: the world outside.  All calls but before_scan/after_scan
// happen with the global image locked; they must be short.
class IoDriver {
 public:
  virtual ~IoDriver() = default;
  // Once, before the tasks start.
  virtual void attach(uint8_t* global, const Layout& layout, uint32_t block_size) {
    (void)global, (void)layout, (void)block_size;
  }
  // Before a task's scan: refresh its input blocks (X, WX) of the global image.
  virtual void read_inputs(uint8_t* global, const ScanContext& c) { (void)global, (void)c; }
  // After a task's scan was copied out, before write_outputs: put back what
  // must hold whatever the scan wrote (the monitor's forced outputs and
  // relays), in the global image and the task's memory `mem` (announced to
  // c.engine).
  virtual void hold_outputs(uint8_t* global, uint8_t* mem, const ScanContext& c) { (void)global, (void)mem, (void)c; }
  // After a task's scan was copied out: publish its output blocks (Y, WY).
  virtual void write_outputs(const uint8_t* global, const ScanContext& c) { (void)global, (void)c; }
  // Outputs to the safe state: the global Y and WY are already all zero.
  virtual void safe_outputs(const uint8_t* global) { (void)global; }
  virtual void state_changed(State s) { (void)s; }
  // On the task's thread around the scan, with its private memory: before
  // (after the inputs were copied in; may set dt), and after (global locked).
  virtual void before_scan(const ScanContext& c, uint8_t* mem, std::optional<int32_t>& dt) { (void)c, (void)mem, (void)dt; }
  virtual void after_scan(const ScanContext& c, const uint8_t* mem, const uint8_t* global) { (void)c, (void)mem, (void)global; }
  // After an online download switched task `task` to `image` (Runtime::
  // replace, on the caller's thread, once the task runs it): the monitor
  // redraws the program.  Runtime::generation(task) already counts it.
  virtual void program_replaced(size_t task, const Image& image) { (void)task, (void)image; }
  // Called once when the runtime shuts down (outputs are safe by then).
  virtual void detach() {}
};

// The trace driver: the rows of an input trace before each scan of task 0
// and a CSV row of watched devices after it -- what run_trace does, so
// `--io=trace --clock=virtual --free-run` prints what `ldrun --trace` prints.
std::unique_ptr<IoDriver> make_trace_driver(const Trace* trace, std::vector<Probe> watch, std::string* out_or_null,
                                            FILE* out_file);
// The shared-memory driver (runtime/shm_layout.h): creates the POSIX shared
// memory object `name` ("/ldc"); throws std::runtime_error if it cannot.
std::unique_ptr<IoDriver> make_shm_driver(const std::string& name);
// No outside world: inputs change only by `set` (the line protocol).
std::unique_ptr<IoDriver> make_null_driver();

struct Options {
  enum class Clock { Real, Virtual } clock = Clock::Real;  // dt: elapsed CLOCK_MONOTONIC, or the period
  bool free_run = false;         // do not sleep between scans
  bool rt = false;               // SCHED_FIFO and mlockall when permitted
  int64_t scans = -1;            // every task stops after this many scans; -1: no limit
  uint32_t watchdog_us = 200000; // scan time limit of tasks that set none; 0: off
  bool start_stopped = false;    // start in STOP (the line protocol's `run` starts)
  uint32_t block_size = 16;
  std::string retain_file;       // "" : nothing is saved
  int64_t retain_every_us = 1000000;
  bool cold = false;             // start with cleared retentive memory if the file is unusable
  std::function<void(const std::string&)> log;  // one message per call (to stderr)
};

using EngineFactory = std::function<std::unique_ptr<Engine>(const Image&)>;

// Per-task timing statistics, in microseconds.
struct Quantiles {
  size_t n = 0;
  double min = 0, median = 0, p99 = 0, max = 0;
};
struct TaskStats {
  std::string task;
  uint32_t period_us = 0;
  uint64_t scans = 0, overruns = 0, skipped_periods = 0, input_retries = 0;
  Quantiles scan_us;    // scan time: start of the scan (after waking) to the end of its output refresh
  Quantiles jitter_us;  // period jitter: start-to-start interval minus the period
  Quantiles wake_us;    // wake-up latency: start of the scan minus its release time
};

// The result of an online download.
struct SwapReport {
  std::string task;
  uint64_t at_scan = 0;      // the first scan that ran the new image
  double latency_us = 0;     // request to the new image in place (waiting for the boundary included)
  double work_us = 0;        // the switch itself, on the task's thread
  CarryReport carry;         // what the new program got of the running one's state
  std::string text() const;
};

class Runtime {
 public:
  // Checks the configuration (conflicts refused, as ldc --project does),
  // prepares every task and restores retentive memory.  Throws
  // std::runtime_error with the message on anything refused.
  Runtime(std::vector<TaskSpec> tasks, Options opt, EngineFactory engines, std::unique_ptr<IoDriver> io);
  ~Runtime();
  Runtime(const Runtime&) = delete;
  Runtime& operator=(const Runtime&) = delete;

  void start();                 // starts the task threads (RUN unless start_stopped)
  void run();                   // STOP/FAULT -> RUN: warm restart (retentive memory kept)
  void stop();                  // RUN -> STOP: outputs to the safe state, retentive memory saved
  void shutdown();              // STOP, final save, threads joined, driver detached (idempotent)
  // One task alone (the monitor's per-task RUN/STOP): stop_task holds task i
  // -- no more scans, the Y and WY points it writes go to the safe state (0)
  // and are published -- while the others run on; run_task releases it with
  // a warm restart of its memory (retentive memory kept) at its next scan.
  // The runtime's state does not change.  Throws std::out_of_range for a bad index.
  void stop_task(size_t i);
  void run_task(size_t i);
  // `restart TASK`: task i alone from its initial state, as STOP -> RUN
  // does for the whole PLC: its Y and WY points to the safe state and
  // published (stop_task), then its memory cleared but for its retentive
  // ranges and its next scan a first scan (S1 set).  The other tasks run on;
  // a held task is released.
  void restart_task(size_t i);
  bool task_held(size_t i) const;
  // How many online downloads task i has run (0: the program it started
  // with).  Bumped at the switch, on the task's thread, so that its I/O
  // driver's before_scan/after_scan see the generation of the memory they get.
  uint64_t generation(size_t i) const;
  State state() const;
  bool faulted() const { return state() == State::Fault; }
  std::string fault_message() const;

  // Waits until every task has completed `n` more scans, or stopped
  // scanning; false on timeout.
  bool wait_scans(uint64_t n, int64_t timeout_ms);
  // Waits until every task reached Options::scans, quit was requested, or
  // (if fault_ends) the runtime faulted; false on timeout (timeout_ms < 0: forever).
  bool wait_finished(int64_t timeout_ms, bool fault_ends = true);
  void request_quit();
  bool quit_requested() const;

  // Online download: validates `img` against the running task (target,
  // I/O write conflicts), prepares it, and switches at the task's next scan
  // boundary, carrying the running program's state by identity
  // (runtime/online_carry.h); waits for the switch.  With `strict`, a
  // download that would reset a variable (its type changed) is refused.
  // Throws std::runtime_error with the reason if refused.
  SwapReport replace(const std::string& task, Image img, const std::string& file, int64_t timeout_ms = 5000,
                     bool strict = false);

  // Reads a device or a variable by name: shared ones from the global image,
  // private ones from the task's memory at its next scan boundary.  "T.D5"
  // names the task; values as ldrun --watch prints them (docs/format.md).
  std::string get(const std::string& device, int64_t timeout_ms = 2000);
  // Writes an input (X, WX) or a global relay (M, K) in the global image, or
  // a task's variable (D, F: at its next scan boundary); the value as a trace
  // cell of it (INT32, a typed variable's type, IEC literals: T#1s, 'text').
  void set(const std::string& device, const std::string& value, int64_t timeout_ms = 2000);

  size_t task_count() const;
  const std::string& task_name(size_t i) const;
  size_t find_task(const std::string& name) const;  // SIZE_MAX if none
  // "TASK.NAME" -> the task and NAME when TASK is a task; else {0, the whole}.
  std::pair<size_t, std::string> split_task(const std::string& device) const;
  std::string status() const;                 // one line
  std::vector<TaskStats> stats() const;       // (after shutdown: exact; while running: approximate)
  static std::string format_stats(const std::vector<TaskStats>& s);

  // Saves the retentive memory now ("" on success, else the error).
  std::string save_retentive();

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

// ---------------------------------------------------------------- retentive file
// A snapshot of retentive memory (docs/runtime.md, "Retentive memory").
struct RetainRecord {
  std::string scope;  // "" : the global image; else a task name
  Area area;
  uint32_t first, count;
  std::vector<uint8_t> bytes;  // count elements of the area
  bool operator==(const RetainRecord&) const = default;
};
struct RetainSnapshot {
  uint64_t sequence = 0;
  uint64_t saved_ns = 0;  // CLOCK_REALTIME
  std::vector<RetainRecord> records;
};
std::vector<uint8_t> encode_retain(const RetainSnapshot& s);
// Throws std::runtime_error "FILE: ..." for anything not exactly right.
RetainSnapshot decode_retain(std::span<const uint8_t> bytes, const std::string& name);
// Writes FILE.tmp, fsyncs it, renames it over FILE and fsyncs the
// directory.  "" on success, else the error.
std::string write_retain_file(const std::string& path, const RetainSnapshot& s);

// ---------------------------------------------------------------- control
// The stdin/stdout line protocol (docs/runtime.md): one command per line,
// one reply line per command.  `load` calls `loader(file)` for the image.
struct Control {
  Runtime& rt;
  std::function<Image(const std::string& file)> loader;
  bool strict = false;  // every `load` as `load --strict` (ldrun --strict)
  // Executes one line; returns the reply (without newline), or "" for a
  // blank or comment line.  Sets quit on `quit`.
  std::string execute(const std::string& line, bool& quit);
};

// Durations for messages: "412 us", "1.25 ms".
std::string format_us(double us);

}  // namespace ldc::plc
