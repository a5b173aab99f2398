// runtime/net/modbus_server.cpp -- the Modbus TCP server of `ldrun --modbus`
// (runtime/net/modbus.h): an IoDriver decorator and a network thread.
//
// The scan threads never wait on the network thread.
//
// Reads.  After each published scan the task's thread copies the areas of
// the map (X Y M K WX WY from the global image, D F from its memory) into the
// back buffer of the task's triple buffer and publishes it with one atomic
// exchange; the network thread answers reads from the newest published
// buffer, so a read never sees half a scan and the two registers of a D word
// never tear.
//
// Writes (docs/faults.md, "Network writes and the scan").  The network thread
// merges each write request into the addressed task's WriteShadow and gets a
// ticket; the task's scan takes the whole shadow at its boundary (try-lock
// only) and applies it in O(elements written), however many requests wrote
// them: shared areas on the global image before its inputs are copied in,
// D and F on its memory just before the scan runs.  Once that scan is
// published its ticket is `done`, and the network thread answers every write
// whose ticket is <= done -- so a client that writes and then reads sees its
// write.  A full shadow answers exception 06 at once; a write no scan took
// within the write timeout is taken back out by the network thread, with
// every write merged after it, and answered 06: not applied.
//
// Connections (docs/faults.md, "Modbus TCP").  Bounded in number, per
// address, in idle time and in the time to finish a frame; a newcomer over a
// bound takes the place of the idlest connection; a failing accept (EMFILE)
// rests the listener instead of spinning; log lines are throttled per cause.
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
#include <list>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <thread>

#include "loader/config.h"
#include "runtime/failsafe.h"
#include "runtime/net/log_throttle.h"
#include "runtime/net/modbus.h"

namespace ldc::modbus {

using plc::IoDriver;
using plc::ScanContext;
using plc::State;
using plc::WriteShadow;

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

size_t descriptors_needed(const ServerOptions& o) { return o.max_connections + 4; }

namespace {

int64_t now_ms() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// What a connection buffers at most: requests read and not served, replies
// not sent.  Past either, the server stops reading it (TCP back-pressure).
constexpr size_t kMaxIn = 4096, kMaxOut = 65536;

// The causes of log lines, each throttled on its own.
constexpr const char* kBadHeader = "closed: not Modbus";
constexpr const char* kIdle = "closed: idle";
constexpr const char* kSlowFrame = "closed: frame too slow";
constexpr const char* kEvicted = "connection replaced";
constexpr const char* kRefused = "connection refused";
constexpr const char* kAcceptFailed = "accept failed";
constexpr const char* kBusy = "write refused: busy";

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

// The writes on their way to one task.  Tickets count the requests merged
// into the shadow: every ticket <= taken has left the shadow (to a scan, or
// dropped by the network thread), every ticket <= done is in memory and
// published.
struct TaskWrites {
  explicit TaskWrites(size_t capacity) : shadow(capacity) {}
  WriteShadow shadow;
  // The task's thread try-locks it (it never waits); the network thread
  // (dropping writes) locks it, state_changed waits for it a bounded time
  // (on the fatal path a thread that failed may hold it).  Guards taken's
  // updates and:
  std::timed_mutex mu;
  WriteShadow::Batch batch;        // taken by the task's scan under way
  bool inflight = false;           // batch taken and not yet done or given back
  bool private_applied = false;    // its D and F written into the task's memory
  std::atomic<uint64_t> taken{0}, done{0};
};

// A write request waiting for its scan.
struct PendingWrite {
  size_t task;
  uint64_t ticket;
  int64_t deadline;
  std::vector<uint8_t> reply;  // the echo, sent once done
};

struct Conn {
  int fd;
  std::string peer, address;  // "HOST:PORT", and HOST alone (the per-address cap)
  int64_t last_ms;             // accepted, or the last request served: idleness
  int64_t frame_since = 0;     // the first byte of an incomplete frame arrived (0: none)
  std::vector<uint8_t> in, out;
  std::optional<PendingWrite> pending;
  bool closing = false;        // closed (fd -1); removed at the end of the loop's turn
};

// An exception 06 (server busy) answering the request whose echo is `echo`.
std::vector<uint8_t> busy_reply(std::vector<uint8_t> echo) {
  uint8_t fc = echo[kMbapSize];
  echo.resize(kMbapSize);
  echo[4] = 0, echo[5] = 3;
  echo.push_back(uint8_t(fc | 0x80));
  echo.push_back(kServerBusy);
  return echo;
}

class ModbusDriver : public IoDriver {
 public:
  ModbusDriver(std::unique_ptr<IoDriver> inner, ServerOptions o)
      : inner_(std::move(inner)), o_(std::move(o)),
        throttle_(o_.log, "ldrun: modbus: ", o_.log_burst, o_.log_window_ms) {
    if (o_.tasks == 0) o_.tasks = 1;
    o_.max_per_address = std::max<size_t>(1, std::min(o_.max_per_address, o_.max_connections));
    o_.pending_writes = std::max<size_t>(o_.pending_writes, 1968);
    listen_fd_ = open_listener();
    wake_fd_ = eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
    spare_fd_ = ::open("/dev/null", O_RDONLY | O_CLOEXEC);
    if (wake_fd_ < 0 || spare_fd_ < 0) {
      std::string why = std::strerror(errno);
      for (int fd : {listen_fd_, wake_fd_, spare_fd_})
        if (fd >= 0) ::close(fd);
      throw std::runtime_error("modbus: cannot open its descriptors: " + why);
    }
  }
  ~ModbusDriver() override {
    stop_thread();
    for (Conn& c : conns_)
      if (c.fd >= 0) ::close(c.fd);
    for (int fd : {listen_fd_, wake_fd_, spare_fd_})
      if (fd >= 0) ::close(fd);
  }

