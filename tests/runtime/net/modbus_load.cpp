// modbus_load -- a bounded load test of `ldrun --modbus` on loopback
// (docs/runtime.md, "Modbus TCP"; CTest label `load`), and the write burst of
// docs/faults.md ("Network writes and the scan").
//
//   modbus_load LDRUN ECHO.ld [--clients 50] [--requests 10000] [--period 1ms] [--rt]
//   modbus_load LDRUN ECHO.ld --burst SECONDS [--clients 16] [--period 1ms] [--watchdog 2ms] [--rt] [--idle]
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
//
// --burst: CLIENTS connections write as fast as the server answers for
// SECONDS, each keeping three writes in flight (pipelined): 1,968 coils of M
// (FC 15, overlapping the other clients': the largest write request there
// is), a block of K coils of its own (FC 15) and a block of D words of its
// own (FC 16), each with values derived from a counter.  A write answered
// exception 06 (busy: the scans do not keep up) was not applied; any other
// error fails.  Then each client reads its own blocks back: they must hold
// what its last acknowledged writes wrote (the last write per device wins,
// and a refused write left nothing behind).  ldrun runs with --watchdog
// (default 2 ms): a FAULT ends it with status 2 and fails the test.  With
// --idle, the same program idle afterwards for comparison.
#include <pthread.h>
#include <sched.h>
#include <sys/resource.h>
#include <sys/syscall.h>
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
#include <functional>
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

// ---- --burst

// Client `i` of `n`: its K coils and D words (echo.ld writes D0..D5: the
// blocks start at D8).
struct Blocks {
  uint32_t k_first, k_count, d_first, d_count;
  Blocks(int i, int n) {
    k_count = std::min<uint32_t>(1968, 8192 / uint32_t(n));
    k_first = uint32_t(i) * k_count;
    d_count = std::min<uint32_t>(61, (8192 - 8) / uint32_t(n));
    d_first = 8 + uint32_t(i) * d_count;
  }
};
bool k_value(uint32_t j, uint32_t k) { return (j * 7 + k) % 3 == 0; }
uint32_t d_value(int i, uint32_t j, uint32_t k) { return uint32_t(i) << 24 | (j & 0xFF) << 16 | (k & 0xFFFF); }

std::vector<uint8_t> fc15(uint32_t start, uint32_t count, const std::function<bool(uint32_t)>& on) {
  std::vector<uint8_t> p{15, uint8_t(start >> 8), uint8_t(start), uint8_t(count >> 8), uint8_t(count), uint8_t((count + 7) / 8)};
  p.resize(6 + (count + 7) / 8, 0);
  for (uint32_t j = 0; j < count; j++)
    if (on(j)) p[6 + j / 8] |= uint8_t(1u << (j % 8));
  return p;
}

struct BurstResult {
  uint64_t writes = 0, acked = 0, busy = 0;
  std::string error;
};

// Sends `pdus` pipelined (transaction ids tid+1...), then reads their replies
// in order: true for an echo, false for exception 06; sets `error` else.
bool pipelined(Client& c, const std::vector<std::vector<uint8_t>>& pdus, std::vector<bool>& ok, std::string& error) {
  std::vector<uint8_t> out;
  uint16_t first = uint16_t(c.tid + 1);
  for (const auto& pdu : pdus) {
    c.tid++;
    uint8_t f[7] = {uint8_t(c.tid >> 8), uint8_t(c.tid), 0, 0, uint8_t((pdu.size() + 1) >> 8), uint8_t(pdu.size() + 1), 1};
    out.insert(out.end(), f, f + 7);
    out.insert(out.end(), pdu.begin(), pdu.end());
  }
  if (send(c.fd, out.data(), out.size(), MSG_NOSIGNAL) != ssize_t(out.size())) return error = "send failed", false;
  ok.assign(pdus.size(), false);
  for (size_t n = 0; n < pdus.size(); n++) {
    uint8_t h[7];
    if (!c.read_n(h, 7)) return error = "no reply (timeout or closed)", false;
    if (uint16_t(h[0] << 8 | h[1]) != uint16_t(first + n)) return error = "wrong transaction identifier", false;
    std::vector<uint8_t> p(size_t(h[4] << 8 | h[5]) - 1);
    if (p.empty() || !c.read_n(p.data(), p.size())) return error = "short reply", false;
    if (p[0] == pdus[n][0] && p.size() == 5) ok[n] = true;
    else if (p[0] == (pdus[n][0] | 0x80) && p.size() == 2 && p[1] == 6) ok[n] = false;
    else return error = "reply " + std::to_string(p[0]) + "/" + std::to_string(p.size() > 1 ? p[1] : 0), false;
  }
  return true;
}

