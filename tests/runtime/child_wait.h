// tests/runtime/child_wait.h -- waiting for an ldrun child with a deadline,
// for the tests that run ldrun as a process.
#pragma once

#include <signal.h>
#include <sys/wait.h>

#include <chrono>
#include <thread>

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

}  // namespace ldc::test
