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

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cstring>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "runtime/failsafe.h"

namespace ldc::http {
namespace {

bool is_tchar(char c) {
  return c != '\0' && (std::isalnum(static_cast<unsigned char>(c)) || std::strchr("!#$%&'*+-.^_`|~", c) != nullptr);
}
bool is_token(std::string_view s) {
  if (s.empty()) return false;
  for (char c : s)
    if (!is_tchar(c)) return false;
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

const char* const kBadLine = "malformed request line (expected: METHOD /path HTTP/1.1)";

// The request line received so far (no line feed yet), judged as far as it
// goes: an Error as soon as no ending can make it a request line the full
// check below accepts -- so a TLS hello or binary junk is refused at its
// first byte, not after the request timeout.  Every Error here is one there.
std::optional<Parse> refuse_line_prefix(std::string_view s, const Limits& lim) {
  size_t i = 0;
  for (; i < s.size() && s[i] != ' '; i++) {  // method
    if (!is_tchar(s[i]))
      return error(400, s[0] == 0x16 ? "not an HTTP request (a TLS handshake? this monitor speaks plain http://)"
                                     : "malformed method");
    if (i + 1 > lim.max_method) return error(400, "method longer than " + std::to_string(lim.max_method) + " bytes");
  }
  if (i == s.size()) return std::nullopt;
  if (i == 0) return error(400, kBadLine);
  const size_t t0 = ++i;
  for (; i < s.size() && s[i] != ' '; i++) {  // target
    unsigned char c = static_cast<unsigned char>(s[i]);
    if (i == t0 && c != '/') return error(400, "the request target must be a path starting with '/'");
    if (c <= 0x20 || c >= 0x7f) return error(400, "control or non-ASCII character in the request target");
    if (i - t0 + 1 > lim.max_target) return error(414, "request target longer than " + std::to_string(lim.max_target) + " bytes");
  }
  if (i == s.size()) return std::nullopt;
  if (i == t0) return error(400, kBadLine);
  const size_t v0 = ++i;
  static const char kShape[] = "HTTP/0.0";  // 0: any digit; then CR, or the line feed to come
  for (; i < s.size(); i++) {
    size_t k = i - v0;
    char c = s[i];
    if (k == 8) return c == '\r' && i + 1 == s.size() ? std::nullopt : std::optional<Parse>(error(400, kBadLine));
    bool fits = kShape[k] == '0' ? std::isdigit(static_cast<unsigned char>(c)) != 0 : c == kShape[k];
    if (!fits) return error(400, "malformed HTTP version");
  }
  return std::nullopt;
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
  if (first_eol == std::string_view::npos)
    if (std::optional<Parse> e = refuse_line_prefix(buf, lim)) return std::move(*e);
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
    return error(400, kBadLine);
  std::string_view method = rl.substr(0, sp1), target = rl.substr(sp1 + 1, sp2 - sp1 - 1), version = rl.substr(sp2 + 1);
  if (!is_token(method)) return error(400, "malformed method");
  if (method.size() > lim.max_method) return error(400, "method longer than " + std::to_string(lim.max_method) + " bytes");
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
  if (std::count_if(r.headers.begin(), r.headers.end(), [](const auto& h) { return h.first == "host"; }) > 1)
    return error(400, "more than one Host header (RFC 9112, section 3.2)");
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
    case 202: return "Accepted";
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

std::string format_response(const Response& r, bool keep_alive, bool head_only) {
  std::string h = "HTTP/1.1 " + std::to_string(r.code) + " " + status_text(r.code) + "\r\n";
  h += "Content-Type: " + r.type + "\r\n";
  h += "Cache-Control: no-store\r\nX-Content-Type-Options: nosniff\r\nReferrer-Policy: no-referrer\r\n";
  h += "Content-Security-Policy: default-src 'self'; style-src 'self'; script-src 'self'; img-src 'self' data:; "
       "frame-ancestors 'none'\r\n";
  if (r.stream) return h + (head_only ? "Connection: close\r\n\r\n" : "Connection: keep-alive\r\n\r\n");
  h += "Content-Length: " + std::to_string(r.body.size()) + "\r\n";
  h += keep_alive ? "Connection: keep-alive\r\n" : "Connection: close\r\n";
  return h + "\r\n" + (head_only ? std::string() : r.body);
}

// ---------------------------------------------------------------- the server

namespace {

int64_t now_ms() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// One line per cause per interval: the first is written at once, the others
// are counted and reported with the next line of that cause (or when the
// interval is over), so a flood of one event costs a few lines, not millions.
class LogThrottle {
 public:
  LogThrottle(std::function<void(const std::string&)> out, int interval_ms) : out_(std::move(out)), interval_(interval_ms) {}
  // `cause` is one of a fixed set of keys (never a peer address: the map stays small).
  void log(const std::string& cause, const std::string& line, int64_t now) {
    if (!out_) return;
    Cause& c = causes_[cause];
    if (c.written && now - c.since < interval_) {
      c.suppressed++;
      c.last = line;
      return;
    }
    out_(line + suppressed_note(c));
    c = Cause{true, now, 0, {}};
  }
  void flush(int64_t now) {
    if (!out_) return;
    for (auto& [cause, c] : causes_)
      if (c.suppressed && now - c.since >= interval_) {
        out_(c.last + suppressed_note(c));
        c = Cause{true, now, 0, {}};
      }
  }

 private:
  struct Cause {
    bool written = false;
    int64_t since = 0;
    uint64_t suppressed = 0;
    std::string last;
  };
  std::string suppressed_note(const Cause& c) const {
    if (!c.suppressed) return "";
    return " (" + std::to_string(c.suppressed) + " more like it in the last " + std::to_string(interval_ / 1000) + " s not shown)";
  }
  std::function<void(const std::string&)> out_;
  int64_t interval_;
  std::map<std::string, Cause> causes_;
};

struct Conn {
  int fd = -1;
  std::string peer;              // the client's address, without its port
  std::string in, out;
  size_t sent = 0;               // bytes of `out` already sent
  bool stream = false;           // an event stream: no more requests are read
  bool closing = false;          // no more requests: closed once `out` is sent
  bool dead = false;             // closed at the end of this round, unsent output dropped
  bool eof = false;              // the client sent its last byte
  bool need_bytes = false;       // `in` holds only the start of a request
  std::optional<Request> parked; // asked again until it is answered
  int64_t parked_at = 0;
  int64_t request_since = -1;    // the first byte of the request being received
  int64_t last_active = 0;       // last byte received or reply queued
  int64_t last_progress = 0;     // last time unsent output shrank (or appeared)
  int64_t over_since = -1;       // unsent output above max_output since then
  size_t unsent() const { return out.size() - sent; }
  bool idle() const { return !stream && !closing && !dead && !parked && in.empty() && unsent() == 0; }
};

void set_nonblock(int fd) { fcntl(fd, F_SETFL, fcntl(fd, F_GETFL) | O_NONBLOCK); }

std::string peer_address(const sockaddr_storage& ss) {
  char b[INET6_ADDRSTRLEN] = "?";
  if (ss.ss_family == AF_INET) {
    inet_ntop(AF_INET, &reinterpret_cast<const sockaddr_in&>(ss).sin_addr, b, sizeof b);
  } else if (ss.ss_family == AF_INET6) {
    inet_ntop(AF_INET6, &reinterpret_cast<const sockaddr_in6&>(ss).sin6_addr, b, sizeof b);
    if (std::strncmp(b, "::ffff:", 7) == 0 && std::strchr(b + 7, '.')) return b + 7;  // an IPv4 client of a v6 socket
  }
  return b;
}

Response plain(int code, const std::string& why) {
  return Response{code, "text/plain; charset=utf-8", std::to_string(code) + " " + status_text(code) + ": " + why + "\n", false};
}

}  // namespace

// The state of one run of the server loop: its connections and what it does
// to them.  Everything here runs on the server thread.
struct Server::Loop {
  Server& s;
  const Config& cfg;
  std::vector<std::unique_ptr<Conn>> conns;
  LogThrottle logs;
  int64_t accept_rest_until = 0;  // the listener is not polled before then

  explicit Loop(Server& srv) : s(srv), cfg(srv.cfg_), logs(srv.cfg_.log, srv.cfg_.log_interval_ms) {}

  // Back-pressure: a connection we owe replies to is not read, nor one that
  // holds more bytes not parsed yet than the largest request (head, its
  // blank line, body): those hold a whole request or an error, served first.
  bool reads(const Conn& c) const {
    return !c.closing && !c.dead && !c.stream && !c.parked && !c.eof && c.unsent() <= cfg.max_output &&
           c.in.size() < cfg.limits.max_head + cfg.limits.max_body + 64;
  }
  bool serves(const Conn& c) const {
    return !c.closing && !c.dead && !c.stream && !c.parked && c.unsent() <= cfg.max_output;
  }

  void queue(Conn& c, std::string_view bytes, int64_t now) {
    if (c.unsent() == 0) {
      c.out.clear(), c.sent = 0;
      c.last_progress = now;
    } else if (c.sent > c.out.size() / 2) {
      c.out.erase(0, c.sent), c.sent = 0;
    }
    c.out.append(bytes);
    if (c.unsent() > cfg.max_output && c.over_since < 0) c.over_since = now;
  }

  void reply_error(Conn& c, int code, const std::string& why, int64_t now) {
    queue(c, format_response(plain(code, why), false), now);
    c.closing = true;
    c.in.clear();
  }

  // ---- connections in

  // A connection is taken if there is room for it, made by closing the
  // oldest idle connection of its peer (at the per-address cap) or of anyone
  // (table full); else it gets 503.
  void accept_all(int64_t now) {
    while (true) {
      sockaddr_storage ss{};
      socklen_t len = sizeof ss;
      int fd = accept4(s.listen_fd_, reinterpret_cast<sockaddr*>(&ss), &len, SOCK_CLOEXEC | SOCK_NONBLOCK);
      if (fd >= 0) {
        admit(fd, peer_address(ss), now);
        continue;
      }
      if (errno == EINTR || errno == ECONNABORTED || errno == EPROTO) continue;
      if (errno == EAGAIN || errno == EWOULDBLOCK) return;
      // EMFILE, ENFILE, ENOBUFS, ENOMEM...: the pending connection stays
      // queued and the listener readable; polling it again at once would spin.
      int e = errno;
      accept_rest_until = now + cfg.accept_backoff_ms;
      logs.log(std::string("accept:") + std::to_string(e),
               "ldrun: monitor: accept: " + std::string(std::strerror(e)) + "; new connections wait " +
                   std::to_string(cfg.accept_backoff_ms) + " ms",
               now);
      return;
    }
  }

  void admit(int fd, const std::string& peer, int64_t now) {
    size_t live = 0, same = 0;
    Conn *oldest = nullptr, *oldest_same = nullptr;
    for (auto& c : conns) {
      if (c->dead) continue;
      live++;
      bool mine = c->peer == peer;
      same += mine;
      if (!c->idle()) continue;
      if (!oldest || c->last_active < oldest->last_active) oldest = c.get();
      if (mine && (!oldest_same || c->last_active < oldest_same->last_active)) oldest_same = c.get();
    }
    Conn* evict = nullptr;
    std::string why;
    if (same >= cfg.max_per_address) {
      if (!(evict = oldest_same))
        why = std::to_string(same) + " connections from " + peer + " already (the per-address cap)";
    } else if (live >= cfg.max_connections) {
      if (!(evict = oldest)) why = std::to_string(live) + " connections already, none idle (the connection cap)";
    }
    if (!why.empty()) {
      std::string busy = format_response(plain(503, "too many monitor connections: " + why), false);
      (void)!send(fd, busy.data(), busy.size(), MSG_NOSIGNAL | MSG_DONTWAIT);
      close(fd);
      logs.log(same >= cfg.max_per_address ? "refused:peer" : "refused:full", "ldrun: monitor: refused a connection: " + why, now);
      return;
    }
    if (evict) evict->dead = true;  // idle: nothing in flight is lost
    auto c = std::make_unique<Conn>();
    c->fd = fd;
    c->peer = peer;
    c->last_active = now;
    conns.push_back(std::move(c));
  }

  void receive(Conn& c, int64_t now) {
    char tmp[16384];
    ssize_t k = recv(c.fd, tmp, sizeof tmp, 0);
    if (k > 0) {
      if (c.in.empty()) c.request_since = now;  // a request's deadline runs from its first byte
      c.in.append(tmp, size_t(k));
      if (c.in.size() > s.peak_input_.load(std::memory_order_relaxed)) s.peak_input_.store(c.in.size(), std::memory_order_relaxed);
      c.need_bytes = false;
      c.last_active = now;
    } else if (k == 0) {
      c.eof = true;  // requests already received are still answered
    } else if (errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR) {
      c.dead = true;
    }
  }

  // ---- requests

  Response call(const Request& r) {
    try {
      return s.handler_(r);
    } catch (std::exception& e) {
      return plain(500, e.what());
    }
  }

  void answer(Conn& c, const Request& req, Response r, int64_t now) {
    bool head = req.method == "HEAD";
    if (r.stream && !head) {
      if (s.nstream_.load() >= cfg.max_streams) {
        r = plain(503, "too many event streams (" + std::to_string(cfg.max_streams) + ", the stream cap)");
        logs.log("refused:streams", "ldrun: monitor: refused an event stream: " + std::to_string(cfg.max_streams) + " open", now);
      } else {
        queue(c, format_response(r, true) + r.body, now);
        c.stream = true;
        s.nstream_.fetch_add(1);
        return;
      }
    }
    bool ka = req.keep_alive() && r.code < 400 && !r.stream;
    queue(c, format_response(r, ka, head), now);
    if (!ka) c.closing = true;
  }

  // Answers the complete requests in `c.in`, up to the round's budget, while
  // the replies owed to the client stay under the bound.
  void serve(Conn& c, int64_t now) {
    for (size_t n = 0; n < cfg.requests_per_round && serves(c) && !c.in.empty(); n++) {
      Parse p = parse_request(c.in, cfg.limits);
      if (p.status == Parse::Status::Incomplete) {
        c.need_bytes = true;
        break;
      }
      if (p.status == Parse::Status::Error) {
        reply_error(c, p.code, p.reason, now);
        break;
      }
      c.in.erase(0, p.consumed);
      c.request_since = c.in.empty() ? -1 : now;
      c.last_active = now;
      failsafe::inject("http");  // the test hook of docs/faults.md (LDC_FAULT_INJECT=http:...), outside call()'s catch
      Response r = call(p.req);
      if (r.defer) {
        c.parked = std::move(p.req);
        c.parked_at = now;
        break;
      }
      answer(c, p.req, std::move(r), now);
    }
    if (c.eof && serves(c) && (c.in.empty() || c.need_bytes)) c.closing = true;
  }

  void retry_parked(Conn& c, int64_t now) {
    Request& q = *c.parked;
    q.retries++;
    q.waited_ms = now - c.parked_at;
    Response r = q.waited_ms > cfg.max_park_ms ? plain(503, "no answer within " + std::to_string(cfg.max_park_ms) + " ms")
                                               : call(q);
    if (r.defer) return;
    Request req = std::move(q);
    c.parked.reset();
    answer(c, req, std::move(r), now);
  }

  // ---- deadlines

  void expire(Conn& c, int64_t now) {
    if (c.dead) return;
    if (c.unsent() > 0 && now - c.last_progress > cfg.send_timeout_ms) {
      drop(c, "replies not read for " + std::to_string(cfg.send_timeout_ms / 1000) + " s", now);
    } else if (c.over_since >= 0 && now - c.over_since > cfg.send_timeout_ms) {
      drop(c, "more than " + std::to_string(cfg.max_output >> 10) + " KiB of replies unread for " +
                  std::to_string(cfg.send_timeout_ms / 1000) + " s", now);
    } else if (reads(c) && c.request_since >= 0 && now - c.request_since > cfg.request_timeout_ms) {
      reply_error(c, 408, "the request took over " + std::to_string(cfg.request_timeout_ms / 1000) + " s to arrive", now);
    } else if (c.idle() && now - c.last_active > cfg.idle_timeout_ms) {
      c.dead = true;
    }
  }

  void drop(Conn& c, const std::string& why, int64_t now) {
    c.dead = true;
    logs.log("dropped", "ldrun: monitor: closed a connection from " + c.peer + ": " + why, now);
  }

  void send_some(Conn& c, int64_t now) {
    while (c.unsent() > 0) {
      ssize_t n = send(c.fd, c.out.data() + c.sent, c.unsent(), MSG_NOSIGNAL);
      if (n > 0) {
        c.sent += size_t(n);
        c.last_progress = now;
        continue;
      }
      if (n < 0 && errno == EINTR) continue;
      if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) break;
      c.dead = true;  // the peer is gone
      return;
    }
    if (c.unsent() == 0) c.out.clear(), c.sent = 0;
    if (c.unsent() <= cfg.max_output) c.over_since = -1;
    if (c.closing && c.unsent() == 0) c.dead = true;
  }

  void tick(int64_t now) {
    std::string ev = s.tick_ ? s.tick_() : std::string();
    logs.flush(now);
    if (ev.empty()) return;
    for (auto& c : conns) {
      if (!c->stream || c->dead) continue;
      if (c->unsent() > cfg.max_pending)
        drop(*c, "event stream " + std::to_string(cfg.max_pending >> 10) + " KiB behind", now);
      else
        queue(*c, ev, now);
    }
  }

  void sweep() {
    for (size_t i = 0; i < conns.size();) {
      Conn& c = *conns[i];
      if (!c.dead) {
        i++;
        continue;
      }
      if (c.stream) s.nstream_.fetch_sub(1);
      close(c.fd);
      conns.erase(conns.begin() + long(i));
    }
    s.nconn_.store(conns.size());
  }

  // How long poll may wait: until the next tick, sooner while requests are
  // parked or the listener rests, not at all while requests wait in a buffer.
  int wait_ms(int64_t now, int64_t next_tick) const {
    int64_t until = next_tick;
    for (const auto& c : conns) {
      if (c->parked) until = std::min(until, now + cfg.park_poll_ms);
      if (serves(*c) && !c->in.empty() && !c->need_bytes) return 0;
    }
    if (accept_rest_until > now) until = std::min(until, accept_rest_until);
    return int(std::clamp<int64_t>(until - now, 0, 1000));
  }

  void run() {
    int64_t next_tick = now_ms() + cfg.tick_ms;
    std::vector<pollfd> fds;
    while (!s.stop_.load()) {
      int64_t now = now_ms();
      fds.clear();
      bool listening = now >= accept_rest_until;
      fds.push_back({listening ? s.listen_fd_ : -1, POLLIN, 0});
      fds.push_back({s.wake_[0], POLLIN, 0});
      for (auto& c : conns) fds.push_back({c->fd, short((reads(*c) ? POLLIN : 0) | (c->unsent() ? POLLOUT : 0)), 0});
      int n = poll(fds.data(), fds.size(), wait_ms(now, next_tick));
      if (n < 0 && errno != EINTR) {
        logs.log("poll", std::string("ldrun: monitor: poll: ") + std::strerror(errno), now);
        poll(nullptr, 0, cfg.accept_backoff_ms);  // never spin on a failing poll
        continue;
      }
      now = now_ms();
      const size_t polled = fds.size() - 2;  // connections accepted below were not polled yet
      for (size_t i = 0; n > 0 && i < polled; i++) {
        Conn& c = *conns[i];
        short re = fds[i + 2].revents;
        if (reads(c) && (re & (POLLIN | POLLHUP | POLLERR))) receive(c, now);
        else if (re & (POLLHUP | POLLERR)) c.dead = true;  // not read: the hang-up would wake poll forever
      }
      if (n > 0 && (fds[0].revents & POLLIN)) accept_all(now);
      for (auto& c : conns)
        if (c->parked && !c->dead) retry_parked(*c, now);
      for (auto& c : conns)
        if (!c->dead) serve(*c, now);
      for (auto& c : conns) expire(*c, now);
      if (now >= next_tick) {
        next_tick = now + cfg.tick_ms;
        tick(now);
      }
      for (auto& c : conns)
        if (!c->dead) send_some(*c, now);
      sweep();
      if (n > 0 && (fds[1].revents & POLLIN)) {
        char b[64];
        while (read(s.wake_[0], b, sizeof b) > 0) {}
      }
    }
    for (auto& c : conns) close(c->fd);
    conns.clear();
    s.nconn_.store(0);
    s.nstream_.store(0);
  }
};

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
  if (cfg_.bound) cfg_.bound(port_);
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

void Server::loop() { Loop(*this).run(); }

}  // namespace ldc::http
