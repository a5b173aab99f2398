// runtime/net/modbus_server.cpp -- the Modbus TCP server of `ldrun --modbus`
// (runtime/net/modbus.h): an IoDriver decorator and a network thread.
//
// The scan threads never wait on the network thread.  After each published
// scan the task's thread copies the areas of the map (X Y M K WX WY from the
// global image, D F from its memory) into the back buffer of the task's
// triple buffer and publishes it with one atomic exchange; the network
// thread answers reads from the newest published buffer, so a read never
// sees half a scan and the two registers of a D word never tear.  Write
// requests are queued (a mutex the scan side only try_locks: if the network
// thread holds it, the writes wait for the next scan), applied by the
// addressed task at its next scan boundary (shared areas on the global image
// before its inputs are copied in, D and F on its memory), and answered once
// that scan's buffer is published, so a client that writes and then reads
// sees its write.
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
#include "runtime/failsafe.h"
#include "runtime/net/modbus.h"

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
  Pending(size_t t, std::vector<Write> w) : task(t), writes(std::move(w)) {}
  size_t task;
  std::vector<Write> writes;
  enum { Queued, Applied, Done, Cancelled };
  std::atomic<int> state{Queued};  // Done: released by the scan thread, acquired by the network thread
  bool private_applied = false;    // D and F written into the task's memory (task thread, under its inflight lock)
};

