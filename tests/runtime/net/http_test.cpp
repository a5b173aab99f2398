// tests/runtime/net/http_test.cpp -- the monitor's HTTP request parser (a pure
// function of the bytes received), form decoding, addresses, and the server
// on a loopback socket: replies, limits, timeouts, the connection bound.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <mutex>
#include <thread>
#include <vector>

#include "runtime/net/http.h"
#include "runtime/net/monitor.h"

using namespace ldc::http;
using S = Parse::Status;

namespace {

Parse P(std::string_view s, Limits l = {}) { return parse_request(s, l); }

// A connection to the server on loopback, from the address `from` if given.
int dial(uint16_t port, const char* from = nullptr) {
  int fd = socket(AF_INET, SOCK_STREAM, 0);
  if (from) {
    sockaddr_in b{};
    b.sin_family = AF_INET;
    inet_pton(AF_INET, from, &b.sin_addr);
    if (bind(fd, reinterpret_cast<sockaddr*>(&b), sizeof b) != 0) { close(fd); return -1; }
  }
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(port);
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) { close(fd); return -1; }
  timeval tv{3, 0};
  setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
  return fd;
}
std::string exchange(int fd, const std::string& req, bool until_close = true) {
  if (!req.empty()) (void)!send(fd, req.data(), req.size(), MSG_NOSIGNAL);
  std::string out;
  char b[4096];
  while (true) {
    ssize_t n = recv(fd, b, sizeof b, 0);
    if (n <= 0) break;
    out.append(b, size_t(n));
    if (!until_close && out.find("\r\n\r\n") != std::string::npos) break;
  }
  return out;
}

// True if the server closed the connection (EOF within a second).
bool closed_by_peer(int fd) {
  timeval tv{1, 0};
  setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
  char b[256];
  ssize_t n;
  while ((n = recv(fd, b, sizeof b, 0)) > 0) {}
  return n == 0;
}

// The server's count of connections once it settles (it closes a socket a
// moment before it counts it gone): n, or what it is after a second.
size_t settled_connections(const Server& s, size_t n) {
  for (int i = 0; i < 100 && s.connections() != n; i++) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  return s.connections();
}

}  // namespace

TEST(HttpParse, CompleteGet) {
  Parse p = P("GET /api/state?x=1 HTTP/1.1\r\nHost: 127.0.0.1:80\r\nX-Thing:  v  \r\n\r\nGET / HTTP/1.1\r\n");
  ASSERT_EQ(p.status, S::Done);
  EXPECT_EQ(p.req.method, "GET");
  EXPECT_EQ(p.req.path, "/api/state");
  EXPECT_EQ(p.req.query, "x=1");
  ASSERT_NE(p.req.header("x-thing"), nullptr);
  EXPECT_EQ(*p.req.header("x-thing"), "v");
  EXPECT_EQ(p.consumed, std::string("GET /api/state?x=1 HTTP/1.1\r\nHost: 127.0.0.1:80\r\nX-Thing:  v  \r\n\r\n").size());
  EXPECT_TRUE(p.req.keep_alive());
}

TEST(HttpParse, BareLineFeedsAndBodies) {
  Parse p = P("POST /api/write HTTP/1.0\nContent-Length: 5\n\nab=cdEXTRA");
  ASSERT_EQ(p.status, S::Done);
  EXPECT_EQ(p.req.body, "ab=cd");
  EXPECT_FALSE(p.req.keep_alive());
  EXPECT_EQ(P("POST / HTTP/1.1\r\nHost: h\r\nContent-Length: 5\r\n\r\nab").status, S::Incomplete);
  EXPECT_EQ(P("GET / HTTP/1.1\r\nHost: h\r\n").status, S::Incomplete);
  EXPECT_EQ(P("GET / HT").status, S::Incomplete);
  EXPECT_EQ(P("").status, S::Incomplete);
}

