// modbus_load -- a bounded load test of `ldrun --modbus` on loopback
// (docs/runtime.md, "Modbus TCP"; CTest label `load`).
//
//   modbus_load LDRUN ECHO.ld [--clients 50] [--requests 10000] [--period 1ms] [--rt]
//
// Runs ECHO.ld twice under `ldrun --io=none --modbus 127.0.0.1:0 --stats`:
// once idle (as many scans as the loaded run lasted, at least 2000), once
// with CLIENTS connections (the server is started with that many allowed)
// each doing REQUESTS requests in a loop of four: write a D word of its own
// with FC 16 (two registers whose halves are derived from one counter), read
// it back with FC 3 (it must be the value just written, both halves of one
// write: no lost write, no torn word), write a coil of its own (FC 5), read
// it back (FC 1).  Also checks the program's scan counter D4 never goes
// back and D5 = D4 x 65537 comes from the same scan (no torn read).  Prints ldrun's scan and jitter statistics of both runs; fails (exit
// 1) on any wrong value, error reply, timeout or ldrun exit status but 0.
// Timing is reported, never asserted.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <mutex>
#include <regex>
#include <string>
#include <thread>
#include <vector>

extern char** environ;

namespace {

using Clock = std::chrono::steady_clock;

// An ldrun process whose stderr is collected by a thread.
struct Ldrun {
  pid_t pid = -1;
  int err = -1;
  std::thread reader;
  std::mutex mu;
  std::condition_variable cv;
  std::string text;
  bool eof = false;

