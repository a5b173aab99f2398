// The Modbus TCP protocol (runtime/net/modbus.h): every function code, the
// address map, every exception, framing; and the server driver in a Runtime
// over a real socket.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cstring>

#include <gtest/gtest.h>

#include "runtime/net/modbus.h"
#include "runtime/runtime.h"

#include <chrono>
#include <mutex>
#include <thread>

using namespace ldc;
using namespace ldc::modbus;

namespace {

using Bytes = std::vector<uint8_t>;

// A request frame: transaction 0x1234, protocol 0, unit, PDU.
Bytes frame(const Bytes& pdu, uint8_t unit = 1, uint16_t tid = 0x1234) {
  Bytes f{uint8_t(tid >> 8), uint8_t(tid), 0, 0, uint8_t((pdu.size() + 1) >> 8), uint8_t(pdu.size() + 1), unit};
  for (uint8_t b : pdu) f.push_back(b);  // (insert() trips GCC 12's -Warray-bounds)
  return f;
}
Bytes pdu_of(const Bytes& reply) { return Bytes(reply.begin() + kMbapSize, reply.end()); }

struct Memory {
  Layout l = Layout::standard(0);
  Bytes global = Bytes(l.size, 0), t0 = Bytes(l.size, 0), t1 = Bytes(l.size, 0);
  View view() { return View{&l, global.data(), {t0.data(), t1.data()}}; }
  void word(Bytes& m, Area a, uint32_t i, uint32_t v) { std::memcpy(m.data() + l.addr(a, i), &v, 4); }
  uint32_t word(const Bytes& m, Area a, uint32_t i) {
    uint32_t v;
    std::memcpy(&v, m.data() + l.addr(a, i), 4);
    return v;
  }
  Outcome serve(const Bytes& pdu, uint8_t unit = 1) { return modbus::serve(frame(pdu, unit), view()); }
};

Bytes exc(uint8_t fc, uint8_t code) { return {uint8_t(fc | 0x80), code}; }

TEST(ModbusPdu, ReadCoilsMapsYThenMThenK) {
  Memory m;
  m.global[m.l.addr(Area::Y, 0)] = 1;
  m.global[m.l.addr(Area::Y, 2)] = 1;
  m.global[m.l.addr(Area::Y, 8)] = 1;
  m.global[m.l.addr(Area::M, 0)] = 1;
  m.global[m.l.addr(Area::K, 8191)] = 1;
  Outcome o = m.serve({1, 0, 0, 0, 10});
  ASSERT_EQ(o.kind, Outcome::Reply);
  EXPECT_EQ(o.consumed, 12u);
  EXPECT_EQ(o.reply, (Bytes{0x12, 0x34, 0, 0, 0, 5, 1, 1, 2, 0x05, 0x01}));
  EXPECT_TRUE(o.writes.empty());
  EXPECT_EQ(pdu_of(m.serve({1, 0x1F, 0xFF, 0, 2}).reply), (Bytes{1, 1, 0x02}));  // Y8191, M0
  EXPECT_EQ(pdu_of(m.serve({1, 0x5F, 0xFF, 0, 1}).reply), (Bytes{1, 1, 0x01}));  // K8191 = coil 24575
  EXPECT_EQ(pdu_of(m.serve({1, 0x60, 0x00, 0, 1}).reply), exc(1, 2));             // coil 24576
  EXPECT_EQ(pdu_of(m.serve({1, 0, 0, 0x07, 0xD0}).reply).size(), 2u + 250);      // 2000 coils
  EXPECT_EQ(pdu_of(m.serve({1, 0, 0, 0x07, 0xD1}).reply), exc(1, 3));             // 2001
  EXPECT_EQ(pdu_of(m.serve({1, 0, 0, 0, 0}).reply), exc(1, 3));                   // 0
  EXPECT_EQ(pdu_of(m.serve({1, 0, 0, 0}).reply), exc(1, 3));                      // short PDU
  EXPECT_EQ(pdu_of(m.serve({1, 0xFF, 0xFF, 0x07, 0xD0}).reply), exc(1, 2));       // past 65535
}

TEST(ModbusPdu, ReadDiscreteInputsAreX) {
  Memory m;
  m.global[m.l.addr(Area::X, 3)] = 1;
  m.global[m.l.addr(Area::X, 8191)] = 1;
  EXPECT_EQ(pdu_of(m.serve({2, 0, 0, 0, 9}).reply), (Bytes{2, 2, 0x08, 0x00}));
  EXPECT_EQ(pdu_of(m.serve({2, 0x1F, 0xFF, 0, 1}).reply), (Bytes{2, 1, 0x01}));
  EXPECT_EQ(pdu_of(m.serve({2, 0x1F, 0xFF, 0, 2}).reply), (Bytes{2, 1, 0x01}));  // X8191, then [T0] (off)
  EXPECT_EQ(pdu_of(m.serve({2, 0, 0, 0x07, 0xD1}).reply), exc(2, 3));
}

// Timers and counters (issue 27; docs/runtime.md, "The map"): done bits as
// discrete inputs 8192 + n ([Tn]) and 8448 + n ([Cn]), elapsed ms and
// counter values as input registers 1024 + 2n and 1536 + 2n, the high half
// first, from the unit's task; read-only.
TEST(ModbusPdu, TimersAndCountersAreReadOnlyInputs) {
  Memory m;
  m.t0[m.l.addr(Area::TQ, 0)] = 1;
  m.t0[m.l.addr(Area::TQ, 255)] = 1;
  m.t0[m.l.addr(Area::CQ, 3)] = 1;
  m.t1[m.l.addr(Area::CQ, 255)] = 1;
  m.word(m.t0, Area::TW, 0, 70000);             // 0x00011170
  m.word(m.t0, Area::TW, 255, 500);
  m.word(m.t0, Area::CW, 4, uint32_t(-2));      // 0xFFFFFFFE
  m.word(m.t1, Area::CW, 255, 0x12345678);
  EXPECT_EQ(pdu_of(m.serve({2, 0x20, 0x00, 0, 1}).reply), (Bytes{2, 1, 0x01}));         // [T0] = 8192
  EXPECT_EQ(pdu_of(m.serve({2, 0x20, 0xFF, 0, 5}).reply), (Bytes{2, 1, 0x11}));         // [T255], [C0..C3]
  EXPECT_EQ(pdu_of(m.serve({2, 0x21, 0xFF, 0, 1}).reply), (Bytes{2, 1, 0x00}));         // [C255] of task 0
  EXPECT_EQ(pdu_of(m.serve({2, 0x21, 0xFF, 0, 1}, 2).reply), (Bytes{2, 1, 0x01}));      // ... of task 1
  EXPECT_EQ(pdu_of(m.serve({2, 0x21, 0xFF, 0, 2}).reply), exc(2, 2));                   // 8704
  EXPECT_EQ(pdu_of(m.serve({4, 0x04, 0x00, 0, 2}).reply), (Bytes{4, 4, 0x00, 0x01, 0x11, 0x70}));  // T0 at 1024
  EXPECT_EQ(pdu_of(m.serve({4, 0x05, 0xFE, 0, 2}).reply), (Bytes{4, 4, 0x00, 0x00, 0x01, 0xF4}));  // T255 at 1534
  EXPECT_EQ(pdu_of(m.serve({4, 0x06, 0x08, 0, 2}).reply), (Bytes{4, 4, 0xFF, 0xFF, 0xFF, 0xFE}));  // C4 at 1544
  EXPECT_EQ(pdu_of(m.serve({4, 0x07, 0xFE, 0, 2}, 2).reply), (Bytes{4, 4, 0x12, 0x34, 0x56, 0x78}));  // C255, task 1
  EXPECT_EQ(pdu_of(m.serve({4, 0x07, 0xFF, 0, 2}).reply), exc(4, 2));                   // 2048
  EXPECT_EQ(pdu_of(m.serve({3, 0x04, 0x00, 0, 2}).reply), (Bytes{3, 4, 0, 0, 0, 0}));   // holding 1024 is still D0
}

TEST(ModbusPdu, ReadHoldingRegistersWyThenDAndFHighHalfFirst) {
  Memory m;
  m.word(m.global, Area::WY, 0, uint32_t(-2));
  m.word(m.global, Area::WY, 1023, 0x12345678);
  m.word(m.t0, Area::D, 0, 0x0001F00D);
  m.word(m.t0, Area::D, 8191, 0xCAFEBABE);
  m.word(m.t1, Area::D, 0, 0x00020003);
  float f = 1.5f;
  uint32_t fb;
  std::memcpy(&fb, &f, 4);
  m.word(m.t0, Area::F, 1023, fb);
  EXPECT_EQ(pdu_of(m.serve({3, 0, 0, 0, 1}).reply), (Bytes{3, 2, 0xFF, 0xFE}));
  EXPECT_EQ(pdu_of(m.serve({3, 0x03, 0xFF, 0, 3}).reply), (Bytes{3, 6, 0x56, 0x78, 0x00, 0x01, 0xF0, 0x0D}));
  EXPECT_EQ(pdu_of(m.serve({3, 0x43, 0xFE, 0, 2}).reply), (Bytes{3, 4, 0xCA, 0xFE, 0xBA, 0xBE}));   // D8191 at 17406
  EXPECT_EQ(pdu_of(m.serve({3, 0x4B, 0xFE, 0, 2}).reply), (Bytes{3, 4, 0x3F, 0xC0, 0x00, 0x00}));   // F1023 at 19454
  EXPECT_EQ(pdu_of(m.serve({3, 0x4C, 0x00, 0, 1}).reply), exc(3, 2));                              // 19456
  EXPECT_EQ(pdu_of(m.serve({3, 0x04, 0x00, 0, 2}, 2).reply), (Bytes{3, 4, 0x00, 0x02, 0x00, 0x03}));  // unit 2: task 1
  EXPECT_EQ(pdu_of(m.serve({3, 0x04, 0x00, 0, 2}, 0).reply), (Bytes{3, 4, 0x00, 0x01, 0xF0, 0x0D}));  // unit 0: task 0
  EXPECT_EQ(pdu_of(m.serve({3, 0x04, 0x00, 0, 2}, 255).reply), (Bytes{3, 4, 0x00, 0x01, 0xF0, 0x0D}));
  EXPECT_EQ(pdu_of(m.serve({3, 0x04, 0x00, 0, 2}, 3).reply), exc(3, 0x0B));  // no third task
  EXPECT_EQ(pdu_of(m.serve({3, 0, 0, 0, 125}).reply).size(), 2u + 250);
  EXPECT_EQ(pdu_of(m.serve({3, 0, 0, 0, 126}).reply), exc(3, 3));
  EXPECT_EQ(pdu_of(m.serve({3, 0, 0, 0, 0}).reply), exc(3, 3));
  EXPECT_EQ(pdu_of(m.serve({3, 0, 0, 0, 1, 0}).reply), exc(3, 3));  // long PDU
}

TEST(ModbusPdu, ReadInputRegistersAreWxLowHalf) {
  Memory m;
  m.word(m.global, Area::WX, 5, 0x00017FFF);
  m.word(m.global, Area::WX, 1023, uint32_t(-300));
  EXPECT_EQ(pdu_of(m.serve({4, 0, 5, 0, 1}).reply), (Bytes{4, 2, 0x7F, 0xFF}));
  EXPECT_EQ(pdu_of(m.serve({4, 0x03, 0xFF, 0, 1}).reply), (Bytes{4, 2, 0xFE, 0xD4}));
  EXPECT_EQ(pdu_of(m.serve({4, 0x07, 0xFF, 0, 2}).reply), exc(4, 2));  // past the counters (2048)
  EXPECT_EQ(pdu_of(m.serve({4, 0, 0, 0, 126}).reply), exc(4, 3));
}

TEST(ModbusPdu, WriteSingleCoilEchoesAndAsksForOneWrite) {
  Memory m;
  Outcome o = m.serve({5, 0x20, 0x01, 0xFF, 0x00});  // coil 8193 = M1 on
  EXPECT_EQ(pdu_of(o.reply), (Bytes{5, 0x20, 0x01, 0xFF, 0x00}));
  EXPECT_EQ(o.writes, (std::vector<Write>{{Area::M, 1, 1, 1}}));
  o = m.serve({5, 0x00, 0x07, 0x00, 0x00});
  EXPECT_EQ(o.writes, (std::vector<Write>{{Area::Y, 7, 0, 1}}));
  o = m.serve({5, 0x40, 0x00, 0xFF, 0x00});
  EXPECT_EQ(o.writes, (std::vector<Write>{{Area::K, 0, 1, 1}}));
  EXPECT_EQ(pdu_of(m.serve({5, 0, 0, 0x00, 0x01}).reply), exc(5, 3));
  EXPECT_EQ(pdu_of(m.serve({5, 0, 0, 0xFF, 0xFF}).reply), exc(5, 3));
  o = m.serve({5, 0x60, 0x00, 0xFF, 0x00});
  EXPECT_EQ(pdu_of(o.reply), exc(5, 2));
  EXPECT_TRUE(o.writes.empty());
}

TEST(ModbusPdu, WriteSingleRegisterSignExtendsWyAndWritesHalvesOfD) {
  Memory m;
  Outcome o = m.serve({6, 0, 3, 0xFF, 0xFE});
  EXPECT_EQ(pdu_of(o.reply), (Bytes{6, 0, 3, 0xFF, 0xFE}));
  EXPECT_EQ(o.writes, (std::vector<Write>{{Area::WY, 3, 0xFFFFFFFEu, 0xFFFFFFFFu}}));
  EXPECT_EQ(m.serve({6, 0x04, 0x02, 0x12, 0x34}).writes, (std::vector<Write>{{Area::D, 1, 0x12340000u, 0xFFFF0000u}}));
  EXPECT_EQ(m.serve({6, 0x04, 0x03, 0x12, 0x34}).writes, (std::vector<Write>{{Area::D, 1, 0x1234u, 0xFFFFu}}));
  EXPECT_EQ(m.serve({6, 0x44, 0x00, 0x3F, 0x80}).writes, (std::vector<Write>{{Area::F, 0, 0x3F800000u, 0xFFFF0000u}}));
  Outcome u = m.serve({6, 0x04, 0x00, 0, 1}, 2);
  EXPECT_EQ(u.task, 1u);
  EXPECT_EQ(pdu_of(m.serve({6, 0x4C, 0x00, 0, 0}).reply), exc(6, 2));
  EXPECT_EQ(pdu_of(m.serve({6, 0, 0, 0}).reply), exc(6, 3));
}

TEST(ModbusPdu, WriteMultipleCoils) {
  Memory m;
  Outcome o = m.serve({15, 0x1F, 0xFE, 0, 10, 2, 0b10100101, 0b11});  // Y8190, Y8191, M0..M7
  EXPECT_EQ(pdu_of(o.reply), (Bytes{15, 0x1F, 0xFE, 0, 10}));
  ASSERT_EQ(o.writes.size(), 10u);
  EXPECT_EQ(o.writes[0], (Write{Area::Y, 8190, 1, 1}));
  EXPECT_EQ(o.writes[1], (Write{Area::Y, 8191, 0, 1}));
  EXPECT_EQ(o.writes[2], (Write{Area::M, 0, 1, 1}));
  EXPECT_EQ(o.writes[9], (Write{Area::M, 7, 1, 1}));
  Bytes max{15, 0, 0, 0x07, 0xB0, 246};
  max.resize(max.size() + 246, 0xFF);
  EXPECT_EQ(m.serve(max).writes.size(), 1968u);
  Bytes over{15, 0, 0, 0x07, 0xB1, 247};
  over.resize(over.size() + 247, 0xFF);
  EXPECT_EQ(pdu_of(m.serve(over).reply), exc(15, 3));
  EXPECT_EQ(pdu_of(m.serve({15, 0, 0, 0, 10, 1, 0}).reply), exc(15, 3));     // byte count 1 for 10 coils
  EXPECT_EQ(pdu_of(m.serve({15, 0, 0, 0, 8, 1, 0, 0}).reply), exc(15, 3));   // a byte more than counted
  EXPECT_EQ(pdu_of(m.serve({15, 0, 0, 0, 0, 0}).reply), exc(15, 3));
  EXPECT_EQ(pdu_of(m.serve({15, 0x5F, 0xFF, 0, 2, 1, 3}).reply), exc(15, 2));
  EXPECT_EQ(pdu_of(m.serve({15, 0, 0}).reply), exc(15, 3));
}

TEST(ModbusPdu, WriteMultipleRegistersAcrossWyAndD) {
  Memory m;
  Outcome o = m.serve({16, 0x03, 0xFF, 0, 3, 6, 0x80, 0x00, 0x00, 0x01, 0x86, 0xA0});  // WY1023, D0 = 100000
  EXPECT_EQ(pdu_of(o.reply), (Bytes{16, 0x03, 0xFF, 0, 3}));
  EXPECT_EQ(o.writes, (std::vector<Write>{{Area::WY, 1023, 0xFFFF8000u, 0xFFFFFFFFu},
                                          {Area::D, 0, 0x00010000u, 0xFFFF0000u},
                                          {Area::D, 0, 0x86A0u, 0xFFFFu}}));
  for (const Write& w : o.writes) plc::apply_element(w, w.area == Area::WY ? m.global.data() : m.t0.data(), m.l);
  EXPECT_EQ(int32_t(m.word(m.global, Area::WY, 1023)), -32768);
  EXPECT_EQ(m.word(m.t0, Area::D, 0), 100000u);
  Bytes max{16, 0, 0, 0, 123, 246};
  max.resize(max.size() + 246, 0);
  EXPECT_EQ(m.serve(max).writes.size(), 123u);
  Bytes over{16, 0, 0, 0, 124, 246};  // 124 registers do not fit in a PDU: any byte count is wrong
  over.resize(over.size() + 246, 0);
  EXPECT_EQ(pdu_of(m.serve(over).reply), exc(16, 3));
  Bytes huge{16, 0, 0, 0, 124, 248};  // a PDU of 254 bytes: not Modbus, the connection closes
  huge.resize(huge.size() + 248, 0);
  EXPECT_EQ(m.serve(huge).kind, Outcome::Close);
  EXPECT_EQ(pdu_of(m.serve({16, 0, 0, 0, 2, 2, 0, 0}).reply), exc(16, 3));   // byte count 2 for 2 registers
  EXPECT_EQ(pdu_of(m.serve({16, 0, 0, 0, 1, 2, 0}).reply), exc(16, 3));      // a byte short
  EXPECT_EQ(pdu_of(m.serve({16, 0x4B, 0xFF, 0, 2, 4, 0, 0, 0, 0}).reply), exc(16, 2));
}

TEST(ModbusPdu, ApplyMasksBitsAndHalves) {
  Memory m;
  m.word(m.t0, Area::D, 7, 0xAAAABBBB);
  plc::apply_element({Area::D, 7, 0x12340000u, 0xFFFF0000u}, m.t0.data(), m.l);
  EXPECT_EQ(m.word(m.t0, Area::D, 7), 0x1234BBBBu);
  plc::apply_element({Area::D, 7, 0x5678u, 0xFFFFu}, m.t0.data(), m.l);
  EXPECT_EQ(m.word(m.t0, Area::D, 7), 0x12345678u);
  plc::apply_element({Area::Y, 9, 1, 1}, m.global.data(), m.l);
  EXPECT_EQ(m.global[m.l.addr(Area::Y, 9)], 1);
}

TEST(ModbusPdu, UnknownFunctionsAreIllegal) {
  Memory m;
  for (uint8_t fc : {0, 7, 8, 17, 22, 23, 43, 0x7F, 0x81, 0xFF}) {
    Outcome o = m.serve({fc, 0, 0, 0, 1});
    EXPECT_EQ(pdu_of(o.reply), exc(fc, 1)) << int(fc);
  }
}

TEST(ModbusFraming, IncompleteBadProtocolBadLengthAndPipelining) {
  Memory m;
  Bytes f = frame({3, 0, 0, 0, 1});
  for (size_t n = 0; n < f.size(); n++)
    EXPECT_EQ(serve(std::span(f.data(), n), m.view()).kind, Outcome::NeedMore) << n;
  Bytes bad = f;
  bad[3] = 1;  // protocol identifier 1
  EXPECT_EQ(serve(bad, m.view()).kind, Outcome::Close);
  bad = f;
  bad[4] = 0, bad[5] = 1;  // length 1: no function code
  EXPECT_EQ(serve(bad, m.view()).kind, Outcome::Close);
  bad[4] = 0, bad[5] = 255;  // length 255: a PDU of 254 bytes
  EXPECT_EQ(serve(bad, m.view()).kind, Outcome::Close);
  Bytes two = f;
  Bytes second = frame({1, 0, 0, 0, 1}, 1, 7);
  two.insert(two.end(), second.begin(), second.end());
  Outcome o = serve(two, m.view());
  EXPECT_EQ(o.consumed, f.size());
  o = serve(std::span(two).subspan(o.consumed), m.view());
  EXPECT_EQ(o.reply, (Bytes{0, 7, 0, 0, 0, 4, 1, 1, 1, 0}));
}

// ---------------------------------------------------------------- the server

// A Modbus client on a blocking socket.
struct Client {
  int fd = -1;
  // From `from` (a loopback address other than 127.0.0.1), or any.
  explicit Client(uint16_t port, const char* from = nullptr) {
    fd = socket(AF_INET, SOCK_STREAM, 0);
    if (from) {
      sockaddr_in s{};
      s.sin_family = AF_INET;
      inet_pton(AF_INET, from, &s.sin_addr);
      if (bind(fd, reinterpret_cast<sockaddr*>(&s), sizeof s) != 0) ADD_FAILURE() << strerror(errno);
    }
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(port);
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) ADD_FAILURE() << strerror(errno);
    timeval tv{5, 0};
    setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
  }
  ~Client() { close(fd); }
  // Sends a frame, returns the reply's PDU (empty on a closed connection).
  Bytes call(const Bytes& pdu, uint8_t unit = 1) {
    Bytes f = frame(pdu, unit);
    if (send(fd, f.data(), f.size(), MSG_NOSIGNAL) != ssize_t(f.size())) return {};
    return read_reply();
  }
  Bytes read_reply() {
    Bytes h(7);
    if (!read_n(h.data(), 7)) return {};
    Bytes p((h[4] << 8 | h[5]) - 1);
    if (!read_n(p.data(), p.size())) return {};
    return p;
  }
  bool closed = false;  // the server closed the connection (not a timeout)
  bool read_n(uint8_t* p, size_t n) {
    while (n) {
      ssize_t k = recv(fd, p, n, 0);
      if (k == 0 || (k < 0 && errno == ECONNRESET)) closed = true;
      if (k <= 0) return false;
      p += k, n -= size_t(k);
    }
    return true;
  }
};