TEST(HttpParse, Refusals) {
  auto code = [](std::string_view s, Limits l = {}) {
    Parse p = P(s, l);
    EXPECT_EQ(p.status, S::Error) << s;
    EXPECT_FALSE(p.reason.empty());
    return p.code;
  };
  EXPECT_EQ(code("GARBAGE\r\n\r\n"), 400);
  EXPECT_EQ(code("GET  / HTTP/1.1\r\nHost: h\r\n\r\n"), 400);
  EXPECT_EQ(code("GET http://x/ HTTP/1.1\r\nHost: h\r\n\r\n"), 400);
  EXPECT_EQ(code("GET / HTTP/2.0\r\n"), 505);  // known at the end of the request line
  EXPECT_EQ(code("GET / HTTX/1.1\r\n\r\n"), 400);
  EXPECT_EQ(code("GET / HTTP/1.1\r\n\r\n"), 400);  // no Host
  EXPECT_EQ(code("GET / HTTP/1.1\r\nHost: h\r\n folded\r\n\r\n"), 400);
  EXPECT_EQ(code("GET / HTTP/1.1\r\nHost h\r\n\r\n"), 400);
  EXPECT_EQ(code("GET / HTTP/1.1\r\nHost: h\rX\r\n\r\n"), 400);
  EXPECT_EQ(code(std::string("GET / HTTP/1.1\r\nHost: a\x01" "b\r\n\r\n")), 400);
  EXPECT_EQ(code("POST / HTTP/1.1\r\nHost: h\r\nTransfer-Encoding: chunked\r\n\r\n"), 501);
  EXPECT_EQ(code("POST / HTTP/1.1\r\nHost: h\r\nContent-Length: -1\r\n\r\n"), 400);
  EXPECT_EQ(code("POST / HTTP/1.1\r\nHost: h\r\nContent-Length: 1\r\nContent-Length: 2\r\n\r\n"), 400);
  EXPECT_EQ(code("POST / HTTP/1.1\r\nHost: h\r\nContent-Length: 4097\r\n\r\n"), 413);
  EXPECT_EQ(code("GET /" + std::string(3000, 'a') + " HTTP/1.1\r\nHost: h\r\n\r\n"), 414);
  EXPECT_EQ(code("GET /" + std::string(3000, 'a')), 414);  // before the line ends
  EXPECT_EQ(code("GET / HTTP/1.1\r\nHost: h\r\nX: " + std::string(9000, 'a')), 431);  // before the head ends
  std::string many = "GET / HTTP/1.1\r\nHost: h\r\n";
  for (int i = 0; i < 70; i++) many += "X" + std::to_string(i) + ": 1\r\n";
  EXPECT_EQ(code(many + "\r\n"), 431);
  EXPECT_EQ(code("GET / HTTP/1.1\r\nHost: a\r\nHost: a\r\n\r\n"), 400);  // RFC 9112, 3.2: even when equal
  EXPECT_EQ(code(std::string(40, 'A') + " / HTTP/1.1\r\nHost: h\r\n\r\n"), 400);  // method over 32 bytes
}

// Bytes that cannot begin a request line are refused as soon as that is
// certain, without waiting for a line feed (the request timeout is 10 s).
TEST(HttpParse, NotHttpIsRefusedAtOnce) {
  auto refused = [](std::string_view s) {
    Parse p = P(s);
    EXPECT_EQ(p.status, S::Error) << s;
    return p.status == S::Error ? p.code : 0;
  };
  // a TLS 1.2 ClientHello's first bytes: record type 0x16, version 3.1
  const char hello[] = {0x16, 0x03, 0x01, 0x02, 0x00, 0x01, 0x00, 0x01, static_cast<char>(0xfc), 0x03, 0x03};
  EXPECT_EQ(refused(std::string_view(hello, sizeof hello)), 400);
  EXPECT_NE(P(std::string_view(hello, 1)).reason.find("TLS"), std::string::npos);
  EXPECT_EQ(refused(std::string(33, 'G')), 400);                  // a method that has outgrown its limit
  EXPECT_EQ(refused("GET x"), 400);                               // the target is not a path
  EXPECT_EQ(refused("GET /a\x01"), 400);                          // a control character in it
  EXPECT_EQ(refused("GET / HTTX"), 400);                          // not HTTP/
  EXPECT_EQ(refused("GET / HTTP/1.1 "), 400);                     // something after the version
  EXPECT_EQ(refused("GET / HTTP/1.1\rX"), 400);                   // a bare CR
  EXPECT_EQ(refused("GET / HTTP/1.1X"), 400);
  EXPECT_EQ(refused(" GET / HTTP/1.1"), 400);
  EXPECT_EQ(refused("GET  /"), 400);
  // ... while every prefix of a good line waits for more
  std::string good = "POST /api/write?x=1 HTTP/1.0\r";
  for (size_t k = 0; k <= good.size(); k++) EXPECT_EQ(P(good.substr(0, k)).status, S::Incomplete) << good.substr(0, k);
  // an Error for a prefix is an Error for the whole (here: a whole request)
  std::string bad = "GET /ok HTTP/1.1X\r\nHost: h\r\n\r\n";
  for (size_t k = 17; k <= bad.size(); k++) EXPECT_EQ(P(bad.substr(0, k)).status, S::Error) << k;
}

