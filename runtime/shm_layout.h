// runtime/shm_layout.h -- the shared-memory I/O image of `ldrun --io=shm`
// (docs/runtime.md, "The shared-memory driver").  Header-only and standard
// C++20 plus POSIX, so a client process includes this file and nothing else
// of ldc (runtime/examples/shm_client.cpp is one).
//
// The segment is a POSIX shared memory object (shm_open) created by ldrun.
// A 4096-byte header is followed by four areas, each starting on a 64-byte
// boundary: X (inputs, one byte per point, 0/1), WX (input words, INT32),
// Y (outputs, one byte per point), WY (output words, INT32), little-endian.
//
// Two sequence counters make every update atomic for readers (a seqlock):
//   inputs  (X, WX): written by clients, read by ldrun;    in_seq
//   outputs (Y, WY): written by ldrun,   read by clients;  out_seq
// A writer makes the counter odd, stores the data, makes it even again.
// A reader reads the counter (even), copies, reads it again; if it changed
// or was odd, the copy may be torn and is retried.  Only one client writes
// inputs at a time: it holds the input lock (in_writer = its pid), taken
// with compare-and-swap and recovered from a client that died holding it.
//
// Version 2 adds who owns the segment and why it stopped: the owner's start
// time (so a reused pid is not taken for the owner) and a reason text.  A
// fatal error in ldrun (a signal, out of memory, an uncaught exception)
// drives Y and WY to 0, sets the state to FAULT with the reason and leaves
// the segment in place; owner_alive() then tells a client the owner is dead
// (docs/faults.md, "The safe state and fatal errors").  An orderly exit sets
// EXITED and removes the segment.
#pragma once

#include <fcntl.h>
#include <signal.h>
#include <time.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>

