// runtime/plc.cpp -- the soft-PLC runtime: tasks, the global image, the
// scan loop, online download, the watchdog and retentive saving
// (runtime/plc.h, docs/runtime.md).
//
// Threads: one per task (scan loop), a watchdog monitor, a retentive saver,
// and the caller's (control).  Data ownership:
//   the global image (X Y M K WX WY)  -- under the image lock (a priority-
//       inheriting mutex), taken twice per scan for short copies;
//   a task's private memory           -- its own thread only; the control
//       thread reaches it through requests run at the task's scan boundary;
//   state and epoch                   -- changed under the image lock, read
//       atomically; a scan publishes its results only if the state is still
//       RUN and the epoch the one it started in.
#include "runtime/plc.h"

#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <cstring>
#include <future>
#include <map>
#include <mutex>
#include <stdexcept>
#include <thread>

#include "runtime/failsafe.h"
#include "runtime/online_carry.h"

namespace ldc::plc {

const char* state_name(State s) {
  switch (s) {
    case State::Stop: return "STOP";
    case State::Run: return "RUN";
    case State::Fault: return "FAULT";
  }
  return "?";
}

std::string format_us(double us) {
  char buf[48];
  if (std::fabs(us) >= 10000) std::snprintf(buf, sizeof buf, "%.2f ms", us / 1000);
  else if (std::fabs(us) >= 100) std::snprintf(buf, sizeof buf, "%.0f us", us);
  else std::snprintf(buf, sizeof buf, "%.1f us", us);
  return buf;
}

std::string SwapReport::text() const {
  return "task " + task + " switched at scan " + std::to_string(at_scan) + ": latency " + format_us(latency_us) +
         " (switch " + format_us(work_us) + "); " + carry.text();
}

namespace {

int64_t now_ns() {
  timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return int64_t(ts.tv_sec) * 1000000000 + ts.tv_nsec;
}

void sleep_until(int64_t t) {
  timespec ts{time_t(t / 1000000000), long(t % 1000000000)};
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {}
}

// The image lock: a mutex with priority inheritance, so a low-priority task
// holding it is boosted while a high-priority one waits (no inversion).
class ImageLock {
 public:
  ImageLock() {
    pthread_mutexattr_t a;
    pthread_mutexattr_init(&a);
    pthread_mutexattr_setprotocol(&a, PTHREAD_PRIO_INHERIT);
    pthread_mutex_init(&m_, &a);
    pthread_mutexattr_destroy(&a);
  }
  ~ImageLock() { pthread_mutex_destroy(&m_); }
  void lock() { pthread_mutex_lock(&m_); }
  void unlock() { pthread_mutex_unlock(&m_); }
  // The fatal path's lock: it must not wait forever for a thread that died
  // holding the lock, nor for its own thread.
  bool try_lock_for_ms(int ms) {
    timespec t;
    clock_gettime(CLOCK_REALTIME, &t);
    t.tv_sec += ms / 1000;
    t.tv_nsec += long(ms % 1000) * 1000000;
    if (t.tv_nsec >= 1000000000) t.tv_sec++, t.tv_nsec -= 1000000000;
    return pthread_mutex_timedlock(&m_, &t) == 0;
  }

 private:
  pthread_mutex_t m_;
};

// A ring of the last samples (ns, clamped to int32) plus exact extremes.
struct Ring {
  std::vector<int32_t> v;
  size_t n = 0;
  int64_t lo = INT64_MAX, hi = INT64_MIN;
  Ring() : v(size_t(1) << 16) {}
  void add(int64_t ns) {
    lo = std::min(lo, ns), hi = std::max(hi, ns);
    v[n++ % v.size()] = int32_t(std::clamp<int64_t>(ns, INT32_MIN, INT32_MAX));
  }
  Quantiles quantiles() const {
    Quantiles q;
    size_t k = std::min(n, v.size());
    q.n = n;
    if (!k) return q;
    std::vector<int32_t> s(v.begin(), v.begin() + k);
    auto at = [&](double f) {
      size_t i = std::min(k - 1, size_t(f * double(k - 1) + 0.5));
      std::nth_element(s.begin(), s.begin() + i, s.end());
      return s[i] / 1000.0;
    };
    q.median = at(0.5), q.p99 = at(0.99);
    q.min = lo / 1000.0, q.max = hi / 1000.0;
    return q;
  }
};

// What the control thread keeps of a task's image (for messages and for
// planning an online download): everything but the code.
Image control_copy(const Image& img) {
  Image c;
  c.target = img.target, c.source = img.source, c.layout = img.layout, c.il = img.il, c.lines = img.lines;
  c.rung_titles = img.rung_titles, c.aliases = img.aliases, c.vars = img.vars, c.retentive = img.retentive;
  return c;
}

// A program ready to run: its engine and the runs its configuration rows give.
struct Prog {
  Image image;
  std::unique_ptr<Engine> engine;
  std::string file;
  std::vector<ConfigRow> own;
  std::vector<IoAccess> accesses;
  std::vector<Run> in_runs;      // read or written blocks: global -> private before the scan
  std::vector<Run> out_runs;     // written blocks: private -> global after it (changed bytes only)
  std::vector<Run> input_runs;   // X/WX blocks read: the driver refreshes them
  std::vector<Run> output_runs;  // Y/WY blocks written: the driver publishes them
  std::vector<RetentiveRange> private_ranges, shared_ranges;
  std::vector<Run> private_retain;  // byte runs of private_ranges
  size_t out_bytes = 0, retain_bytes = 0;
};

void add_run(std::vector<Run>& runs, uint32_t off, uint32_t size) {
  if (!runs.empty() && runs.back().offset + runs.back().size == off) runs.back().size += size;
  else runs.push_back(Run{off, size});
}

std::unique_ptr<Prog> make_prog(Image img, const std::string& file, uint32_t block_size, const EngineFactory& engines) {
  auto p = std::make_unique<Prog>();
  p->file = file;
  p->accesses = io_accesses(img.il);
  if (img.config) {
    // The image's own rows, checked against its IL by read_image.
    for (const ConfigRow& r : img.config->rows)
      if (r.flags & (kBlockRead | kBlockWrite)) p->own.push_back(ConfigRow{r.area, r.block, uint8_t(r.flags & 3), 0, 0});
  } else {
    p->own = own_rows(p->accesses, block_size);
  }
  const Layout& L = img.layout;
  for (const ConfigRow& r : p->own) {
    uint32_t first = r.block * block_size, n = std::min(block_size, L.count[int(r.area)] - first);
    uint32_t off = L.addr(r.area, first), size = n * L.elem_size(r.area);
    add_run(p->in_runs, off, size);
    bool input = r.area == Area::X || r.area == Area::WX, output = r.area == Area::Y || r.area == Area::WY;
    if (r.flags & kBlockWrite) add_run(p->out_runs, off, size), p->out_bytes += size;
    if (input && (r.flags & kBlockRead)) add_run(p->input_runs, off, size);
    if (output && (r.flags & kBlockWrite)) add_run(p->output_runs, off, size);
  }
  for (const RetentiveRange& r : img.retentive) {
    if (area_is_shared(r.area)) {
      p->shared_ranges.push_back(r);
    } else {
      p->private_ranges.push_back(r);
      uint32_t size = r.count * L.elem_size(r.area);
      p->private_retain.push_back(Run{L.addr(r.area, r.first), size});
      p->retain_bytes += size;
    }
  }
  p->engine = engines(img);
  p->image = std::move(img);
  return p;
}

struct Task {
  TaskSpec spec;  // its image moved into prog
  std::unique_ptr<Prog> prog;
  ImageBytes mem;  // the task's memory image, between guard pages
  std::vector<uint8_t> snapshot, retain_shadow, retain_tmp;
  uint32_t watchdog_us = 0;
  std::thread th;