TEST(HttpParse, FormsAndEscapes) {
  EXPECT_EQ(percent_decode("%41b+c").value(), "Ab c");
  EXPECT_FALSE(percent_decode("%4"));
  EXPECT_FALSE(percent_decode("%"));
  EXPECT_FALSE(percent_decode("%zz"));
  EXPECT_FALSE(percent_decode("a%00"));
  EXPECT_EQ(form_value("device=X0&value=1&force", "value").value(), "1");
  EXPECT_EQ(form_value("device=X0&value=1&force", "force").value(), "");
  EXPECT_FALSE(form_value("device=X0", "value"));
  EXPECT_EQ(form_value("d%65vice=%58%30", "device").value(), "X0");
}

TEST(HttpParse, Responses) {
  Response r{404, "text/plain", "no", false};
  std::string t = format_response(r, false);
  EXPECT_EQ(t.rfind("HTTP/1.1 404 Not Found\r\n", 0), 0u);
  EXPECT_NE(t.find("Content-Length: 2\r\n"), std::string::npos);
  EXPECT_NE(t.find("Connection: close\r\n"), std::string::npos);
  EXPECT_EQ(t.substr(t.size() - 6), "\r\n\r\nno");
}

TEST(MonitorAddress, LoopbackUnlessAskedFor) {
  using ldc::plc::parse_monitor_address;
  EXPECT_EQ(parse_monitor_address("8080", false), std::make_pair(std::string("127.0.0.1"), uint16_t(8080)));
  EXPECT_EQ(parse_monitor_address("localhost:0", false).first, "127.0.0.1");
  EXPECT_EQ(parse_monitor_address("[::1]:9", false), std::make_pair(std::string("::1"), uint16_t(9)));
  EXPECT_THROW(parse_monitor_address("0.0.0.0:8080", false), std::runtime_error);
  EXPECT_EQ(parse_monitor_address("0.0.0.0:8080", true).first, "0.0.0.0");
  EXPECT_THROW(parse_monitor_address("127.0.0.1:70000", false), std::runtime_error);
  EXPECT_THROW(parse_monitor_address("127.0.0.1:", false), std::runtime_error);
  EXPECT_THROW(parse_monitor_address("[::1]8080", false), std::runtime_error);
}

TEST(HttpServer, RepliesAndStreams) {
  Server::Config c;
  c.port = 0;
  c.tick_ms = 20;
  Server s(c,
           [](const Request& r) {
             if (r.path == "/events") return Response{200, "text/event-stream", "", true};
             return Response{200, "text/plain", "hello " + r.path, false};
           },
           [] { return std::string("data: tick\n\n"); });
  s.start();
  ASSERT_NE(s.port(), 0);
  int a = dial(s.port());
  std::string got = exchange(a, "GET /x HTTP/1.1\r\nHost: h\r\nConnection: close\r\n\r\n");
  EXPECT_NE(got.find("200 OK"), std::string::npos);
  EXPECT_NE(got.find("hello /x"), std::string::npos);
  close(a);
  int b = dial(s.port());
  got = exchange(b, "BAD\r\n\r\n");
  EXPECT_NE(got.find("400 Bad Request"), std::string::npos);
  close(b);
  // an event stream gets the ticks
  int e = dial(s.port());
  std::string ev = exchange(e, "GET /events HTTP/1.1\r\nHost: h\r\n\r\n", false);
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  char buf[8192];
  ssize_t n = recv(e, buf, sizeof buf, 0);
  if (n > 0) ev.append(buf, size_t(n));
  EXPECT_NE(ev.find("text/event-stream"), std::string::npos);
  EXPECT_NE(ev.find("data: tick"), std::string::npos);
  close(e);
  s.stop();
}