namespace ldc::shm {

constexpr char kMagic[8] = {'L', 'D', 'C', 'S', 'H', 'M', '\0', '\1'};
constexpr uint32_t kVersion = 2;
constexpr uint32_t kHeaderSize = 4096;
constexpr uint32_t kXCount = 8192, kYCount = 8192, kWXCount = 1024, kWYCount = 1024;
constexpr uint32_t kXOffset = kHeaderSize;
constexpr uint32_t kWXOffset = kXOffset + kXCount;
constexpr uint32_t kYOffset = kWXOffset + 4 * kWXCount;
constexpr uint32_t kWYOffset = kYOffset + kYCount;
constexpr uint32_t kTotalSize = kWYOffset + 4 * kWYCount;  // 28672 bytes
constexpr uint32_t kReasonSize = 256;  // the reason text, NUL-terminated

enum State : uint32_t { kStop = 0, kRun = 1, kFault = 2, kExited = 3 };

// The header.  Plain integers; the fields marked "atomic" are only ever
// accessed through std::atomic_ref (lock-free and address-free for 4 and 8 bytes).
struct Header {
  char magic[8];           // kMagic
  uint32_t version;        // kVersion
  uint32_t header_size;    // kHeaderSize
  uint32_t total_size;     // kTotalSize
  uint32_t x_offset, x_count;
  uint32_t wx_offset, wx_count;
  uint32_t y_offset, y_count;
  uint32_t wy_offset, wy_count;
  uint32_t block_size;     // the configuration's I/O block size (informative)
  int32_t owner_pid;       // the ldrun process that created the segment
  alignas(64) uint32_t in_seq;   // atomic: inputs sequence, odd while a client writes
  int32_t in_writer;             // atomic: pid of the client holding the input lock, 0 if none
  alignas(64) uint32_t out_seq;  // atomic: outputs sequence, odd while ldrun writes
  uint32_t pad0;
  uint64_t out_count;            // atomic: output publications so far
  alignas(64) uint32_t state;    // atomic: State
  uint32_t pad1;
  uint64_t heartbeat_ns;         // atomic: CLOCK_MONOTONIC time of the last publication
  uint64_t scans;                // atomic: scans completed by all tasks
  // version 2
  uint64_t owner_start;          // the owner's start time: field 22 of /proc/PID/stat (clock ticks after boot); 0: unknown
  alignas(64) uint32_t reason_seq;  // atomic: sequence of `reason`, odd while ldrun writes it
  uint32_t pad2;
  alignas(8) char reason[kReasonSize];  // why the state is FAULT (ldrun's message); "" if it never was
};
static_assert(sizeof(Header) <= kHeaderSize);
static_assert(std::atomic_ref<uint32_t>::is_always_lock_free && std::atomic_ref<uint64_t>::is_always_lock_free);

template <class T>
inline std::atomic_ref<T> at(T& x) { return std::atomic_ref<T>(x); }

inline uint8_t* base(Header* h) { return reinterpret_cast<uint8_t*>(h); }

// Copies n bytes (a multiple of 8, both ends 8-byte aligned) with relaxed
// atomic 8-byte loads and stores: no torn words, no data race in the C++ sense.
inline void copy_words(uint8_t* dst, const uint8_t* src, size_t n) {
  for (size_t i = 0; i < n; i += 8) {
    uint64_t v = std::atomic_ref<uint64_t>(*const_cast<uint64_t*>(reinterpret_cast<const uint64_t*>(src + i)))
                     .load(std::memory_order_relaxed);
    std::atomic_ref<uint64_t>(*reinterpret_cast<uint64_t*>(dst + i)).store(v, std::memory_order_relaxed);
  }
}
// Single-byte and word stores and loads inside a sequence-protected area.
inline void store8(uint8_t* p, uint8_t v) { std::atomic_ref<uint8_t>(*p).store(v, std::memory_order_relaxed); }
inline uint8_t load8(const uint8_t* p) {
  return std::atomic_ref<uint8_t>(*const_cast<uint8_t*>(p)).load(std::memory_order_relaxed);
}
inline void store32(uint8_t* p, int32_t v) {
  std::atomic_ref<uint32_t>(*reinterpret_cast<uint32_t*>(p)).store(uint32_t(v), std::memory_order_relaxed);
}
inline int32_t load32(const uint8_t* p) {
  return int32_t(std::atomic_ref<uint32_t>(*const_cast<uint32_t*>(reinterpret_cast<const uint32_t*>(p)))
                     .load(std::memory_order_relaxed));
}

// ---- the seqlock
// Writer: begin_write, relaxed stores, end_write.  There is one writer at a
// time per counter (ldrun under its image lock; a client under the input lock).
inline void begin_write(uint32_t& seq) {
  auto s = at(seq);
  uint32_t v = s.load(std::memory_order_relaxed);
  if (v & 1) v++;  // a writer died in the middle: start from the next even value
  s.store(v + 1, std::memory_order_relaxed);
  std::atomic_thread_fence(std::memory_order_release);
}
inline void end_write(uint32_t& seq) {
  auto s = at(seq);
  s.store(s.load(std::memory_order_relaxed) + 1, std::memory_order_release);
}
// Reader: v = begin_read (false if a write is under way), copy, then
// end_read(v) is true if the copy is consistent.
inline bool begin_read(uint32_t& seq, uint32_t& v) {
  v = at(seq).load(std::memory_order_acquire);
  return (v & 1) == 0;
}
inline bool end_read(uint32_t& seq, uint32_t v) {
  std::atomic_thread_fence(std::memory_order_acquire);
  return at(seq).load(std::memory_order_relaxed) == v;
}

// ---- the reason text and the safe state
// Everything below is async-signal-safe (atomic stores, no locks, no
// allocation): ldrun's fatal-signal handler calls it.

// Writes `text` (cut to kReasonSize - 1 bytes) as the reason, under reason_seq.
inline void write_reason(Header* h, const char* text) {
  alignas(8) char buf[kReasonSize] = {};
  for (uint32_t i = 0; i + 1 < kReasonSize && text[i]; i++) buf[i] = text[i];
  begin_write(h->reason_seq);
  copy_words(reinterpret_cast<uint8_t*>(h->reason), reinterpret_cast<const uint8_t*>(buf), kReasonSize);
  end_write(h->reason_seq);
}
// Reads the reason into out[kReasonSize]; false if it was being written all along.
inline bool read_reason(Header* h, char* out) {
  for (int attempt = 0; attempt < 1000; attempt++) {
    uint32_t v;
    if (!begin_read(h->reason_seq, v)) continue;
    copy_words(reinterpret_cast<uint8_t*>(out), reinterpret_cast<const uint8_t*>(h->reason), kReasonSize);
    if (!end_read(h->reason_seq, v)) continue;
    out[kReasonSize - 1] = 0;
    return true;
  }
  return false;
}
// Every output (Y, WY) to 0 in one update of out_seq.
inline void zero_outputs(Header* h) {
  uint8_t* b = base(h);
  begin_write(h->out_seq);
  for (uint32_t i = 0; i < kYCount; i += 8) at(*reinterpret_cast<uint64_t*>(b + kYOffset + i)).store(0, std::memory_order_relaxed);
  for (uint32_t i = 0; i < 4 * kWYCount; i += 8)
    at(*reinterpret_cast<uint64_t*>(b + kWYOffset + i)).store(0, std::memory_order_relaxed);
  end_write(h->out_seq);
  at(h->out_count).fetch_add(1, std::memory_order_relaxed);
}

// ---- the owner
// The start time of process `pid` (field 22 of /proc/PID/stat), 0 if unknown.
inline uint64_t process_start(int32_t pid) {
  char path[40], buf[1024];
  std::snprintf(path, sizeof path, "/proc/%d/stat", int(pid));
  int fd = ::open(path, O_RDONLY | O_CLOEXEC);
  if (fd < 0) return 0;
  ssize_t n = ::read(fd, buf, sizeof buf - 1);
  ::close(fd);
  if (n <= 0) return 0;
  buf[n] = 0;
  const char* p = std::strrchr(buf, ')');  // the command name may hold spaces and ')'
  if (!p) return 0;
  // after ") ": field 3 (state) ... field 22 (starttime)
  for (int field = 2; field < 22 && *p; p++)
    if (*p == ' ') field++;
  return std::strtoull(p, nullptr, 10);
}
// Whether the ldrun that owns the segment still runs (a pid that exists
// but started at another time belongs to another process now).
inline bool owner_alive(const Header* h) {
  int32_t pid = h->owner_pid;
  if (pid <= 0) return false;
  if (::kill(pid, 0) != 0 && errno == ESRCH) return false;
  uint64_t recorded = h->owner_start, now = recorded ? process_start(pid) : 0;
  return recorded == 0 || now == 0 || now == recorded;
}

// ---- the input lock (clients only)
// Takes the input lock for `pid`; a holder that no longer exists is replaced.
// Returns false if another live client kept it for `spins` attempts.
inline bool lock_inputs(Header* h, int32_t pid, int spins = 1000000) {
  auto w = at(h->in_writer);
  for (int i = 0; i < spins; i++) {
    int32_t cur = 0;
    if (w.compare_exchange_weak(cur, pid, std::memory_order_acquire)) return true;
    if (cur != 0 && ::kill(cur, 0) != 0 && errno == ESRCH) {  // the holder died: take over
      if (w.compare_exchange_strong(cur, pid, std::memory_order_acquire)) return true;
    }
    if (i % 64 == 63) {
      struct timespec ts = {0, 50000};
      nanosleep(&ts, nullptr);
    }
  }
  return false;
}
inline void unlock_inputs(Header* h, int32_t pid) {
  int32_t cur = pid;
  at(h->in_writer).compare_exchange_strong(cur, 0, std::memory_order_release);
}

// Initializes a fresh segment of kTotalSize zero bytes (ldrun does this).
inline void init(Header* h, uint32_t block_size, int32_t owner) {
  std::memset(static_cast<void*>(h), 0, kTotalSize);
  std::memcpy(h->magic, kMagic, 8);
  h->version = kVersion;
  h->header_size = kHeaderSize;
  h->total_size = kTotalSize;
  h->x_offset = kXOffset, h->x_count = kXCount;
  h->wx_offset = kWXOffset, h->wx_count = kWXCount;
  h->y_offset = kYOffset, h->y_count = kYCount;
  h->wy_offset = kWYOffset, h->wy_count = kWYCount;
  h->block_size = block_size;
  h->owner_pid = owner;
  h->owner_start = process_start(owner);
}
// "" if a mapped segment of `size` bytes is one this header describes, else why not.
inline const char* check(const Header* h, size_t size) {
  if (size < kTotalSize) return "segment smaller than the layout";
  if (std::memcmp(h->magic, kMagic, 8) != 0) return "not an ldc I/O segment (bad magic)";
  if (h->version != kVersion) return "unsupported layout version";
  if (h->header_size != kHeaderSize || h->total_size != kTotalSize || h->x_offset != kXOffset ||
      h->y_offset != kYOffset || h->wx_offset != kWXOffset || h->wy_offset != kWYOffset)
    return "unexpected layout";
  return "";
}

}  // namespace ldc::shm
