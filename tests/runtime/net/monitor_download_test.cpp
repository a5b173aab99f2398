// The monitor across an online download (docs/runtime.md, "The monitor"):
// Runtime::generation and IoDriver::program_replaced, and the monitor's
// /api/program and /api/state before and after Runtime::replace.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <chrono>
#include <cstring>
#include <mutex>
#include <thread>
#include <vector>

#include "ir/ir.h"
#include "runtime/net/monitor.h"
#include "runtime/plc.h"
#include "runtime/runtime.h"

using namespace ldc;

namespace {

// An image of IL text with its line map (the monitor splits rungs by it).
Image image_of(const std::string& il) {
  Program p = parse_il_text(il, "t.il");
  BinaryIl b = encode_il(p);
  Image img;
  img.layout = p.layout();
  img.il = b.code;
  size_t k = 0;
  for (size_t r = 0; r < p.rungs.size(); r++)
    for (size_t i = 0; i < p.rungs[r].code.size(); i++, k++)
      img.lines.push_back(LineEntry{0, b.instr_offset[k], p.rungs[r].line, uint32_t(r)});
  return img;
}

// Program A writes 1 to D0 each scan, program B 2 (and has an edge slot, so
// its memory is larger: the edge area is last).
const char* kA = ".rung line 1\n TRUE\n MOV 1 D0\n.end\n";
const char* kB = ".edges 1\n.rung line 1\n TRUE\n MOV 2 D0\n.rung line 2\n LOADP X0 E0\n OUT Y0\n.end\n";

plc::TaskSpec task(const char* il) {
  plc::TaskSpec s;
  s.name = "main", s.program = "p", s.period_us = 1000;
  s.image = image_of(il);
  return s;
}
std::unique_ptr<Engine> interp(const Image& img) { return make_interp_engine(img.il, img.layout); }

// Records what the task thread saw after each scan: the task's generation
// (read there) and D0 of the memory it was given; and each program_replaced.
struct Recorder : plc::IoDriver {
  plc::Runtime* rt = nullptr;
  std::mutex mu;
  std::vector<std::pair<uint64_t, int32_t>> scans;  // generation, D0
  std::vector<std::pair<uint64_t, size_t>> replaced;  // generation then, IL bytes of the new image
  std::thread::id replaced_on;
  void after_scan(const plc::ScanContext& c, const uint8_t* mem, const uint8_t*) override {
    int32_t d0;
    std::memcpy(&d0, mem + Layout::standard(0).addr(Area::D, 0), 4);
    std::lock_guard<std::mutex> l(mu);
    scans.emplace_back(rt->generation(c.task), d0);
  }
  void program_replaced(size_t task, const Image& img) override {
    std::lock_guard<std::mutex> l(mu);
    replaced.emplace_back(rt->generation(task), img.il.size());
    replaced_on = std::this_thread::get_id();
  }
};

TEST(MonitorDownload, TheGenerationTellsWhichProgramsMemoryAScanHas) {
  auto rec_owned = std::make_unique<Recorder>();
  Recorder* rec = rec_owned.get();
  plc::Options opt;
  plc::Runtime rt({task(kA)}, opt, interp, std::move(rec_owned));
  rec->rt = &rt;
  EXPECT_EQ(rt.generation(0), 0u);
  rt.start();
  ASSERT_TRUE(rt.wait_scans(3, 5000));
  Image b = image_of(kB);
  const size_t b_il = b.il.size();
  rt.replace("main", std::move(b), "b.il");
  EXPECT_EQ(rt.generation(0), 1u);
  ASSERT_TRUE(rt.wait_scans(3, 5000));
  rt.shutdown();
  std::lock_guard<std::mutex> l(rec->mu);
  // told once, on the thread that asked for the download, after the switch
  ASSERT_EQ(rec->replaced.size(), 1u);
  EXPECT_EQ(rec->replaced[0], std::make_pair(uint64_t(1), b_il));
  EXPECT_EQ(rec->replaced_on, std::this_thread::get_id());
  // every scan of generation 0 ran A (D0 = 1), every one of generation 1 ran B
  // (D0 = 2), and the generation never goes back
  size_t g0 = 0, g1 = 0;
  uint64_t last = 0;
  for (auto [g, d0] : rec->scans) {
    EXPECT_GE(g, last);
    last = g;
    EXPECT_EQ(d0, g == 0 ? 1 : 2) << "generation " << g;
    (g == 0 ? g0 : g1)++;
  }
  EXPECT_GE(g0, 3u);
  EXPECT_GE(g1, 3u);
}

// ---- the monitor in the same process, over HTTP

std::string http_get(uint16_t port, const std::string& path) {
  int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(port);
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) {
    close(fd);
    return "";
  }
  timeval tv{3, 0};
  setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
  std::string req = "GET " + path + " HTTP/1.1\r\nHost: 127.0.0.1:" + std::to_string(port) + "\r\nConnection: close\r\n\r\n";
  (void)!send(fd, req.data(), req.size(), MSG_NOSIGNAL);
  std::string out;
  char b[4096];
  for (ssize_t n; (n = recv(fd, b, sizeof b, 0)) > 0;) out.append(b, size_t(n));
  close(fd);
  size_t body = out.find("\r\n\r\n");
  return body == std::string::npos ? out : out.substr(body + 4);
}
size_t count(const std::string& s, const std::string& what) {
  size_t n = 0;
  for (size_t at = s.find(what); at != std::string::npos; at = s.find(what, at + 1)) n++;
  return n;
}