Image image_of(const std::string& il) {
  Program p = parse_il_text(il, "t.il");
  Image img;
  img.layout = p.layout();
  img.il = encode_il(p).code;
  return img;
}

uint16_t port_of(const std::string& log) {
  size_t c = log.rfind(':', log.find(" ("));
  return uint16_t(std::stoul(log.substr(c + 1)));
}

// A program: Y0 = M0, WY0 = D0 + 1 (MOV/ADD through the IL), run by a Runtime with the Modbus driver.
TEST(ModbusServer, WritesApplyAtTheNextScanAndReadsSeeWholeScans) {
  plc::TaskSpec s;
  s.name = "main", s.program = "p", s.period_us = 1000;
  s.image = image_of(".rung line 1\n LOAD M0\n OUT Y0\n.rung line 2\n TRUE\n ADD D0 1 WY0\n.end\n");
  std::string listening;
  ServerOptions o;
  o.port = 0;
  o.log = [&](const std::string& m) { if (m.find("listening") != std::string::npos) listening = m; };
  auto drv = make_modbus_driver(plc::make_null_driver(), o);
  uint16_t port = port_of(listening);
  plc::Options opt;
  plc::Runtime rt({s}, opt, [](const Image& img) { return make_interp_engine(img.il, img.layout); }, std::move(drv));
  rt.start();
  ASSERT_TRUE(rt.wait_scans(2, 5000));
  Client c(port);
  EXPECT_EQ(c.call({1, 0, 0, 0, 1}), (Bytes{1, 1, 0}));
  EXPECT_EQ(c.call({5, 0x20, 0x00, 0xFF, 0x00}), (Bytes{5, 0x20, 0x00, 0xFF, 0x00}));  // M0 on
  EXPECT_EQ(rt.get("M0"), "1");
  ASSERT_TRUE(rt.wait_scans(1, 5000));
  EXPECT_EQ(c.call({1, 0, 0, 0, 1}), (Bytes{1, 1, 1}));  // Y0 followed
  EXPECT_EQ(c.call({16, 0x04, 0x00, 0, 2, 4, 0x00, 0x01, 0x00, 0x00}), (Bytes{16, 0x04, 0x00, 0, 2}));  // D0 = 65536
  ASSERT_TRUE(rt.wait_scans(1, 5000));
  EXPECT_EQ(rt.get("D0"), "65536");
  EXPECT_EQ(c.call({3, 0x04, 0x00, 0, 2}), (Bytes{3, 4, 0, 1, 0, 0}));
  EXPECT_EQ(rt.get("WY0"), "65537");
  EXPECT_EQ(c.call({3, 0, 0, 0, 1}), (Bytes{3, 2, 0, 1}));  // the low half of 65537
  EXPECT_EQ(c.call({65, 0, 0, 0, 1}), (Bytes{0xC1, 1}));
  rt.stop();
  // In STOP no scan takes a write: exception 06 after the write timeout.
  EXPECT_EQ(c.call({5, 0x20, 0x01, 0xFF, 0x00}), (Bytes{0x85, 6}));
  EXPECT_EQ(rt.get("M1"), "0");
  rt.shutdown();
}

