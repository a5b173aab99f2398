// runtime/net/monitor.h -- the live ladder view of `ldrun --monitor HOST:PORT`
// (docs/runtime.md, "The monitor"): an I/O driver decorator that copies a
// snapshot of each task's memory at its scan boundary (only when a page is
// watching) and applies client writes (merged in write shadows,
// runtime/write_shadow.h) and forced devices at every boundary,
// and an HTTP server (runtime/net/http.h) that serves one built-in page, the rungs
// as grids (ir/ladder.h) drawn with the IEC 61131-3 symbols, their power flow
// evaluated on the snapshot off the scan thread, a device table, trends,
// statistics and, with --monitor-write, RUN/STOP, writes and forcing (also by
// clicking a contact).  After an online download (IoDriver::program_replaced)
// it shows the new program; snapshots and writes follow Runtime::generation,
// and every value the page gets carries the generation of its program.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "runtime/plc.h"

namespace ldc::plc {

struct MonitorTask {
  std::string name;
  uint32_t period_us = 0;
  Image image;  // its IL, line map, titles and aliases are drawn (the code is not needed)
  // An ST or IL program: its source text, shown line by line with the live
  // value of each variable a line assigns beside its name (instead of rungs);
  // or, when the text is not at hand, why (said on the page, rungs drawn).
  std::string source_text, source_note;
};

// The write path's guards and the server's bounds: docs/faults.md, "The
// monitor (HTTP)".
struct MonitorOptions {
  std::string host = "127.0.0.1";
  uint16_t port = 0;            // 0: any free port
  bool write = false;           // --monitor-write: RUN/STOP, writes and forcing allowed
  std::vector<std::string> hosts;  // --monitor-host: more names a request's Host may give ("name" or "name:port")
  std::string token;            // not empty: every POST must carry X-LDC-Token with it
  size_t max_connections = 64;  // --monitor-connections
  size_t max_per_address = 32;  // --monitor-per-address
  size_t max_streams = 32;      // --monitor-streams
  size_t write_backlog = 8192;  // distinct devices written and not yet taken by a scan (per shadow)
  size_t max_forced = 256;      // devices forced at once
  int tick_ms = 50;             // event stream period (20 updates/s)
  std::function<void(const std::string&)> log;  // throttled server messages (stderr in ldrun)
  // After an online download: the source text of task `task`'s new image
  // (as MonitorTask::source_text / source_note), or nothing.
  std::function<void(size_t task, const Image& image, std::string& text, std::string& note)> source_of;
};

// --monitor-host NAME[,NAME...]: host names (or IP literals) with an
// optional :PORT, appended to `out`.  Throws std::runtime_error with the reason.
void parse_monitor_hosts(const std::string& list, std::vector<std::string>& out);
// --monitor-token: 16 to 128 of A-Z a-z 0-9 . _ ~ - (fits a URL and a header
// unescaped).  Throws std::runtime_error with the reason.
void check_monitor_token(const std::string& token);
// A fresh write token: 128 bits from /dev/urandom as 32 hex digits.  Throws
// std::runtime_error if /dev/urandom cannot be read.
std::string make_monitor_token();

// "127.0.0.1:8080", "[::1]:8080", "localhost:8080", "8080" (loopback) ->
// host, port.  A host that is not a loopback address needs `remote`.
// Throws std::runtime_error with the reason.
std::pair<std::string, uint16_t> parse_monitor_address(const std::string& s, bool remote);

class Monitor {
 public:
  Monitor(std::vector<MonitorTask> tasks, MonitorOptions opt);
  ~Monitor();
  Monitor(const Monitor&) = delete;
  Monitor& operator=(const Monitor&) = delete;

  // The driver the runtime gets: forwards everything to `inner`.
  std::unique_ptr<IoDriver> wrap(std::unique_ptr<IoDriver> inner);
  // RUN/STOP and statistics come from the runtime (set before start()).
  void attach(Runtime* rt);
  void start();  // listens; throws std::runtime_error
  void stop();
  uint16_t port() const;

  struct Impl;

 private:
  std::shared_ptr<Impl> impl_;
};

}  // namespace ldc::plc