TEST(MonitorDownload, PagesGetTheNewProgramAndValuesOfItsGenerationOnly) {
  plc::MonitorTask mt{"main", 1000, image_of(kA), "", ""};
  plc::MonitorOptions mo;
  mo.port = 0;
  plc::Monitor mon({mt}, mo);
  plc::Options opt;
  plc::Runtime rt({task(kA)}, opt, interp, mon.wrap(plc::make_null_driver()));
  mon.attach(&rt);
  mon.start();
  rt.start();
  ASSERT_TRUE(rt.wait_scans(2, 5000));
  std::string p0 = http_get(mon.port(), "/api/program"), s0 = http_get(mon.port(), "/api/state");
  EXPECT_NE(p0.find("\"gen\":0,\"switched_ms\":0"), std::string::npos) << p0;
  EXPECT_EQ(count(p0, "\"title\":"), 1u);  // A has one rung
  EXPECT_NE(s0.find("\"gen\":0"), std::string::npos) << s0;
  EXPECT_EQ(p0.find("\"k\":\"p\""), std::string::npos);

  const auto before = std::chrono::system_clock::now();
  rt.replace("main", image_of(kB), "b.il");
  const auto after = std::chrono::system_clock::now();
  // a page opened now draws B: two rungs, its edge contact -|P|-, the time of the switch
  std::string p1 = http_get(mon.port(), "/api/program");
  EXPECT_NE(p1.find("\"gen\":1"), std::string::npos) << p1;
  EXPECT_EQ(count(p1, "\"title\":"), 2u);
  EXPECT_NE(p1.find("\"k\":\"p\",\"d\":\"X0\",\"dv\":\"X0\""), std::string::npos) << p1;
  size_t at = p1.find("\"switched_ms\":");
  ASSERT_NE(at, std::string::npos);
  int64_t ms = std::stoll(p1.substr(at + 14));
  auto ms_of = [](auto t) { return std::chrono::duration_cast<std::chrono::milliseconds>(t.time_since_epoch()).count(); };
  EXPECT_GE(ms, ms_of(before));
  EXPECT_LE(ms, ms_of(after));
  // the values: of generation 1, once a scan of B was copied; B's two rungs
  ASSERT_TRUE(rt.wait_scans(2, 5000));
  std::string s1 = http_get(mon.port(), "/api/state");
  EXPECT_NE(s1.find("\"gen\":1"), std::string::npos) << s1;
  EXPECT_EQ(s1.find("\"pending\""), std::string::npos) << s1;
  EXPECT_EQ(count(s1, "{\"n\":"), 2u) << s1;
  // a second download, back to the smaller memory of A: generation 2, one rung
  rt.replace("main", image_of(kA), "a.il");
  ASSERT_TRUE(rt.wait_scans(2, 5000));
  std::string s2 = http_get(mon.port(), "/api/state");
  EXPECT_NE(s2.find("\"gen\":2"), std::string::npos) << s2;
  EXPECT_EQ(count(s2, "{\"n\":"), 1u) << s2;
  rt.shutdown();
  mon.stop();
}

// In STOP a download switches too, but no scan of the new program runs: its
// values are "pending" (none) rather than zeros or the old program's.
TEST(MonitorDownload, NoValuesUntilTheNewProgramScanned) {
  plc::MonitorTask mt{"main", 1000, image_of(kA), "", ""};
  plc::MonitorOptions mo;
  mo.port = 0;
  plc::Monitor mon({mt}, mo);
  plc::Options opt;
  opt.start_stopped = true;
  plc::Runtime rt({task(kA)}, opt, interp, mon.wrap(plc::make_null_driver()));
  mon.attach(&rt);
  mon.start();
  rt.start();
  rt.replace("main", image_of(kB), "b.il");
  std::string s = http_get(mon.port(), "/api/state");
  EXPECT_NE(s.find("\"gen\":1,\"scan\":0,\"held\":false,\"pending\":true"), std::string::npos) << s;
  EXPECT_NE(s.find("\"rungs\":[],\"dev\":[]"), std::string::npos) << s;
  rt.run();
  ASSERT_TRUE(rt.wait_scans(2, 5000));
  s = http_get(mon.port(), "/api/state");
  EXPECT_EQ(s.find("\"pending\""), std::string::npos) << s;
  EXPECT_EQ(count(s, "{\"n\":"), 2u) << s;
  rt.shutdown();
  mon.stop();
}

}  // namespace
