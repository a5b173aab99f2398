// runtime/net/monitor.h -- the live ladder view of `ldrun --monitor HOST:PORT`
// (docs/runtime.md, "The monitor"): an I/O driver decorator that copies a
// snapshot of each task's memory at its scan boundary (only when a page is
// watching) and applies queued writes and forced inputs at the next boundary,
// and an HTTP server (runtime/net/http.h) that serves one built-in page, the rungs
// as grids (ir/ladder.h), their power flow evaluated on the snapshot off the
// scan thread, a device table, statistics and, with --monitor-write, RUN/STOP,
// writes and forcing.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "runtime/plc.h"

namespace ldc::plc {

struct MonitorTask {
  std::string name;
  uint32_t period_us = 0;
  Image image;  // its IL, line map, titles and aliases are drawn (the code is not needed)
};

struct MonitorOptions {
  std::string host = "127.0.0.1";
  uint16_t port = 0;            // 0: any free port
  bool write = false;           // --monitor-write: RUN/STOP, writes and forcing allowed
  size_t max_connections = 32;
  int tick_ms = 50;             // event stream period (20 updates/s)
};

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
