// The soft-PLC runtime as real processes: online download during 10,000
// running scans, kill -9 during retentive saves, the shared-memory driver
// and its client, the watchdog.  No timing assertions beyond sanity bounds;
// the figures are printed (docs/runtime.md quotes them).
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <poll.h>
#include <unistd.h>

#include <chrono>
#include <cstring>
#include <fstream>
#include <random>
#include <sstream>
#include <thread>

#include "driver/c40_target.h"
#include "driver/driver.h"
#include "assembler/x86.h"
#include "driver/x86_target.h"
#include "runtime/plc.h"
#include "runtime/sandbox.h"
#include "tests/runtime/process_util.h"
#include "runtime/runtime.h"
#include "runtime/shm_layout.h"

extern "C" char** environ;

namespace ldc {
namespace {

using namespace std::chrono_literals;

std::string slurp(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::ostringstream ss;
  ss << f.rdbuf();
  return ss.str();
}
void spit(const std::string& path, const std::string& text) {
  std::ofstream f(path, std::ios::binary);
  f << text;
}
bool exists(const std::string& path) {
  struct stat st;
  return stat(path.c_str(), &st) == 0;
}

// A child process with its stdin (optionally) and stdout on pipes and its
// stderr in a file.
struct Proc {
  pid_t pid = -1;
  int in = -1, out = -1;
  std::string err_file, buf;

  static Proc spawn(const std::vector<std::string>& args, const std::string& err_file, bool pipe_in = true) {
    Proc p;
    p.err_file = err_file;
    int inp[2], outp[2];
    if (pipe(inp) != 0 || pipe(outp) != 0) throw std::runtime_error("pipe");
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    if (pipe_in) posix_spawn_file_actions_adddup2(&fa, inp[0], 0);
    else posix_spawn_file_actions_addopen(&fa, 0, "/dev/null", O_RDONLY, 0);
    posix_spawn_file_actions_adddup2(&fa, outp[1], 1);
    posix_spawn_file_actions_addopen(&fa, 2, err_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    for (int fd : {inp[0], inp[1], outp[0], outp[1]}) posix_spawn_file_actions_addclose(&fa, fd);
    std::vector<char*> argv;
    std::vector<std::string> copy = args;
    for (auto& a : copy) argv.push_back(a.data());
    argv.push_back(nullptr);
    int rc = posix_spawn(&p.pid, argv[0], &fa, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&fa);
    close(inp[0]);
    close(outp[1]);
    if (rc != 0) throw std::runtime_error("cannot run " + args[0] + ": " + std::strerror(rc));
    p.in = inp[1];
    p.out = outp[0];
    if (!pipe_in) close(p.in), p.in = -1;
    return p;
  }
  void send(const std::string& line) {
    std::string l = line + "\n";
    ASSERT_EQ(write(in, l.data(), l.size()), ssize_t(l.size()));
  }
  // The next line of stdout, or "" after timeout / end.
  std::string line(int timeout_ms = 20000) {
    auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
    while (true) {
      size_t nl = buf.find('\n');
      if (nl != std::string::npos) {
        std::string l = buf.substr(0, nl);
        buf.erase(0, nl + 1);
        return l;
      }
      int left = int(std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now()).count());
      if (left <= 0) return "";
      pollfd pf{out, POLLIN, 0};
      if (poll(&pf, 1, left) <= 0) continue;
      char tmp[4096];
      ssize_t n = read(out, tmp, sizeof tmp);
      if (n <= 0) return "";
      buf.append(tmp, size_t(n));
    }
  }
  std::string ask(const std::string& cmd) {
    send(cmd);
    return line();
  }
  // Waits for the exit; closes stdin first (end of input quits ldrun) unless keep_stdin.
  int wait(int timeout_ms = 30000, bool keep_stdin = false) {
    if (in >= 0 && !keep_stdin) close(in), in = -1;
    int st = test::wait_child(pid, std::chrono::milliseconds(timeout_ms));
    if (st < 0) return -1;
    if (out >= 0) close(out), out = -1;
    return WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
  }
  std::string err() const { return slurp(err_file); }
  ~Proc() {
    if (pid > 0) {
      ::kill(pid, SIGKILL);
      waitpid(pid, nullptr, 0);
    }
    if (in >= 0) close(in);
    if (out >= 0) close(out);
  }
  Proc() = default;
  Proc(Proc&& o) noexcept { *this = std::move(o); }
  Proc& operator=(Proc&& o) noexcept {
    std::swap(pid, o.pid), std::swap(in, o.in), std::swap(out, o.out);
    err_file = o.err_file, buf = o.buf;
    return *this;
  }
};

using test::TmpDir;

// Compiles a source text to an image file with ldc's own library.
Image compile_text(const TmpDir& d, const std::string& name, const std::string& text) {
  spit(d / name, text);
  Compiled c = compile_source(d / name);
  return make_x86_image(c.il, build_x86(c.il, d / name));
}
void write_image_file(const std::string& path, const Image& im) {
  std::vector<uint8_t> b = write_image(im);
  spit(path, std::string(b.begin(), b.end()));
}


// ---------------------------------------------------------------- online download

// The three versions of the swapped program: the same edge slots in the same
// order (E0 = rising edge of X0, E1 = counter C0's input); the new one adds E2.
// Each marks its version in WY0 (first rung) and WY1 (last rung): a scan that
// mixed two images would show two different marks.
std::string swap_program(int version) {
  std::string v = std::to_string(version);
  std::string s = "rung \"version mark, first rung\"\n|--(MOV " + v + " WY0)\n\n"
                  "rung \"count rising edges of X0\"\n|--[P X0]--(ADD D0 " + v + " D0)\n\n"
                  "rung \"timer and counter on X1\"\n|--[X1]--+--(TON T0 3ms)\n|        +--(CTU C0 100000)\n\n";
  if (version == 2) s += "rung \"accumulate WX0 (new: subtract)\"\n|--(SUB D1 WX0 D1)\n\n"
                         "rung \"falling edges of X1 (new)\"\n|--[N X1]--(ADD D2 1 D2)\n\n";
  else s += "rung \"accumulate WX0\"\n|--(ADD D1 WX0 D1)\n\n";
  s += "rung \"outputs\"\n|--(MOV D0 WY2)\n|--(MOV D1 WY3)\n|--(MOV D2 WY4)\n|--[T0]--(Y0)\n\n"
       "rung \"version mark, last rung\"\n|--(MOV " + v + " WY1)\n";
  return s;
}

// Runs old for scans < at1, new for at1 <= scan < at2, old again after.
class SwitchingEngine : public Engine {
 public:
  SwitchingEngine(Engine& a, Engine& b, uint64_t at1, uint64_t at2) : a_(a), b_(b), at1_(at1), at2_(at2) {}
  void scan(ImageBytes& mem_bytes) override {
    n_++;
    (n_ >= at1_ && n_ < at2_ ? b_ : a_).scan(mem_bytes);
  }

