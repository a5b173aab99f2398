// The log throttle (runtime/net/log_throttle.h): at most `burst` lines per
// cause and window, then one summary line with the count held back.  Time is
// given by the test.
#include <gtest/gtest.h>

#include "runtime/net/log_throttle.h"

namespace ldc::net {
namespace {

struct Log {
  std::vector<std::string> lines;
  LogThrottle::Sink sink() {
    return [this](const std::string& l) { lines.push_back(l); };
  }
};

TEST(LogThrottle, PassesABurstPerCauseThenCountsAndSummarises) {
  Log log;
  LogThrottle t(log.sink(), "srv: ", 2, 1000);
  for (int i = 0; i < 10; i++) t.log("bad header", "bad " + std::to_string(i), 100 + i);
  t.log("idle", "idle 0", 150);  // another cause has its own burst
  EXPECT_EQ(log.lines, (std::vector<std::string>{"bad 0", "bad 1", "idle 0"}));
  t.flush(1099);  // the window (100..1099) is not over
  EXPECT_EQ(log.lines.size(), 3u);
  t.flush(1100);
  EXPECT_EQ(log.lines.back(), "srv: 8 more 'bad header' messages suppressed in 1 s");
  EXPECT_EQ(t.suppressed(), 8u);
  // a new window: a new burst
  EXPECT_TRUE(t.log("bad header", "bad 10", 1200));
  EXPECT_TRUE(t.log("bad header", "bad 11", 1201));
  EXPECT_FALSE(t.log("bad header", "bad 12", 1202));
  EXPECT_EQ(log.lines.size(), 6u);
}

TEST(LogThrottle, ALineAfterTheWindowEndsItWithoutAFlush) {
  Log log;
  LogThrottle t(log.sink(), "srv: ", 1, 1000);
  t.log("c", "a", 0);
  t.log("c", "b", 10);
  t.log("c", "c", 5000);
  EXPECT_EQ(log.lines, (std::vector<std::string>{"a", "srv: 1 more 'c' message suppressed in 1 s", "c"}));
}

TEST(LogThrottle, AFloodCostsBurstPlusOneLinesPerWindow) {
  // 100,000 lines of one cause over 10 windows: at most (burst + 1) x 10 logged.
  Log log;
  {
    LogThrottle t(log.sink(), "srv: ", 5, 1000);
    for (int i = 0; i < 100000; i++) {
      t.log("flood", "line", i / 10);
      t.flush(i / 10);
    }
  }  // the destructor summarises the last window
  EXPECT_LE(log.lines.size(), 60u);
  EXPECT_GE(log.lines.size(), 50u);
  uint64_t counted = 0;
  for (const std::string& l : log.lines)
    if (l != "line") counted += std::stoull(l.substr(5));
  EXPECT_EQ(counted + 50, 100000u);  // every line is logged or counted once
}

}  // namespace
}  // namespace ldc::net