  void program_replaced(size_t task, const Image& image) override { inner_->program_replaced(task, image); }

  void attach(uint8_t* global, const Layout& layout, uint32_t block_size) override {
    inner_->attach(global, layout, block_size);
    layout_ = layout;
    snaps_ = std::vector<Triple>(o_.tasks);
    for (Triple& t : snaps_)
      for (auto& b : t.buf) b.assign(layout.size, 0);
    for (size_t t = 0; t < o_.tasks; t++) writes_.push_back(std::make_unique<TaskWrites>(o_.pending_writes));
    for (size_t t = 0; t < o_.tasks; t++) fill(snaps_[t], global, nullptr), snaps_[t].publish();
    view_.layout = &layout_;
    view_.tasks.assign(o_.tasks, nullptr);
    view_.named = &o_.named;
    thread_ = std::thread([this] { serve_loop(); });
  }

  // ---- scan side: the task's thread, never waiting on the network thread

  // The shadow taken, its shared areas applied before the inputs are copied in.
  void read_inputs(uint8_t* global, const ScanContext& c) override {
    inner_->read_inputs(global, c);
    if (c.task >= writes_.size()) return;
    TaskWrites& w = *writes_[c.task];
    std::unique_lock<std::timed_mutex> l(w.mu, std::try_to_lock);
    if (!l.owns_lock()) return;      // the network thread is dropping writes: the next scan
    if (w.inflight) give_back(w);    // taken by a scan that was not published (a held task)
    if (!w.shadow.take(w.batch)) return;  // a request being merged: the next scan
    w.taken.store(w.batch.ticket);
    w.inflight = true, w.private_applied = false;
    for (const Write& e : w.batch.writes)
      if (area_is_shared(e.area)) plc::apply_element(e, global, layout_);
  }
  // D and F of the shadow taken, on the task's memory, just before the scan.
  void before_scan(const ScanContext& c, uint8_t* mem, std::optional<int32_t>& dt) override {
    inner_->before_scan(c, mem, dt);
    if (c.task >= writes_.size()) return;
    TaskWrites& w = *writes_[c.task];
    std::unique_lock<std::timed_mutex> l(w.mu, std::try_to_lock);
    if (!l.owns_lock() || !w.inflight || w.private_applied) return;  // not applied: not done, given back next scan
    for (const Write& e : w.batch.writes)
      if (!area_is_shared(e.area)) plc::apply_element(e, mem, layout_), c.written(layout_, e.area, e.index);
    w.private_applied = true;
  }
  void hold_outputs(uint8_t* global, uint8_t* mem, const ScanContext& c) override { inner_->hold_outputs(global, mem, c); }
  void write_outputs(const uint8_t* global, const ScanContext& c) override { inner_->write_outputs(global, c); }
  // Reads of Y and WY show the safe state until the next published scan.
  void safe_outputs(const uint8_t* global) override {
    inner_->safe_outputs(global);
    safe_gen_.fetch_add(1);
  }
  // A scan under way will not be published: the writes it applied wholly are
  // in memory (done); the others go back into the shadow, for the next scan
  // or for exception 06 at their timeout.  (If the lock stays taken -- a
  // thread that failed holds it -- the batch is left to the task's next scan.)
  void state_changed(State s) override {
    inner_->state_changed(s);
    for (auto& wp : writes_) {
      TaskWrites& w = *wp;
      std::unique_lock<std::timed_mutex> l(w.mu, std::chrono::milliseconds(100));
      if (!l.owns_lock() || !w.inflight) continue;
      if (w.private_applied) w.done.store(w.batch.ticket), w.inflight = false;
      else give_back(w);
    }
    if (!writes_.empty()) wake();
  }
  // The scan is published: its snapshot, then the writes it took are done.
  void after_scan(const ScanContext& c, const uint8_t* mem, const uint8_t* global) override {
    inner_->after_scan(c, mem, global);
    if (c.task >= snaps_.size()) return;
    fill(snaps_[c.task], global, mem);
    snaps_[c.task].publish();
    TaskWrites& w = *writes_[c.task];
    std::unique_lock<std::timed_mutex> l(w.mu, std::try_to_lock);
    if (!l.owns_lock() || !w.inflight || !w.private_applied) return;  // given back at the next scan
    w.inflight = false;
    if (w.batch.ticket > w.done.load()) {
      w.done.store(w.batch.ticket, std::memory_order_release);
      wake();
    }
  }
  void detach() override {
    stop_thread();
    inner_->detach();
  }