TEST(HttpServer, HeadRepliesCarryTheLengthNotTheBody) {
  Server s({}, [](const Request&) { return Response{200, "text/plain", std::string(1612, 'b'), false}; }, nullptr);
  s.start();
  int a = dial(s.port());
  std::string got = exchange(a, "HEAD / HTTP/1.1\r\nHost: h\r\nConnection: close\r\n\r\n");
  EXPECT_EQ(got.rfind("HTTP/1.1 200 OK\r\n", 0), 0u);
  EXPECT_NE(got.find("Content-Length: 1612\r\n"), std::string::npos);  // the GET's length (RFC 9110, 9.3.2)
  EXPECT_EQ(got.substr(got.size() - 4), "\r\n\r\n") << "a body after the head";
  close(a);
  s.stop();
}

// Connections that are not idle: each has sent the start of a request.
std::vector<int> busy_connections(uint16_t port, int n, const char* from = nullptr) {
  std::vector<int> v;
  for (int i = 0; i < n; i++) {
    int fd = dial(port, from);
    EXPECT_GE(fd, 0);
    (void)!send(fd, "GET / HTTP/1.1\r\n", 16, MSG_NOSIGNAL);
    v.push_back(fd);
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(150));
  return v;
}

TEST(HttpServer, TheTableFullClosesTheOldestIdleConnectionElse503) {
  Server::Config c;
  c.max_connections = 3;
  std::vector<std::string> log;
  std::mutex log_mu;
  c.log = [&](const std::string& l) { std::lock_guard<std::mutex> g(log_mu); log.push_back(l); };
  Server s(c, [](const Request&) { return Response{200, "text/plain", "ok", false}; }, nullptr);
  s.start();
  // three idle connections: a fourth closes the oldest of them and is served
  int i1 = dial(s.port());
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  int i2 = dial(s.port()), i3 = dial(s.port());
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  int f = dial(s.port());
  EXPECT_NE(exchange(f, "GET / HTTP/1.1\r\nHost: h\r\nConnection: close\r\n\r\n").find("200 OK"), std::string::npos);
  close(f);
  EXPECT_TRUE(closed_by_peer(i1)) << "the oldest idle connection was not the one closed";
  EXPECT_EQ(settled_connections(s, 2), 2u);
  close(i1), close(i2), close(i3);
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  // three connections in the middle of a request: nothing to close, 503
  std::vector<int> held = busy_connections(s.port(), 3);
  for (int k = 0; k < 20; k++) {
    int g = dial(s.port());
    std::string got = exchange(g, "");
    EXPECT_NE(got.find("503"), std::string::npos);
    EXPECT_NE(got.find("connection cap"), std::string::npos);
    close(g);
  }
  for (int h : held) close(h);
  s.stop();
  // 20 refusals of one cause: one line (the rest counted, reported later)
  std::lock_guard<std::mutex> g(log_mu);
  EXPECT_EQ(std::count_if(log.begin(), log.end(), [](const std::string& l) { return l.find("connection cap") != std::string::npos; }), 1);
}

TEST(HttpServer, OnePeerAddressGetsItsShareOnly) {
  Server::Config c;
  c.max_connections = 8;
  c.max_per_address = 2;
  Server s(c, [](const Request&) { return Response{200, "text/plain", "ok", false}; }, nullptr);
  s.start();
  std::vector<int> a = busy_connections(s.port(), 2, "127.0.0.1");
  int third = dial(s.port(), "127.0.0.1");
  std::string got = exchange(third, "");
  EXPECT_NE(got.find("503"), std::string::npos);
  EXPECT_NE(got.find("per-address cap"), std::string::npos);
  close(third);
  // another address (127.0.0.0/8 is all loopback) is served
  int other = dial(s.port(), "127.0.0.2");
  ASSERT_GE(other, 0);
  EXPECT_NE(exchange(other, "GET / HTTP/1.1\r\nHost: h\r\nConnection: close\r\n\r\n").find("200 OK"), std::string::npos);
  close(other);
  for (int h : a) close(h);
  s.stop();
}

