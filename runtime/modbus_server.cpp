// runtime/modbus_server.cpp -- the Modbus TCP server of `ldrun --modbus`
// (runtime/modbus.h): an IoDriver decorator and a network thread.
//
// The scan threads and the network thread share one mutex, held only for
// copies: after each scan the task's thread copies the areas of the map into
// a snapshot, which the network thread answers reads from (so a read never
// sees half a scan, and two registers of one word never tear); write
// requests are queued, applied by the addressed task at its next scan
// boundary (shared areas on the global image before its inputs are copied
// in, D and F on its memory), and answered after that scan's snapshot, so a
// client that writes and then reads sees its write.  The scan never waits on
// the network.
#include <arpa/inet.h>
#include <fcntl.h>
#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/eventfd.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <deque>
#include <list>
#include <mutex>
#include <stdexcept>
#include <thread>

#include "loader/config.h"
#include "runtime/modbus.h"

namespace ldc::modbus {

using plc::IoDriver;
using plc::ScanContext;
using plc::State;

void parse_address(const std::string& text, ServerOptions& o) {
  std::string host, port = text;
  if (!text.empty() && text[0] == '[') {
    size_t close = text.find("]:");
    if (close == std::string::npos) throw std::runtime_error("bad Modbus address '" + text + "' (e.g. [::1]:5020)");
    host = text.substr(1, close - 1), port = text.substr(close + 2);
  } else if (size_t colon = text.rfind(':'); colon != std::string::npos) {
    host = text.substr(0, colon), port = text.substr(colon + 1);
  }
  if (port.empty() || port.size() > 5 || port.find_first_not_of("0123456789") != std::string::npos ||
      std::stoul(port) > 65535)
    throw std::runtime_error("bad Modbus address '" + text + "' (PORT, :PORT or HOST:PORT; port 0..65535)");
  o.host = host.empty() ? "127.0.0.1" : host;
  o.port = uint16_t(std::stoul(port));
}

namespace {

int64_t now_ms() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// A write request on its way: queued, taken by its task's scan, done after
// that scan's snapshot (or cancelled by the network thread on timeout).
struct Pending {
  size_t task;
  std::vector<Write> writes;
  enum { Queued, Applied, Done, Cancelled } state = Queued;
  bool private_applied = false;  // D and F written into the task's memory
};

struct Conn {
  int fd;
  std::string peer;
  std::vector<uint8_t> in, out;
  int64_t last_ms;
  std::shared_ptr<Pending> pending;   // a write waiting for its scan
  std::vector<uint8_t> pending_reply;
  int64_t pending_deadline = 0;
  bool closing = false;
};

class ModbusDriver : public IoDriver {
 public:
  ModbusDriver(std::unique_ptr<IoDriver> inner, ServerOptions o) : inner_(std::move(inner)), o_(std::move(o)) {
    if (o_.tasks == 0) o_.tasks = 1;
    listen_fd_ = open_listener();
    wake_fd_ = eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
    if (wake_fd_ < 0) {
      ::close(listen_fd_);
      throw std::runtime_error(std::string("modbus: eventfd: ") + std::strerror(errno));
    }
  }
  ~ModbusDriver() override {
    stop_thread();
    for (Conn& c : conns_) ::close(c.fd);
    ::close(listen_fd_);
    ::close(wake_fd_);
  }