 private:
  // With w.mu held: the batch goes back in front of what was merged since.
  static void give_back(TaskWrites& w) {
    w.shadow.put_back(w.batch);
    w.inflight = false, w.private_applied = false;
    w.taken.store(w.done.load());
  }

  // The back buffer: X Y M K and WX WY (two contiguous ranges of the standard
  // layout) from the global image; the done bits TQ CQ and D F TW CW from the
  // task's memory.
  void fill(Triple& t, const uint8_t* global, const uint8_t* mem) {
    uint8_t* b = t.buf[t.back].data();
    auto copy = [&](const uint8_t* from_mem, Area first, Area last) {
      uint32_t from = layout_.offset[int(first)], to = layout_.addr(last, layout_.count[int(last)]);
      if (from_mem) std::memcpy(b + from, from_mem + from, to - from);
    };
    copy(global, Area::X, Area::K);
    copy(global, Area::WX, Area::WY);
    copy(mem, Area::TQ, Area::CQ);
    copy(mem, Area::D, Area::CW);
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
    if (o_.listening) o_.listening(name_of(ss, true));
    log("ldrun: modbus: listening on " + name_of(ss, true) + " (" + std::to_string(o_.max_connections) +
        " connections at most, " + std::to_string(o_.max_per_address) +
        " per address; Modbus has no authentication)");
    return fd;
  }
  // "HOST:PORT" ("[V6]:PORT"), or HOST alone.
  static std::string name_of(const sockaddr_storage& ss, bool with_port) {
    char host[INET6_ADDRSTRLEN] = "?";
    if (ss.ss_family == AF_INET) {
      auto* s = reinterpret_cast<const sockaddr_in*>(&ss);
      inet_ntop(AF_INET, &s->sin_addr, host, sizeof host);
      return with_port ? std::string(host) + ":" + std::to_string(ntohs(s->sin_port)) : std::string(host);
    }
    auto* s = reinterpret_cast<const sockaddr_in6*>(&ss);
    inet_ntop(AF_INET6, &s->sin6_addr, host, sizeof host);
    return with_port ? "[" + std::string(host) + "]:" + std::to_string(ntohs(s->sin6_port)) : std::string(host);
  }
  void log(const std::string& m) {
    if (o_.log) o_.log(m);
  }
  void note(const char* cause, const std::string& m) { throttle_.log(cause, "ldrun: modbus: " + m, now_ms()); }
  void stop_thread() {
    if (!thread_.joinable()) return;
    stopping_ = true;
    wake();
    thread_.join();
    throttle_.flush_all();
  }