  // requests run at the scan boundary
  std::mutex req_mu;
  std::condition_variable req_cv;
  std::vector<std::function<void()>> reqs;
  std::atomic<bool> has_req{false};

  // status, read by other threads
  std::atomic<uint64_t> scans{0};      // since the last (re)start
  std::atomic<uint64_t> total_scans{0}, overruns{0}, skipped{0};
  std::atomic<int64_t> scan_begin{0};  // of the scan under way, 0 if none
  std::atomic<int64_t> last_scan_ns{0}, max_scan_ns{0};
  std::atomic<bool> finished{false};
  std::atomic<bool> held{false};     // stopped alone (stop_task); changed under glock
  std::atomic<bool> restart{false};  // run_task: warm restart at the next scan
  std::atomic<uint64_t> generation{0};  // online downloads run (Runtime::generation)

  // the task thread's own
  uint64_t epoch = 0;
  bool first = true;
  int64_t carry_ns = 0, last_start = 0, release = 0;
  Ring scan_ring, jitter_ring, wake_ring;
  std::mutex stats_mu;  // the rings; the task only try_locks it

  // control-side copies (under Impl::ctl_mu), so control never reads prog
  std::string ctl_file;
  std::vector<IoAccess> ctl_accesses;
  std::vector<Alias> ctl_aliases;
  Image ctl_image;  // the running image without its code (control_copy)
};

void clear_shared_outputs(uint8_t* g, const Layout& L) {
  std::memset(g + L.offset[int(Area::Y)], 0, L.count[int(Area::Y)]);
  std::memset(g + L.offset[int(Area::WY)], 0, 4 * L.count[int(Area::WY)]);
}

}  // namespace

struct Runtime::Impl {
  Options opt;
  EngineFactory engines;
  std::unique_ptr<IoDriver> io;
  Layout glayout = Layout::standard(0);
  std::vector<uint8_t> global;
  ImageLock glock;
  std::vector<std::unique_ptr<Task>> tasks;
  std::atomic<State> state{State::Stop};
  std::atomic<uint64_t> epoch{1};
  std::string fault_msg;                 // under glock
  std::vector<RetentiveRange> global_ranges;  // shared retentive ranges (union), under glock

  std::mutex mu;  // quit / finished / fault notifications
  std::condition_variable cv;
  bool quit = false;
  std::atomic<bool> stopping{false};
  bool started = false, shut = false;
  std::thread saver, monitor;
  std::mutex ctl_mu;   // control operations (replace, get, status) among themselves
  std::timed_mutex save_mu;  // one retentive save at a time (timed: the fatal path's rescue waits a bounded time)
  uint64_t retain_seq = 0;
  std::vector<RetainRecord> last_saved;
  std::atomic<bool> warned_rt{false};

  void log(const std::string& m) {
    if (opt.log) opt.log(m);
  }

  // ---- configuration
  void check_conflicts(const std::vector<const std::vector<IoAccess>*>& acc, size_t only_task, const std::string& new_file) {
    std::vector<ConfigTask> cts;
    for (size_t i = 0; i < tasks.size(); i++) {
      const TaskSpec& s = tasks[i]->spec;
      ConfigTask c;
      c.program = s.program, c.task = s.name, c.resource = s.resource;
      c.processor = s.processor, c.period_us = s.period_us, c.priority = s.priority, c.exclusive = s.exclusive;
      c.accesses = *acc[i];
      cts.push_back(std::move(c));
    }
    SystemConfig sc = configure(cts, opt.block_size);
    std::string msg;
    for (const WriteConflict& c : sc.conflicts) {
      if (only_task != SIZE_MAX && c.first != only_task && c.second != only_task) continue;
      const TaskSpec &a = tasks[c.first]->spec, &b = tasks[c.second]->spec;
      auto who = [](const TaskSpec& t) {
        return "program '" + t.program + "' (task " + t.name + ", processor " + std::to_string(t.processor) + ")";
      };
      std::string why = a.processor != b.processor ? "a block is written by one processor only"
                        : a.exclusive ? "task '" + a.name + "' is exclusive" : "task '" + b.name + "' is exclusive";
      if (!msg.empty()) msg += "\n";
      msg += (new_file.empty() ? std::string() : new_file + ": error: ") + "I/O block " +
             block_name(c.area, c.block, opt.block_size) + " is written by " + who(a) + " and by " + who(b) + "; " + why;
      const auto& mine = c.first == only_task ? c.first_writes : c.second_writes;
      if (only_task != SIZE_MAX && !mine.empty()) msg += " (the new image writes " + point_name(mine[0].area, mine[0].index) + ")";
    }
    if (!msg.empty()) throw std::runtime_error(msg);
  }

  // ---- state changes (all under glock)
  void fault(const std::string& msg) {
    std::string driver_error;
    {
      std::lock_guard<ImageLock> g(glock);
      if (state.load() == State::Fault) return;
      state.store(State::Fault);
      fault_msg = msg;
      failsafe::note_fault(msg.c_str());
      driver_error = enter_safe_state(State::Fault);
    }
    log(msg);
    if (!driver_error.empty()) log(driver_error);
    std::lock_guard<std::mutex> l(mu);
    cv.notify_all();
  }

  // Under glock: the global outputs to 0, published through the driver,
  // and the new state.  A driver that fails here cannot stop the safe
  // state: the shared-memory segment is zeroed directly; "" or what failed.
  std::string enter_safe_state(State s) {
    clear_shared_outputs(global.data(), glayout);
    std::string err;
    try {
      io->safe_outputs(global.data());
    } catch (const std::exception& e) {
      failsafe::zero_segment_outputs();
      err = std::string("ldrun: the I/O driver failed to drive the outputs safe (") + e.what() +
            "); the shared-memory outputs were zeroed directly";
    }
    try {
      io->state_changed(s);
    } catch (const std::exception& e) {
      if (err.empty()) err = std::string("ldrun: the I/O driver failed to take the state ") + state_name(s) + ": " + e.what();
    }
    return err;
  }