// A Runtime running `il` (one task, 1 ms) with the Modbus driver on a free
// port of 127.0.0.1, its log lines kept.
struct Served {
  std::mutex mu;
  std::vector<std::string> lines;
  uint16_t port = 0;
  std::unique_ptr<plc::Runtime> rt;
  Served(ServerOptions o, const std::string& il, bool stopped = false) {
    plc::TaskSpec s;
    s.name = "main", s.program = "p", s.period_us = 1000;
    s.image = image_of(il);
    o.port = 0;
    o.log = [this](const std::string& m) {
      std::lock_guard<std::mutex> g(mu);
      lines.push_back(m);
    };
    auto drv = make_modbus_driver(plc::make_null_driver(), o);
    port = port_of(lines.at(0));
    plc::Options opt;
    opt.start_stopped = stopped;
    rt = std::make_unique<plc::Runtime>(std::vector<plc::TaskSpec>{s}, opt,
                                         [](const Image& img) { return make_interp_engine(img.il, img.layout); },
                                         std::move(drv));
    rt->start();
  }
  ~Served() { rt->shutdown(); }
  size_t count(const std::string& part) {
    std::lock_guard<std::mutex> g(mu);
    size_t n = 0;
    for (const std::string& l : lines) n += l.find(part) != std::string::npos;
    return n;
  }
};
const char* const kM0ToY0 = ".rung line 1\n LOAD M0\n OUT Y0\n.end\n";