// A triple buffer: one writer (a task's thread, or safe_outputs, always under
// the runtime's image lock) and one reader (the network thread) each own one
// buffer; the third is exchanged.  No lock, no wait, no data race.
struct Triple {
  static constexpr uint32_t kFresh = 4;
  std::vector<uint8_t> buf[3];
  uint64_t safe_gen[3] = {};        // the safe-state generation when the buffer was filled
  std::atomic<uint32_t> middle{1};
  uint32_t back = 0, front = 2;
  void publish() { back = middle.exchange(back | kFresh, std::memory_order_acq_rel) & 3; }
  // The newest published buffer (the reader's own from then on).
  uint32_t latest() {
    if (middle.load(std::memory_order_acquire) & kFresh) front = middle.exchange(front, std::memory_order_acq_rel) & 3;
    return front;
  }
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
    snaps_ = std::vector<Triple>(o_.tasks);
    for (Triple& t : snaps_)
      for (auto& b : t.buf) b.assign(layout.size, 0);
    inflight_ = std::vector<Inflight>(o_.tasks);
    for (size_t t = 0; t < o_.tasks; t++) fill(snaps_[t], global, nullptr), snaps_[t].publish();
    view_.layout = &layout_;
    view_.tasks.assign(o_.tasks, nullptr);
    thread_ = std::thread([this] { serve_loop(); });
  }
  // Shared areas of the queued writes for this task, before its inputs are copied in.
  void read_inputs(uint8_t* global, const ScanContext& c) override {
    inner_->read_inputs(global, c);
    if (c.task >= inflight_.size()) return;
    std::unique_lock<std::mutex> q(mu_, std::try_to_lock);
    if (!q.owns_lock() || queue_.empty()) return;  // the network thread holds it: next scan
    std::lock_guard<std::mutex> g(inflight_[c.task].mu);
    for (auto it = queue_.begin(); it != queue_.end();) {
      Pending& p = **it;
      if (p.task != c.task) { ++it; continue; }
      for (const Write& w : p.writes)
        if (area_is_shared(w.area)) apply(w, global, layout_);
      p.state.store(Pending::Applied);
      inflight_[c.task].list.push_back(*it);
      it = queue_.erase(it);
    }
  }
  void write_outputs(const uint8_t* global, const ScanContext& c) override { inner_->write_outputs(global, c); }
  // Reads of Y and WY show the safe state until the next published scan.
  void safe_outputs(const uint8_t* global) override {
    inner_->safe_outputs(global);
    safe_gen_.fetch_add(1);
  }
  void state_changed(State s) override {
    inner_->state_changed(s);
    // A scan that took writes and then was not published: writes it applied
    // completely are answered (a restart may clear them as it clears all
    // non-retentive memory); one whose D/F part it had not reached yet goes
    // back to the queue, for the next scan (or exception 06 on timeout).
    bool any = false;
    std::lock_guard<std::mutex> q(mu_);
    for (Inflight& f : inflight_) {
      std::lock_guard<std::mutex> g(f.mu);
      for (auto it = f.list.rbegin(); it != f.list.rend(); ++it) {
        Pending& p = **it;
        if (p.private_applied) {
          p.state.store(Pending::Done), any = true;
        } else {
          p.state.store(Pending::Queued);
          queue_.push_front(*it);
        }
      }
      f.list.clear();
    }
    if (any) wake();
  }
  // D and F of the writes taken, on the task's memory, just before the scan.
  void before_scan(const ScanContext& c, uint8_t* mem, std::optional<int32_t>& dt) override {
    inner_->before_scan(c, mem, dt);
    if (c.task >= inflight_.size()) return;
    std::lock_guard<std::mutex> g(inflight_[c.task].mu);  // contended only by state_changed
    for (auto& p : inflight_[c.task].list) {
      for (const Write& w : p->writes)
        if (!area_is_shared(w.area)) apply(w, mem, layout_);
      p->private_applied = true;
    }
  }
  // The scan is published: its snapshot, then the writes it took are done.
  void after_scan(const ScanContext& c, const uint8_t* mem, const uint8_t* global) override {
    inner_->after_scan(c, mem, global);
    if (c.task >= snaps_.size()) return;
    fill(snaps_[c.task], global, mem);
    snaps_[c.task].publish();
    bool any = false;
    {
      std::lock_guard<std::mutex> g(inflight_[c.task].mu);
      for (auto& p : inflight_[c.task].list) p->state.store(Pending::Done), any = true;
      inflight_[c.task].list.clear();
    }
    if (any) wake();
  }
  void detach() override {
    stop_thread();
    inner_->detach();
  }

 private:
  struct Inflight {
    std::mutex mu;
    std::vector<std::shared_ptr<Pending>> list;  // taken by the task's scan under way
  };

  // ---- scan side (under the runtime's image lock)

  // The back buffer: X Y M K and WX WY (two contiguous ranges of the standard
  // layout) from the global image, D and F from the task's memory.
  void fill(Triple& t, const uint8_t* global, const uint8_t* mem) {
    uint8_t* b = t.buf[t.back].data();
    auto copy = [&](const uint8_t* from_mem, Area first, Area last) {
      uint32_t from = layout_.offset[int(first)], to = layout_.addr(last, layout_.count[int(last)]);
      if (from_mem) std::memcpy(b + from, from_mem + from, to - from);
    };
    copy(global, Area::X, Area::K);
    copy(global, Area::WX, Area::WY);
    copy(mem, Area::D, Area::F);
    t.safe_gen[t.back] = safe_gen_.load();
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
      failsafe::inject("modbus");  // the test hook of docs/faults.md (LDC_FAULT_INJECT=modbus:...)
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

  // The view a request sees: every task's newest published buffer, shared
  // areas from the addressed task's.  If the outputs went to the safe state
  // after that scan, Y and WY read 0 (as they are).
  const View& view_for(const std::vector<uint8_t>& in) {
    for (size_t t = 0; t < snaps_.size(); t++) {
      Triple& s = snaps_[t];
      uint32_t f = s.latest();
      uint8_t* b = s.buf[f].data();
      if (s.safe_gen[f] != safe_gen_.load()) {
        for (Area a : {Area::Y, Area::WY}) std::memset(b + layout_.offset[int(a)], 0, layout_.count[int(a)] * layout_.elem_size(a));
        s.safe_gen[f] = safe_gen_.load();
      }
      view_.tasks[t] = b;
    }
    size_t unit = in.size() >= kMbapSize ? in[6] : 0;
    size_t task = unit == 0 || unit == 255 || unit > snaps_.size() ? 0 : unit - 1;
    view_.global = view_.tasks[task];
    return view_;
  }

  // Serves the complete requests of c.in, in order; stops at a write until
  // its scan is done.
  void handle_requests(Conn& c) {
    while (!c.pending && !c.closing) {
      Outcome o = serve(c.in, view_for(c.in));
      if (o.kind == Outcome::Reply && !o.writes.empty()) {
        c.pending = std::make_shared<Pending>(o.task, std::move(o.writes));
        std::lock_guard<std::mutex> g(mu_);
        queue_.push_back(c.pending);
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
      if (c.pending->state.load() != Pending::Done) continue;
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
        if (c.pending->state.load() == Pending::Queued) {
          c.pending->state.store(Pending::Cancelled);
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
      c.pending->state.store(Pending::Done);
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

  Layout layout_;
  View view_;                       // the network thread's
  std::vector<Triple> snaps_;       // per task
  std::atomic<uint64_t> safe_gen_{0};
  std::mutex mu_;                   // the queue (the scan side only try_locks it)
  std::deque<std::shared_ptr<Pending>> queue_;
  std::vector<Inflight> inflight_;  // per task
};

}  // namespace

std::unique_ptr<IoDriver> make_modbus_driver(std::unique_ptr<IoDriver> inner, ServerOptions o) {
  return std::make_unique<ModbusDriver>(std::move(inner), std::move(o));
}

}  // namespace ldc::modbus