  // ---- the fatal path's rescue (runtime/failsafe.h), on the rescue thread
  // while the thread that failed waits; the segment's outputs are off
  // already.  Under the image lock: FAULT with the reason (no scan publishes
  // after it) and a copy of the retentive memory, consistent because no scan
  // is half published; then the save; then the outputs through the driver
  // chain (Modbus and the monitor see them), last because a driver's own lock
  // may be held by the thread that failed.  Every wait is bounded.
  static void rescue(void* self, const char* reason) { static_cast<Impl*>(self)->rescue(reason); }
  void rescue(const char* reason) {
    if (!glock.try_lock_for_ms(1000)) {
      log("ldrun: fatal: the image lock stayed taken for 1 s; retentive memory not saved");
      return;
    }
    std::vector<RetainRecord> recs;
    bool collected = false;
    try {
      state.store(State::Fault);
      fault_msg = reason;
      clear_shared_outputs(global.data(), glayout);
      recs = collect_retain();
      collected = true;
    } catch (const std::exception& e) {
      log(std::string("ldrun: fatal: rescue: ") + e.what());
    }
    glock.unlock();
    if (collected) save_in_rescue(std::move(recs));
    if (!glock.try_lock_for_ms(1000)) return;
    std::string driver_error;
    try {
      driver_error = enter_safe_state(State::Fault);
    } catch (const std::exception& e) {
      driver_error = std::string("ldrun: fatal: rescue: ") + e.what();
    }
    glock.unlock();
    if (!driver_error.empty()) log(driver_error);
  }
  void save_in_rescue(std::vector<RetainRecord> recs) {
    if (opt.retain_file.empty()) return;
    std::unique_lock<std::timed_mutex> l(save_mu, std::chrono::seconds(1));
    if (!l.owns_lock()) {
      log("ldrun: fatal: a retentive save under way did not end within 1 s; retentive memory not saved");
      return;
    }
    std::string err = write_snapshot(std::move(recs));
    log(err.empty() ? "ldrun: fatal: retentive memory saved to " + opt.retain_file
                    : "ldrun: fatal: retentive memory not saved: " + err);
  }

  void clear_nonretentive_shared() {
    // A warm restart: Y, M, WY and the non-retentive part of K start at
    // 0; the inputs keep what the field says.
    std::vector<uint8_t> keep;
    for (const RetentiveRange& r : global_ranges) {
      uint32_t off = glayout.addr(r.area, r.first), n = r.count * glayout.elem_size(r.area);
      keep.insert(keep.end(), global.begin() + off, global.begin() + off + n);
    }
    for (Area a : {Area::Y, Area::M, Area::K, Area::WY})
      std::memset(global.data() + glayout.offset[int(a)], 0, glayout.count[int(a)] * glayout.elem_size(a));
    size_t k = 0;
    for (const RetentiveRange& r : global_ranges) {
      uint32_t off = glayout.addr(r.area, r.first), n = r.count * glayout.elem_size(r.area);
      std::memcpy(global.data() + off, keep.data() + k, n);
      k += n;
    }
  }

  // ---- the task thread
  void warm_restart(Task& t) {
    Prog& p = *t.prog;
    size_t k = 0;
    for (const Run& r : p.private_retain) std::memcpy(t.retain_tmp.data() + k, t.mem.data() + r.offset, r.size), k += r.size;
    std::fill(t.mem.begin(), t.mem.end(), 0);
    k = 0;
    for (const Run& r : p.private_retain) std::memcpy(t.mem.data() + r.offset, t.retain_tmp.data() + k, r.size), k += r.size;
    t.first = true;
    t.carry_ns = 0;
    t.scans.store(0);
  }

  void service(Task& t) {
    if (!t.has_req.load(std::memory_order_acquire)) return;
    std::vector<std::function<void()>> rs;
    {
      std::lock_guard<std::mutex> l(t.req_mu);
      rs.swap(t.reqs);
      t.has_req.store(false, std::memory_order_relaxed);
    }
    for (auto& f : rs) f();
  }

  void set_rt_priority(Task& t) {
    if (!opt.rt) return;
    sched_param sp{};
    sp.sched_priority = std::clamp(80 - int(t.spec.priority), 1, 80);
    int e = pthread_setschedparam(pthread_self(), SCHED_FIFO, &sp);
    if (e != 0 && !warned_rt.exchange(true))
      log("ldrun: warning: cannot use SCHED_FIFO (" + std::string(std::strerror(e)) +
          "); tasks run under the normal scheduler");
  }

  // A task's thread.  An error outside the program (the I/O driver) faults
  // the runtime like the watchdog does, and the task waits for RUN again;
  // running out of memory ends ldrun on the fatal path.
  void task_main(size_t ti) {
    Task& t = *tasks[ti];
    while (true) {
      try {
        task_loop(ti);
        return;
      } catch (const std::bad_alloc& e) {
        char where[200];  // no allocation: memory ran out
        std::snprintf(where, sizeof where, "task '%s'", t.spec.name.c_str());
        fatal_on_thread(where, e);
      } catch (const std::exception& e) {
        t.scan_begin.store(0);
        fault("ldrun: task '" + t.spec.name + "' scan " + std::to_string(t.scans.load() + 1) +
              " stopped by an error outside its program (I/O driver): " + e.what() +
              "; outputs driven to the safe state (all Y off, WY 0); the runtime is in FAULT");
      }
    }
  }

  // The fatal path for an exception on one of the runtime's threads.
  [[noreturn]] static void fatal_on_thread(const char* where, const std::exception& e) {
    char what[300];
    bool oom = dynamic_cast<const std::bad_alloc*>(&e) != nullptr;
    std::snprintf(what, sizeof what, "%s (%s) on %s", oom ? "out of memory" : "an unexpected error", e.what(), where);
    failsafe::fatal(what);
  }

