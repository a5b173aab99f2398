// runtime/net/http.h -- the small HTTP/1.1 server behind `ldrun --monitor`
// (docs/runtime.md, "The monitor"): a request parser that is a pure function
// of the bytes received, and a poll() loop on POSIX sockets serving a bounded
// number of connections, some of them Server-Sent Event streams.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <thread>
#include <utility>
#include <vector>

namespace ldc::http {

struct Limits {
  size_t max_head = 8192;     // request line and headers, bytes (431 beyond)
  size_t max_target = 2048;   // request target, bytes (414 beyond)
  size_t max_headers = 64;    // header fields (431 beyond)
  size_t max_body = 4096;     // Content-Length (413 beyond)
};

struct Request {
  std::string method, target, path, query, version;  // path: target up to '?', not decoded
  std::vector<std::pair<std::string, std::string>> headers;  // names lower-cased, values trimmed
  std::string body;
  // The first header of that (lower-case) name.
  const std::string* header(std::string_view name) const;
  bool keep_alive() const;  // HTTP/1.1 unless "Connection: close"; 1.0 only with keep-alive
};

struct Parse {
  enum class Status { Incomplete, Done, Error } status = Status::Incomplete;
  int code = 0;            // Error: the status code to reply (400, 413, 414, 431, 501, 505)
  std::string reason;      // Error: why, for the reply body
  size_t consumed = 0;     // Done: bytes of `buf` the request took
  Request req;
};
// Parses the first request in `buf`.  Incomplete when more bytes are needed
// (never while the head is over the limit: that is an Error at once).
Parse parse_request(std::string_view buf, const Limits& lim = {});

// "%41b+c" -> "Ab c"; nullopt for a bad escape or a NUL.
std::optional<std::string> percent_decode(std::string_view s);
// Value of `name` in an application/x-www-form-urlencoded string (a query or
// a body); nullopt if absent or badly encoded.
std::optional<std::string> form_value(std::string_view form, std::string_view name);

struct Response {
  int code = 200;
  std::string type = "text/plain; charset=utf-8";
  std::string body;
  bool stream = false;  // Server-Sent Events: headers now, events later
};
const char* status_text(int code);
// Status line, headers and body (or only the head of a stream).
std::string format_response(const Response& r, bool keep_alive);

// One listening socket and its connections, on one thread.
class Server {
 public:
  using Handler = std::function<Response(const Request&)>;
  struct Config {
    std::string host = "127.0.0.1";
    uint16_t port = 0;           // 0: any free port (see port())
    size_t max_connections = 32; // beyond: 503 and close
    size_t max_pending = 1 << 20;// bytes queued to a slow client before it is dropped
    int idle_timeout_ms = 10000; // an incomplete request older than this: 408 and close
    int tick_ms = 50;            // how often `tick` runs
    Limits limits;
  };
  // `tick` runs on the server thread every tick_ms; what it returns (if not
  // empty) is sent to every event stream.
  Server(Config c, Handler h, std::function<std::string()> tick);
  ~Server();
  Server(const Server&) = delete;
  Server& operator=(const Server&) = delete;

  // Binds and listens; throws std::runtime_error with the reason.
  void start();
  void stop();  // joins the thread, closes every socket
  uint16_t port() const { return port_; }
  size_t connections() const { return nconn_.load(); }
  size_t streams() const { return nstream_.load(); }

 private:
  void loop();
  Config cfg_;
  Handler handler_;
  std::function<std::string()> tick_;
  int listen_fd_ = -1, wake_[2] = {-1, -1};
  uint16_t port_ = 0;
  std::thread th_;
  std::atomic<bool> stop_{false};
  std::atomic<size_t> nconn_{0}, nstream_{0};
};

}  // namespace ldc::http
