// runtime/failsafe.cpp -- see failsafe.h.  Everything a signal handler
// touches here is a lock-free atomic or a plain buffer written before the
// handler can run; the handler calls only async-signal-safe functions
// (write, nanosleep, sigaction, raise, syscall).
#include "runtime/failsafe.h"

#include <pthread.h>
#include <semaphore.h>
#include <signal.h>
#include <sys/mman.h>
#include <sys/syscall.h>
#include <time.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <memory>
#include <mutex>
#include <new>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace ldc::failsafe {
namespace {

std::atomic<shm::Header*> g_segment{nullptr};
std::atomic<bool> g_fatal{false};   // a fatal path has begun: publications are refused
std::atomic<int> g_publishing{0};   // publications under way, all threads
thread_local int t_publishing = 0;  // ... of this thread (a handler must not wait for its own)
std::atomic<long> g_owner{0};       // the thread running the fatal path
std::atomic<bool> g_armed{true};    // false in a forked child (the sandbox's)

std::mutex g_rescue_mu;  // the hook below; held only to copy or set it
Rescue g_rescue = nullptr;
void* g_rescue_ctx = nullptr;
sem_t g_go, g_done;
std::atomic<bool> g_installed{false};
char g_reason[512];  // the fatal path's reason, written before g_go is posted

// Address space set aside at start and given back when memory runs out, so
// that the fatal path can still allocate under an address-space limit.
constexpr size_t kReserveBytes = size_t(32) << 20;
// How long fatal() waits for the runtime's rescue before it ends the process anyway.
constexpr int kRescueSeconds = 5;
std::atomic<void*> g_reserve{nullptr};

struct SignalName {
  int no;
  const char* name;
};
// The signals whose default action ends the process (SIGINT and SIGTERM are
// ldrun's orderly stop, taken by sigtimedwait; SIGKILL and SIGSTOP cannot be caught).
constexpr SignalName kFatalSignals[] = {
    {SIGSEGV, "SIGSEGV"}, {SIGBUS, "SIGBUS"},   {SIGFPE, "SIGFPE"},   {SIGILL, "SIGILL"},   {SIGABRT, "SIGABRT"},
    {SIGTRAP, "SIGTRAP"}, {SIGSYS, "SIGSYS"},   {SIGQUIT, "SIGQUIT"}, {SIGHUP, "SIGHUP"},   {SIGPIPE, "SIGPIPE"},
    {SIGXCPU, "SIGXCPU"}, {SIGXFSZ, "SIGXFSZ"}, {SIGALRM, "SIGALRM"}, {SIGUSR1, "SIGUSR1"}, {SIGUSR2, "SIGUSR2"}};
constexpr size_t kSignals = sizeof kFatalSignals / sizeof kFatalSignals[0];
struct sigaction g_previous[kSignals];  // what each signal did before install()

long thread_id() { return long(syscall(SYS_gettid)); }

void say(const char* s) {
  size_t n = std::strlen(s);
  while (n > 0) {
    ssize_t w = ::write(2, s, n);
    if (w < 0 && errno == EINTR) continue;
    if (w <= 0) return;
    s += w, n -= size_t(w);
  }
}

void nap_us(long us) {
  timespec ts{us / 1000000, (us % 1000000) * 1000};
  nanosleep(&ts, nullptr);
}

void release_reserve() {
  if (void* p = g_reserve.exchange(nullptr)) munmap(p, kReserveBytes);
}

// The first caller owns the fatal path (true).  Another thread waits here
// for the owner to end the process (false after 20 s); the owner's own
// thread coming back (a fault inside the fatal path) gets false at once.
bool claim() {
  long me = thread_id(), none = 0;
  if (g_owner.compare_exchange_strong(none, me)) {
    g_fatal.store(true);
    return true;
  }
  if (none == me) return false;
  for (int i = 0; i < 20000; i++) nap_us(1000);
  return false;
}

// The raw path: the segment's outputs to 0, its reason and state FAULT.
// Publications under way on other threads end first (they are a few
// microseconds long; the wait is bounded in case one of them is stuck).
void raw_safe_state(const char* reason) {
  g_fatal.store(true);
  for (int i = 0; i < 500 && g_publishing.load() - t_publishing > 0; i++) nap_us(100);
  shm::Header* h = g_segment.load();
  if (!h) return;
  shm::zero_outputs(h);
  shm::write_reason(h, reason);
  shm::at(h->state).store(shm::kFault, std::memory_order_release);
}

// Appends s to buf[cap] (async-signal-safe strcat).
void append(char* buf, size_t cap, const char* s) {
  size_t n = std::strlen(buf);
  while (*s && n + 1 < cap) buf[n++] = *s++;
  buf[n] = 0;
}

// The signal handler: the raw path, then the signal again with the action it
// had before install() (the default: the process ends and its status names
// the signal; under ASan, its report).
void on_fatal_signal(int sig) {
  const int saved_errno = errno;
  size_t k = 0;
  while (k < kSignals && kFatalSignals[k].no != sig) k++;
  if (g_armed.load() && k < kSignals && claim()) {
    char reason[shm::kReasonSize] = "ldrun: fatal: signal ";
    append(reason, sizeof reason, kFatalSignals[k].name);
    append(reason, sizeof reason,
           "; outputs driven to the safe state (all Y off, WY 0); retentive memory not saved (not safe in a signal handler)");
    raw_safe_state(reason);
    say(reason);
    say("\n");
  }
  if (k < kSignals) sigaction(sig, &g_previous[k], nullptr);
  else signal(sig, SIG_DFL);
  raise(sig);  // blocked while the handler runs: delivered when it returns (a fault strikes again)
  errno = saved_errno;
}

void on_terminate() {
  release_reserve();
  char what[400] = "std::terminate called without an exception";
  if (std::exception_ptr e = std::current_exception()) {
    try {
      std::rethrow_exception(e);
    } catch (const std::bad_alloc& x) {
      std::snprintf(what, sizeof what, "out of memory (%s), uncaught on a thread", x.what());
    } catch (const std::exception& x) {
      std::snprintf(what, sizeof what, "an uncaught exception on a thread: %s", x.what());
    } catch (...) {
      std::snprintf(what, sizeof what, "an uncaught exception of unknown type on a thread");
    }
  }
  fatal(what);
}

// The rescue thread: waits for a fatal path, runs the runtime's rescue.
void rescue_main() {
  {
    // The thread's allocator arena, made now while memory is plentiful.
    std::unique_ptr<char[]> warm(new char[4096]);
    std::memset(warm.get(), 0, 4096);
  }
  while (sem_wait(&g_go) != 0) {}
  Rescue f;
  void* ctx;
  {
    std::lock_guard<std::mutex> l(g_rescue_mu);
    f = g_rescue, ctx = g_rescue_ctx;
  }
  try {
    if (f) f(ctx, g_reason);
  } catch (const std::exception& e) {  // e.g. out of memory again: the raw path has done the essential
    say("ldrun: fatal: the rescue failed: ");
    say(e.what());
    say("\n");
  }
  sem_post(&g_done);
}

// LDC_FAULT_INJECT, parsed once.
struct Injection {
  std::string text, where, what;
  long at = 1;
  bool on = false;
};
const Injection& injection() {
  static const Injection inj = [] {
    Injection j;
    const char* env = std::getenv("LDC_FAULT_INJECT");
    if (!env || !*env) return j;
    j.text = env;
    std::string s = env;
    size_t colon = s.find(':'), at = s.find('@');
    j.where = s.substr(0, colon);
    j.what = colon == std::string::npos ? "" : s.substr(colon + 1, at == std::string::npos ? std::string::npos : at - colon - 1);
    if (at != std::string::npos) {
      char* end = nullptr;
      j.at = std::strtol(s.c_str() + at + 1, &end, 10);
      if (*end || j.at < 1) j.at = 0;
    }
    bool where_ok = j.where == "http" || j.where == "modbus" || j.where == "io";
    bool what_ok = j.what == "throw" || j.what == "bad_alloc" || j.what == "oom";
    j.on = where_ok && what_ok && j.at >= 1;
    return j;
  }();
  return inj;
}
std::atomic<long> g_injection_hits{0};

// Allocates 64 MiB blocks (untouched: address space, not memory) until an
// allocation fails; gives up after 1 TiB.  The blocks stay allocated while
// the std::bad_alloc travels, as an attacker's would.
void exhaust_memory() {
  std::vector<std::unique_ptr<char[]>> hog;
  hog.reserve(16384);
  for (size_t i = 0; i < 16384; i++) hog.emplace_back(new char[size_t(64) << 20]);
  say("ldrun: LDC_FAULT_INJECT: 1 TiB allocated without failing (no address-space limit?)\n");
}

}  // namespace