  void task_loop(size_t ti) {
    Task& t = *tasks[ti];
    set_rt_priority(t);
    const int64_t period = int64_t(t.spec.period_us) * 1000;
    bool idle = true;
    while (!stopping.load()) {
      State s = state.load();
      if (s != State::Run || t.finished.load() || t.held.load()) {
        // STOP, FAULT, held or done: serve requests, wait for RUN.
        std::unique_lock<std::mutex> l(t.req_mu);
        t.req_cv.wait_for(l, std::chrono::milliseconds(50), [&] {
          return t.has_req.load() || stopping.load() ||
                 (state.load() == State::Run && !t.finished.load() && !t.held.load());
        });
        l.unlock();
        service(t);
        idle = true;
        continue;
      }
      if (idle) {
        t.release = now_ns();  // a new time grid from RUN on
        idle = false;
      }
      if (!opt.free_run) sleep_until(t.release);
      const int64_t start = now_ns();
      // A pending warm restart first, so that what the requests write (a set
      // of a task's variable) is what the scan starts from, not cleared by it.
      auto restart_if_due = [&] {
        const uint64_t ep = epoch.load();
        if (ep != t.epoch) warm_restart(t), t.epoch = ep;
        if (t.restart.exchange(false)) warm_restart(t);
      };
      if (state.load() == State::Run && !stopping.load()) restart_if_due();
      service(t);  // online download, probes: at the scan boundary, never mid-scan
      if (state.load() != State::Run || stopping.load()) continue;
      restart_if_due();
      Prog& p = *t.prog;
      uint8_t* mem = t.mem.data();
      const int64_t begin = now_ns();
      t.scan_begin.store(begin);

      // dt: the elapsed time (or the period) in whole ms, the rest carried.
      int64_t elapsed = (t.first || opt.clock == Options::Clock::Virtual) ? period : start - t.last_start;
      t.carry_ns += elapsed;
      int64_t dt_ms = std::min<int64_t>(t.carry_ns / 1000000, INT32_MAX);
      t.carry_ns -= dt_ms * 1000000;
      const uint64_t scan_no = t.scans.load() + 1;

      bool published = false;
      {
        std::lock_guard<ImageLock> g(glock);
        if (state.load() == State::Run && epoch.load() == t.epoch && !t.held.load()) {
          io->read_inputs(global.data(), ScanContext{ti, scan_no, p.input_runs});
          if (!p.engine->tracks_writes()) {
            for (const Run& r : p.in_runs) std::memcpy(mem + r.offset, global.data() + r.offset, r.size);
          } else {  // a change-driven engine hears of each byte that a client's write or another task changed
            for (const Run& r : p.in_runs)
              for (uint32_t b = r.offset; b < r.offset + r.size; b++)
                if (mem[b] != global[b]) mem[b] = global[b], p.engine->written(b, 1);
          }
        }
      }
      size_t k = 0;
      for (const Run& r : p.out_runs) std::memcpy(t.snapshot.data() + k, mem + r.offset, r.size), k += r.size;
      std::optional<int32_t> dt;
      // what a driver writes into the task's memory it announces
      // (ScanContext::written), for a change-driven engine
      if (t.first) p.engine->written_all();  // a (re)start: memory cleared, retentive memory put back
      io->before_scan(ScanContext{ti, scan_no, {}, p.engine.get()}, mem, dt);
      int32_t dtv = dt ? *dt : int32_t(dt_ms);
      std::memcpy(mem + kSysDt, &dtv, 4);
      mem[t.prog->image.layout.addr(Area::S, kBitFirstScan)] = t.first ? 1 : 0;
      std::memset(mem + kSysFault, 0, 4);  // no fault yet (a RUN after a FAULT starts clean)

      try {
        p.engine->scan(t.mem);
      } catch (const std::exception& e) {  // the sandbox stopped its child (ldrun --sandbox)
        t.scan_begin.store(0);
        fault("ldrun: task '" + t.spec.name + "' scan " + std::to_string(scan_no) + " failed: " + e.what() +
              "; outputs driven to the safe state (all Y off, WY 0); the runtime is in FAULT");
        continue;
      }
      // The watchdog judges the scan before it publishes anything: a scan
      // over its limit neither drives outputs nor counts as done.
      const int64_t ran = now_ns() - begin;
      if (t.watchdog_us && ran > int64_t(t.watchdog_us) * 1000) {
        t.scan_begin.store(0);
        fault("ldrun: watchdog: task '" + t.spec.name + "' scan " + std::to_string(scan_no) + " took " +
              format_us(double(ran) / 1000) + ", limit " + format_us(t.watchdog_us) +
              "; outputs driven to the safe state (all Y off, WY 0); the runtime is in FAULT");
        continue;
      }

      // A scan that faulted (an array index outside its bounds) ended early:
      // it publishes nothing, and the PLC stops with its outputs safe.
      if (auto f = read_scan_fault(mem)) {
        t.scan_begin.store(0);
        fault("ldrun: task '" + t.spec.name + "' scan " + std::to_string(scan_no) + ": " +
              describe_scan_fault(*f, &t.prog->image) +
              "; outputs driven to the safe state (all Y off, WY 0); the runtime is in FAULT");
        continue;
      }
      uint32_t n32 = uint32_t(scan_no);
      std::memcpy(mem + kSysScan, &n32, 4);
      {
        std::lock_guard<ImageLock> g(glock);
        // A restart pending (restart_task) drops the scan under way.
        if (state.load() == State::Run && epoch.load() == t.epoch && !t.held.load() && !t.restart.load()) {
          // Changed bytes only: another task on this processor may write
          // other points of a block this task writes.
          size_t j = 0;
          for (const Run& r : p.out_runs) {
            const uint8_t* now = mem + r.offset;
            const uint8_t* was = t.snapshot.data() + j;
            uint8_t* gl = global.data() + r.offset;
            for (uint32_t b = 0; b < r.size; b++)
              if (now[b] != was[b]) gl[b] = now[b];
            j += r.size;
          }
          size_t q = 0;
          for (const Run& r : p.private_retain) std::memcpy(t.retain_shadow.data() + q, mem + r.offset, r.size), q += r.size;
          io->hold_outputs(global.data(), mem, ScanContext{ti, scan_no, p.output_runs, p.engine.get()});
          io->write_outputs(global.data(), ScanContext{ti, scan_no, p.output_runs});
          io->after_scan(ScanContext{ti, scan_no, {}}, mem, global.data());
          published = true;
        }
      }
      const int64_t end = now_ns();
      t.scan_begin.store(0);
      t.first = false;
      if (!published) continue;  // stopped or faulted meanwhile: this scan does not count
      t.scans.store(scan_no);
      t.total_scans.fetch_add(1);
      const int64_t took = end - begin;
      t.last_scan_ns.store(took);
      if (took > t.max_scan_ns.load()) t.max_scan_ns.store(took);
      if (t.stats_mu.try_lock()) {
        t.scan_ring.add(took);
        if (!opt.free_run) {
          t.wake_ring.add(start - t.release);
          if (t.last_start) t.jitter_ring.add(start - t.last_start - period);
        }
        t.stats_mu.unlock();
      }
      t.last_start = start;
      if (!opt.free_run) {
        if (end > t.release + period) t.overruns.fetch_add(1);
        t.release += period;
        if (t.release <= end) {  // late: skip the releases already past
          int64_t missed = (end - t.release) / period + 1;
          t.release += missed * period;
          t.skipped.fetch_add(uint64_t(missed));
        }
      }
      if (opt.scans >= 0 && t.scans.load() >= uint64_t(opt.scans)) {
        t.finished.store(true);
        std::lock_guard<std::mutex> l(mu);
        cv.notify_all();
      }
    }
  }

  // ---- the watchdog monitor: catches a scan that does not end
  void monitor_main() {
    try {
      watch_scans();
    } catch (const std::exception& e) {
      fatal_on_thread("the watchdog thread", e);
    }
  }
  void watch_scans() {
    uint32_t lim = UINT32_MAX;
    for (auto& t : tasks)
      if (t->watchdog_us) lim = std::min(lim, t->watchdog_us);
    if (lim == UINT32_MAX) return;
    if (opt.rt) {
      // Above every task, so a task that never ends its scan cannot starve it.
      sched_param sp{};
      sp.sched_priority = 90;
      pthread_setschedparam(pthread_self(), SCHED_FIFO, &sp);
    }
    int64_t tick = std::clamp<int64_t>(int64_t(lim) * 1000 / 4, 1000000, 50000000);
    while (!stopping.load()) {
      {
        std::unique_lock<std::mutex> l(mu);
        cv.wait_for(l, std::chrono::nanoseconds(tick), [&] { return stopping.load(); });
      }
      int64_t now = now_ns();
      for (auto& t : tasks) {
        int64_t b = t->scan_begin.load();
        if (b && t->watchdog_us && now - b > int64_t(t->watchdog_us) * 1000 && state.load() == State::Run)
          fault("ldrun: watchdog: task '" + t->spec.name + "' has been in its scan for " + format_us(double(now - b) / 1000) +
                ", limit " + format_us(t->watchdog_us) +
                "; outputs driven to the safe state (all Y off, WY 0); the runtime is in FAULT");
      }
    }
  }