TEST(HttpServer, EventStreamsAreBounded) {
  Server::Config c;
  c.max_streams = 2;
  Server s(c, [](const Request&) { return Response{200, "text/event-stream", "", true}; }, [] { return std::string("data: x\n\n"); });
  s.start();
  int e1 = dial(s.port()), e2 = dial(s.port()), e3 = dial(s.port());
  EXPECT_NE(exchange(e1, "GET /e HTTP/1.1\r\nHost: h\r\n\r\n", false).find("200 OK"), std::string::npos);
  EXPECT_NE(exchange(e2, "GET /e HTTP/1.1\r\nHost: h\r\n\r\n", false).find("200 OK"), std::string::npos);
  std::string third = exchange(e3, "GET /e HTTP/1.1\r\nHost: h\r\n\r\n");
  EXPECT_NE(third.find("503"), std::string::npos);
  EXPECT_NE(third.find("stream cap"), std::string::npos);
  EXPECT_EQ(s.streams(), 2u);
  close(e1), close(e2), close(e3);
  s.stop();
}

TEST(HttpServer, ARequestsDeadlineRunsFromItsFirstByte) {
  Server::Config c;
  c.request_timeout_ms = 400;
  c.idle_timeout_ms = 60000;
  Server s(c, [](const Request&) { return Response{200, "text/plain", "ok", false}; }, nullptr);
  s.start();
  // never silent for more than 100 ms, yet never done: 408 at ~400 ms
  int t = dial(s.port());
  std::string head = "GET / HTTP/1.1\r\nHost: h\r\nX: ";
  auto start = std::chrono::steady_clock::now();
  std::string got;
  for (int i = 0; i < 30 && got.empty(); i++) {
    (void)!send(t, head.data() + std::min<size_t>(i, head.size() - 1), 1, MSG_NOSIGNAL);
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    char b[512];
    ssize_t n = recv(t, b, sizeof b, MSG_DONTWAIT);
    if (n > 0) got.assign(b, size_t(n));
  }
  double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  EXPECT_NE(got.find("408"), std::string::npos);
  EXPECT_LT(ms, 2000);
  close(t);
  s.stop();
}

TEST(HttpServer, AnIdleConnectionIsClosed) {
  Server::Config c;
  c.idle_timeout_ms = 200;
  Server s(c, [](const Request&) { return Response{200, "text/plain", "ok", false}; }, nullptr);
  s.start();
  int t = dial(s.port());
  EXPECT_NE(exchange(t, "GET / HTTP/1.1\r\nHost: h\r\n\r\n", false).find("200 OK"), std::string::npos);
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  EXPECT_EQ(settled_connections(s, 0), 0u);
  close(t);
  s.stop();
}

