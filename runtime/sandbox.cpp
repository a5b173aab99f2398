// runtime/sandbox.cpp -- a seccomp-confined child process that runs scans
// (sandbox.h).
#include "runtime/sandbox.h"

#include <linux/audit.h>
#include <linux/filter.h>
#include <linux/seccomp.h>
#include <poll.h>
#include <signal.h>
#include <ucontext.h>
#include <sys/prctl.h>
#include <sys/socket.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstddef>
#include <cstring>
#include <vector>

namespace ldc {
namespace {

sock_filter stmt(uint16_t code, uint32_t k) { return {code, 0, 0, k}; }
sock_filter jeq(uint32_t k, uint8_t jt, uint8_t jf) { return {BPF_JMP | BPF_JEQ | BPF_K, jt, jf, k}; }
constexpr uint32_t kNr = offsetof(seccomp_data, nr);
constexpr uint32_t kArch = offsetof(seccomp_data, arch);
constexpr uint32_t kArg0Lo = offsetof(seccomp_data, args[0]), kArg0Hi = kArg0Lo + 4;

// One block per allowed call: a call that matches the number but not the
// argument is refused at once; one that does not match falls to the next block.
std::vector<sock_filter> filter_program(std::span<const AllowedSyscall> allowed) {
  const uint16_t ld = BPF_LD | BPF_W | BPF_ABS, ret = BPF_RET | BPF_K;
  std::vector<sock_filter> f = {stmt(ld, kArch), jeq(AUDIT_ARCH_X86_64, 1, 0), stmt(ret, SECCOMP_RET_KILL_PROCESS)};
  for (const AllowedSyscall& a : allowed) {
    f.push_back(stmt(ld, kNr));
    if (a.arg0 < 0) {
      f.push_back(jeq(uint32_t(a.nr), 0, 1));
      f.push_back(stmt(ret, SECCOMP_RET_ALLOW));
      continue;
    }
    f.push_back(jeq(uint32_t(a.nr), 0, 6));
    f.push_back(stmt(ld, kArg0Lo));
    f.push_back(jeq(uint32_t(a.arg0), 0, 3));
    f.push_back(stmt(ld, kArg0Hi));
    f.push_back(jeq(uint32_t(uint64_t(a.arg0) >> 32), 0, 1));
    f.push_back(stmt(ret, SECCOMP_RET_ALLOW));
    f.push_back(stmt(ret, SECCOMP_RET_TRAP));
  }
  f.push_back(stmt(ret, SECCOMP_RET_TRAP));
  return f;
}

// Installs a filter; async-signal-safe (it runs in a child forked from a
// process that may have threads): 0, or the errno.
int install(std::vector<sock_filter>& f) {
  sock_fprog prog{uint16_t(f.size()), f.data()};
  if (prctl(PR_SET_NO_NEW_PRIVS, 1, 0, 0, 0) != 0) return errno;
  if (prctl(PR_SET_SECCOMP, SECCOMP_MODE_FILTER, &prog, 0, 0) != 0) return errno;
  return 0;
}

// What the child sends after each scan: a scan done, or the signal that ended it.
struct Report {
  int32_t signo = 0;   // 0: the scan ended
  int32_t syscall = -1;
  uint64_t addr = 0;
  uint64_t ip = 0;     // where the signal struck
};

int g_report_fd = -1;

// Runs in the confined child: report the signal, then leave (both allowed).
void on_fatal_signal(int sig, siginfo_t* si, void* ctx) {
  Report r;
  r.signo = sig;
  r.addr = uint64_t(reinterpret_cast<uintptr_t>(si->si_addr));
  r.ip = uint64_t(static_cast<ucontext_t*>(ctx)->uc_mcontext.gregs[REG_RIP]);
  if (sig == SIGSYS) r.syscall = si->si_syscall;
  (void)!write(g_report_fd, &r, sizeof r);
  syscall(SYS_exit_group, 128 + sig);
}

std::string describe(const Report& r) {
  char buf[160];
  if (r.signo == SIGSYS)
    std::snprintf(buf, sizeof buf, "the sandboxed scan made system call %d, which the sandbox refuses", r.syscall);
  else
    std::snprintf(buf, sizeof buf, "the sandboxed scan was stopped by %s at address 0x%llx (instruction at 0x%llx)",
                  strsignal(r.signo), (unsigned long long)r.addr, (unsigned long long)r.ip);
  return buf;
}

class SandboxEngine : public Engine {
 public:
  SandboxEngine(std::unique_ptr<Engine> inner, const Layout& layout, int timeout_ms)
      : shared_(layout.size, ImageBytes::Sharing::Shared), timeout_ms_(timeout_ms) {
    int sv[2];
    if (socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, sv) != 0)
      throw SandboxError(std::string("sandbox: socketpair: ") + std::strerror(errno));
    altstack_.resize(64 * 1024);
    // Everything the child needs is made here: after fork it allocates nothing.
    const AllowedSyscall allowed[] = {{SYS_read, sv[1]}, {SYS_write, sv[1]}, {SYS_exit_group}};
    filter_ = filter_program(allowed);
    pid_ = fork();
    if (pid_ < 0) {
      close(sv[0]), close(sv[1]);
      throw SandboxError(std::string("sandbox: fork: ") + std::strerror(errno));
    }
    if (pid_ == 0) {
      close(sv[0]);
      child(*inner, sv[1]);
    }
    close(sv[1]);
    fd_ = sv[0];
  }
  ~SandboxEngine() override {
    close(fd_);  // the child reads end of file and exits
    reap();
  }