  // ---- requests at a task's scan boundary
  // Runs f on the task's thread at its next boundary; false on timeout
  // (f then never runs).  What f throws is thrown here, on the caller's
  // thread (it used to leave the caller waiting for ever).
  bool at_boundary(Task& t, std::function<void()> f, int64_t timeout_ms) {
    struct Shared {
      std::atomic<int> phase{0};  // 0 queued, 1 taken, 2 cancelled
      std::promise<void> done;
    };
    auto sh = std::make_shared<Shared>();
    std::future<void> fut = sh->done.get_future();
    {
      std::lock_guard<std::mutex> l(t.req_mu);
      t.reqs.push_back([sh, f = std::move(f)] {
        int expect = 0;
        if (!sh->phase.compare_exchange_strong(expect, 1)) return;
        try {
          f();
          sh->done.set_value();
        } catch (...) {  // the caller gets it: its request failed, the task scans on
          sh->done.set_exception(std::current_exception());
        }
      });
      t.has_req.store(true, std::memory_order_release);
    }
    t.req_cv.notify_all();
    if (fut.wait_for(std::chrono::milliseconds(timeout_ms)) != std::future_status::ready) {
      int expect = 0;
      if (sh->phase.compare_exchange_strong(expect, 2)) return false;
    }
    fut.get();  // taken: it finishes soon; rethrows what f threw
    return true;
  }

  // ---- retentive memory
  std::vector<RetainRecord> snapshot_retain() {
    std::lock_guard<ImageLock> g(glock);
    return collect_retain();
  }
  // Under glock.
  std::vector<RetainRecord> collect_retain() {
    std::vector<RetainRecord> recs;
    for (const RetentiveRange& r : global_ranges) {
      uint32_t off = glayout.addr(r.area, r.first), n = r.count * glayout.elem_size(r.area);
      recs.push_back(RetainRecord{"", r.area, r.first, r.count, {global.begin() + off, global.begin() + off + n}});
    }
    for (auto& t : tasks) {
      size_t k = 0;
      for (const RetentiveRange& r : t->prog->private_ranges) {
        uint32_t n = r.count * t->prog->image.layout.elem_size(r.area);
        recs.push_back(RetainRecord{t->spec.name, r.area, r.first, r.count,
                                    {t->retain_shadow.begin() + k, t->retain_shadow.begin() + k + n}});
        k += n;
      }
    }
    return recs;
  }

  std::string save(bool force) {
    if (opt.retain_file.empty()) return "";
    std::lock_guard<std::timed_mutex> l(save_mu);
    std::vector<RetainRecord> recs = snapshot_retain();
    if (!force && recs == last_saved) return "";
    return write_snapshot(std::move(recs));
  }
  // Under save_mu.
  std::string write_snapshot(std::vector<RetainRecord> recs) {
    RetainSnapshot s;
    s.sequence = ++retain_seq;
    timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    s.saved_ns = uint64_t(ts.tv_sec) * 1000000000 + uint64_t(ts.tv_nsec);
    s.records = recs;
    std::string err = write_retain_file(opt.retain_file, s);
    if (err.empty()) last_saved = std::move(recs);
    return err;
  }

  void saver_main() {
    try {
      save_periodically();
    } catch (const std::exception& e) {
      fatal_on_thread("the retentive saver thread", e);
    }
  }
  void save_periodically() {
    while (true) {
      {
        std::unique_lock<std::mutex> l(mu);
        cv.wait_for(l, std::chrono::microseconds(opt.retain_every_us), [&] { return stopping.load(); });
      }
      if (stopping.load()) return;
      if (state.load() != State::Run) continue;
      std::string e = save(false);
      if (!e.empty()) log("ldrun: warning: retentive save failed: " + e);
    }
  }

  void restore_retain() {
    if (opt.retain_file.empty()) return;
    FILE* f = std::fopen(opt.retain_file.c_str(), "rb");
    if (!f) {
      if (errno != ENOENT)
        throw std::runtime_error(opt.retain_file + ": error: cannot open the retentive file: " + std::strerror(errno));
      log("ldrun: " + opt.retain_file + ": no retentive file yet; retentive memory starts cleared");
      return;
    }
    std::vector<uint8_t> bytes;
    uint8_t buf[65536];
    size_t n;
    while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) bytes.insert(bytes.end(), buf, buf + n);
    std::fclose(f);
    if (opt.cold) {
      log("ldrun: " + opt.retain_file + ": cold start as asked (--cold): retentive memory starts cleared");
      return;
    }
    RetainSnapshot s;
    try {
      s = decode_retain(bytes, opt.retain_file);
    } catch (std::exception& e) {
      throw std::runtime_error(std::string(e.what()) +
                               "; refusing to start (--cold starts with cleared retentive memory)");
    }
    retain_seq = s.sequence;
    size_t applied = 0;
    for (const RetainRecord& r : s.records) {
      bool done = false;
      if (r.scope.empty()) {
        for (const RetentiveRange& g : global_ranges)
          if (g.area == r.area && g.first == r.first && g.count == r.count) {
            std::memcpy(global.data() + glayout.addr(r.area, r.first), r.bytes.data(), r.bytes.size());
            done = true;
          }
      } else {
        for (auto& t : tasks) {
          if (t->spec.name != r.scope) continue;
          size_t k = 0;
          for (const RetentiveRange& g : t->prog->private_ranges) {
            uint32_t nb = g.count * t->prog->image.layout.elem_size(g.area);
            if (g.area == r.area && g.first == r.first && g.count == r.count) {
              std::memcpy(t->mem.data() + t->prog->image.layout.addr(r.area, r.first), r.bytes.data(), nb);
              std::memcpy(t->retain_shadow.data() + k, r.bytes.data(), nb);
              done = true;
            }
            k += nb;
          }
        }
      }
      if (done) applied++;
      else
        log("ldrun: warning: " + opt.retain_file + ": record " + (r.scope.empty() ? "global" : r.scope) + " " +
            area_name(r.area) + "[" + std::to_string(r.first) + ".." + std::to_string(r.first + r.count - 1) +
            "] matches no retentive range of the running configuration; ignored");
    }
    last_saved = snapshot_retain();
    log("ldrun: " + opt.retain_file + ": retentive memory restored (save " + std::to_string(s.sequence) + ", " +
        std::to_string(applied) + " record" + (applied == 1 ? "" : "s") + ")");
  }

  void add_global_ranges(const std::vector<RetentiveRange>& rs) {
    // Union per shared area, kept as disjoint sorted ranges.
    std::map<int, std::vector<uint8_t>> mask;
    for (const auto& lists : {global_ranges, rs})
      for (const RetentiveRange& r : lists) {
        auto& m = mask[int(r.area)];
        m.resize(glayout.count[int(r.area)]);
        std::fill(m.begin() + r.first, m.begin() + r.first + r.count, 1);
      }
    global_ranges.clear();
    for (auto& [a, m] : mask)
      for (uint32_t i = 0; i < m.size();) {
        if (!m[i]) { i++; continue; }
        uint32_t j = i;
        while (j < m.size() && m[j]) j++;
        global_ranges.push_back(RetentiveRange{Area(a), i, j - i});
        i = j;
      }
  }

  void install(Task& t, std::unique_ptr<Prog> p) {
    t.mem = ImageBytes(p->image.layout.size);
    t.snapshot.assign(p->out_bytes, 0);
    t.retain_shadow.assign(p->retain_bytes, 0);
    t.retain_tmp.assign(p->retain_bytes, 0);
    t.ctl_file = p->file;
    t.ctl_accesses = p->accesses;
    t.ctl_aliases = p->image.aliases;
    t.ctl_image = control_copy(p->image);
    t.prog = std::move(p);
  }
};

// ---------------------------------------------------------------- Runtime

