// runtime/net/log_throttle.h -- at most a few log lines per cause and time
// window (docs/faults.md, "Modbus TCP": the log flood).
//
// A server that logs a line per bad frame, refused connection or failed
// accept lets any client fill the disk: 111,000 connections with a bad
// header in 10 s wrote 10.8 MB.  A LogThrottle passes the first `burst`
// lines of each cause in a window of `window_ms`, counts the rest, and when
// the window is over says how many it held back, in one line.  So each
// cause costs at most burst + 1 lines per window, however fast it happens.
// Not thread-safe: one per thread (the server's network thread).
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace ldc::net {

class LogThrottle {
 public:
  using Sink = std::function<void(const std::string&)>;
  // `prefix` starts the summary lines ("ldrun: modbus: ").
  LogThrottle(Sink sink, std::string prefix, size_t burst = 5, int64_t window_ms = 10000);
  ~LogThrottle();  // says what it still held back
  LogThrottle(const LogThrottle&) = delete;
  LogThrottle& operator=(const LogThrottle&) = delete;

  // Logs `line` if `cause` (a fixed phrase: "bad header", "refused") has
  // logged fewer than `burst` lines in its current window; else counts it.
  // Returns whether it was logged.
  bool log(const std::string& cause, const std::string& line, int64_t now_ms);
  // Ends the windows that are over at `now_ms`: a summary line for each
  // cause that held lines back.  Call it now and then (the server: at each
  // turn of its loop), so that a summary does not wait for the next line.
  void flush(int64_t now_ms);
  // Ends every window now.
  void flush_all();

  uint64_t suppressed() const { return suppressed_total_; }  // lines held back so far, all causes

 private:
  struct Cause {
    std::string name;
    int64_t since = 0;      // start of its window
    size_t logged = 0;      // lines logged in the window
    uint64_t held = 0;      // lines held back in the window
  };
  Cause& cause(const std::string& name);
  void end_window(Cause& c);

  Sink sink_;
  std::string prefix_;
  size_t burst_;
  int64_t window_ms_;
  std::vector<Cause> causes_;  // few: the causes are fixed phrases of the code
  uint64_t suppressed_total_ = 0;
};

}  // namespace ldc::net