  void serve_loop() {
    std::vector<pollfd> fds;
    std::vector<Conn*> of;
    while (!stopping_) {
      fds.clear(), of.clear();
      int64_t now = now_ms();
      bool listening = now >= listen_rest_until_;
      fds.push_back({listening ? listen_fd_ : -1, POLLIN, 0});  // a negative fd is not polled
      fds.push_back({wake_fd_, POLLIN, 0});
      for (Conn& c : conns_) {
        short ev = 0;
        if (!c.pending && c.in.size() < kMaxIn && c.out.size() < kMaxOut) ev |= POLLIN;
        if (!c.out.empty()) ev |= POLLOUT;
        fds.push_back({c.fd, ev, 0});
        of.push_back(&c);
      }
      int r = ::poll(fds.data(), fds.size(), int(std::max<int64_t>(0, next_deadline(now) - now)));
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
      if (r > 0 && listening && (fds[0].revents & POLLIN)) accept_all();
      conns_.remove_if([](const Conn& c) { return c.closing; });
      throttle_.flush(now_ms());
    }
  }

  // When the loop must look again without being woken: the first idle,
  // frame or write deadline, the end of the listener's rest; at most 1 s
  // (the log throttle's summaries).
  int64_t next_deadline(int64_t now) const {
    int64_t next = now + 1000;
    if (now < listen_rest_until_) next = std::min(next, listen_rest_until_);
    for (const Conn& c : conns_) {
      if (c.pending) {
        // past its deadline a write waits for the scan that took it, which wakes us
        if (c.pending->deadline > now) next = std::min(next, c.pending->deadline);
        continue;
      }
      next = std::min(next, c.last_ms + o_.idle_timeout_ms);
      if (c.frame_since) next = std::min(next, c.frame_since + o_.frame_timeout_ms);
    }
    return next;
  }

  void close_conn(Conn& c) {
    if (c.fd >= 0) ::close(c.fd);
    c.fd = -1, c.closing = true;
  }

  // ---- accepting

  void accept_all() {
    for (int round = 0; round < 64; round++) {  // the rest at the next turn: the loop goes on serving
      sockaddr_storage ss{};
      socklen_t len = sizeof ss;
      int fd = ::accept4(listen_fd_, reinterpret_cast<sockaddr*>(&ss), &len, SOCK_NONBLOCK | SOCK_CLOEXEC);
      if (fd >= 0) {
        failsafe::inject("modbus");  // the test hook of docs/faults.md (LDC_FAULT_INJECT=modbus:...)
        admit(fd, ss);
        continue;
      }
      if (errno == EINTR || errno == ECONNABORTED) continue;
      if (errno != EAGAIN && errno != EWOULDBLOCK) accept_failed(errno);
      return;
    }
  }

  // Out of descriptors (or memory): the listener would be ready again at
  // once, so it rests for a while instead of spinning; the client waiting
  // first is told at once (accepted on the spare descriptor and closed).
  void accept_failed(int err) {
    bool shed = false;
    if ((err == EMFILE || err == ENFILE) && spare_fd_ >= 0) {
      ::close(spare_fd_);
      int fd = ::accept4(listen_fd_, nullptr, nullptr, SOCK_CLOEXEC);
      if (fd >= 0) ::close(fd), shed = true;
      spare_fd_ = ::open("/dev/null", O_RDONLY | O_CLOEXEC);
    }
    listen_rest_until_ = now_ms() + o_.accept_backoff_ms;
    note(kAcceptFailed, std::string("accept: ") + std::strerror(err) + "; new connections wait " +
                            std::to_string(o_.accept_backoff_ms) + " ms" +
                            (shed ? " (the first one waiting was closed)" : "") + "; " + std::to_string(live()) +
                            " connections open");
  }

  size_t live() const {
    size_t n = 0;
    for (const Conn& c : conns_) n += !c.closing;
    return n;
  }