Runtime::Runtime(std::vector<TaskSpec> specs, Options opt, EngineFactory engines, std::unique_ptr<IoDriver> io)
    : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.opt = std::move(opt);
  m.engines = std::move(engines);
  m.io = io ? std::move(io) : make_null_driver();
  if (specs.empty()) throw std::runtime_error("no task to run");
  if (m.opt.block_size < 16 || m.opt.block_size % 16 || m.opt.block_size > kMaxBlockSize)
    throw std::runtime_error("bad I/O block size " + std::to_string(m.opt.block_size));
  m.global.assign(m.glayout.size, 0);
  for (TaskSpec& s : specs) {
    auto t = std::make_unique<Task>();
    if (s.period_us == 0) throw std::runtime_error("task '" + s.name + "': the period must be above 0");
    if (s.image.config) {
      const IoConfig& c = *s.image.config;
      if (c.block_size != m.opt.block_size)
        throw std::runtime_error(s.file + ": error: the image was configured with I/O blocks of " +
                                 std::to_string(c.block_size) + " points, the runtime uses " +
                                 std::to_string(m.opt.block_size) + " (rebuild with ldc --project)");
      if (c.processor != s.processor)
        throw std::runtime_error(s.file + ": error: the image was configured for processor " + std::to_string(c.processor) +
                                 ", task '" + s.name + "' runs on processor " + std::to_string(s.processor));
    }
    for (auto& o : m.tasks)
      if (o->spec.name == s.name) throw std::runtime_error("two tasks named '" + s.name + "'");
    Image img = std::move(s.image);
    s.image = Image{};
    t->spec = s;
    t->watchdog_us = s.watchdog_us ? s.watchdog_us : m.opt.watchdog_us;
    m.install(*t, make_prog(std::move(img), s.file, m.opt.block_size, m.engines));
    m.tasks.push_back(std::move(t));
  }
  std::vector<const std::vector<IoAccess>*> acc;
  for (auto& t : m.tasks) acc.push_back(&t->ctl_accesses);
  m.check_conflicts(acc, SIZE_MAX, "");
  for (auto& t : m.tasks) m.add_global_ranges(t->prog->shared_ranges);
  m.io->attach(m.global.data(), m.glayout, m.opt.block_size);
  m.restore_retain();
}

Runtime::~Runtime() {
  try {
    shutdown();
  } catch (...) {
  }
}

void Runtime::start() {
  Impl& m = *impl_;
  if (m.started) return;
  m.started = true;
  if (m.opt.rt) {
    if (mlockall(MCL_CURRENT | MCL_FUTURE) != 0)
      m.log(std::string("ldrun: warning: mlockall failed (") + std::strerror(errno) + "); memory may be paged");
  }
  {
    std::lock_guard<ImageLock> g(m.glock);
    m.state.store(m.opt.start_stopped ? State::Stop : State::Run);
    m.io->state_changed(m.state.load());
  }
  if (m.opt.scans == 0)
    for (auto& t : m.tasks) t->finished.store(true);
  for (size_t i = 0; i < m.tasks.size(); i++) m.tasks[i]->th = std::thread([&m, i] { m.task_main(i); });
  m.monitor = std::thread([&m] { m.monitor_main(); });
  if (!m.opt.retain_file.empty()) m.saver = std::thread([&m] { m.saver_main(); });
  failsafe::set_rescue(&Impl::rescue, &m);
}

void Runtime::run() {
  Impl& m = *impl_;
  {
    std::lock_guard<ImageLock> g(m.glock);
    if (m.state.load() == State::Run) return;
    m.clear_nonretentive_shared();
    m.fault_msg.clear();
    for (auto& t : m.tasks) t->finished.store(false);
    m.epoch.fetch_add(1);
    m.state.store(State::Run);
    m.io->state_changed(State::Run);
  }
  for (auto& t : m.tasks) t->req_cv.notify_all();
}

void Runtime::stop() {
  Impl& m = *impl_;
  bool was_run = false;
  std::string driver_error;
  {
    std::lock_guard<ImageLock> g(m.glock);
    if (m.state.load() == State::Run) {
      was_run = true;
      m.state.store(State::Stop);
      driver_error = m.enter_safe_state(State::Stop);
    }
  }
  if (!driver_error.empty()) m.log(driver_error);
  if (was_run) {
    std::string e = m.save(false);
    if (!e.empty()) m.log("ldrun: warning: retentive save failed: " + e);
  }
}

void Runtime::stop_task(size_t i) {
  Impl& m = *impl_;
  Task& t = *m.tasks.at(i);
  std::lock_guard<std::mutex> c(m.ctl_mu);  // ctl_accesses
  std::lock_guard<ImageLock> g(m.glock);
  if (t.held.exchange(true)) return;
  // the task's own Y and WY points to the safe state, then published
  std::vector<Run> runs;
  for (const IoAccess& a : t.ctl_accesses) {
    if (!a.write || (a.area != Area::Y && a.area != Area::WY)) continue;
    uint32_t size = a.area == Area::Y ? 1 : 4, off = m.glayout.addr(a.area, a.index);
    std::memset(m.global.data() + off, 0, size);
    runs.push_back(Run{off, size});
  }
  m.io->write_outputs(m.global.data(), ScanContext{i, t.scans.load(), runs});
}

void Runtime::run_task(size_t i) {
  Impl& m = *impl_;
  Task& t = *m.tasks.at(i);
  {
    std::lock_guard<ImageLock> g(m.glock);
    if (!t.held.load()) return;
    t.restart.store(true);
    t.held.store(false);
  }
  t.req_cv.notify_all();
}

void Runtime::restart_task(size_t i) {
  Impl& m = *impl_;
  Task& t = *m.tasks.at(i);
  {
    std::lock_guard<std::mutex> c(m.ctl_mu);  // ctl_accesses
    std::lock_guard<ImageLock> g(m.glock);
    // As STOP -> RUN does for the whole image, for the task's own points:
    // its outputs to the safe state (published), the relays it writes to 0
    // but for the retentive ranges; the scan under way, if any, publishes
    // nothing (a restart is pending), the next is a first scan.
    std::vector<Run> runs;
    for (const IoAccess& a : t.ctl_accesses) {
      if (!a.write) continue;
      uint32_t size = m.glayout.elem_size(a.area), off = m.glayout.addr(a.area, a.index);
      bool retained = std::any_of(m.global_ranges.begin(), m.global_ranges.end(), [&](const RetentiveRange& r) {
        return r.area == a.area && a.index >= r.first && a.index - r.first < r.count;
      });
      if (a.area == Area::Y || a.area == Area::WY) runs.push_back(Run{off, size});
      else if ((a.area != Area::M && a.area != Area::K) || retained) continue;
      std::memset(m.global.data() + off, 0, size);
    }
    t.restart.store(true);
    t.held.store(false);
    m.io->write_outputs(m.global.data(), ScanContext{i, t.scans.load(), runs});
  }
  t.req_cv.notify_all();
}

bool Runtime::task_held(size_t i) const { return impl_->tasks.at(i)->held.load(); }
uint64_t Runtime::generation(size_t i) const { return impl_->tasks.at(i)->generation.load(std::memory_order_acquire); }