  void scan(ImageBytes& mem_bytes) override {
    uint8_t* mem = mem_bytes.data();
    if (!dead_.empty()) throw SandboxError(dead_);
    std::memcpy(shared_.data(), mem, shared_.size());
    char go = 's';
    if (send(fd_, &go, 1, MSG_NOSIGNAL) != 1) fail("the sandbox child is gone");
    Report r;
    size_t got = 0;
    while (got < sizeof r) {
      pollfd p{fd_, POLLIN, 0};
      int n = poll(&p, 1, timeout_ms_);
      if (n < 0 && errno == EINTR) continue;
      if (n == 0) fail("the sandboxed scan did not end within " + std::to_string(timeout_ms_) + " ms");
      ssize_t k = recv(fd_, reinterpret_cast<char*>(&r) + got, sizeof r - got, 0);
      if (k < 0 && errno == EINTR) continue;
      if (k <= 0) fail("the sandbox child ended without a report");
      got += size_t(k);
    }
    if (r.signo != 0) fail(describe(r));
    if (!shared_.slack_intact()) fail("the sandboxed scan wrote past the end of the memory image");
    std::memcpy(mem, shared_.data(), shared_.size());
  }

 private:
  // UBSan's vptr check, on a type it has not seen, probes memory with
  // pipe2 and write, which the filter refuses; the child checks no vptr (in
  // a sanitizer build: ASan's own interceptors need no system call here).
  [[noreturn]] __attribute__((no_sanitize("vptr"))) void child(Engine& inner, int fd) {
    g_report_fd = fd;
    stack_t ss{};
    ss.ss_sp = altstack_.data();
    ss.ss_size = altstack_.size();
    sigaltstack(&ss, nullptr);
    struct sigaction sa {};
    sa.sa_sigaction = on_fatal_signal;
    sa.sa_flags = SA_SIGINFO | SA_ONSTACK;
    for (int s : {SIGSEGV, SIGBUS, SIGILL, SIGFPE, SIGTRAP, SIGSYS}) sigaction(s, &sa, nullptr);
    if (install(filter_) != 0) syscall(SYS_exit_group, 3);
    for (;;) {
      char c;
      if (read(fd, &c, 1) != 1) syscall(SYS_exit_group, 0);
      inner.scan(shared_);
      Report r;
      if (write(fd, &r, sizeof r) != ssize_t(sizeof r)) syscall(SYS_exit_group, 4);
    }
  }
  [[noreturn]] void fail(std::string why) {
    dead_ = why;
    if (pid_ > 0) kill(pid_, SIGKILL);
    reap();
    throw SandboxError(why);
  }
  void reap() {
    if (pid_ <= 0) return;
    while (waitpid(pid_, nullptr, 0) < 0 && errno == EINTR) {}
    pid_ = -1;
  }

  ImageBytes shared_;
  int timeout_ms_;
  std::vector<char> altstack_;
  std::vector<sock_filter> filter_;
  pid_t pid_ = -1;
  int fd_ = -1;
  std::string dead_;
};

}  // namespace

std::string confine(std::span<const AllowedSyscall> allowed) {
  std::vector<sock_filter> f = filter_program(allowed);
  int e = install(f);
  return e ? std::string("seccomp: ") + std::strerror(e) : "";
}

std::unique_ptr<Engine> make_sandboxed_engine(std::unique_ptr<Engine> inner, const Layout& layout, int timeout_ms) {
  return std::make_unique<SandboxEngine>(std::move(inner), layout, timeout_ms);
}

}  // namespace ldc