  // The idlest connection (of `address`, or of any if empty) that has no
  // write waiting for a scan; nullptr if none.
  Conn* idlest(const std::string& address) {
    Conn* best = nullptr;
    for (Conn& c : conns_) {
      if (c.closing || c.pending || (!address.empty() && c.address != address)) continue;
      if (!best || c.last_ms < best->last_ms) best = &c;
    }
    return best;
  }

  // A new connection, within the caps: over its address's cap it replaces
  // that address's idlest connection, over the table's the idlest of all;
  // if there is none to replace it is closed at once.
  void admit(int fd, const sockaddr_storage& ss) {
    std::string peer = name_of(ss, true), address = name_of(ss, false);
    size_t same = 0;
    for (const Conn& c : conns_) same += !c.closing && c.address == address;
    const bool per_address = same >= o_.max_per_address;
    if (per_address || live() >= o_.max_connections) {
      Conn* v = idlest(per_address ? address : "");
      std::string why = per_address ? std::to_string(o_.max_per_address) + " connections from " + address + " are open"
                                    : std::to_string(o_.max_connections) + " connections are open";
      if (!v) {
        ::close(fd);
        note(kRefused, "refused a connection from " + peer + ": " + why + ", each with a write pending");
        return;
      }
      note(kEvicted, "closed the connection from " + v->peer + " (idle " + std::to_string(now_ms() - v->last_ms) +
                         " ms) for one from " + peer + ": " + why);
      close_conn(*v);
    }
    int one = 1;
    setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
    conns_.push_back(Conn{fd, peer, address, now_ms()});
  }

  // ---- serving

  void on_ready(Conn& c, short ev) {
    if (c.closing) return;
    if (ev & POLLIN) {
      uint8_t buf[4096];
      ssize_t n = ::recv(c.fd, buf, sizeof buf, 0);
      if (n == 0 || (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR)) {
        close_conn(c);
        return;
      }
      if (n > 0) {
        if (c.in.empty()) c.frame_since = now_ms();
        c.in.insert(c.in.end(), buf, buf + n);
        handle_requests(c);
      }
    } else if (ev & (POLLERR | POLLHUP | POLLNVAL)) {
      close_conn(c);
      return;
    }
    if (!c.closing && (ev & POLLOUT) && !c.out.empty()) {
      flush(c);
      // requests that waited for the replies to drain
      if (!c.closing && !c.pending && !c.in.empty() && c.out.size() < kMaxOut) handle_requests(c);
    }
  }