void Runtime::shutdown() {
  Impl& m = *impl_;
  if (m.shut) return;
  m.shut = true;
  failsafe::clear_rescue(&m);
  State before = m.state.load();
  if (before == State::Run) stop();
  m.stopping.store(true);
  {
    std::lock_guard<std::mutex> l(m.mu);
    m.cv.notify_all();
  }
  for (auto& t : m.tasks) {
    t->req_cv.notify_all();
    if (t->th.joinable()) t->th.join();
  }
  if (m.monitor.joinable()) m.monitor.join();
  if (m.saver.joinable()) m.saver.join();
  if (m.started && before != State::Run) {
    std::string e = m.save(false);
    if (!e.empty()) m.log("ldrun: warning: retentive save failed: " + e);
  }
  {
    std::lock_guard<ImageLock> g(m.glock);
    clear_shared_outputs(m.global.data(), m.glayout);
    try {
      m.io->safe_outputs(m.global.data());
    } catch (const std::exception& e) {
      failsafe::zero_segment_outputs();
      m.log(std::string("ldrun: the I/O driver failed to drive the outputs safe (") + e.what() +
            "); the shared-memory outputs were zeroed directly");
    }
  }
  m.io->detach();
}

State Runtime::state() const { return impl_->state.load(); }

std::string Runtime::fault_message() const {
  std::lock_guard<ImageLock> g(impl_->glock);
  return impl_->fault_msg;
}