  explicit Ldrun(const std::vector<std::string>& args) {
    int p[2];
    if (pipe(p) != 0) throw std::runtime_error("pipe");
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_adddup2(&fa, p[1], 2);
    posix_spawn_file_actions_addclose(&fa, p[0]);
    std::vector<char*> argv;
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    if (posix_spawn(&pid, argv[0], &fa, nullptr, argv.data(), environ) != 0) throw std::runtime_error("cannot run " + args[0]);
    posix_spawn_file_actions_destroy(&fa);
    close(p[1]);
    err = p[0];
    reader = std::thread([this] {
      char buf[4096];
      ssize_t n;
      while ((n = read(err, buf, sizeof buf)) > 0) {
        std::lock_guard<std::mutex> g(mu);
        text.append(buf, size_t(n));
        cv.notify_all();
      }
      std::lock_guard<std::mutex> g(mu);
      eof = true;
      cv.notify_all();
    });
  }
  // The port it listens on (0 if it did not say so within 30 s).
  int port() {
    std::unique_lock<std::mutex> l(mu);
    std::smatch m;
    static const std::regex re("listening on 127\\.0\\.0\\.1:([0-9]+)");
    cv.wait_for(l, std::chrono::seconds(30), [&] { return eof || std::regex_search(text, m, re); });
    return std::regex_search(text, m, re) ? std::stoi(m[1]) : 0;
  }
  // Waits for the exit (SIGTERM first if `stop`); the exit status, or -1.
  int finish(bool stop) {
    if (stop) kill(pid, SIGTERM);
    int st = 0;
    for (int i = 0; i < 600; i++) {  // 60 s
      if (waitpid(pid, &st, WNOHANG) == pid) {
        reader.join();
        close(err);
        return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    kill(pid, SIGKILL);
    waitpid(pid, &st, 0);
    reader.join();
    close(err);
    return -1;
  }
};

struct Client {
  int fd = -1;
  uint16_t tid = 0;
  std::string error;
  explicit Client(int port) {
    fd = socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(uint16_t(port));
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    timeval tv{10, 0};
    setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
    int one = 1;
    setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
    if (connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) error = std::string("connect: ") + strerror(errno);
  }
  ~Client() { close(fd); }
  // One request; its reply PDU, or empty with `error` set.
  std::vector<uint8_t> call(const std::vector<uint8_t>& pdu) {
    tid++;
    std::vector<uint8_t> f{uint8_t(tid >> 8), uint8_t(tid), 0, 0, 0, uint8_t(pdu.size() + 1), 1};
    for (uint8_t b : pdu) f.push_back(b);
    if (send(fd, f.data(), f.size(), MSG_NOSIGNAL) != ssize_t(f.size())) return fail("send failed");
    uint8_t h[7];
    if (!read_n(h, 7)) return fail("no reply (timeout or closed)");
    if ((h[0] << 8 | h[1]) != tid) return fail("wrong transaction identifier");
    std::vector<uint8_t> p(size_t(h[4] << 8 | h[5]) - 1);
    if (!read_n(p.data(), p.size())) return fail("short reply");
    if (p.empty() || p[0] != pdu[0]) return fail("exception " + std::to_string(p.size() > 1 ? p[1] : 0));
    return p;
  }
  std::vector<uint8_t> fail(const std::string& m) {
    if (error.empty()) error = m;
    return {};
  }
  bool read_n(uint8_t* p, size_t n) {
    while (n) {
      ssize_t k = recv(fd, p, n, 0);
      if (k <= 0) return false;
      p += k, n -= size_t(k);
    }
    return true;
  }
};

// Client `i`: D(100+i) (holding 1024 + 2(100+i)) and coil M(100+i).
std::string run_client(int port, int i, int requests, uint64_t& done) {
  Client c(port);
  if (!c.error.empty()) return c.error;
  uint32_t reg = 1024 + 2 * (100 + uint32_t(i)), coil = 8192 + 100 + uint32_t(i);
  uint32_t last_count = 0;
  for (int k = 0; done < uint64_t(requests); k++) {
    uint16_t hi = uint16_t(k * 7 + i), lo = uint16_t(~hi);
    auto w = c.call({16, uint8_t(reg >> 8), uint8_t(reg), 0, 2, 4, uint8_t(hi >> 8), uint8_t(hi), uint8_t(lo >> 8), uint8_t(lo)});
    if (w.empty()) return c.error;
    auto r = c.call({3, uint8_t(reg >> 8), uint8_t(reg), 0, 2});
    if (r.size() != 6) return c.error.empty() ? "bad read reply" : c.error;
    uint16_t rhi = uint16_t(r[2] << 8 | r[3]), rlo = uint16_t(r[4] << 8 | r[5]);
    if (rhi != hi || rlo != lo)
      return "D" + std::to_string(100 + i) + " read " + std::to_string(rhi) + "/" + std::to_string(rlo) + " after writing " +
             std::to_string(hi) + "/" + std::to_string(lo) + (uint16_t(~rhi) == rlo ? " (a lost write)" : " (a torn word)");
    uint8_t on = k & 1;
    auto cw = c.call({5, uint8_t(coil >> 8), uint8_t(coil), uint8_t(on ? 0xFF : 0), 0});
    if (cw.empty()) return c.error;
    auto cr = c.call({1, uint8_t(coil >> 8), uint8_t(coil), 0, 1});
    if (cr.size() != 3) return c.error.empty() ? "bad coil reply" : c.error;
    if ((cr[2] & 1) != on) return "coil M" + std::to_string(100 + i) + " lost a write";
    done += 4;
    if (k % 50 == 0) {  // the scan counter D4 never goes back; D5 = D4 x 65537 of the same scan
      auto s = c.call({3, 0x04, 0x08, 0, 4});
      if (s.size() != 10) return c.error;
      uint32_t n = uint32_t(s[2] << 24 | s[3] << 16 | s[4] << 8 | s[5]);
      uint32_t d5 = uint32_t(s[6] << 24 | s[7] << 16 | s[8] << 8 | s[9]);
      if (n < last_count) return "the scan counter went back from " + std::to_string(last_count) + " to " + std::to_string(n);
      if (n < 65536 && d5 != n * 65537u)
        return "D4 = " + std::to_string(n) + " but D5 = " + std::to_string(d5) + ": not one scan";
      last_count = n;
      done++;
    }
  }
  return "";
}

std::string stats_of(const std::string& text) {
  std::string out;
  size_t p = text.find("task main");
  return p == std::string::npos ? "(no statistics)\n" + text : text.substr(p);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: modbus_load LDRUN ECHO.ld [--clients 50] [--requests 10000] [--period 1ms] [--rt]\n");
    return 2;
  }
  std::string ldrun = argv[1], echo = argv[2], period = "1ms";
  int clients = 50, requests = 10000;
  bool rt = false;
  for (int i = 3; i < argc; i++) {
    std::string a = argv[i];
    if (a == "--clients" && i + 1 < argc) clients = std::stoi(argv[++i]);
    else if (a == "--requests" && i + 1 < argc) requests = std::stoi(argv[++i]);
    else if (a == "--period" && i + 1 < argc) period = argv[++i];
    else if (a == "--rt") rt = true;
    else {
      std::fprintf(stderr, "modbus_load: unknown argument '%s'\n", a.c_str());
      return 2;
    }
  }
  std::vector<std::string> base{ldrun, echo, "--io=none", "--period", period, "--stats", "--modbus", "127.0.0.1:0",
                                "--modbus-connections", std::to_string(clients + 2)};
  if (rt) base.push_back("--rt");

  // Under load.
  auto t0 = Clock::now();
  std::vector<std::string> failures;
  Ldrun loaded(base);
  int port = loaded.port();
  if (!port) {
    loaded.finish(true);
    std::fprintf(stderr, "modbus_load: ldrun did not listen:\n%s", loaded.text.c_str());
    return 1;
  }
  std::vector<std::thread> threads;
  std::vector<std::string> errors(static_cast<size_t>(clients));
  std::vector<uint64_t> done(static_cast<size_t>(clients), 0);
  for (int w = 0; w < clients; w++)
    threads.emplace_back([&, w] { errors[size_t(w)] = run_client(port, w, requests, done[size_t(w)]); });
  for (auto& t : threads) t.join();
  double secs = std::chrono::duration<double>(Clock::now() - t0).count();
  int st = loaded.finish(true);
  uint64_t total = 0;
  for (int w = 0; w < clients; w++) {
    total += done[size_t(w)];
    if (!errors[size_t(w)].empty()) failures.push_back("client " + std::to_string(w) + ": " + errors[size_t(w)]);
  }
  if (st != 0) failures.push_back("ldrun under load exited with status " + std::to_string(st));
  std::printf("loaded: %d clients x %d requests: %llu requests in %.1f s (%.0f requests/s)\n", clients, requests,
              (unsigned long long)total, secs, double(total) / secs);
  std::printf("ldrun --period %s%s under load:\n%s", period.c_str(), rt ? " --rt" : "", stats_of(loaded.text).c_str());

  // Idle, as long.
  int64_t period_us = std::stoi(period) * (period.find("us") != std::string::npos ? 1 : 1000);
  int64_t scans = std::max<int64_t>(2000, int64_t(secs * 1e6) / period_us);
  std::vector<std::string> idle_args = base;
  idle_args.push_back("--scans");
  idle_args.push_back(std::to_string(scans));
  Ldrun idle(idle_args);
  int ist = idle.finish(false);
  if (ist != 0) failures.push_back("ldrun idle exited with status " + std::to_string(ist));
  std::printf("ldrun --period %s%s idle, %lld scans:\n%s", period.c_str(), rt ? " --rt" : "", (long long)scans,
              stats_of(idle.text).c_str());

  for (const auto& f : failures) std::printf("FAIL %s\n", f.c_str());
  std::printf("%s\n", failures.empty() ? "ok: no lost or torn write, no error reply" : "FAILED");
  return failures.empty() ? 0 : 1;
}
