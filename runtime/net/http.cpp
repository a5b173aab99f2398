// runtime/net/http.cpp -- see http.h.  The grammar the parser accepts (RFC 9112,
// narrowed to what the monitor needs):
//   request = request-line *( header-field EOL ) EOL [ body ]
//   request-line = method SP origin-target SP ( "HTTP/1.1" | "HTTP/1.0" ) EOL
//   header-field = token ":" OWS value OWS          EOL = CRLF | LF
// No obsolete line folding, no Transfer-Encoding (501), a body only by
// Content-Length.
#include "runtime/net/http.h"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netdb.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cctype>
#include <chrono>
#include <cstring>
#include <memory>
#include <stdexcept>

#include "runtime/failsafe.h"

namespace ldc::http {
namespace {

bool is_tchar(char c) {
  return std::isalnum(static_cast<unsigned char>(c)) || std::strchr("!#$%&'*+-.^_`|~", c) != nullptr;
}
bool is_token(std::string_view s) {
  if (s.empty()) return false;
  for (char c : s)
    if (!is_tchar(c) || c == '\0') return false;
  return true;
}
std::string lower(std::string_view s) {
  std::string o(s);
  for (char& c : o) c = char(std::tolower(static_cast<unsigned char>(c)));
  return o;
}
Parse error(int code, std::string why) {
  Parse p;
  p.status = Parse::Status::Error;
  p.code = code;
  p.reason = std::move(why);
  return p;
}

}  // namespace

const std::string* Request::header(std::string_view name) const {
  for (const auto& [k, v] : headers)
    if (k == name) return &v;
  return nullptr;
}

bool Request::keep_alive() const {
  const std::string* c = header("connection");
  std::string v = c ? lower(*c) : "";
  if (version == "HTTP/1.0") return v == "keep-alive";
  return v.find("close") == std::string::npos;
}

// request = request-line *( header-field EOL ) EOL [ body ]
Parse parse_request(std::string_view buf, const Limits& lim) {
  // the head ends at the first empty line
  size_t head_end = std::string_view::npos, body_at = 0;
  for (size_t i = 0; i < buf.size(); i++) {
    if (buf[i] != '\n') continue;
    if (i + 1 < buf.size() && buf[i + 1] == '\n') { head_end = i + 1, body_at = i + 2; break; }
    if (i + 2 < buf.size() && buf[i + 1] == '\r' && buf[i + 2] == '\n') { head_end = i + 1, body_at = i + 3; break; }
  }
  size_t first_eol = buf.find('\n');
  if (first_eol == std::string_view::npos && buf.size() > lim.max_target + 32) return error(414, "request line too long");
  if (head_end == std::string_view::npos) {
    if (buf.size() > lim.max_head) return error(431, "request head larger than " + std::to_string(lim.max_head) + " bytes");
    // a request line that cannot be right is refused before the rest arrives
    if (first_eol == std::string_view::npos) return Parse{};
  }
  if (head_end != std::string_view::npos && body_at > lim.max_head + 2)
    return error(431, "request head larger than " + std::to_string(lim.max_head) + " bytes");

  // lines of the head, each without its EOL
  std::vector<std::string_view> lines;
  size_t end = head_end == std::string_view::npos ? first_eol + 1 : head_end;
  for (size_t s = 0; s < end;) {
    size_t nl = buf.find('\n', s);
    std::string_view l = buf.substr(s, nl - s);
    if (!l.empty() && l.back() == '\r') l.remove_suffix(1);
    if (l.find('\r') != std::string_view::npos) return error(400, "bare CR in the request head");
    lines.push_back(l);
    s = nl + 1;
  }

  // request-line = method SP origin-target SP version
  Parse p;
  Request& r = p.req;
  std::string_view rl = lines[0];
  size_t sp1 = rl.find(' '), sp2 = sp1 == std::string_view::npos ? sp1 : rl.find(' ', sp1 + 1);
  if (sp1 == std::string_view::npos || sp2 == std::string_view::npos || rl.find(' ', sp2 + 1) != std::string_view::npos)
    return error(400, "malformed request line (expected: METHOD /path HTTP/1.1)");
  std::string_view method = rl.substr(0, sp1), target = rl.substr(sp1 + 1, sp2 - sp1 - 1), version = rl.substr(sp2 + 1);
  if (!is_token(method)) return error(400, "malformed method");
  if (target.size() > lim.max_target) return error(414, "request target longer than " + std::to_string(lim.max_target) + " bytes");
  if (target.empty() || target[0] != '/') return error(400, "the request target must be a path starting with '/'");
  for (char c : target)
    if (static_cast<unsigned char>(c) <= 0x20 || static_cast<unsigned char>(c) >= 0x7f)
      return error(400, "control or non-ASCII character in the request target");
  if (version != "HTTP/1.1" && version != "HTTP/1.0") {
    if (version.size() == 8 && version.substr(0, 5) == "HTTP/" && std::isdigit(static_cast<unsigned char>(version[5])) &&
        version[6] == '.' && std::isdigit(static_cast<unsigned char>(version[7])))
      return error(505, "only HTTP/1.1 and HTTP/1.0 are served");
    return error(400, "malformed HTTP version");
  }
  if (head_end == std::string_view::npos) return Parse{};  // the line is fine; wait for the rest

  r.method = method, r.target = target, r.version = version;
  size_t q = target.find('?');
  r.path = target.substr(0, q);
  if (q != std::string_view::npos) r.query = target.substr(q + 1);

  // header-field = token ":" OWS value OWS
  for (size_t i = 1; i < lines.size(); i++) {
    std::string_view l = lines[i];
    if (l.empty()) break;
    if (l[0] == ' ' || l[0] == '\t') return error(400, "obsolete header line folding");
    size_t colon = l.find(':');
    if (colon == std::string_view::npos || !is_token(l.substr(0, colon))) return error(400, "malformed header field");
    std::string_view v = l.substr(colon + 1);
    while (!v.empty() && (v.front() == ' ' || v.front() == '\t')) v.remove_prefix(1);
    while (!v.empty() && (v.back() == ' ' || v.back() == '\t')) v.remove_suffix(1);
    for (char c : v)
      if ((static_cast<unsigned char>(c) < 0x20 && c != '\t') || c == 0x7f) return error(400, "control character in a header value");
    if (r.headers.size() >= lim.max_headers) return error(431, "more than " + std::to_string(lim.max_headers) + " header fields");
    r.headers.emplace_back(lower(l.substr(0, colon)), std::string(v));
  }
  if (r.version == "HTTP/1.1" && !r.header("host")) return error(400, "HTTP/1.1 request without Host");
  if (r.header("transfer-encoding")) return error(501, "Transfer-Encoding is not supported; send Content-Length");
  size_t length = 0;
  bool have_length = false;
  for (const auto& [k, v] : r.headers) {
    if (k != "content-length") continue;
    if (v.empty() || v.size() > 9 || v.find_first_not_of("0123456789") != std::string::npos)
      return error(400, "malformed Content-Length");
    size_t n = std::stoul(v);
    if (have_length && n != length) return error(400, "conflicting Content-Length fields");
    length = n, have_length = true;
  }
  if (length > lim.max_body) return error(413, "request body larger than " + std::to_string(lim.max_body) + " bytes");
  if (buf.size() - body_at < length) return Parse{};
  r.body = buf.substr(body_at, length);
  p.status = Parse::Status::Done;
  p.consumed = body_at + length;
  return p;
}

std::optional<std::string> percent_decode(std::string_view s) {
  std::string o;
  for (size_t i = 0; i < s.size(); i++) {
    char c = s[i];
    if (c == '+') c = ' ';
    else if (c == '%') {
      if (i + 2 >= s.size()) return std::nullopt;
      auto hex = [](char h) -> int {
        if (h >= '0' && h <= '9') return h - '0';
        h = char(std::tolower(static_cast<unsigned char>(h)));
        if (h >= 'a' && h <= 'f') return h - 'a' + 10;
        return -1;
      };
      int a = hex(s[i + 1]), b = hex(s[i + 2]);
      if (a < 0 || b < 0) return std::nullopt;
      c = char(a * 16 + b);
      i += 2;
    }
    if (c == '\0') return std::nullopt;
    o += c;
  }
  return o;
}

std::optional<std::string> form_value(std::string_view form, std::string_view name) {
  size_t s = 0;
  while (s <= form.size()) {
    size_t e = form.find('&', s);
    std::string_view kv = form.substr(s, e == std::string_view::npos ? std::string_view::npos : e - s);
    size_t eq = kv.find('=');
    auto k = percent_decode(kv.substr(0, eq));
    if (k && *k == name) return eq == std::string_view::npos ? std::optional<std::string>("") : percent_decode(kv.substr(eq + 1));
    if (e == std::string_view::npos) break;
    s = e + 1;
  }
  return std::nullopt;
}

const char* status_text(int code) {
  switch (code) {
    case 200: return "OK";
    case 204: return "No Content";
    case 400: return "Bad Request";
    case 403: return "Forbidden";
    case 404: return "Not Found";
    case 405: return "Method Not Allowed";
    case 408: return "Request Timeout";
    case 409: return "Conflict";
    case 413: return "Content Too Large";
    case 414: return "URI Too Long";
    case 415: return "Unsupported Media Type";
    case 421: return "Misdirected Request";
    case 431: return "Request Header Fields Too Large";
    case 500: return "Internal Server Error";
    case 501: return "Not Implemented";
    case 503: return "Service Unavailable";
    case 505: return "HTTP Version Not Supported";
    default: return "Unknown";
  }
}

std::string format_response(const Response& r, bool keep_alive) {
  std::string h = "HTTP/1.1 " + std::to_string(r.code) + " " + status_text(r.code) + "\r\n";
  h += "Content-Type: " + r.type + "\r\n";
  h += "Cache-Control: no-store\r\nX-Content-Type-Options: nosniff\r\n";
  h += "Content-Security-Policy: default-src 'self'; style-src 'self'; script-src 'self'; img-src 'self' data:\r\n";
  if (r.stream) return h + "Connection: keep-alive\r\n\r\n";
  h += "Content-Length: " + std::to_string(r.body.size()) + "\r\n";
  h += keep_alive ? "Connection: keep-alive\r\n" : "Connection: close\r\n";
  return h + "\r\n" + r.body;
}

// ---------------------------------------------------------------- the server

namespace {

int64_t now_ms() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

struct Conn {
  int fd = -1;
  std::string in, out;
  bool stream = false, closing = false;
  int64_t since = 0;  // start of the request being received (or of idleness)
};

void set_nonblock(int fd) { fcntl(fd, F_SETFL, fcntl(fd, F_GETFL) | O_NONBLOCK); }

}  // namespace

Server::Server(Config c, Handler h, std::function<std::string()> tick)
    : cfg_(std::move(c)), handler_(std::move(h)), tick_(std::move(tick)) {}

Server::~Server() { stop(); }

void Server::start() {
  addrinfo hints{}, *res = nullptr;
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  hints.ai_flags = AI_NUMERICHOST | AI_NUMERICSERV;
  std::string port = std::to_string(cfg_.port);
  if (int e = getaddrinfo(cfg_.host.c_str(), port.c_str(), &hints, &res); e != 0)
    throw std::runtime_error("monitor: bad address '" + cfg_.host + "': " + gai_strerror(e) + " (give a numeric address such as 127.0.0.1 or ::1)");
  std::unique_ptr<addrinfo, decltype(&freeaddrinfo)> hold(res, freeaddrinfo);
  int fd = socket(res->ai_family, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd < 0) throw std::runtime_error(std::string("monitor: socket: ") + std::strerror(errno));
  int one = 1;
  setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
  if (bind(fd, res->ai_addr, res->ai_addrlen) != 0 || listen(fd, 16) != 0) {
    int e = errno;
    close(fd);
    throw std::runtime_error("monitor: cannot listen on " + cfg_.host + ":" + port + ": " + std::strerror(e));
  }
  sockaddr_storage ss{};
  socklen_t len = sizeof ss;
  getsockname(fd, reinterpret_cast<sockaddr*>(&ss), &len);
  port_ = ntohs(ss.ss_family == AF_INET6 ? reinterpret_cast<sockaddr_in6*>(&ss)->sin6_port
                                         : reinterpret_cast<sockaddr_in*>(&ss)->sin_port);
  set_nonblock(fd);
  if (pipe2(wake_, O_CLOEXEC | O_NONBLOCK) != 0) {
    close(fd);
    throw std::runtime_error(std::string("monitor: pipe: ") + std::strerror(errno));
  }
  listen_fd_ = fd;
  th_ = std::thread([this] { loop(); });
}

void Server::stop() {
  if (!th_.joinable()) return;
  stop_.store(true);
  char c = 1;
  (void)!write(wake_[1], &c, 1);
  th_.join();
  close(listen_fd_);
  close(wake_[0]);
  close(wake_[1]);
  listen_fd_ = wake_[0] = wake_[1] = -1;
}

void Server::loop() {
  std::vector<std::unique_ptr<Conn>> conns;
  int64_t next_tick = now_ms() + cfg_.tick_ms;
  auto send_some = [](Conn& c) {  // false: the peer is gone
    while (!c.out.empty()) {
      ssize_t n = send(c.fd, c.out.data(), c.out.size(), MSG_NOSIGNAL);
      if (n > 0) { c.out.erase(0, size_t(n)); continue; }
      if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) return true;
      if (n < 0 && errno == EINTR) continue;
      return false;
    }
    return true;
  };
  auto reply_error = [](Conn& c, int code, const std::string& why) {
    Response r;
    r.code = code;
    r.body = std::to_string(code) + " " + status_text(code) + ": " + why + "\n";
    c.out += format_response(r, false);
    c.closing = true;
    c.in.clear();
  };
  while (!stop_.load()) {
    std::vector<pollfd> fds;
    fds.push_back({listen_fd_, POLLIN, 0});
    fds.push_back({wake_[0], POLLIN, 0});
    for (auto& c : conns) fds.push_back({c->fd, short((c->stream || c->closing ? 0 : POLLIN) | (c->out.empty() ? 0 : POLLOUT)), 0});
    int wait = int(std::max<int64_t>(0, next_tick - now_ms()));
    int n = poll(fds.data(), fds.size(), wait);
    if (n < 0 && errno != EINTR) break;
    int64_t now = now_ms();
    const size_t polled = fds.size() - 2;  // connections accepted below were not polled yet
    if (n > 0 && (fds[0].revents & POLLIN)) {
      while (true) {
        int fd = accept4(listen_fd_, nullptr, nullptr, SOCK_CLOEXEC | SOCK_NONBLOCK);
        if (fd < 0) break;
        if (conns.size() >= cfg_.max_connections) {
          std::string busy = format_response({503, "text/plain; charset=utf-8", "503 Service Unavailable: too many monitor connections\n"}, false);
          (void)!send(fd, busy.data(), busy.size(), MSG_NOSIGNAL | MSG_DONTWAIT);
          close(fd);
          continue;
        }
        auto c = std::make_unique<Conn>();
        c->fd = fd;
        c->since = now;
        conns.push_back(std::move(c));
      }
    }
    for (size_t i = 0; i < polled; i++) {
      if (n <= 0) break;
      Conn& c = *conns[i];
      short re = fds[i + 2].revents;
      if (re & (POLLIN | POLLHUP | POLLERR)) {
        char tmp[16384];
        ssize_t k = recv(c.fd, tmp, sizeof tmp, 0);
        if (k <= 0 && !(k < 0 && (errno == EAGAIN || errno == EINTR))) { c.closing = true, c.out.clear(); continue; }
        if (k > 0 && !c.stream && !c.closing) {
          if (c.in.empty()) c.since = now;
          c.in.append(tmp, size_t(k));
          while (!c.closing && !c.stream) {
            Parse p = parse_request(c.in, cfg_.limits);
            if (p.status == Parse::Status::Incomplete) break;
            if (p.status == Parse::Status::Error) { reply_error(c, p.code, p.reason); break; }
            c.in.erase(0, p.consumed);
            c.since = now;
            failsafe::inject("http");  // the test hook of docs/faults.md (LDC_FAULT_INJECT=http:...)
            Response r;
            try {
              r = handler_(p.req);
            } catch (std::exception& e) {
              r = Response{500, "text/plain; charset=utf-8", std::string("500 Internal Server Error: ") + e.what() + "\n"};
            }
            bool ka = p.req.keep_alive() && r.code < 400;
            c.out += format_response(r, ka || r.stream);
            if (r.stream) {
              c.stream = true;
              c.out += r.body;
              nstream_.fetch_add(1);
            } else if (!ka) {
              c.closing = true;
            }
          }
        }
      }
    }
    // idle requests, ticks, writes
    for (auto& c : conns)
      if (!c->stream && !c->closing && now - c->since > cfg_.idle_timeout_ms) {
        if (!c->in.empty()) reply_error(*c, 408, "the request took too long to arrive");
        else c->closing = true;
      }
    if (now >= next_tick) {
      next_tick = now + cfg_.tick_ms;
      std::string ev = tick_ ? tick_() : std::string();
      if (!ev.empty())
        for (auto& c : conns)
          if (c->stream) {
            if (c->out.size() > cfg_.max_pending) c->closing = true, c->out.clear();  // too slow: dropped
            else c->out += ev;
          }
    }
    for (size_t i = 0; i < conns.size();) {
      Conn& c = *conns[i];
      bool alive = send_some(c) && !(c.closing && c.out.empty());
      if (!alive) {
        if (c.stream) nstream_.fetch_sub(1);
        close(c.fd);
        conns.erase(conns.begin() + long(i));
      } else {
        i++;
      }
    }
    nconn_.store(conns.size());
    if (n > 0 && (fds[1].revents & POLLIN)) {
      char b[64];
      while (read(wake_[0], b, sizeof b) > 0) {}
    }
  }
  for (auto& c : conns) close(c->fd);
  nconn_.store(0);
  nstream_.store(0);
}

}  // namespace ldc::http
