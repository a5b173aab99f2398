// runtime/net/http.h -- the small HTTP/1.1 server behind `ldrun --monitor`
// (docs/runtime.md, "The monitor"; docs/faults.md, "The monitor (HTTP)"): a
// request parser that is a pure function of the bytes received, and a poll()
// loop on POSIX sockets serving a bounded number of connections, some of them
// Server-Sent Event streams.  Nothing on its thread sleeps or blocks: a
// handler that cannot answer yet parks its request (Response::defer) and is
// asked again; every buffer a client can fill is bounded.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <thread>
#include <utility>
#include <vector>

namespace ldc::http {

struct Limits {
  size_t max_head = 8192;     // request line and headers, bytes (431 beyond)
  size_t max_method = 32;     // method, bytes (400 beyond)
  size_t max_target = 2048;   // request target, bytes (414 beyond)
  size_t max_headers = 64;    // header fields (431 beyond)
  size_t max_body = 4096;     // Content-Length (413 beyond)
};

struct Request {
  std::string method, target, path, query, version;  // path: target up to '?', not decoded
  std::vector<std::pair<std::string, std::string>> headers;  // names lower-cased, values trimmed
  std::string body;
  // A parked request (Response::defer) asked again: how many times, and how
  // long since it was first asked (0 the first time).
  int retries = 0;
  int64_t waited_ms = 0;
  // The handler's own state for a request it parked (kept with the request).
  mutable std::shared_ptr<void> state;
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
// -- never while the head is over the limit, and never once the bytes so far
// cannot begin a request line (a TLS hello, binary data, a line with no line
// feed that has outgrown the limits): those are an Error at once.  An Error
// for a prefix of `buf` is an Error for `buf` too.
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
  bool defer = false;   // not ready: the server parks the request and asks again soon
};
const char* status_text(int code);
// Status line, headers and body (or only the head of a stream).  head_only
// (a HEAD request): the same head, Content-Length included, without the body.
std::string format_response(const Response& r, bool keep_alive, bool head_only = false);

// One listening socket and its connections, on one thread.
class Server {
 public:
  using Handler = std::function<Response(const Request&)>;
  // Every bound of the server (docs/faults.md, "The monitor (HTTP)").
  struct Config {
    std::string host = "127.0.0.1";
    uint16_t port = 0;              // 0: any free port (see port())
    size_t max_connections = 64;    // table full: the oldest idle connection is closed, else 503
    size_t max_per_address = 32;    // from one peer address: its oldest idle one is closed, else 503
    size_t max_streams = 32;        // event streams at once (503 beyond)
    size_t max_output = 256 << 10;  // unsent reply bytes above which a connection is no longer read
    size_t max_pending = 1 << 20;   // unsent event bytes beyond which a stream client is dropped
    int request_timeout_ms = 10000; // first byte of a request to its last: 408 and close beyond
    int idle_timeout_ms = 10000;    // a connection with nothing in flight that long is closed
    int send_timeout_ms = 10000;    // unsent output that does not drain (or stays above max_output) that long: closed
    int max_park_ms = 5000;         // a parked request not answered by then gets 503
    int park_poll_ms = 5;           // how often parked requests are asked again
    int accept_backoff_ms = 250;    // accept failed for lack of descriptors/memory: the listener rests this long
    size_t requests_per_round = 16; // requests of one connection served before the others get a turn
    int tick_ms = 50;               // how often `tick` runs
    int log_interval_ms = 10000;    // one log line per cause per interval; the others are counted
    Limits limits;
    std::function<void(const std::string&)> log;  // one line per call (none if empty)
    std::function<void(uint16_t port)> bound;     // by start(), listening, before any request is served
  };
  // `tick` runs on the server thread every tick_ms; what it returns (if not
  // empty) is sent to every event stream.
  // The handler runs on the server thread and must not block: it answers, or
  // returns Response::defer and is called again with the same request.
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
  // The most bytes received and not yet parsed one connection held (at most
  // the largest request, 12 KiB + 64, plus one 16 KiB read).
  size_t peak_input() const { return peak_input_.load(); }

 private:
  struct Loop;
  void loop();
  Config cfg_;
  Handler handler_;
  std::function<std::string()> tick_;
  int listen_fd_ = -1, wake_[2] = {-1, -1};
  uint16_t port_ = 0;
  std::thread th_;
  std::atomic<bool> stop_{false};
  std::atomic<size_t> nconn_{0}, nstream_{0}, peak_input_{0};
};

}  // namespace ldc::http