double seconds_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

TEST(ModbusServer, ClosesBadFramesAndIdleConnections) {
  ServerOptions o;
  o.idle_timeout_ms = 300;
  Served p(o, kM0ToY0);
  Client a(p.port), b(p.port);
  EXPECT_EQ(a.call({1, 0, 0, 0, 1}), (Bytes{1, 1, 0}));
  EXPECT_EQ(b.call({1, 0, 0, 0, 1}), (Bytes{1, 1, 0}));
  Bytes bad{0, 1, 0, 9, 0, 6, 1, 3, 0, 0, 0, 1};  // protocol 9
  ASSERT_EQ(send(a.fd, bad.data(), bad.size(), MSG_NOSIGNAL), ssize_t(bad.size()));
  EXPECT_EQ(a.read_reply(), Bytes{});
  EXPECT_TRUE(a.closed);
  auto t0 = std::chrono::steady_clock::now();
  EXPECT_EQ(b.read_reply(), Bytes{});  // b idles out after 300 ms (the client waits up to 5 s)
  EXPECT_TRUE(b.closed);
  EXPECT_LT(seconds_since(t0), 2.0);
  EXPECT_EQ(p.count("protocol identifier 9, not 0"), 1u);
  EXPECT_EQ(p.count("no request for"), 1u);
}

