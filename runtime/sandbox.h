// runtime/sandbox.h -- running the scans of an untrusted image in a confined
// child process (ldrun --sandbox; docs/runtime.md, "The sandbox";
// docs/image-format.md, "Threat model").
#pragma once

#include <memory>
#include <span>
#include <stdexcept>
#include <string>

#include "runtime/runtime.h"

namespace ldc {

// A system call a confined process may still make: its number and, if arg0 is
// not -1, the exact value its first argument must have (a file descriptor).
struct AllowedSyscall {
  long nr;
  long arg0 = -1;
};

// Confines the calling process for good: no new privileges, then a seccomp
// filter under which every system call but `allowed` (x86-64 ABI only) raises
// SIGSYS.  Returns "" on success, else why it could not.
std::string confine(std::span<const AllowedSyscall> allowed);

// What ended a confined child's scan other than the scan itself.
struct SandboxError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Wraps `inner` so that its scans run in a child process forked now and
// confined by confine() to reading and writing one socket and exiting.  The
// memory image travels through a shared ImageBytes: each scan copies the
// caller's image in, wakes the child, waits, and copies the image back.  A
// scan that faults (the signal and address are named), makes a system call
// (its number is named) or runs past `timeout_ms` kills the child and throws
// SandboxError; every later scan throws too.
std::unique_ptr<Engine> make_sandboxed_engine(std::unique_ptr<Engine> inner, const Layout& layout,
                                              int timeout_ms = 1000);

}  // namespace ldc
