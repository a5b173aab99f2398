// runtime/examples/shm_client.cpp -- a small client of `ldrun --io=shm`:
// writes inputs and reads outputs of the shared-memory I/O image with the
// sequence handshake of runtime/shm_layout.h, which is all it includes of ldc.
//
//   shm_client [--name /ldc] set X3 1 WX0 250    one atomic update of inputs
//   shm_client [--name /ldc] get Y0 WY1 X3       one consistent snapshot
//   shm_client [--name /ldc] wait Y0 1 [MS]      poll until Y0 is 1 (exit 1 on timeout)
//   shm_client [--name /ldc] status              owner (running or dead), state, scans,
//                                                output publications, the reason of a FAULT;
//                                                exit status 3 if the owner is dead
#include <fcntl.h>
#include <sys/mman.h>
#include <time.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "runtime/shm_layout.h"

namespace shm = ldc::shm;

namespace {

struct Point {
  std::string name;
  uint32_t offset;  // in the segment
  bool word, input;
};

bool parse_point(const std::string& s, Point& p) {
  std::string u;
  for (char c : s) u += char(std::toupper(static_cast<unsigned char>(c)));
  size_t digits = u.find_first_of("0123456789");
  if (digits == std::string::npos || u.find_first_not_of("0123456789", digits) != std::string::npos) return false;
  std::string prefix = u.substr(0, digits);
  unsigned long i = std::strtoul(u.c_str() + digits, nullptr, 10);
  p.name = s;
  if (prefix == "X" && i < shm::kXCount) p = {s, uint32_t(shm::kXOffset + i), false, true};
  else if (prefix == "Y" && i < shm::kYCount) p = {s, uint32_t(shm::kYOffset + i), false, false};
  else if (prefix == "WX" && i < shm::kWXCount) p = {s, uint32_t(shm::kWXOffset + 4 * i), true, true};
  else if (prefix == "WY" && i < shm::kWYCount) p = {s, uint32_t(shm::kWYOffset + 4 * i), true, false};
  else return false;
  return true;
}

int64_t mono_ms() {
  timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return int64_t(ts.tv_sec) * 1000 + ts.tv_nsec / 1000000;
}

// One consistent snapshot of the points: each group (inputs, outputs) is
// copied under its sequence counter and retried while a writer is at work.
bool snapshot(shm::Header* h, const std::vector<Point>& pts, std::vector<int32_t>& out) {
  uint8_t* b = shm::base(h);
  out.assign(pts.size(), 0);
  for (int group = 0; group < 2; group++) {
    uint32_t& seq = group == 0 ? h->in_seq : h->out_seq;
    bool ok = false;
    for (int attempt = 0; attempt < 100000 && !ok; attempt++) {
      uint32_t v;
      if (!shm::begin_read(seq, v)) continue;
      for (size_t i = 0; i < pts.size(); i++)
        if (pts[i].input == (group == 0)) out[i] = pts[i].word ? shm::load32(b + pts[i].offset) : shm::load8(b + pts[i].offset);
      ok = shm::end_read(seq, v);
    }
    if (!ok) return false;
  }
  return true;
}

const char kUsage[] = "usage: shm_client [--name /ldc] set DEV VALUE... | get DEV... | wait DEV VALUE [MS] | status\n";
int usage() {
  std::fputs(kUsage, stderr);
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  std::string name = "/ldc";
  int i = 1;
  if (argc == 2 && (std::string(argv[1]) == "--help" || std::string(argv[1]) == "-h")) {
    std::fputs(kUsage, stdout);  // installed beside ldrun: a --help as the other tools have
    return 0;
  }
  if (i + 1 < argc && std::string(argv[i]) == "--name") name = argv[i + 1], i += 2;
  if (i >= argc) return usage();
  std::string cmd = argv[i++];
  int fd = shm_open(name.c_str(), O_RDWR, 0);
  if (fd < 0) {
    std::fprintf(stderr, "shm_client: cannot open %s: %s (is ldrun --io=shm:%s running?)\n", name.c_str(),
                 std::strerror(errno), name.c_str());
    return 1;
  }
  void* m = mmap(nullptr, shm::kTotalSize, PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
  close(fd);
  if (m == MAP_FAILED) {
    std::fprintf(stderr, "shm_client: cannot map %s: %s\n", name.c_str(), std::strerror(errno));
    return 1;
  }
  auto* h = static_cast<shm::Header*>(m);
  if (const char* why = shm::check(h, shm::kTotalSize); *why) {
    std::fprintf(stderr, "shm_client: %s: %s\n", name.c_str(), why);
    return 1;
  }
  uint8_t* b = shm::base(h);
  // A segment outlives an ldrun that ended on a fatal error (docs/faults.md):
  // its outputs are then the safe state that ldrun left, no longer live.
  const bool alive = shm::owner_alive(h);
  if (!alive && cmd != "status")
    std::fprintf(stderr, "shm_client: warning: ldrun process %d that owns %s is not running: nothing is scanned\n",
                 h->owner_pid, name.c_str());

  if (cmd == "set") {
    if ((argc - i) % 2 || i >= argc) return usage();
    std::vector<std::pair<Point, int32_t>> writes;
    for (; i < argc; i += 2) {
      Point p;
      if (!parse_point(argv[i], p) || !p.input) {
        std::fprintf(stderr, "shm_client: '%s' is not an input (X0..X8191, WX0..WX1023)\n", argv[i]);
        return 1;
      }
      char* end;
      long v = std::strtol(argv[i + 1], &end, 0);
      if (*end || (!p.word && v != 0 && v != 1)) {
        std::fprintf(stderr, "shm_client: bad value '%s' for %s\n", argv[i + 1], argv[i]);
        return 1;
      }
      writes.emplace_back(p, int32_t(v));
    }
    int32_t pid = int32_t(getpid());
    if (!shm::lock_inputs(h, pid)) {
      std::fprintf(stderr, "shm_client: another client holds the input lock\n");
      return 1;
    }
    shm::begin_write(h->in_seq);  // all the writes below appear to ldrun at once
    for (auto& [p, v] : writes) {
      if (p.word) shm::store32(b + p.offset, v);
      else shm::store8(b + p.offset, uint8_t(v));
    }
    shm::end_write(h->in_seq);
    shm::unlock_inputs(h, pid);
    return 0;
  }
  if (cmd == "get") {
    std::vector<Point> pts;
    for (; i < argc; i++) {
      Point p;
      if (!parse_point(argv[i], p)) {
        std::fprintf(stderr, "shm_client: unknown point '%s' (X Y WX WY)\n", argv[i]);
        return 1;
      }
      pts.push_back(p);
    }
    if (pts.empty()) return usage();
    std::vector<int32_t> v;
    if (!snapshot(h, pts, v)) {
      std::fprintf(stderr, "shm_client: no consistent snapshot (a writer is stuck)\n");
      return 1;
    }
    for (size_t k = 0; k < pts.size(); k++) std::printf("%s %d\n", pts[k].name.c_str(), v[k]);
    return 0;
  }
  if (cmd == "wait") {
    if (argc - i < 2 || argc - i > 3) return usage();
    Point p;
    if (!parse_point(argv[i], p)) return usage();
    int32_t want = int32_t(std::strtol(argv[i + 1], nullptr, 0));
    int64_t deadline = mono_ms() + (argc - i == 3 ? std::atol(argv[i + 2]) : 5000);
    std::vector<int32_t> v;
    while (mono_ms() < deadline) {
      if (snapshot(h, {p}, v) && v[0] == want) {
        std::printf("%s %d\n", p.name.c_str(), v[0]);
        return 0;
      }
      usleep(1000);
    }
    std::fprintf(stderr, "shm_client: %s did not become %d\n", p.name.c_str(), want);
    return 1;
  }
  if (cmd == "status") {
    static const char* states[] = {"STOP", "RUN", "FAULT", "EXITED"};
    uint32_t s = shm::at(h->state).load();
    std::printf("owner %d (%s) state %s scans %llu publications %llu block %u\n", h->owner_pid, alive ? "running" : "dead",
                s < 4 ? states[s] : "?", (unsigned long long)shm::at(h->scans).load(),
                (unsigned long long)shm::at(h->out_count).load(), h->block_size);
    char reason[shm::kReasonSize];
    if (s == shm::kFault && shm::read_reason(h, reason) && reason[0]) std::printf("reason %s\n", reason);
    return alive ? 0 : 3;
  }
  return usage();
}