TEST(ModbusServer, ANewcomerToAFullTableReplacesTheIdlest) {
  ServerOptions o;
  o.max_connections = 2;
  Served p(o, kM0ToY0);
  Client a(p.port), b(p.port);
  EXPECT_EQ(a.call({1, 0, 0, 0, 1}), (Bytes{1, 1, 0}));
  EXPECT_EQ(b.call({1, 0, 0, 0, 1}), (Bytes{1, 1, 0}));  // a is now the idlest
  Client c(p.port);
  EXPECT_EQ(c.call({1, 0, 0, 0, 1}), (Bytes{1, 1, 0}));
  EXPECT_EQ(a.call({1, 0, 0, 0, 1}), Bytes{});
  EXPECT_TRUE(a.closed);
  EXPECT_EQ(b.call({2, 0, 0, 0, 1}), (Bytes{2, 1, 0}));
  EXPECT_EQ(p.count("for one from 127.0.0.1"), 1u);
}

TEST(ModbusServer, ConnectionsPerAddressAreCappedWithinTheirAddress) {
  ServerOptions o;
  o.max_connections = 4, o.max_per_address = 2;
  Served p(o, kM0ToY0);
  // 127.0.0.2 is loopback too (127/8): a second client address on one machine.
  Client a1(p.port, "127.0.0.2"), a2(p.port, "127.0.0.2"), b(p.port);
  EXPECT_EQ(a1.call({1, 0, 0, 0, 1}), (Bytes{1, 1, 0}));
  EXPECT_EQ(b.call({1, 0, 0, 0, 1}), (Bytes{1, 1, 0}));  // b is idler than a2 below, but of another address
  EXPECT_EQ(a2.call({1, 0, 0, 0, 1}), (Bytes{1, 1, 0}));
  Client a3(p.port, "127.0.0.2");  // the table has room; the address has not: a1 gives way
  EXPECT_EQ(a3.call({1, 0, 0, 0, 1}), (Bytes{1, 1, 0}));
  EXPECT_EQ(a1.call({1, 0, 0, 0, 1}), Bytes{});
  EXPECT_TRUE(a1.closed);
  EXPECT_EQ(a2.call({1, 0, 0, 0, 1}), (Bytes{1, 1, 0}));
  EXPECT_EQ(b.call({1, 0, 0, 0, 1}), (Bytes{1, 1, 0}));
  EXPECT_EQ(p.count("2 connections from 127.0.0.2 are open"), 1u);
}