void install() {
  const Injection& inj = injection();
  if (!inj.text.empty() && !inj.on)
    throw std::runtime_error("bad LDC_FAULT_INJECT '" + inj.text +
                             "' (WHERE:WHAT[@N]: WHERE http, modbus or io; WHAT throw, bad_alloc or oom; N >= 1)");
  if (g_installed.exchange(true)) return;
  void* p = mmap(nullptr, kReserveBytes, PROT_NONE, MAP_PRIVATE | MAP_ANONYMOUS | MAP_NORESERVE, -1, 0);
  if (p != MAP_FAILED) g_reserve.store(p);
  sem_init(&g_go, 0, 0);
  sem_init(&g_done, 0, 0);
  // The rescue thread takes no signal: it is created with all of them blocked.
  sigset_t all, old;
  sigfillset(&all);
  pthread_sigmask(SIG_BLOCK, &all, &old);
  std::thread(rescue_main).detach();
  pthread_sigmask(SIG_SETMASK, &old, nullptr);
  pthread_atfork(nullptr, nullptr, [] { g_armed.store(false); });
  std::set_terminate(on_terminate);
  for (size_t k = 0; k < kSignals; k++) {
    sigaction(kFatalSignals[k].no, nullptr, &g_previous[k]);
    if (g_previous[k].sa_handler == SIG_IGN) continue;  // ignored by who started ldrun (nohup): stays so
    struct sigaction sa {};
    sa.sa_handler = on_fatal_signal;
    sa.sa_flags = SA_ONSTACK;
    sigemptyset(&sa.sa_mask);
    sigaction(kFatalSignals[k].no, &sa, nullptr);
  }
}

