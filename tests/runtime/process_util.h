// tests/runtime/process_util.h -- for the tests that run ldrun as a process:
// waiting for the child with a deadline, and a scratch directory.
#pragma once

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>

#include <chrono>
#include <cstdio>
#include <string>
#include <thread>

#include "driver/driver.h"

namespace ldc::test {

// The child's raw wait status, or -1 after `timeout` (the child is then
// killed and reaped).  `pid` is -1 afterwards either way.
inline int wait_child(pid_t& pid, std::chrono::milliseconds timeout) {
  auto deadline = std::chrono::steady_clock::now() + timeout;
  int st = 0;
  while (waitpid(pid, &st, WNOHANG) == 0) {
    if (std::chrono::steady_clock::now() > deadline) {
      ::kill(pid, SIGKILL);
      waitpid(pid, &st, 0);
      pid = -1;
      return -1;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  pid = -1;
  return st;
}

// A fresh directory, removed at the end of the test unless it failed (then
// kept, and named on stderr, to look at).
struct TmpDir {
  std::string path = make_temp_dir();
  ~TmpDir() {
    if (!::testing::Test::HasFailure()) remove_tree(path);
    else std::fprintf(stderr, "kept %s\n", path.c_str());
  }
  std::string operator/(const std::string& f) const { return path + "/" + f; }
};

}  // namespace ldc::test