  void attach(uint8_t* global, const Layout& layout, uint32_t block_size) override {
    inner_->attach(global, layout, block_size);
    layout_ = layout;
    snap_global_.assign(layout.size, 0);
    snap_tasks_.assign(o_.tasks, std::vector<uint8_t>(layout.size, 0));
    inflight_.resize(o_.tasks);
    copy_global(global);
    thread_ = std::thread([this] { serve_loop(); });
  }
  void read_inputs(uint8_t* global, const ScanContext& c) override {
    inner_->read_inputs(global, c);
    std::lock_guard<std::mutex> g(mu_);
    if (c.task >= inflight_.size()) return;
    for (auto it = queue_.begin(); it != queue_.end();) {
      Pending& p = **it;
      if (p.task != c.task) { ++it; continue; }
      for (const Write& w : p.writes)
        if (area_is_shared(w.area)) apply(w, global, layout_);
      p.state = Pending::Applied;
      inflight_[c.task].push_back(*it);
      it = queue_.erase(it);
    }
  }
  void write_outputs(const uint8_t* global, const ScanContext& c) override { inner_->write_outputs(global, c); }
  void safe_outputs(const uint8_t* global) override {
    inner_->safe_outputs(global);
    std::lock_guard<std::mutex> g(mu_);
    copy_global(global);
  }
  void state_changed(State s) override {
    inner_->state_changed(s);
    // A scan that took writes and then was not published: writes it applied
    // completely are answered (a restart may clear them as it clears all
    // non-retentive memory); one whose D/F part it had not reached yet goes
    // back to the queue, for the next scan (or exception 06 on timeout).
    bool any = false;
    {
      std::lock_guard<std::mutex> g(mu_);
      for (auto& list : inflight_) {
        for (auto it = list.rbegin(); it != list.rend(); ++it) {
          Pending& p = **it;
          if (p.private_applied) {
            p.state = Pending::Done, any = true;
          } else {
            p.state = Pending::Queued;
            queue_.push_front(*it);
          }
        }
        list.clear();
      }
    }
    if (any) wake();
  }
  void before_scan(const ScanContext& c, uint8_t* mem, std::optional<int32_t>& dt) override {
    inner_->before_scan(c, mem, dt);
    std::lock_guard<std::mutex> g(mu_);
    if (c.task >= inflight_.size()) return;
    for (auto& p : inflight_[c.task]) {
      for (const Write& w : p->writes)
        if (!area_is_shared(w.area)) apply(w, mem, layout_);
      p->private_applied = true;
    }
  }
  void after_scan(const ScanContext& c, const uint8_t* mem, const uint8_t* global) override {
    inner_->after_scan(c, mem, global);
    bool any = false;
    {
      std::lock_guard<std::mutex> g(mu_);
      copy_global(global);
      if (c.task < snap_tasks_.size()) {
        uint32_t from = layout_.offset[int(Area::D)], to = layout_.addr(Area::F, layout_.count[int(Area::F)]);
        std::memcpy(snap_tasks_[c.task].data() + from, mem + from, to - from);
        for (auto& p : inflight_[c.task]) p->state = Pending::Done, any = true;
        inflight_[c.task].clear();
      }
    }
    if (any) wake();
  }
  void detach() override {
    stop_thread();
    inner_->detach();
  }

 private:
  // ---- scan side

  // X Y M K and WX WY: two contiguous ranges of the standard layout.
  void copy_global(const uint8_t* global) {
    for (auto [a, b] : {std::pair{Area::X, Area::K}, std::pair{Area::WX, Area::WY}}) {
      uint32_t from = layout_.offset[int(a)], to = layout_.addr(b, layout_.count[int(b)]);
      std::memcpy(snap_global_.data() + from, global + from, to - from);
    }
  }
  void wake() {
    uint64_t one = 1;
    ssize_t n = ::write(wake_fd_, &one, 8);
    (void)n;  // a full counter wakes the thread all the same
  }

  // ---- network side

  int open_listener() {
    addrinfo hints{};
    hints.ai_family = AF_UNSPEC;
    hints.ai_socktype = SOCK_STREAM;
    hints.ai_flags = AI_PASSIVE | AI_NUMERICSERV;
    addrinfo* res = nullptr;
    std::string port = std::to_string(o_.port);
    int e = getaddrinfo(o_.host.c_str(), port.c_str(), &hints, &res);
    if (e != 0) throw std::runtime_error("modbus: cannot resolve '" + o_.host + "': " + gai_strerror(e));
    std::string why = "no address";
    int fd = -1;
    for (addrinfo* a = res; a && fd < 0; a = a->ai_next) {
      fd = ::socket(a->ai_family, a->ai_socktype | SOCK_NONBLOCK | SOCK_CLOEXEC, a->ai_protocol);
      if (fd < 0) { why = std::strerror(errno); continue; }
      int one = 1;
      setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
      if (::bind(fd, a->ai_addr, a->ai_addrlen) != 0 || ::listen(fd, 64) != 0) {
        why = std::strerror(errno);
        ::close(fd);
        fd = -1;
      }
    }
    freeaddrinfo(res);
    if (fd < 0) throw std::runtime_error("modbus: cannot listen on " + o_.host + ":" + port + ": " + why);
    sockaddr_storage ss{};
    socklen_t len = sizeof ss;
    getsockname(fd, reinterpret_cast<sockaddr*>(&ss), &len);
    log("ldrun: modbus: listening on " + name_of(ss) + " (" + std::to_string(o_.max_connections) +
        " connections at most; Modbus has no authentication)");
    return fd;
  }
  static std::string name_of(const sockaddr_storage& ss) {
    char host[INET6_ADDRSTRLEN] = "?";
    uint16_t port = 0;
    if (ss.ss_family == AF_INET) {
      auto* s = reinterpret_cast<const sockaddr_in*>(&ss);
      inet_ntop(AF_INET, &s->sin_addr, host, sizeof host);
      port = ntohs(s->sin_port);
      return std::string(host) + ":" + std::to_string(port);
    }
    auto* s = reinterpret_cast<const sockaddr_in6*>(&ss);
    inet_ntop(AF_INET6, &s->sin6_addr, host, sizeof host);
    return "[" + std::string(host) + "]:" + std::to_string(ntohs(s->sin6_port));
  }
  void log(const std::string& m) {
    if (o_.log) o_.log(m);
  }
  void stop_thread() {
    if (!thread_.joinable()) return;
    stopping_ = true;
    wake();
    thread_.join();
  }