BurstResult burst_client(int port, int i, int n, Clock::time_point until) {
  setpriority(PRIO_PROCESS, pid_t(syscall(SYS_gettid)), 10);  // the load, not the PLC, gives way on a busy machine
  BurstResult r;
  Client c(port);
  if (!c.error.empty()) return r.error = c.error, r;
  Blocks b(i, n);
  uint32_t m_first = uint32_t(i * 613) % (8192 - 1968);
  int64_t k_acked = -1, d_acked = -1;  // the counter of the last acknowledged write, -1: none
  std::vector<bool> ok;
  for (uint32_t k = 0; Clock::now() < until; k++) {
    std::vector<uint8_t> load = fc15(8192 + m_first, 1968, [k](uint32_t j) { return (j + k) & 1; });
    std::vector<uint8_t> own_k = fc15(16384 + b.k_first, b.k_count, [k](uint32_t j) { return k_value(j, k); });
    std::vector<uint8_t> own_d{16, 0, 0, 0, uint8_t(2 * b.d_count), uint8_t(4 * b.d_count)};
    uint32_t reg = 1024 + 2 * b.d_first;
    own_d[1] = uint8_t(reg >> 8), own_d[2] = uint8_t(reg);
    for (uint32_t j = 0; j < b.d_count; j++) {
      uint32_t v = d_value(i, j, k);
      for (int s : {24, 16, 8, 0}) own_d.push_back(uint8_t(v >> s));
    }
    if (!pipelined(c, {load, own_k, own_d}, ok, r.error)) return r;
    r.writes += 3;
    for (bool a : ok) r.acked += a, r.busy += !a;
    if (ok[1]) k_acked = k;
    if (ok[2]) d_acked = k;
  }
  // Read back (the reply to the last write came after its scan was published).
  if (k_acked >= 0) {
    auto bits = c.call({1, uint8_t((16384 + b.k_first) >> 8), uint8_t(16384 + b.k_first), uint8_t(b.k_count >> 8), uint8_t(b.k_count)});
    if (bits.size() != 2 + (b.k_count + 7) / 8) return r.error = "K read back: " + c.error, r;
    for (uint32_t j = 0; j < b.k_count; j++)
      if (bool(bits[2 + j / 8] >> (j % 8) & 1) != k_value(j, uint32_t(k_acked)))
        return r.error = "K" + std::to_string(b.k_first + j) + " is not the last acknowledged write's (" + std::to_string(k_acked) + ")", r;
  }
  if (d_acked >= 0) {
    uint32_t reg = 1024 + 2 * b.d_first;
    auto regs = c.call({3, uint8_t(reg >> 8), uint8_t(reg), 0, uint8_t(2 * b.d_count)});
    if (regs.size() != 2 + 4 * b.d_count) return r.error = "D read back: " + c.error, r;
    for (uint32_t j = 0; j < b.d_count; j++) {
      uint32_t v = uint32_t(regs[2 + 4 * j]) << 24 | regs[3 + 4 * j] << 16 | regs[4 + 4 * j] << 8 | regs[5 + 4 * j];
      if (v != d_value(i, j, uint32_t(d_acked)))
        return r.error = "D" + std::to_string(b.d_first + j) + " = " + std::to_string(v) + ", not the last acknowledged write's (" +
                         std::to_string(d_value(i, j, uint32_t(d_acked))) + ")", r;
    }
  }
  return r;
}

std::string stats_of(const std::string& text);

// --modbus on a free port with room for every client: all come from
// 127.0.0.1, so the per-address cap is raised too (MODBUS_LOAD_OLD=1 leaves
// it out, for an ldrun that predates it).
void add_server_args(std::vector<std::string>& args, int clients) {
  for (const char* a : {"--modbus", "127.0.0.1:0", "--modbus-connections"}) args.push_back(a);
  args.push_back(std::to_string(clients + 2));
  if (std::getenv("MODBUS_LOAD_OLD")) return;
  args.push_back("--modbus-per-address");
  args.push_back(std::to_string(clients + 2));
}

// Whether this process may run a thread under SCHED_FIFO (what ldrun --rt asks for).
bool fifo_permitted() {
  bool ok = false;
  std::thread([&] {
    sched_param sp{};
    sp.sched_priority = 1;
    ok = pthread_setschedparam(pthread_self(), SCHED_FIFO, &sp) == 0;
  }).join();
  return ok;
}