 private:
  Engine &a_, &b_;
  uint64_t at1_, at2_, n_ = 0;
};

uint64_t scan_of(const std::string& reply) {
  size_t at = reply.find("switched at scan ");
  return at == std::string::npos ? 0 : std::stoull(reply.substr(at + 17));
}

TEST(OnlineDownload, SwapsDuringTenThousandScansWithNoMixedScan) {
  TmpDir d;
  Image v1 = compile_text(d, "v1.ld", swap_program(1)), v2 = compile_text(d, "v2.ld", swap_program(2));
  write_image_file(d / "v1.bin", v1);
  write_image_file(d / "v2.bin", v2);
  const int kScans = 10000;
  std::string csv = "X0,X1,WX0\n";
  for (int k = 1; k <= kScans; k++)
    csv += std::to_string((k / 7) % 2) + "," + std::to_string((k / 29) % 2) + "," + std::to_string(k % 100 - 50) + "\n";
  spit(d / "in.csv", csv);
  const std::string watch = "WY0,WY1,WY2,WY3,WY4,T0,C0,Y0";
  // 10,000 scans paced at 200 us with the virtual clock (dt = the period):
  // about 2 s, deterministic, and the loads land while it runs.
  Proc p = Proc::spawn({LDRUN, d / "v1.bin", "--io=trace", "--trace", d / "in.csv", "--watch", watch, "--clock=virtual",
                        "--period", "200us", "--control=stdin", "--out", d / "run.csv"},
                       d / "err");
  ASSERT_EQ(p.ask("wait 100"), "ok") << p.err();  // running (however slow the start)
  std::this_thread::sleep_for(400ms);
  std::string r1 = p.ask("load " + d / "v2.bin");
  std::this_thread::sleep_for(400ms);
  std::string r2 = p.ask("load " + d / "v1.bin");
  ASSERT_EQ(p.wait(30000, true), 0) << p.err();  // it ends after the trace's 10,000 scans
  std::printf("first switch:  %s\nsecond switch: %s\n", r1.c_str(), r2.c_str());
  ASSERT_EQ(r1.rfind("ok task main switched at scan ", 0), 0u) << r1 << "\n" << p.err();
  ASSERT_EQ(r2.rfind("ok task main switched at scan ", 0), 0u) << r2;
  uint64_t at1 = scan_of(r1), at2 = scan_of(r2);
  ASSERT_GT(at1, 100u);
  ASSERT_GT(at2, at1);
  ASSERT_LE(at2, uint64_t(kScans)) << "the run ended before the second load";

  // Zero mixed scans: both marks of every row are the same version, and the
  // version changes exactly at the reported scans.
  std::string run = slurp(d / "run.csv");
  std::istringstream rows(run);
  std::string line;
  std::getline(rows, line);
  EXPECT_EQ(line, "scan," + watch);
  uint64_t n = 0, mixed = 0, wrong = 0;
  while (std::getline(rows, line)) {
    n++;
    std::istringstream cells(line);
    std::string scan, wy0, wy1;
    std::getline(cells, scan, ','), std::getline(cells, wy0, ','), std::getline(cells, wy1, ',');
    if (wy0 != wy1) mixed++;
    std::string want = n >= at1 && n < at2 ? "2" : "1";
    if (wy0 != want) wrong++;
  }
  EXPECT_EQ(n, uint64_t(kScans));
  EXPECT_EQ(mixed, 0u);
  EXPECT_EQ(wrong, 0u);

  // Identical to running the new image from the switch on, with the memory
  // (timers, counters, edges, data words) carried over.
  std::unique_ptr<Engine> e1 = make_native_engine(map_checked_code(v1.code, v1.entry, v1.layout)),
                          e2 = make_native_engine(map_checked_code(v2.code, v2.entry, v2.layout));
  SwitchingEngine sw(*e1, *e2, at1, at2);
  RunOptions ro;
  ro.period_ms = 0;  // 200 us periods on the virtual clock: dt 0,0,0,0,1,... (carried)
  for (const char* w : {"WY0", "WY1", "WY2", "WY3", "WY4", "T0", "C0", "Y0"}) ro.watch.push_back(resolve_probe(w, {}));
  // run_trace keeps dt constant, so feed the carried dt through a dt column.
  std::string csv_dt = "X0,X1,WX0,dt\n";
  {
    std::istringstream in(csv);
    std::string l;
    std::getline(in, l);
    int64_t carry = 0;
    for (int k = 1; k <= kScans && std::getline(in, l); k++) {
      carry += 200;
      int64_t dt = carry / 1000;
      carry -= dt * 1000;
      csv_dt += l + "," + std::to_string(dt) + "\n";
    }
  }
  Trace tr_dt = read_trace(csv_dt, "in.csv", {});
  std::string want;
  run_trace(sw, v2.layout.size > v1.layout.size ? v2.layout : v1.layout, &tr_dt, "in.csv", ro, want);
  if (run != want) {
    size_t at = 0;
    while (at < run.size() && at < want.size() && run[at] == want[at]) at++;
    size_t line_start = run.rfind('\n', at);
    line_start = line_start == std::string::npos ? 0 : line_start + 1;
    ADD_FAILURE() << "the run differs from the reference at byte " << at << ":\n  run:       "
                  << run.substr(line_start, run.find('\n', at) - line_start) << "\n  reference: "
                  << want.substr(line_start, want.find('\n', at) - line_start);
  }
}

TEST(OnlineDownload, AMovedEdgeStartsNewAndACorruptImageIsRefused) {
  TmpDir d;
  write_image_file(d / "v1.bin", compile_text(d, "v1.ld", swap_program(1)));
  // Edge slot E0 now remembers X3 instead of X0: identities, not slot
  // numbers, are carried (runtime/online_carry.h), so X0's edge is dropped
  // and X3's starts new; everything else (the same rungs) is carried.
  std::string moved = swap_program(1);
  moved.replace(moved.find("[P X0]"), 6, "[P X3]");
  write_image_file(d / "edge.bin", compile_text(d, "edge.ld", moved));
  write_image_file(d / "garbage.bin", compile_text(d, "g.ld", "|--(Y0)\n"));
  {
    std::string bytes = slurp(d / "garbage.bin");
    bytes[bytes.size() / 2] ^= 0x55;
    spit(d / "garbage.bin", bytes);
  }
  Proc p = Proc::spawn({LDRUN, d / "v1.bin", "--io=stdio", "--period", "1ms"}, d / "err");
  EXPECT_EQ(p.ask("wait 3"), "ok");
  std::string e = p.ask("load " + d / "edge.bin");
  EXPECT_EQ(e.rfind("ok task main switched at scan ", 0), 0u) << e;
  // Slots of swap_program(1): [P X0] E0 (line 5), CTU C0 E1 (line 8); C0's rung is unchanged.
  EXPECT_NE(e.find("carried 1 edge slot and 0 variables, devices by address; new: edge [P X3] (line 5); dropped: edge [P X0] (line 5)"),
            std::string::npos)
      << e;
  std::string g = p.ask("load " + d / "garbage.bin");
  EXPECT_EQ(g.rfind("error: " + d / "garbage.bin" + ": error:", 0), 0u) << g;
  EXPECT_EQ(p.ask("get WY0"), "WY0 = 1");
  EXPECT_EQ(p.ask("wait 2"), "ok");
  EXPECT_EQ(p.ask("quit"), "ok bye");
  EXPECT_EQ(p.wait(), 0) << p.err();
}

// ldrun --strict: every load that would reset a variable is refused, the
// task keeps running and keeps the value; without --strict the same load is
// accepted and says what it reset.
TEST(OnlineDownload, StrictRefusesAResetAndTheReplySaysWhatWasReset) {
  TmpDir d;
  spit(d / "v1.ld", "alias x = D0 : INT\n|--[P X0]--(ADD x 1 x)\n");
  spit(d / "v2.ld", "alias x = D0 : DINT\n|--[P X0]--(ADD x 1 x)\n");
  for (bool strict : {true, false}) {
    std::vector<std::string> args = {LDRUN, d / "v1.ld", "--io=stdio", "--period", "1ms"};
    if (strict) args.push_back("--strict");
    Proc p = Proc::spawn(args, d / "err");
    EXPECT_EQ(p.ask("set x 41"), "ok");
    EXPECT_EQ(p.ask("wait 2"), "ok");
    std::string r = p.ask("load " + d / "v2.ld");
    if (strict) {
      EXPECT_NE(r.find("error: " + d / "v2.ld" + ": refused for task 'main': --strict: it would reset x (INT in D -> DINT in D: initial value)"),
                std::string::npos) << r;
      EXPECT_EQ(p.ask("get x"), "x = 41");
    } else {
      EXPECT_NE(r.find("; carried 1 edge slot and 0 variables, devices by address; reset: x (INT in D -> DINT in D: initial value)"),
                std::string::npos) << r;
      EXPECT_EQ(p.ask("get x"), "x = 0");
    }
    EXPECT_EQ(p.ask("quit"), "ok bye");
    EXPECT_EQ(p.wait(), 0) << p.err();
  }
}

TEST(OnlineDownload, ReloadsAWatchedProgramFile) {
  TmpDir d;
  spit(d / "p.ld", "|--[X0]--(Y0)\n");
  Proc p = Proc::spawn({LDRUN, d / "p.ld", "--io=stdio", "--period", "1ms", "--reload"}, d / "err");
  EXPECT_EQ(p.ask("set X0 1"), "ok");
  EXPECT_EQ(p.ask("wait 3"), "ok");
  EXPECT_EQ(p.ask("get Y0"), "Y0 = 1");
  EXPECT_EQ(p.ask("get Y1"), "Y1 = 0");
  std::this_thread::sleep_for(50ms);
  spit(d / "p.ld.new", "|--[X0]--+--(Y0)\n|        +--(Y1)\n");
  ASSERT_EQ(rename((d / "p.ld.new").c_str(), (d / "p.ld").c_str()), 0);
  std::string y1;
  for (int i = 0; i < 100 && y1 != "Y1 = 1"; i++) {
    std::this_thread::sleep_for(50ms);
    y1 = p.ask("get Y1");
  }
  EXPECT_EQ(y1, "Y1 = 1") << p.err();
  EXPECT_EQ(p.ask("quit"), "ok bye");
  EXPECT_EQ(p.wait(), 0);
  EXPECT_NE(p.err().find("ldrun: reloaded " + d / "p.ld" + ": task main switched at scan"), std::string::npos) << p.err();
}

// ---------------------------------------------------------------- retentive memory

// The sequence number of the retentive file's last save, 0 if none (yet).
uint64_t saved_sequence(const std::string& file) {
  std::string b = slurp(file);
  try {
    return plc::decode_retain(std::vector<uint8_t>(b.begin(), b.end()), file).sequence;
  } catch (std::exception&) {
    return 0;
  }
}

TEST(Retentive, KillNineDuringSavesRestartsFromACompleteState) {
  TmpDir d;
  Image im = compile_text(d, "count.ld",
                          "rung \"count scans in a retentive word\"\n|--(ADD D0 1 D0)\n\n"
                          "rung \"K0 toggles every scan, K1 follows it\"\n|--[/K0]--(K0)\n\n|--[K0]--(K1)\n\n"
                          "rung \"a second copy of the count\"\n|--(MOV D0 D1)\n");
  im.retentive = {{Area::K, 0, 8192}, {Area::D, 0, 4}};
  write_image_file(d / "count.bin", im);
  const std::string ret = d / "state.ret";
  std::mt19937 rng(20260101);
  long prev = 0;
  int kills = 0, tmp_left = 0;
  for (int iter = 0; iter < 8; iter++) {
    Proc p = Proc::spawn({LDRUN, d / "count.bin", "--io=none", "--period", "200us", "--retain", ret, "--retain-every", "1ms",
                          "--watchdog", "0"},
                         d / "err", false);
    // Once this run has saved (its sequence passed the file's), kill it at
    // a random moment: saves every 1 ms are nearly always under way.
    uint64_t before = saved_sequence(ret);
    for (int i = 0; i < 1000 && saved_sequence(ret) <= before; i++) std::this_thread::sleep_for(10ms);
    ASSERT_GT(saved_sequence(ret), before) << p.err();
    std::this_thread::sleep_for(std::chrono::milliseconds(20 + rng() % 150));
    ::kill(p.pid, SIGKILL);
    EXPECT_EQ(p.wait(), 128 + SIGKILL);
    kills++;
    if (exists(ret + ".tmp")) tmp_left++;
    // Restart stopped and read the state back.
    Proc q = Proc::spawn({LDRUN, d / "count.bin", "--io=stdio", "--stop", "--retain", ret}, d / "err2");
    std::string d0 = q.ask("get D0"), d1 = q.ask("get D1"), k0 = q.ask("get K0"), k1 = q.ask("get K1");
    EXPECT_EQ(q.ask("quit"), "ok bye");
    ASSERT_EQ(q.wait(), 0) << q.err();
    ASSERT_EQ(d0.rfind("D0 = ", 0), 0u) << d0 << q.err();
    long v0 = std::stol(d0.substr(5)), v1 = std::stol(d1.substr(5));
    int b0 = k0.back() - '0', b1 = k1.back() - '0';
    EXPECT_EQ(v0, v1) << "torn state: D0 and D1 differ";
    EXPECT_EQ(b0, b1) << "torn state: K0 and K1 differ";
    EXPECT_EQ(b0, int(v0 % 2)) << "torn state: K0 does not match D0";
    EXPECT_GE(v0, prev) << "went back to an older state than the last restart";
    EXPECT_GT(v0, 0) << q.err();
    EXPECT_NE(q.err().find("retentive memory restored"), std::string::npos) << q.err();
    prev = v0;
  }
  std::printf("%d kill -9 during saves, %d left a temporary file behind; last count %ld\n", kills, tmp_left, prev);

  // A corrupt file is refused; --cold starts with cleared retentive memory.
  std::string bytes = slurp(ret);
  bytes[bytes.size() / 2] ^= 0x10;
  spit(ret, bytes);
  Proc r = Proc::spawn({LDRUN, d / "count.bin", "--io=none", "--retain", ret, "--scans", "5"}, d / "err3", false);
  EXPECT_EQ(r.wait(), 1);
  EXPECT_NE(r.err().find(ret + ": error: retentive file is corrupt: checksum"), std::string::npos) << r.err();
  EXPECT_NE(r.err().find("refusing to start (--cold starts with cleared retentive memory)"), std::string::npos) << r.err();
  Proc c = Proc::spawn({LDRUN, d / "count.bin", "--io=stdio", "--retain", ret, "--cold", "--stop"}, d / "err4");
  EXPECT_EQ(c.ask("get D0"), "D0 = 0");
  EXPECT_EQ(c.ask("run"), "ok RUN");
  EXPECT_EQ(c.ask("wait 5"), "ok");
  EXPECT_EQ(c.ask("stop"), "ok STOP");  // saves
  EXPECT_EQ(c.ask("quit"), "ok bye");
  EXPECT_EQ(c.wait(), 0) << c.err();
  bytes = slurp(ret);
  plc::RetainSnapshot s = plc::decode_retain(std::vector<uint8_t>(bytes.begin(), bytes.end()), ret);
  EXPECT_GE(s.records.size(), 2u);
}

// An LDmicro PERSIST variable (docs/ldmicro.md): its D word is listed in the
// image's retentive section and survives a restart with --retain; the other
// counter starts again from 0.
TEST(Retentive, LdmicroPersistVariableSurvivesARestart) {
  TmpDir d;
  Image im = compile_text(d, "persist.ld",
                          "LDmicro0.2\nCYCLE=10000 us\nPROGRAM\nRUNG 1\n  ADD kept kept 1\n  ADD lost lost 1\nEND\n"
                          "RUNG 2\n  PERSIST kept\nEND\n");
  std::vector<RetentiveRange> want = {{Area::K, 0, 8192}, {Area::D, 0, 1}};
  EXPECT_EQ(im.retentive, want);
  Compiled c = compile_source(d / "persist.ld");  // the C40 image lists it too, and both read back
  EXPECT_EQ(read_image(write_image(make_c40_image(c.il, build_c40(c.il, d / "persist.ld"))), "c40.bin").retentive, want);
  EXPECT_EQ(read_image(write_image(im), "x86.bin").retentive, want);
  write_image_file(d / "persist.bin", im);
  const std::string ret = d / "state.ret";
  Proc p = Proc::spawn({LDRUN, d / "persist.bin", "--io=stdio", "--stop", "--retain", ret}, d / "err");
  EXPECT_EQ(p.ask("run"), "ok RUN");
  EXPECT_EQ(p.ask("wait 5"), "ok");
  EXPECT_EQ(p.ask("stop"), "ok STOP");  // saves
  std::string kept = p.ask("get kept"), lost = p.ask("get lost");
  EXPECT_EQ(p.ask("quit"), "ok bye");
  ASSERT_EQ(p.wait(), 0) << p.err();
  ASSERT_EQ(kept.rfind("kept = ", 0), 0u) << kept;
  EXPECT_GE(std::stol(kept.substr(7)), 5) << kept;
  EXPECT_EQ(kept.substr(7), lost.substr(7));  // both counted the same scans
  Proc q = Proc::spawn({LDRUN, d / "persist.bin", "--io=stdio", "--stop", "--retain", ret}, d / "err2");
  EXPECT_EQ(q.ask("get kept"), kept);
  EXPECT_EQ(q.ask("get lost"), "lost = 0");
  EXPECT_EQ(q.ask("quit"), "ok bye");
  ASSERT_EQ(q.wait(), 0) << q.err();
  EXPECT_NE(q.err().find("retentive memory restored"), std::string::npos) << q.err();
}

// ---------------------------------------------------------------- shared memory

TEST(SharedMemory, ClientWritesInputsAndReadsOutputsWithoutTornUpdates) {
  TmpDir d;
  std::string prog = "|--[X5]--(Y5)\n\n|--[/X6]--(Y6)\n\n";
  for (int i = 0; i < 16; i++) prog += "|--(MOV WX" + std::to_string(i) + " WY" + std::to_string(i) + ")\n\n";
  write_image_file(d / "copy.bin", compile_text(d, "copy.ld", prog));
  std::string name = "/ldc-test-" + std::to_string(getpid());
  Proc p = Proc::spawn({LDRUN, d / "copy.bin", "--io=shm:" + name, "--period", "500us"}, d / "err", false);
  // Wait for the segment.
  int fd = -1;
  for (int i = 0; i < 500 && fd < 0; i++) {
    fd = shm_open(name.c_str(), O_RDWR, 0);
    if (fd < 0) std::this_thread::sleep_for(10ms);
  }
  ASSERT_GE(fd, 0) << p.err();
  void* m = mmap(nullptr, shm::kTotalSize, PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
  close(fd);
  ASSERT_NE(m, MAP_FAILED);
  auto* h = static_cast<shm::Header*>(m);
  for (int i = 0; i < 500 && *shm::check(h, shm::kTotalSize); i++) std::this_thread::sleep_for(10ms);
  ASSERT_STREQ(shm::check(h, shm::kTotalSize), "");

  auto client = [&](std::vector<std::string> args) {
    args.insert(args.begin(), {SHM_CLIENT, "--name", name});
    Proc c = Proc::spawn(args, d / "client.err", false);
    std::string out = c.line(10000);
    int rc = c.wait();
    return std::to_string(rc) + ":" + out;
  };
  EXPECT_EQ(client({"set", "X5", "1"}), "0:");
  EXPECT_EQ(client({"wait", "Y5", "1", "5000"}), "0:Y5 1");
  EXPECT_EQ(client({"set", "X5", "0", "WX3", "1234"}), "0:");
  EXPECT_EQ(client({"wait", "Y5", "0", "5000"}), "0:Y5 0");
  EXPECT_EQ(client({"wait", "WY3", "1234", "5000"}), "0:WY3 1234");
  EXPECT_NE(client({"status"}).find("state RUN"), std::string::npos);
  EXPECT_EQ(client({"set", "Y3", "1"}).substr(0, 2), "1:");  // not an input

  EXPECT_EQ(client({"set", "WX3", "0"}), "0:");
  EXPECT_EQ(client({"wait", "WY3", "0", "5000"}), "0:WY3 0");

  // An input byte of 2 (a client writing its own encoding) is the input on:
  // the normally closed contact on X6 opens (read as it lies, the NC contact's
  // `xor 1` left it closed, and the bit stack took a stray bit)
  EXPECT_EQ(client({"wait", "Y6", "1", "5000"}), "0:Y6 1");
  {
    ASSERT_TRUE(shm::lock_inputs(h, int32_t(getpid())));
    shm::begin_write(h->in_seq);
    shm::base(h)[shm::kXOffset + 6] = 2;
    shm::end_write(h->in_seq);
    shm::unlock_inputs(h, int32_t(getpid()));
  }
  EXPECT_EQ(client({"wait", "Y6", "0", "5000"}), "0:Y6 0");

  // Torn-update stress: a writer sets WX0..WX15 to one value per update; the
  // program copies them to WY0..WY15; every snapshot a reader takes must
  // show sixteen equal words.
  std::atomic<bool> stop{false};
  std::atomic<uint64_t> updates{0};
  std::thread writer([&] {
    int32_t me = int32_t(getpid());
    uint8_t* b = shm::base(h);
    for (int32_t v = 1; !stop.load(); v++) {
      ASSERT_TRUE(shm::lock_inputs(h, me));
      shm::begin_write(h->in_seq);
      for (int i = 0; i < 16; i++) shm::store32(b + shm::kWXOffset + 4 * i, v);
      shm::end_write(h->in_seq);
      shm::unlock_inputs(h, me);
      updates++;
      std::this_thread::sleep_for(20us);  // a busy field bus, not a livelock
    }
  });
  uint64_t snapshots = 0, torn = 0, changes = 0;
  int32_t last = 0;
  auto until = std::chrono::steady_clock::now() + 1500ms;
  uint8_t* b = shm::base(h);
  while (std::chrono::steady_clock::now() < until) {
    int32_t w[16];
    uint32_t v;
    if (!shm::begin_read(h->out_seq, v)) continue;
    for (int i = 0; i < 16; i++) w[i] = shm::load32(b + shm::kWYOffset + 4 * i);
    if (!shm::end_read(h->out_seq, v)) continue;
    snapshots++;
    for (int i = 1; i < 16; i++)
      if (w[i] != w[0]) {
        if (!torn) {
          std::string t;
          for (int j = 0; j < 16; j++) t += " " + std::to_string(w[j]);
          std::printf("first torn snapshot:%s\n", t.c_str());
        }
        torn++;
        break;
      }
    if (w[0] != last) changes++, last = w[0];
  }
  stop = true;
  writer.join();
  std::printf("%llu input updates, %llu output snapshots, %llu distinct, %llu torn\n", (unsigned long long)updates.load(),
              (unsigned long long)snapshots, (unsigned long long)changes, (unsigned long long)torn);
  EXPECT_EQ(torn, 0u);
  EXPECT_GT(changes, 100u);
  munmap(m, shm::kTotalSize);

  ::kill(p.pid, SIGTERM);
  EXPECT_EQ(p.wait(), 0) << p.err();
  EXPECT_LT(shm_open(name.c_str(), O_RDONLY, 0), 0) << "the segment outlived ldrun";
}

// ---------------------------------------------------------------- watchdog

std::string slow_program() {
  // About 4000 REAL function calls: tens of microseconds per scan.
  std::string s = "rung \"outputs on\"\n|--(Y0)\n|--(MOV 77 WY3)\n\n";
  for (int i = 0; i < 1000; i++) s += "|--(SIN F0 F1)\n|--(COS F1 F2)\n|--(EXP F2 F3)\n|--(LN F3 F0)\n\n";
  return s;
}

TEST(Watchdog, ASlowScanStopsTheRuntimeAndDrivesOutputsSafe) {
  TmpDir d;
  write_image_file(d / "slow.bin", compile_text(d, "slow.ld", slow_program()));
  // Without the line protocol a watchdog fault ends the run: exit status 2.
  Proc a = Proc::spawn({LDRUN, d / "slow.bin", "--io=none", "--period", "10ms", "--watchdog", "2us"}, d / "err", false);
  EXPECT_EQ(a.wait(), 2) << a.err();
  // The scan thread (\"scan 1 took\") or the monitor (\"has been in its
  // scan for\") may see the overrun first; either way it is task main's.
  EXPECT_NE(a.err().find("ldrun: watchdog: task 'main' "), std::string::npos) << a.err();
  EXPECT_NE(a.err().find("limit 2.0 us; outputs driven to the safe state (all Y off, WY 0); the runtime is in FAULT"),
            std::string::npos)
      << a.err();
  // With it, the runtime stays up in FAULT with the outputs off.
  Proc b = Proc::spawn({LDRUN, d / "slow.bin", "--io=stdio", "--period", "10ms", "--watchdog", "2us", "--stop"}, d / "err2");
  EXPECT_EQ(b.ask("get Y0"), "Y0 = 0");
  EXPECT_EQ(b.ask("run"), "ok RUN");
  EXPECT_EQ(b.ask("wait 1"), "ok");
  std::string st = b.ask("status");
  EXPECT_EQ(st.rfind("state FAULT", 0), 0u) << st;
  EXPECT_EQ(b.ask("get Y0"), "Y0 = 0");
  EXPECT_EQ(b.ask("get WY3"), "WY3 = 0");
  EXPECT_EQ(b.ask("quit"), "ok bye");
  EXPECT_EQ(b.wait(), 0) << b.err();
  // A generous limit: the same program runs and its outputs are on; a
  // period shorter than the scan counts overruns but is no fault.
  Proc c = Proc::spawn({LDRUN, d / "slow.bin", "--io=stdio", "--period", "50us", "--watchdog", "1s"}, d / "err3");
  EXPECT_EQ(c.ask("wait 20"), "ok");
  EXPECT_EQ(c.ask("get Y0"), "Y0 = 1");
  EXPECT_EQ(c.ask("get WY3"), "WY3 = 77");
  st = c.ask("status");
  EXPECT_EQ(st.rfind("state RUN", 0), 0u) << st;
  std::printf("%s\n", st.c_str());
  EXPECT_EQ(c.ask("quit"), "ok bye");
  EXPECT_EQ(c.wait(), 0) << c.err();
}

// A scan that ends in an exception (the sandbox stopped its child) faults the
// runtime like the watchdog does: outputs safe, the reason named, no crash.
struct Segfault : Engine {
  volatile uintptr_t where = 0x10;
  void scan(ImageBytes& m_bytes) override {
    uint8_t* m = m_bytes.data();
    m[Layout::standard(0).addr(Area::Y, 0)] = 1;
    *reinterpret_cast<volatile int*>(where) = 1;
  }
};

TEST(Sandbox, AScanStoppedInTheSandboxFaultsTheRuntime) {
  TmpDir d;
  plc::TaskSpec s;
  s.name = "main", s.program = "on", s.file = d / "on.ld", s.period_us = 1000;
  s.image = compile_text(d, "on.ld", "|--(Y0)\n|--(MOV 5 WY0)\n");
  std::vector<plc::TaskSpec> specs;
  specs.push_back(std::move(s));
  plc::Options opt;
  opt.clock = plc::Options::Clock::Virtual, opt.free_run = true, opt.scans = 50;
  std::vector<std::string> logged;
  opt.log = [&](const std::string& m) { logged.push_back(m); };
  int built = 0;
  auto engines = [&](const Image& img) -> std::unique_ptr<Engine> {
    // the first build runs the image's own code; the failing one replaces it
    if (built++ == 0) return make_sandboxed_engine(make_native_engine(map_checked_code(img.code, img.entry, img.layout)), img.layout);
    return make_sandboxed_engine(std::make_unique<Segfault>(), img.layout);
  };
  plc::Runtime ok(std::vector<plc::TaskSpec>(specs), opt, engines, plc::make_null_driver());
  ok.start();
  ASSERT_TRUE(ok.wait_finished(10000));
  EXPECT_FALSE(ok.faulted()) << ok.fault_message();
  EXPECT_EQ(ok.get("Y0"), "1");
  EXPECT_EQ(ok.get("WY0"), "5");
  ok.shutdown();

  plc::Runtime bad(std::move(specs), opt, engines, plc::make_null_driver());
  bad.start();
  ASSERT_TRUE(bad.wait_finished(10000));
  ASSERT_TRUE(bad.faulted());
  std::string m = bad.fault_message();
  EXPECT_NE(m.find("ldrun: task 'main' scan 1 failed: the sandboxed scan was stopped by Segmentation fault at address 0x10"),
            std::string::npos) << m;
  EXPECT_NE(m.find("outputs driven to the safe state"), std::string::npos) << m;
  EXPECT_EQ(bad.get("Y0"), "0");
  EXPECT_EQ(bad.get("WY0"), "0");
  bad.shutdown();
  ASSERT_FALSE(logged.empty());
  EXPECT_EQ(logged.back(), m);
}

// A scan whose array index leaves its bounds ends there (docs/il.md, "Index
// faults"): the runtime publishes nothing of it and stops in FAULT with the
// outputs safe, naming the index, its bounds and the source line.
TEST(ScanFault, AnIndexOutOfItsBoundsStopsThePlcWithOutputsSafe) {
  TmpDir d;
  plc::TaskSpec s;
  s.name = "main", s.program = "idx", s.file = d / "idx.il", s.period_us = 1000;
  s.image = compile_text(d, "idx.il", ".rung line 1 \"POU main\"\nTRUE\nADD.DINT D9 1 D9\nIDX.DINT D9 1 10\n"
                                      "LDX.INT D20 1 D16\nOUT Y0\nMOVE.INT 5 WY0\n.end\n");  // run by the interpreter below
  std::vector<plc::TaskSpec> specs;
  specs.push_back(std::move(s));
  plc::Options opt;
  opt.clock = plc::Options::Clock::Virtual, opt.free_run = true, opt.scans = 50;
  auto engines = [&](const Image& img) -> std::unique_ptr<Engine> { return make_interp_engine(img.il, img.layout); };
  plc::Runtime rt(std::move(specs), opt, engines, plc::make_null_driver());
  rt.start();
  ASSERT_TRUE(rt.wait_finished(10000));
  ASSERT_TRUE(rt.faulted());
  std::string m = rt.fault_message();
  // D9 counts 1, 2, ... from its first scan: 11 on the 11th, outside 1..10 (IDX on line 4)
  EXPECT_NE(m.find("ldrun: task 'main' scan 11: index 11 outside 1..10 at "), std::string::npos) << m;
  EXPECT_NE(m.find("idx.il:4 (rung 1 \"POU main\"); outputs driven to the safe state"), std::string::npos) << m;
  EXPECT_EQ(rt.get("Y0"), "0");
  EXPECT_EQ(rt.get("WY0"), "0");
  EXPECT_EQ(rt.get("D9"), "11");  // memory as the fault left it, for the diagnosis
  rt.shutdown();
}

// Native code of any size runs from its own mapping: code of 256 KiB and more
// goes on 2 MiB-aligned memory with MADV_HUGEPAGE (one iTLB entry for the
// whole program where the kernel grants it; docs/runtime.md), the rest on
// ordinary pages.  Each body is the -O0 frame around `add dword ptr [rbx+0x8],
// 1` (83 43 18 01: Sys+24, a reserved word nothing else writes) repeated, padded
// with nops to the size: a copy cut short or misplaced counts wrong or faults.
TEST(NativeEngine, CodeOfEverySizeRunsWhole) {
  const Layout L = Layout::standard(0);
  auto put = [](std::vector<uint8_t>& code, const as::x86::Instruction& in) {
    std::vector<uint8_t> b = as::x86::encode_at(in, code.size());
    code.insert(code.end(), b.begin(), b.end());
  };
  size_t frame = 0;
  for (auto seq : {as::x86::scan_prologue(false), as::x86::scan_epilogue(false)})
    for (const auto& in : seq) frame += as::x86::encode_at(in).size();
  // sizes around the huge-page threshold (kHuge / 8 = 256 KiB) and 2 MiB boundaries
  for (size_t size : {size_t(64), size_t(90001), size_t(262143), size_t(262144), size_t(2097153), size_t(4194304)}) {
    const size_t reps = (size - frame) / 4, pad = (size - frame) % 4;
    std::vector<uint8_t> code;
    code.reserve(size);
    for (const auto& in : as::x86::scan_prologue(false)) put(code, in);
    for (size_t i = 0; i < reps; i++) code.insert(code.end(), {0x83, 0x43, 0x18, 0x01});
    code.insert(code.end(), pad, 0x90);
    for (const auto& in : as::x86::scan_epilogue(false)) put(code, in);
    ASSERT_EQ(code.size(), size);
    std::unique_ptr<Engine> e = make_native_engine(map_checked_code(code, 0, L));
    Memory m(L);
    e->scan(m.bytes);
    e->scan(m.bytes);
    uint32_t count, next;
    std::memcpy(&count, m.data() + 24, 4), std::memcpy(&next, m.data() + 28, 4);
    EXPECT_EQ(count, uint32_t(2 * reps)) << code.size() << " bytes of code";
    EXPECT_EQ(next, 0u);
  }
}

// A trace column of a typed alias takes values of its type only (docs/il.md):
// an INT's range, an unsigned UDINT, a LINT past 32 bits, hex; never octal.
TEST(TypedTrace, ColumnsTakeTheirTypesValues) {
  std::vector<Alias> aliases = {{"small", {Dev::D, 0}, Ty::INT}, {"u", {Dev::D, 1}, Ty::UDINT}, {"big", {Dev::D, 2}, Ty::LINT}};
  auto error = [&](const std::string& csv) -> std::string {
    try {
      read_trace(csv, "in.csv", aliases);
    } catch (std::exception& e) {
      return e.what();
    }
    return "accepted";
  };
  EXPECT_EQ(error("small,u,big\n-32768,4294967295,-9223372036854775808\n0x7fff,0,9223372036854775807\n"), "accepted");
  EXPECT_EQ(error("small,u,big\n32768,,\n"), "in.csv:2:1: error: value out of the INT range: '32768' for small");
  EXPECT_EQ(error("small,u,big\n,-1,\n"), "in.csv:2:2: error: value out of the UDINT range: '-1' for u");
  EXPECT_EQ(error("small,u,big\n,4294967296,\n"), "in.csv:2:2: error: value out of the UDINT range: '4294967296' for u");
  EXPECT_EQ(error("small,u,big\n,,9223372036854775808\n"), "in.csv:2:3: error: value out of the LINT range: '9223372036854775808' for big");
  EXPECT_EQ(error("small,u,big\n1x,,\n"), "in.csv:2:1: error: bad INT '1x' for small");
  Trace t = read_trace("small,u,big\n010,0x10,-5000000000\n", "in.csv", aliases);
  Layout L = Layout::standard(0);
  std::vector<uint8_t> mem(L.size);
  for (size_t i = 0; i < 3; i++) put_trace_cell(mem.data(), L, t.columns[i], t.rows[0][i]);
  EXPECT_EQ(format_probe(mem.data(), L, t.columns[0]), "10");  // decimal, not octal
  EXPECT_EQ(format_probe(mem.data(), L, t.columns[1]), "16");
  EXPECT_EQ(format_probe(mem.data(), L, t.columns[2]), "-5000000000");
}

}  // namespace
}  // namespace ldc