  void serve_loop() {
    std::vector<pollfd> fds;
    std::vector<Conn*> of;
    while (!stopping_) {
      fds.clear(), of.clear();
      fds.push_back({listen_fd_, POLLIN, 0});
      fds.push_back({wake_fd_, POLLIN, 0});
      int64_t now = now_ms(), next = now + 1000;
      for (Conn& c : conns_) {
        short ev = 0;
        if (!c.pending && c.in.size() < 4096 && c.out.size() < 65536) ev |= POLLIN;
        if (!c.out.empty()) ev |= POLLOUT;
        fds.push_back({c.fd, ev, 0});
        of.push_back(&c);
        next = std::min(next, c.pending ? c.pending_deadline : c.last_ms + o_.idle_timeout_ms);
      }
      int r = ::poll(fds.data(), fds.size(), int(std::max<int64_t>(0, next - now)));
      if (r < 0 && errno != EINTR) {
        log(std::string("ldrun: modbus: poll: ") + std::strerror(errno));
        break;
      }
      if (r > 0 && (fds[1].revents & POLLIN)) {
        uint64_t n;
        ssize_t k = ::read(wake_fd_, &n, 8);
        (void)k;
      }
      for (size_t i = 0; i < of.size(); i++) on_ready(*of[i], fds[i + 2].revents);
      finish_writes();
      expire();
      if (r > 0 && (fds[0].revents & POLLIN)) accept_all();
      conns_.remove_if([](Conn& c) {
        if (c.closing) ::close(c.fd);
        return c.closing;
      });
    }
  }

  void accept_all() {
    while (true) {
      sockaddr_storage ss{};
      socklen_t len = sizeof ss;
      int fd = ::accept4(listen_fd_, reinterpret_cast<sockaddr*>(&ss), &len, SOCK_NONBLOCK | SOCK_CLOEXEC);
      if (fd < 0) {
        if (errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR && errno != ECONNABORTED)
          log(std::string("ldrun: modbus: accept: ") + std::strerror(errno));
        return;
      }
      if (conns_.size() >= o_.max_connections) {
        ::close(fd);
        if (refused_++ % 100 == 0)
          log("ldrun: modbus: refused a connection from " + name_of(ss) + ": " + std::to_string(o_.max_connections) +
              " connections are open (" + std::to_string(refused_) + " refused so far)");
        continue;
      }
      int one = 1;
      setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
      conns_.push_back(Conn{fd, name_of(ss), {}, {}, now_ms()});
    }
  }

  void on_ready(Conn& c, short ev) {
    if (c.closing) return;
    if (ev & POLLIN) {
      uint8_t buf[4096];
      ssize_t n = ::recv(c.fd, buf, sizeof buf, 0);
      if (n == 0 || (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR)) {
        c.closing = true;
        return;
      }
      if (n > 0) {
        c.in.insert(c.in.end(), buf, buf + n);
        c.last_ms = now_ms();
        handle_requests(c);
      }
    } else if (ev & (POLLERR | POLLHUP | POLLNVAL)) {
      c.closing = true;
      return;
    }
    if ((ev & POLLOUT) && !c.out.empty()) flush(c);
  }