int run_burst(const std::string& ldrun, const std::string& echo, double seconds, int clients, const std::string& period,
              std::string watchdog, bool rt, bool idle_too) {
  // The watchdog measures wall time: without a real-time scheduler, a task
  // preempted by anything else on a busy machine (other tests, other builds)
  // overruns 2 ms with no client at all.  So --rt; where SCHED_FIFO is not
  // permitted the watchdog is 20 ms, and the run says so.
  if (rt && !fifo_permitted()) {
    std::printf("note: SCHED_FIFO is not permitted here: --watchdog 20ms instead of %s (preemption, not clients, "
                "would trip it)\n", watchdog.c_str());
    watchdog = "20ms";
  }
  std::vector<std::string> args{ldrun, echo, "--io=none", "--period", period, "--watchdog", watchdog, "--stats"};
  add_server_args(args, clients);
  if (rt) args.push_back("--rt");
  std::vector<std::string> failures;
  Ldrun loaded(args);
  int port = loaded.port();
  if (!port) {
    loaded.finish(true);
    std::fprintf(stderr, "modbus_load: ldrun did not listen:\n%s", loaded.text.c_str());
    return 1;
  }
  auto t0 = Clock::now();
  auto until = t0 + std::chrono::milliseconds(int64_t(seconds * 1000));
  std::vector<BurstResult> res(static_cast<size_t>(clients));
  std::vector<std::thread> threads;
  for (int i = 0; i < clients; i++) threads.emplace_back([&, i] { res[size_t(i)] = burst_client(port, i, clients, until); });
  for (auto& t : threads) t.join();
  double secs = std::chrono::duration<double>(Clock::now() - t0).count();
  int st = loaded.finish(true);
  BurstResult sum;
  for (int i = 0; i < clients; i++) {
    const BurstResult& r = res[size_t(i)];
    sum.writes += r.writes, sum.acked += r.acked, sum.busy += r.busy;
    if (!r.error.empty()) failures.push_back("client " + std::to_string(i) + ": " + r.error);
  }
  if (st != 0) failures.push_back("ldrun under the burst exited with status " + std::to_string(st));
  if (loaded.text.find("watchdog") != std::string::npos) failures.push_back("the watchdog fired");
  std::printf("burst: %d clients for %.1f s: %llu writes (%.0f/s), %llu applied, %llu answered busy (06)\n", clients, secs,
              (unsigned long long)sum.writes, double(sum.writes) / secs, (unsigned long long)sum.acked,
              (unsigned long long)sum.busy);
  std::printf("ldrun --period %s --watchdog %s%s under the burst:\n%s", period.c_str(), watchdog.c_str(), rt ? " --rt" : "",
              stats_of(loaded.text).c_str());
  if (idle_too) {
    int64_t period_us = std::stoi(period) * (period.find("us") != std::string::npos ? 1 : 1000);
    int64_t scans = std::max<int64_t>(2000, int64_t(secs * 1e6) / period_us);
    args.push_back("--scans");
    args.push_back(std::to_string(scans));
    Ldrun idle(args);
    int ist = idle.finish(false);
    if (ist != 0) failures.push_back("ldrun idle exited with status " + std::to_string(ist));
    std::printf("ldrun --period %s%s idle, %lld scans:\n%s", period.c_str(), rt ? " --rt" : "", (long long)scans,
                stats_of(idle.text).c_str());
  }
  for (const auto& f : failures) std::printf("FAIL %s\n", f.c_str());
  if (!failures.empty()) std::printf("ldrun's stderr:\n%s", loaded.text.substr(0, 4000).c_str());
  std::printf("%s\n", failures.empty() ? "ok: no FAULT; every device holds its last acknowledged write" : "FAILED");
  return failures.empty() ? 0 : 1;
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
  std::string ldrun = argv[1], echo = argv[2], period = "1ms", watchdog = "2ms";
  int clients = 50, requests = 10000;
  bool rt = false, idle_too = false, clients_given = false;
  double burst = 0;
  for (int i = 3; i < argc; i++) {
    std::string a = argv[i];
    if (a == "--clients" && i + 1 < argc) clients = std::stoi(argv[++i]), clients_given = true;
    else if (a == "--burst" && i + 1 < argc) burst = std::stod(argv[++i]);
    else if (a == "--watchdog" && i + 1 < argc) watchdog = argv[++i];
    else if (a == "--idle") idle_too = true;
    else if (a == "--requests" && i + 1 < argc) requests = std::stoi(argv[++i]);
    else if (a == "--period" && i + 1 < argc) period = argv[++i];
    else if (a == "--rt") rt = true;
    else {
      std::fprintf(stderr, "modbus_load: unknown argument '%s'\n", a.c_str());
      return 2;
    }
  }
  if (burst > 0) return run_burst(ldrun, echo, burst, clients_given ? clients : 16, period, watchdog, rt, idle_too);
  std::vector<std::string> base{ldrun, echo, "--io=none", "--period", period, "--stats"};
  add_server_args(base, clients);
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
