// runtime/io_drivers.cpp -- the I/O drivers of the soft-PLC runtime: the
// trace driver (what run_trace does), the shared-memory driver
// (runtime/shm_layout.h) and the null driver (docs/runtime.md).
#include <fcntl.h>
#include <signal.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <stdexcept>

#include "loader/config.h"
#include "runtime/failsafe.h"
#include "runtime/plc.h"
#include "runtime/shm_layout.h"

namespace ldc::plc {
namespace {

// ---------------------------------------------------------------- null

class NullDriver : public IoDriver {};

// ---------------------------------------------------------------- trace
// Row k of the trace is written before scan k of task 0 (shared devices into
// the global image, private ones into the task's memory), and after the scan
// the watched devices are printed -- the CSV run_trace prints.

class TraceDriver : public IoDriver {
 public:
  TraceDriver(const Trace* trace, std::vector<Probe> watch, std::string* out, FILE* file)
      : trace_(trace), watch_(std::move(watch)), out_(out), file_(file) {}

  void attach(uint8_t*, const Layout& layout, uint32_t) override {
    layout_ = layout;
    std::string h = "scan";
    for (const Probe& p : watch_) h += "," + csv_name(p.name);
    emit(h + "\n");
  }
  void read_inputs(uint8_t* global, const ScanContext& c) override {
    if (c.task != 0 || !trace_ || c.scan - 1 >= trace_->rows.size()) return;
    const auto& row = trace_->rows[c.scan - 1];
    for (size_t i = 0; i < row.size(); i++)
      if (!row[i].empty() && int(i) != trace_->dt_column && area_is_shared(trace_->columns[i].area))
        put_trace_cell(global, layout_, trace_->columns[i], row[i]);
  }
  void before_scan(const ScanContext& c, uint8_t* mem, std::optional<int32_t>& dt) override {
    if (c.task != 0) return;
    if (c.scan == 1) dt_.reset();  // a (re)start
    if (trace_ && c.scan - 1 < trace_->rows.size()) {
      const auto& row = trace_->rows[c.scan - 1];
      for (size_t i = 0; i < row.size(); i++) {
        if (row[i].empty()) continue;
        if (int(i) == trace_->dt_column) dt_ = int32_t(trace_cell_int(row[i]));
        else if (!area_is_shared(trace_->columns[i].area)) {
          const Probe& pr = trace_->columns[i];
          put_trace_cell(mem, layout_, pr, row[i]);
          if (c.engine) c.engine->written(layout_.addr(pr.area, pr.index), probe_width(pr, layout_));
        }
      }
    }
    if (dt_) dt = dt_;
  }
  void after_scan(const ScanContext& c, const uint8_t* mem, const uint8_t* global) override {
    if (c.task != 0) return;
    std::string line = std::to_string(c.scan);
    for (const Probe& p : watch_) line += "," + format_probe(area_is_shared(p.area) ? global : mem, layout_, p);
    emit(line + "\n");
  }
  void detach() override {
    if (file_) std::fflush(file_);
  }