  void flush(Conn& c) {
    ssize_t n = ::send(c.fd, c.out.data(), c.out.size(), MSG_NOSIGNAL);
    if (n < 0) {
      if (errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR) c.closing = true;
      return;
    }
    c.out.erase(c.out.begin(), c.out.begin() + n);
  }

  // Serves the complete requests of c.in, in order; stops at a write until
  // its scan is done.
  void handle_requests(Conn& c) {
    while (!c.pending && !c.closing) {
      Outcome o;
      {
        std::lock_guard<std::mutex> g(mu_);
        View v{&layout_, snap_global_.data(), {}};
        for (auto& t : snap_tasks_) v.tasks.push_back(t.data());
        o = serve(c.in, v);
        if (o.kind == Outcome::Reply && !o.writes.empty()) {
          c.pending = std::make_shared<Pending>(Pending{o.task, std::move(o.writes)});
          queue_.push_back(c.pending);
        }
      }
      if (o.kind == Outcome::NeedMore) break;
      c.in.erase(c.in.begin(), c.in.begin() + o.consumed);
      if (o.kind == Outcome::Close) {
        log("ldrun: modbus: closed the connection from " + c.peer + ": " + o.error);
        c.closing = true;
        break;
      }
      if (c.pending) {
        c.pending_reply = std::move(o.reply);
        c.pending_deadline = now_ms() + o_.write_timeout_ms;
      } else {
        c.out.insert(c.out.end(), o.reply.begin(), o.reply.end());
      }
    }
    if (!c.out.empty()) flush(c);
  }

  // Writes whose scan is done get their reply; the connection goes on.
  void finish_writes() {
    for (Conn& c : conns_) {
      if (!c.pending || c.closing) continue;
      bool done;
      {
        std::lock_guard<std::mutex> g(mu_);
        done = c.pending->state == Pending::Done;
      }
      if (!done) continue;
      c.pending.reset();
      c.out.insert(c.out.end(), c.pending_reply.begin(), c.pending_reply.end());
      c.last_ms = now_ms();
      handle_requests(c);
    }
  }

  // Idle connections close; writes no scan took in time are cancelled and
  // answered with exception 06 (server busy: the runtime is not running).
  void expire() {
    int64_t now = now_ms();
    for (Conn& c : conns_) {
      if (c.closing) continue;
      if (!c.pending) {
        if (now - c.last_ms >= o_.idle_timeout_ms) {
          log("ldrun: modbus: closed the connection from " + c.peer + ": idle for " +
              std::to_string(o_.idle_timeout_ms / 1000) + " s");
          c.closing = true;
        }
        continue;
      }
      if (now < c.pending_deadline) continue;
      bool cancelled = false;
      {
        std::lock_guard<std::mutex> g(mu_);
        if (c.pending->state == Pending::Queued) {
          c.pending->state = Pending::Cancelled;
          std::erase(queue_, c.pending);
          cancelled = true;
        }
      }
      if (!cancelled) continue;  // taken by a scan: it will be done
      std::vector<uint8_t>& r = c.pending_reply;  // the echo becomes an exception reply
      uint8_t fc = r[kMbapSize];
      r.resize(kMbapSize);
      r[4] = 0, r[5] = 3;
      r.push_back(uint8_t(fc | 0x80));
      r.push_back(kServerBusy);
      c.pending->state = Pending::Done;
    }
    finish_writes();
  }

  std::unique_ptr<IoDriver> inner_;
  ServerOptions o_;
  int listen_fd_ = -1, wake_fd_ = -1;
  std::thread thread_;
  std::atomic<bool> stopping_{false};
  std::list<Conn> conns_;
  uint64_t refused_ = 0;

  // shared by the scan threads and the network thread
  std::mutex mu_;
  Layout layout_;
  std::vector<uint8_t> snap_global_;
  std::vector<std::vector<uint8_t>> snap_tasks_;
  std::deque<std::shared_ptr<Pending>> queue_;
  std::vector<std::vector<std::shared_ptr<Pending>>> inflight_;
};

}  // namespace

std::unique_ptr<IoDriver> make_modbus_driver(std::unique_ptr<IoDriver> inner, ServerOptions o) {
  return std::make_unique<ModbusDriver>(std::move(inner), std::move(o));
}

}  // namespace ldc::modbus
