// runtime/net/log_throttle.cpp -- see log_throttle.h.
#include "runtime/net/log_throttle.h"

#include <utility>

namespace ldc::net {

LogThrottle::LogThrottle(Sink sink, std::string prefix, size_t burst, int64_t window_ms)
    : sink_(std::move(sink)), prefix_(std::move(prefix)), burst_(burst), window_ms_(window_ms) {}

LogThrottle::~LogThrottle() { flush_all(); }

LogThrottle::Cause& LogThrottle::cause(const std::string& name) {
  for (Cause& c : causes_)
    if (c.name == name) return c;
  causes_.push_back(Cause{name});
  return causes_.back();
}

void LogThrottle::end_window(Cause& c) {
  if (c.held && sink_)
    sink_(prefix_ + std::to_string(c.held) + " more '" + c.name + "' message" + (c.held == 1 ? "" : "s") +
          " suppressed in " + std::to_string(window_ms_ / 1000) + " s");
  c.logged = 0, c.held = 0;
}

bool LogThrottle::log(const std::string& name, const std::string& line, int64_t now_ms) {
  Cause& c = cause(name);
  if (c.logged + c.held > 0 && now_ms - c.since >= window_ms_) end_window(c);
  if (c.logged + c.held == 0) c.since = now_ms;
  if (c.logged < burst_) {
    c.logged++;
    if (sink_) sink_(line);
    return true;
  }
  c.held++, suppressed_total_++;
  return false;
}

void LogThrottle::flush(int64_t now_ms) {
  for (Cause& c : causes_)
    if (c.held && now_ms - c.since >= window_ms_) end_window(c);
}

void LogThrottle::flush_all() {
  for (Cause& c : causes_) end_window(c);
}

}  // namespace ldc::net