TEST(ModbusServer, ANewcomerIsRefusedWhenEveryConnectionWaitsForAWrite) {
  ServerOptions o;
  o.max_connections = 1, o.write_timeout_ms = 1500;
  Served p(o, kM0ToY0, true);  // STOP: the write waits
  Client a(p.port);
  Bytes w = frame({5, 0x20, 0x05, 0xFF, 0x00});  // M5 on
  ASSERT_EQ(send(a.fd, w.data(), w.size(), MSG_NOSIGNAL), ssize_t(w.size()));
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  Client b(p.port);
  EXPECT_EQ(b.call({1, 0, 0, 0, 1}), Bytes{});
  EXPECT_TRUE(b.closed);
  EXPECT_EQ(a.read_reply(), (Bytes{0x85, 6}));  // no scan took it: busy, not applied
  EXPECT_EQ(p.count("each with a write pending"), 1u);
  p.rt->run();
  ASSERT_TRUE(p.rt->wait_scans(2, 5000));
  EXPECT_EQ(p.rt->get("M5"), "0");
}

TEST(ModbusServer, AFrameBegunMustBeFinishedInTime) {
  ServerOptions o;
  o.frame_timeout_ms = 400;
  Served p(o, kM0ToY0);
  Bytes f = frame({1, 0, 0, 0, 1});
  // a whole frame in three parts within the deadline: answered
  Client a(p.port);
  for (size_t at : {0, 3, 8}) {
    size_t to = at == 8 ? f.size() : at == 0 ? 3 : 8;
    ASSERT_EQ(send(a.fd, f.data() + at, to - at, MSG_NOSIGNAL), ssize_t(to - at));
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  EXPECT_EQ(a.read_reply(), (Bytes{1, 1, 0}));
  // a byte every 100 ms: the connection is busy but the frame never ends (slowloris)
  Client b(p.port);
  auto t0 = std::chrono::steady_clock::now();
  size_t sent = 0;
  while (sent < f.size() - 1 && send(b.fd, f.data() + sent, 1, MSG_NOSIGNAL) == 1) {
    sent++;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  EXPECT_EQ(b.read_reply(), Bytes{});
  EXPECT_TRUE(b.closed);
  double took = seconds_since(t0);
  EXPECT_GE(took, 0.35);
  EXPECT_LT(took, 3.0);
  EXPECT_EQ(p.count("still incomplete"), 1u);
}

TEST(ModbusServer, AFullShadowAnswersBusyAtOnceAndDropsNothingElse) {
  ServerOptions o;
  o.pending_writes = 1968, o.write_timeout_ms = 1500;
  Served p(o, kM0ToY0, true);  // STOP: nothing takes the shadow
  Client a(p.port), b(p.port);
  Bytes all{15, 0x20, 0x00, 0x07, 0xB0, 246};  // M0..M1967 on: the shadow is full
  all.resize(all.size() + 246, 0xFF);
  Bytes f = frame(all);
  ASSERT_EQ(send(a.fd, f.data(), f.size(), MSG_NOSIGNAL), ssize_t(f.size()));
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  auto t0 = std::chrono::steady_clock::now();
  EXPECT_EQ(b.call({5, 0x27, 0xD0, 0xFF, 0x00}), (Bytes{0x85, 6}));  // M2000: one element more
  EXPECT_LT(seconds_since(t0), 1.0);
  EXPECT_EQ(a.read_reply(), (Bytes{0x8F, 6}));  // then a's write times out, not applied
  p.rt->run();
  ASSERT_TRUE(p.rt->wait_scans(2, 5000));
  EXPECT_EQ(p.rt->get("M0"), "0");
  EXPECT_EQ(p.rt->get("M2000"), "0");
  // running, the same write is applied and answered
  EXPECT_EQ(a.call(all), (Bytes{15, 0x20, 0x00, 0x07, 0xB0}));
  EXPECT_EQ(p.rt->get("M1967"), "1");
  EXPECT_EQ(p.count("exception 06"), 1u);
}

TEST(ModbusServer, WritesFromManyRequestsLandInOrder) {
  // 8 connections each write their own D word 200 times (FC 16) and one
  // shared coil; the value each reads back right after its write is its own
  // write (the reply waits for the scan), and at the end each D word holds
  // the last value its client wrote.
  Served p(ServerOptions{}, kM0ToY0);
  std::vector<std::thread> th;
  std::vector<std::string> errors(8);
  for (int i = 0; i < 8; i++)
    th.emplace_back([&, i] {
      Client c(p.port);
      uint16_t reg = uint16_t(1024 + 2 * i);
      for (uint16_t k = 1; k <= 200; k++) {
        uint16_t hi = uint16_t(i), lo = k;
        Bytes r = c.call({16, uint8_t(reg >> 8), uint8_t(reg), 0, 2, 4, uint8_t(hi >> 8), uint8_t(hi), uint8_t(lo >> 8), uint8_t(lo)});
        if (r != Bytes{16, uint8_t(reg >> 8), uint8_t(reg), 0, 2}) return void(errors[i] = "write " + std::to_string(k));
        if (c.call({3, uint8_t(reg >> 8), uint8_t(reg), 0, 2}) != Bytes{3, 4, 0, uint8_t(i), uint8_t(lo >> 8), uint8_t(lo)})
          return void(errors[i] = "read after write " + std::to_string(k));
      }
    });
  for (auto& t : th) t.join();
  for (int i = 0; i < 8; i++) {
    EXPECT_EQ(errors[i], "") << i;
    EXPECT_EQ(p.rt->get("D" + std::to_string(i)), std::to_string(i * 65536 + 200));
  }
}

TEST(ModbusServer, PipelinedRequestsBeyondTheReplyBufferAreAllAnswered) {
  // 1,000 reads of 125 registers sent at once, the replies (259 KB) read
  // only after: the server stops reading at 64 KiB of replies not sent and
  // goes on as they drain; every reply comes, in order.
  Served p(ServerOptions{}, kM0ToY0);
  Client c(p.port);
  Bytes all;
  for (int i = 0; i < 1000; i++) {
    Bytes f = frame({3, 0, 0, 0, 125}, 1, uint16_t(i));
    all.insert(all.end(), f.begin(), f.end());
  }
  ASSERT_EQ(send(c.fd, all.data(), all.size(), MSG_NOSIGNAL), ssize_t(all.size()));
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  for (int i = 0; i < 1000; i++) {
    Bytes h(7);
    ASSERT_TRUE(c.read_n(h.data(), 7)) << i;
    ASSERT_EQ(h[0] << 8 | h[1], i);
    Bytes pdu((h[4] << 8 | h[5]) - 1);
    ASSERT_TRUE(c.read_n(pdu.data(), pdu.size())) << i;
    ASSERT_EQ(pdu.size(), 252u) << i;
  }
}

TEST(ModbusServer, LogLinesAreThrottledPerCause) {
  ServerOptions o;
  o.log_burst = 3;  // window 10 s: the test is well within one
  auto p = std::make_unique<Served>(o, kM0ToY0);
  Bytes bad{0, 1, 0, 9, 0, 6, 1, 3, 0, 0, 0, 1};
  for (int i = 0; i < 50; i++) {
    Client c(p->port);
    ASSERT_EQ(send(c.fd, bad.data(), bad.size(), MSG_NOSIGNAL), ssize_t(bad.size()));
    EXPECT_EQ(c.read_reply(), Bytes{});
  }
  EXPECT_EQ(p->count("closed the connection from"), 3u);
  std::vector<std::string> lines;
  {
    Served& s = *p;
    s.rt->shutdown();  // the server stops: it says what it held back
    std::lock_guard<std::mutex> g(s.mu);
    lines = s.lines;
  }
  size_t summaries = 0;
  for (const std::string& l : lines)
    summaries += l == "ldrun: modbus: 47 more 'closed: not Modbus' messages suppressed in 10 s";
  EXPECT_EQ(summaries, 1u);
}

TEST(ModbusAddress, Parses) {
  ServerOptions o;
  parse_address("5020", o);
  EXPECT_EQ(o.host, "127.0.0.1");
  EXPECT_EQ(o.port, 5020);
  parse_address(":502", o);
  EXPECT_EQ(o.host, "127.0.0.1");
  parse_address("0.0.0.0:1502", o);
  EXPECT_EQ(o.host, "0.0.0.0");
  EXPECT_EQ(o.port, 1502);
  parse_address("[::1]:0", o);
  EXPECT_EQ(o.host, "::1");
  EXPECT_EQ(o.port, 0);
  EXPECT_THROW(parse_address("host:", o), std::runtime_error);
  EXPECT_THROW(parse_address("70000", o), std::runtime_error);
  EXPECT_THROW(parse_address("[::1]", o), std::runtime_error);
  EXPECT_THROW(parse_address("12x", o), std::runtime_error);
}

}  // namespace