 private:
  void emit(const std::string& s) {
    if (out_) *out_ += s;
    if (file_) std::fwrite(s.data(), 1, s.size(), file_);
  }
  const Trace* trace_;
  std::vector<Probe> watch_;
  std::string* out_;
  FILE* file_;
  Layout layout_;
  std::optional<int32_t> dt_;
};

// ---------------------------------------------------------------- shared memory

class ShmDriver : public IoDriver {
 public:
  explicit ShmDriver(std::string name) : name_(std::move(name)) {
    if (name_.size() < 2 || name_[0] != '/' || name_.find('/', 1) != std::string::npos)
      throw std::runtime_error("shared memory name '" + name_ + "' must be '/' and a name without '/', e.g. /ldc");
    int fd = shm_open(name_.c_str(), O_RDWR | O_CREAT, 0660);
    if (fd < 0) throw std::runtime_error("cannot create shared memory " + name_ + ": " + std::strerror(errno));
    struct stat st;
    if (fstat(fd, &st) == 0 && size_t(st.st_size) >= shm::kTotalSize) {
      // A segment is there already: refuse it if a live ldrun owns it.
      void* p = mmap(nullptr, shm::kTotalSize, PROT_READ, MAP_SHARED, fd, 0);
      if (p != MAP_FAILED) {
        const shm::Header* h = static_cast<const shm::Header*>(p);
        bool ours = !*shm::check(h, shm::kTotalSize);
        int32_t owner = ours ? h->owner_pid : 0;
        bool live = ours && shm::at(const_cast<uint32_t&>(h->state)).load() != shm::kExited && shm::owner_alive(h);
        munmap(p, shm::kTotalSize);
        if (live && owner != getpid()) {
          close(fd);
          throw std::runtime_error("shared memory " + name_ + " is in use by ldrun process " + std::to_string(owner));
        }
      }
    }
    if (ftruncate(fd, shm::kTotalSize) != 0) {
      int e = errno;
      close(fd);
      throw std::runtime_error("cannot size shared memory " + name_ + ": " + std::strerror(e));
    }
    void* p = mmap(nullptr, shm::kTotalSize, PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
    int e = errno;
    close(fd);
    if (p == MAP_FAILED) throw std::runtime_error("cannot map shared memory " + name_ + ": " + std::strerror(e));
    h_ = static_cast<shm::Header*>(p);
  }
  ~ShmDriver() override { detach(); }

  void attach(uint8_t*, const Layout& layout, uint32_t block_size) override {
    layout_ = layout;
    shm::init(h_, block_size, int32_t(getpid()));
    scratch_.resize(shm::kXCount + 4 * shm::kWXCount);
    failsafe::register_segment(h_);  // a fatal signal zeroes its outputs directly
  }
  // The shm offset of a byte of the X, WX, Y or WY area of the memory image.
  uint32_t shm_offset(uint32_t image_offset) const {
    for (auto [a, o] : {std::pair{Area::X, shm::kXOffset}, {Area::WX, shm::kWXOffset}, {Area::Y, shm::kYOffset},
                        {Area::WY, shm::kWYOffset}}) {
      uint32_t lo = layout_.offset[int(a)], hi = lo + layout_.count[int(a)] * layout_.elem_size(a);
      if (image_offset >= lo && image_offset < hi) return o + (image_offset - lo);
    }
    return UINT32_MAX;
  }
  void read_inputs(uint8_t* global, const ScanContext& c) override {
    if (!h_ || c.runs.empty()) return;
    uint8_t* b = shm::base(h_);
    // A consistent copy of the blocks, or none: after a bounded number of
    // tries (a client is writing) this scan keeps the previous inputs.
    for (int attempt = 0; attempt < 200; attempt++) {
      uint32_t v;
      if (!shm::begin_read(h_->in_seq, v)) {
        busy_retries_++;
        continue;
      }
      size_t k = 0;
      for (const Run& r : c.runs) shm::copy_words(scratch_.data() + k, b + shm_offset(r.offset), r.size), k += r.size;
      if (!shm::end_read(h_->in_seq, v)) {
        busy_retries_++;
        continue;
      }
      k = 0;
      for (const Run& r : c.runs) std::memcpy(global + r.offset, scratch_.data() + k, r.size), k += r.size;
      bits_as_zero_or_one(global, c);
      return;
    }
  }
  // An input point is a byte the client may set to anything: any byte but 0
  // is 1 (a bit device holds 0 or 1, and the engines' bit instructions read it so)
  void bits_as_zero_or_one(uint8_t* global, const ScanContext& c) const {
    const uint32_t lo = layout_.offset[int(Area::X)], hi = lo + layout_.count[int(Area::X)];
    for (const Run& r : c.runs)
      for (uint32_t a = std::max(r.offset, lo), end = std::min(r.offset + r.size, hi); a < end; a++) global[a] = global[a] != 0;
  }
  void write_outputs(const uint8_t* global, const ScanContext& c) override {
    failsafe::inject("io");
    failsafe::Publication pub;
    if (!h_ || !pub) return;
    uint8_t* b = shm::base(h_);
    if (!c.runs.empty()) {
      shm::begin_write(h_->out_seq);
      for (const Run& r : c.runs) shm::copy_words(b + shm_offset(r.offset), global + r.offset, r.size);
      shm::end_write(h_->out_seq);
      shm::at(h_->out_count).fetch_add(1, std::memory_order_relaxed);
    }
    shm::at(h_->scans).fetch_add(1, std::memory_order_relaxed);
    timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    shm::at(h_->heartbeat_ns).store(uint64_t(ts.tv_sec) * 1000000000 + uint64_t(ts.tv_nsec), std::memory_order_relaxed);
  }
  void safe_outputs(const uint8_t*) override {
    failsafe::Publication pub;
    if (h_ && pub) shm::zero_outputs(h_);
  }
  void state_changed(State s) override {
    failsafe::Publication pub;
    if (h_ && pub) shm::at(h_->state).store(uint32_t(s), std::memory_order_release);
  }
  // An orderly end: EXITED, and the segment removed.  Once a fatal path has
  // begun it stays as that path left it (FAULT, the reason, a dead owner).
  void detach() override {
    if (!h_) return;
    if (!failsafe::unregister_segment(h_)) return;
    shm::at(h_->state).store(shm::kExited, std::memory_order_release);
    munmap(h_, shm::kTotalSize);
    h_ = nullptr;
    shm_unlink(name_.c_str());
  }

 private:
  std::string name_;
  shm::Header* h_ = nullptr;
  Layout layout_;
  std::vector<uint8_t> scratch_;
  uint64_t busy_retries_ = 0;
};

}  // namespace

std::unique_ptr<IoDriver> make_trace_driver(const Trace* trace, std::vector<Probe> watch, std::string* out, FILE* file) {
  return std::make_unique<TraceDriver>(trace, std::move(watch), out, file);
}
std::unique_ptr<IoDriver> make_shm_driver(const std::string& name) { return std::make_unique<ShmDriver>(name); }
std::unique_ptr<IoDriver> make_null_driver() { return std::make_unique<NullDriver>(); }

}  // namespace ldc::plc