// A client pipelines requests and reads no reply: the server stops reading
// it once it owes max_output bytes (plus what the kernel buffers), then
// closes it when nothing drains for send_timeout.
TEST(HttpServer, UnreadRepliesStopTheReadingThenTheConnection) {
  Server::Config c;
  c.max_output = 64 << 10;
  c.send_timeout_ms = 600;
  std::atomic<int> calls{0};
  Server s(c, [&](const Request&) { calls++; return Response{200, "text/plain", std::string(64 << 10, 'r'), false}; }, nullptr);
  s.start();
  int t = dial(s.port());
  int small = 4096;
  setsockopt(t, SOL_SOCKET, SO_RCVBUF, &small, sizeof small);
  std::string many;
  for (int i = 0; i < 3000; i++) many += "GET / HTTP/1.1\r\nHost: h\r\n\r\n";
  size_t off = 0;
  for (int i = 0; i < 100 && off < many.size(); i++) {  // as much as the kernel takes
    ssize_t n = send(t, many.data() + off, many.size() - off, MSG_DONTWAIT | MSG_NOSIGNAL);
    if (n > 0) off += size_t(n);
    else std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  // 3000 requests sent, at most a few hundred answered: the kernel holds a few
  // MB of 64 KiB replies at most (tcp_wmem), the server 64 KiB more
  int answered = calls.load();
  EXPECT_LT(answered, 300);
  EXPECT_GT(answered, 0);
  std::this_thread::sleep_for(std::chrono::milliseconds(1000));
  EXPECT_EQ(settled_connections(s, 0), 0u) << "the connection was not closed after send_timeout";
  EXPECT_EQ(calls.load(), answered);
  // a well-behaved client is served all along
  int g = dial(s.port());
  EXPECT_NE(exchange(g, "GET / HTTP/1.1\r\nHost: h\r\nConnection: close\r\n\r\n").find("200 OK"), std::string::npos);
  close(g), close(t);
  s.stop();
}

// Many small requests pipelined while the replies are read: the server reads
// no more of a connection than one request's limits (plus one read) ahead of
// what it has parsed, whatever the client sends.
TEST(HttpServer, PipelinedInputIsReadOnlyAsFastAsItIsServed) {
  Server::Config c;
  std::atomic<int> calls{0};
  Server s(c, [&](const Request&) { calls++; return Response{200, "text/plain", "ok", false}; }, nullptr);
  s.start();
  int t = dial(s.port());
  const std::string one = "GET / HTTP/1.1\r\nHost: h\r\n\r\n";
  std::string many;
  for (int i = 0; i < 20000; i++) many += one;  // 560 KB
  std::thread reader([&] {
    std::string got;
    char b[65536];
    size_t n = 0;
    while (n < 20000) {
      ssize_t k = recv(t, b, sizeof b, 0);
      if (k <= 0) break;
      got.append(b, size_t(k));
      for (size_t at; (at = got.find("200 OK")) != std::string::npos;) got.erase(0, at + 6), n++;
    }
  });
  (void)!send(t, many.data(), many.size(), MSG_NOSIGNAL);
  reader.join();
  EXPECT_EQ(calls.load(), 20000);
  EXPECT_LE(s.peak_input(), c.limits.max_head + c.limits.max_body + 64 + 16384);
  close(t);
  s.stop();
}

// The largest request the limits allow (a head of 8 KiB and its blank line, a
// body of 4 KiB) is read whole and served, not left waiting for its deadline.
TEST(HttpServer, TheLargestRequestIsServed) {
  Server::Config c;
  c.request_timeout_ms = 3000;
  Server s(c, [](const Request& r) { return Response{200, "text/plain", std::to_string(r.body.size()), false}; }, nullptr);
  s.start();
  std::string head = "POST / HTTP/1.1\r\nHost: h\r\nConnection: close\r\nContent-Length: 4096\r\nX: ";
  head += std::string(c.limits.max_head + 2 - head.size() - 4, 'p') + "\r\n\r\n";
  ASSERT_EQ(head.size(), c.limits.max_head + 2);
  EXPECT_EQ(parse_request(head + std::string(4096, 'b'), c.limits).status, S::Done);
  int t = dial(s.port());
  // all but its last 2 bytes, then those: the server must still be reading
  std::string whole = head + std::string(4096, 'b');
  (void)!send(t, whole.data(), whole.size() - 2, MSG_NOSIGNAL);
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  std::string got = ::exchange(t, whole.substr(whole.size() - 2));
  EXPECT_EQ(got.rfind("HTTP/1.1 200 OK", 0), 0u) << got.substr(0, 100);
  EXPECT_EQ(got.substr(got.size() - 4), "4096");
  close(t);
  s.stop();
}

// A handler that cannot answer yet parks the request; the server thread
// serves the others meanwhile and asks again.
TEST(HttpServer, ParkedRequestsDoNotBlockTheServer) {
  Server::Config c;
  c.max_park_ms = 700;
  std::atomic<bool> ready{false};
  Server s(c,
           [&](const Request& r) {
             if (r.path == "/wait" && !ready.load()) return Response{200, "", "", false, true};
             if (r.path == "/never") return Response{200, "", "", false, true};
             return Response{200, "text/plain", r.path + " after " + std::to_string(r.retries) + " retries", false};
           },
           nullptr);
  s.start();
  int w = dial(s.port());
  (void)!send(w, "GET /wait HTTP/1.1\r\nHost: h\r\nConnection: close\r\n\r\n", 50, MSG_NOSIGNAL);
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  int o = dial(s.port());
  auto t0 = std::chrono::steady_clock::now();
  EXPECT_NE(exchange(o, "GET /other HTTP/1.1\r\nHost: h\r\nConnection: close\r\n\r\n").find("/other after 0"), std::string::npos);
  double waited = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_LT(waited, 500);
  ready.store(true);
  std::string got = exchange(w, "");
  EXPECT_NE(got.find("200 OK"), std::string::npos);
  EXPECT_NE(got.find("/wait after "), std::string::npos);
  EXPECT_EQ(got.find("after 0 "), std::string::npos);
  close(w), close(o);
  int n = dial(s.port());
  EXPECT_NE(exchange(n, "GET /never HTTP/1.1\r\nHost: h\r\n\r\n").find("503"), std::string::npos);  // max_park_ms
  close(n);
  s.stop();
}