void register_segment(shm::Header* h) { g_segment.store(h); }

bool unregister_segment(shm::Header* h) {
  shm::Header* expect = h;
  g_segment.compare_exchange_strong(expect, nullptr);
  return !g_fatal.load();
}

void set_rescue(Rescue f, void* ctx) {
  std::lock_guard<std::mutex> l(g_rescue_mu);
  g_rescue = f, g_rescue_ctx = ctx;
}

void clear_rescue(void* ctx) {
  std::lock_guard<std::mutex> l(g_rescue_mu);
  if (g_rescue_ctx == ctx) g_rescue = nullptr, g_rescue_ctx = nullptr;
}

Publication::Publication() {
  t_publishing++;
  g_publishing.fetch_add(1);
  open_ = !g_fatal.load();
  if (!open_) g_publishing.fetch_sub(1), t_publishing--;
}

Publication::~Publication() {
  if (!open_) return;
  g_publishing.fetch_sub(1);
  t_publishing--;
}

void note_fault(const char* reason) {
  if (shm::Header* h = g_segment.load(); h && !g_fatal.load()) shm::write_reason(h, reason);
}

void zero_segment_outputs() {
  if (shm::Header* h = g_segment.load(); h && !g_fatal.load()) shm::zero_outputs(h);
}

void fatal(const char* what) {
  if (!g_armed.load() || !claim()) _exit(kFatalExit);  // a forked child leaves the segment alone
  release_reserve();
  std::snprintf(g_reason, sizeof g_reason,
                "ldrun: fatal: %s; outputs driven to the safe state (all Y off, WY 0); the runtime is in FAULT", what);
  raw_safe_state(g_reason);
  say(g_reason);
  say("\n");
  bool rescue;
  {
    std::unique_lock<std::mutex> l(g_rescue_mu, std::try_to_lock);
    rescue = g_installed.load() && (!l.owns_lock() || g_rescue);
  }
  if (rescue) {
    sem_post(&g_go);
    timespec deadline;
    clock_gettime(CLOCK_REALTIME, &deadline);
    deadline.tv_sec += kRescueSeconds;
    int r;
    while ((r = sem_timedwait(&g_done, &deadline)) != 0 && errno == EINTR) {}
    if (r != 0) say("ldrun: fatal: the rescue did not end within 5 s; retentive memory may not have been saved\n");
  }
  _exit(kFatalExit);
}

void inject(const char* where) {
  const Injection& inj = injection();
  if (!inj.on || inj.where != where || g_injection_hits.fetch_add(1) + 1 != inj.at) return;
  say(("ldrun: LDC_FAULT_INJECT=" + inj.text + ": injected\n").c_str());
  if (inj.what == "throw") throw std::runtime_error("fault injected by LDC_FAULT_INJECT=" + inj.text);
  if (inj.what == "bad_alloc") throw std::bad_alloc();
  exhaust_memory();
}

}  // namespace ldc::failsafe