  void flush(Conn& c) {
    ssize_t n = ::send(c.fd, c.out.data(), c.out.size(), MSG_NOSIGNAL);
    if (n < 0) {
      if (errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR) close_conn(c);
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

  // Serves the complete requests of c.in, in order, and sends the replies;
  // stops at a write until its scan is done, and while the replies the
  // client has not taken fill their buffer.
  void handle_requests(Conn& c) {
    bool served = false;
    while (true) {
      served |= serve_queued(c);
      if (c.closing || c.out.empty()) break;
      size_t unsent = c.out.size();
      flush(c);
      // room again: on with the requests that waited (else POLLOUT resumes)
      if (c.closing || c.pending || c.in.empty() || c.out.size() == unsent || c.out.size() >= kMaxOut) break;
    }
    if (c.closing) return;
    // A frame left incomplete began with the bytes that came after the last
    // request; requests waiting for the replies to drain are no slow frame
    // (the idle timeout covers a client that does not read).
    if (c.in.empty() || c.out.size() >= kMaxOut) c.frame_since = 0;
    else if (served || !c.frame_since) c.frame_since = now_ms();
  }
  // The serving part: true if a request was served.
  bool serve_queued(Conn& c) {
    bool served = false;
    while (!c.pending && !c.closing && c.out.size() < kMaxOut) {
      Outcome o = serve(c.in, view_for(c.in));
      if (o.kind == Outcome::NeedMore) break;
      c.in.erase(c.in.begin(), c.in.begin() + o.consumed);
      if (o.kind == Outcome::Close) {
        note(kBadHeader, "closed the connection from " + c.peer + ": " + o.error);
        close_conn(c);
        break;
      }
      served = true;
      c.last_ms = now_ms();
      if (o.writes.empty()) {
        c.out.insert(c.out.end(), o.reply.begin(), o.reply.end());
        continue;
      }
      uint64_t ticket = writes_[o.task]->shadow.post(o.writes);
      if (ticket == 0) {  // the shadow is full: the scans do not keep up
        note(kBusy, "exception 06 to " + c.peer + ": " + std::to_string(o_.pending_writes) +
                        " elements written are waiting for a scan of task " + std::to_string(o.task));
        std::vector<uint8_t> busy = busy_reply(std::move(o.reply));
        c.out.insert(c.out.end(), busy.begin(), busy.end());
        continue;
      }
      c.pending = PendingWrite{o.task, ticket, c.last_ms + o_.write_timeout_ms, std::move(o.reply)};
    }
    return served;
  }

  // Writes whose scan is done get their reply; the connection goes on.
  void finish_writes() {
    for (Conn& c : conns_) {
      if (!c.pending || c.closing) continue;
      if (writes_[c.pending->task]->done.load(std::memory_order_acquire) < c.pending->ticket) continue;
      answer(c, std::move(c.pending->reply));
    }
  }
  void answer(Conn& c, std::vector<uint8_t> reply) {
    c.pending.reset();
    c.out.insert(c.out.end(), reply.begin(), reply.end());
    c.last_ms = now_ms();
    c.frame_since = c.in.empty() ? 0 : c.last_ms;  // bytes that waited for the write: their frame starts now
    handle_requests(c);
  }

  // Idle connections and frames begun too long ago close; writes no scan
  // took in time are dropped and answered with exception 06 (server busy:
  // the task is not running).
  void expire() {
    int64_t now = now_ms();
    for (Conn& c : conns_) {
      if (c.closing) continue;
      if (c.pending) {
        const PendingWrite& p = *c.pending;
        if (now >= p.deadline && writes_[p.task]->taken.load() < p.ticket) drop_untaken(p.task);
        continue;
      }
      if (c.frame_since && now - c.frame_since >= o_.frame_timeout_ms) {
        note(kSlowFrame, "closed the connection from " + c.peer + ": a frame begun " +
                             std::to_string(now - c.frame_since) + " ms ago is still incomplete (" +
                             std::to_string(c.in.size()) + " bytes)");
        close_conn(c);
      } else if (now - c.last_ms >= o_.idle_timeout_ms) {
        note(kIdle, "closed the connection from " + c.peer + ": no request for " +
                        std::to_string(o_.idle_timeout_ms / 1000) + " s");
        close_conn(c);
      }
    }
  }

  // Takes back what the shadow of `task` holds -- every write merged since
  // the last scan took it -- and answers those writes with exception 06.
  // A write taken by a scan meanwhile is left to that scan.
  void drop_untaken(size_t task) {
    TaskWrites& w = *writes_[task];
    uint64_t lo, hi;
    {
      std::lock_guard<std::timed_mutex> l(w.mu);  // the scan side only try-locks it
      lo = w.taken.load();
      WriteShadow::Batch dropped;
      if (!w.shadow.take(dropped)) return;  // cannot happen: takes and posts hold w.mu or are ours
      hi = dropped.ticket;
      w.taken.store(hi);
    }
    for (Conn& c : conns_)
      if (!c.closing && c.pending && c.pending->task == task && c.pending->ticket > lo && c.pending->ticket <= hi)
        answer(c, busy_reply(std::move(c.pending->reply)));
  }

  std::unique_ptr<IoDriver> inner_;
  ServerOptions o_;
  net::LogThrottle throttle_;  // the network thread's
  int listen_fd_ = -1, wake_fd_ = -1;
  int spare_fd_ = -1;            // given up on EMFILE to accept and close one client
  int64_t listen_rest_until_ = 0;
  std::thread thread_;
  std::atomic<bool> stopping_{false};
  std::list<Conn> conns_;

  Layout layout_;
  View view_;                       // the network thread's
  std::vector<Triple> snaps_;       // per task
  std::atomic<uint64_t> safe_gen_{0};
  std::vector<std::unique_ptr<TaskWrites>> writes_;  // per task
};

}  // namespace

std::unique_ptr<IoDriver> make_modbus_driver(std::unique_ptr<IoDriver> inner, ServerOptions o) {
  return std::make_unique<ModbusDriver>(std::move(inner), std::move(o));
}

}  // namespace ldc::modbus