bool Runtime::wait_scans(uint64_t n, int64_t timeout_ms) {
  Impl& m = *impl_;
  std::vector<uint64_t> goal;
  for (auto& t : m.tasks) goal.push_back(t->total_scans.load() + n);
  auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
  while (true) {
    bool all = true;
    for (size_t i = 0; i < m.tasks.size(); i++) {
      Task& t = *m.tasks[i];
      bool scanning = m.state.load() == State::Run && !t.finished.load();
      if (scanning && t.total_scans.load() < goal[i]) all = false;
    }
    if (all) return true;
    if (std::chrono::steady_clock::now() > deadline) return false;
    std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
}

bool Runtime::wait_finished(int64_t timeout_ms, bool fault_ends) {
  Impl& m = *impl_;
  std::unique_lock<std::mutex> l(m.mu);
  auto done = [&] {
    if (m.quit || (fault_ends && m.state.load() == State::Fault)) return true;
    if (m.opt.scans < 0) return false;
    for (auto& t : m.tasks)
      if (!t->finished.load()) return false;
    return true;
  };
  if (timeout_ms < 0) {
    m.cv.wait(l, done);
    return true;
  }
  return m.cv.wait_for(l, std::chrono::milliseconds(timeout_ms), done);
}

void Runtime::request_quit() {
  std::lock_guard<std::mutex> l(impl_->mu);
  impl_->quit = true;
  impl_->cv.notify_all();
}

bool Runtime::quit_requested() const {
  std::lock_guard<std::mutex> l(impl_->mu);
  return impl_->quit;
}

size_t Runtime::task_count() const { return impl_->tasks.size(); }
const std::string& Runtime::task_name(size_t i) const { return impl_->tasks.at(i)->spec.name; }
size_t Runtime::find_task(const std::string& name) const {
  for (size_t i = 0; i < impl_->tasks.size(); i++)
    if (impl_->tasks[i]->spec.name == name) return i;
  return SIZE_MAX;
}

SwapReport Runtime::replace(const std::string& task, Image img, const std::string& file, int64_t timeout_ms, bool strict) {
  Impl& m = *impl_;
  std::lock_guard<std::mutex> cl(m.ctl_mu);
  size_t ti = find_task(task);
  if (ti == SIZE_MAX) throw std::runtime_error("no task named '" + task + "'");
  Task& t = *m.tasks[ti];
  auto refuse = [&](const std::string& why) {
    return std::runtime_error(file + ": refused for task '" + task + "': " + why + "; task '" + task +
                              "' keeps running its current image");
  };
  if (img.config) {
    if (img.config->block_size != m.opt.block_size)
      throw refuse("configured with I/O blocks of " + std::to_string(img.config->block_size) + " points, the runtime uses " +
                   std::to_string(m.opt.block_size));
    if (img.config->processor != t.spec.processor)
      throw refuse("configured for processor " + std::to_string(img.config->processor) + ", the task runs on processor " +
                   std::to_string(t.spec.processor));
  }
  // State is carried by identity (runtime/online_carry.h); --strict refuses
  // a download that would reset something the running program has.
  CarryPlan plan = plan_carry(t.ctl_image, img);
  if (strict && !plan.report.reset.empty()) {
    std::string items;
    for (const std::string& r : plan.report.reset) items += (items.empty() ? "" : ", ") + r;
    throw refuse("--strict: it would reset " + items);
  }
  std::vector<IoAccess> acc = io_accesses(img.il);
  {
    std::vector<const std::vector<IoAccess>*> all;
    for (auto& o : m.tasks) all.push_back(o.get() == &t ? &acc : &o->ctl_accesses);
    try {
      m.check_conflicts(all, ti, "");
    } catch (std::exception& e) {
      throw refuse(e.what());
    }
  }
  std::vector<RetentiveRange> shared_ranges;
  std::unique_ptr<Prog> np;
  try {
    np = make_prog(std::move(img), file, m.opt.block_size, m.engines);
  } catch (std::exception& e) {
    throw refuse(e.what());
  }
  // Everything the switch needs is prepared here, off the task's thread.
  struct Prepared {
    std::unique_ptr<Prog> prog;
    ImageBytes mem;
    std::vector<uint8_t> snapshot, shadow, tmp;
    uint64_t at_scan = 0;
    int64_t t_done = 0, work = 0;
  };
  auto pr = std::make_shared<Prepared>();
  const Layout& nl = np->image.layout;
  pr->mem = ImageBytes(nl.size);
  pr->snapshot.assign(np->out_bytes, 0);
  pr->shadow.assign(np->retain_bytes, 0);
  pr->tmp.assign(np->retain_bytes, 0);
  pr->prog = std::move(np);
  std::vector<RetentiveRange> new_shared = pr->prog->shared_ranges;
  std::vector<IoAccess> new_acc = pr->prog->accesses;
  Image new_ctl = control_copy(pr->prog->image);
  std::vector<Alias> new_aliases = pr->prog->image.aliases;
  auto carry = std::make_shared<const CarryPlan>(std::move(plan));
  const int64_t t0 = now_ns();
  bool ok = m.at_boundary(
      t,
      [&m, &t, pr, carry] {
        const int64_t w0 = now_ns();
        Prog& op = *t.prog;
        if (carry->touches_shared()) {
          // Shared variables (M, K) that moved are moved in the global image.
          std::lock_guard<ImageLock> g(m.glock);
          apply_carry(*carry, op.image.layout, t.mem.data(), pr->prog->image.layout, pr->mem.data(), m.global.data());
        } else {
          apply_carry(*carry, op.image.layout, t.mem.data(), pr->prog->image.layout, pr->mem.data(), nullptr);
        }
        size_t k = 0;
        for (const Run& r : pr->prog->private_retain)
          std::memcpy(pr->shadow.data() + k, pr->mem.data() + r.offset, r.size), k += r.size;
        {
          // The saver reads the program's retentive ranges and shadow under the image lock.
          std::lock_guard<ImageLock> g(m.glock);
          std::swap(t.mem, pr->mem);
          std::swap(t.snapshot, pr->snapshot);
          std::swap(t.retain_shadow, pr->shadow);
          std::swap(t.retain_tmp, pr->tmp);
          std::swap(t.prog, pr->prog);  // the old program leaves with pr, freed by the caller
        }
        t.generation.fetch_add(1, std::memory_order_release);
        pr->at_scan = t.scans.load() + 1;
        pr->t_done = now_ns();
        pr->work = pr->t_done - w0;
      },
      timeout_ms);
  if (!ok)
    throw refuse("the task did not reach a scan boundary within " + std::to_string(timeout_ms) + " ms");
  t.ctl_file = file;
  t.ctl_accesses = std::move(new_acc);
  t.ctl_image = std::move(new_ctl);
  t.ctl_aliases = std::move(new_aliases);
  {
    std::lock_guard<ImageLock> g(m.glock);
    m.add_global_ranges(new_shared);
  }
  m.io->program_replaced(ti, t.prog->image);
  SwapReport rep;
  rep.task = task;
  rep.at_scan = pr->at_scan;
  rep.latency_us = double(pr->t_done - t0) / 1000;
  rep.work_us = double(pr->work) / 1000;
  rep.carry = carry->report;
  pr.reset();  // the old engine and memory are released here, not on the task's thread
  return rep;
}

namespace {

}  // namespace

// "TASK.NAME" names the task when TASK is one of the project's tasks; else the
// whole text is a name of the first task's program (`tank.level`, `c[2].v`).
std::pair<size_t, std::string> Runtime::split_task(const std::string& device) const {
  if (size_t dot = device.find('.'); dot != std::string::npos && device[0] != '%') {
    size_t ti = find_task(device.substr(0, dot));
    if (ti != SIZE_MAX) return {ti, device.substr(dot + 1)};
  }
  return {0, device};
}

// The task and the probe of a get/set operand; "no task named" when a
// TASK.NAME names neither a task nor a variable of the first task.
static Probe resolve_in(const std::string& device, const std::string& dev, const std::vector<Alias>& aliases) {
  try {
    return resolve_probe(dev, aliases);
  } catch (std::runtime_error&) {
    size_t dot = device.find('.');
    if (dev == device && dot != std::string::npos && device[0] != '%' && device.find('[') > dot)
      throw std::runtime_error("no task named '" + device.substr(0, dot) + "' and no variable '" + device + "'");
    throw;
  }
}

std::string Runtime::get(const std::string& device, int64_t timeout_ms) {
  Impl& m = *impl_;
  std::lock_guard<std::mutex> cl(m.ctl_mu);
  auto [ti, dev] = split_task(device);
  Task& t = *m.tasks[ti];
  Probe p = resolve_in(device, dev, t.ctl_aliases);
  if (area_is_shared(p.area)) {
    std::lock_guard<ImageLock> g(m.glock);
    return format_probe(m.global.data(), m.glayout, p);
  }
  std::string out;
  if (!m.at_boundary(t, [&] { out = format_probe(t.mem.data(), t.prog->image.layout, p); }, timeout_ms))
    throw std::runtime_error("task '" + t.spec.name + "' did not reach a scan boundary in time");
  return out;
}

// What `set` writes: what Modbus and the monitor write (docs/runtime.md, "The
// line protocol"): inputs and relays at once in the global image, outputs
// only while the PLC runs (else they stay in the safe state), and a task's
// words, timer and counter values and S0 at its next scan boundary.
void Runtime::set(const std::string& device, const std::string& value, int64_t timeout_ms) {
  Impl& m = *impl_;
  std::lock_guard<std::mutex> cl(m.ctl_mu);
  auto [ti, dev] = split_task(device);
  Task& t = *m.tasks[ti];
  Probe p = resolve_in(device, dev, t.ctl_aliases);
  bool shared = area_is_shared(p.area);  // X Y M K WX WY
  bool output = p.area == Area::Y || p.area == Area::WY;
  bool word = p.area == Area::D || p.area == Area::F || p.area == Area::TW || p.area == Area::CW;
  if (!shared && !word && !(p.area == Area::S && p.index == kBitError))
    throw std::runtime_error("'" + device + "' cannot be set: set writes inputs (X, WX), outputs (Y, WY), relays (M, K), " +
                             "a task's words (D, F), timer and counter values (T, C) and S0; not done bits or system bits");
  if (value.empty()) throw std::runtime_error("bad value ''");
  if (std::string why = trace_cell_problem(p, value); !why.empty()) throw std::runtime_error(why);
  if (shared) {
    std::lock_guard<ImageLock> g(m.glock);
    if (output && m.state.load() != State::Run)
      throw std::runtime_error("'" + device + "' is an output: outputs are set only while the PLC runs (state " +
                               state_name(m.state.load()) + ": they stay in the safe state; 'run' first)");
    put_trace_cell(m.global.data(), m.glayout, p, value);
    return;
  }
  auto put = [&] {
    const Layout& L = t.prog->image.layout;
    put_trace_cell(t.mem.data(), L, p, value);
    t.prog->engine->written(L.addr(p.area, p.index), probe_width(p, L));  // a change-driven engine runs what depends on it
  };
  if (!m.at_boundary(t, put, timeout_ms))
    throw std::runtime_error("task '" + t.spec.name + "' did not reach a scan boundary in time");
}

std::string Runtime::status() const {
  Impl& m = *impl_;
  std::string s = std::string("state ") + state_name(m.state.load());
  for (auto& t : m.tasks) {
    s += "; task " + t->spec.name + ": " + std::to_string(t->total_scans.load()) + " scans, " +
         std::to_string(t->overruns.load()) + " overruns, scan " + format_us(double(t->last_scan_ns.load()) / 1000) +
         " (max " + format_us(double(t->max_scan_ns.load()) / 1000) + ")";
  }
  if (m.state.load() == State::Fault) s += "; fault: " + fault_message();
  return s;
}

std::vector<TaskStats> Runtime::stats() const {
  std::vector<TaskStats> out;
  for (auto& t : impl_->tasks) {
    TaskStats s;
    s.task = t->spec.name;
    s.period_us = t->spec.period_us;
    s.scans = t->total_scans.load();
    s.overruns = t->overruns.load();
    s.skipped_periods = t->skipped.load();
    std::lock_guard<std::mutex> l(t->stats_mu);
    s.scan_us = t->scan_ring.quantiles();
    s.jitter_us = t->jitter_ring.quantiles();
    s.wake_us = t->wake_ring.quantiles();
    out.push_back(s);
  }
  return out;
}

std::string Runtime::format_stats(const std::vector<TaskStats>& v) {
  std::string s;
  char buf[256];
  auto q = [&](const char* what, const Quantiles& x) {
    if (!x.n) return;
    std::snprintf(buf, sizeof buf, "  %-17s min %9.1f  median %9.1f  p99 %9.1f  max %9.1f  (us, last %zu samples)\n", what,
                  x.min, x.median, x.p99, x.max, std::min<size_t>(x.n, size_t(1) << 16));
    s += buf;
  };
  for (const TaskStats& t : v) {
    std::snprintf(buf, sizeof buf, "task %s: period %u us, %llu scans, %llu overruns, %llu skipped periods\n", t.task.c_str(),
                  t.period_us, (unsigned long long)t.scans, (unsigned long long)t.overruns,
                  (unsigned long long)t.skipped_periods);
    s += buf;
    q("scan time", t.scan_us);
    q("period jitter", t.jitter_us);
    q("wake-up latency", t.wake_us);
  }
  return s;
}

std::string Runtime::save_retentive() {
  if (impl_->opt.retain_file.empty()) return "no retentive file (--retain FILE)";
  return impl_->save(true);
}

}  // namespace ldc::plc
