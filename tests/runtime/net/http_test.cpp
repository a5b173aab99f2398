// tests/runtime/net/http_test.cpp -- the monitor's HTTP request parser (a pure
// function of the bytes received), form decoding, addresses, and the server
// on a loopback socket: replies, limits, timeouts, the connection bound.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include "runtime/net/http.h"
#include "runtime/net/monitor.h"

using namespace ldc::http;
using S = Parse::Status;

namespace {

Parse P(std::string_view s, Limits l = {}) { return parse_request(s, l); }

int dial(uint16_t port) {
  int fd = socket(AF_INET, SOCK_STREAM, 0);
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

TEST(HttpServer, RepliesLimitsAndStreams) {
  Server::Config c;
  c.port = 0;
  c.max_connections = 3;
  c.idle_timeout_ms = 300;
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
  // the bound: three connections, the fourth is turned away
  int i1 = dial(s.port()), i2 = dial(s.port());
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  int f = dial(s.port());
  got = exchange(f, "");
  EXPECT_NE(got.find("503"), std::string::npos);
  close(f);
  // an incomplete request times out with 408
  got = exchange(i1, "GET / HTTP/1.1\r\n");
  EXPECT_NE(got.find("408"), std::string::npos);
  close(i1), close(i2), close(e);
  s.stop();
}
