// runtime/failsafe.h -- the fatal paths of ldrun (docs/faults.md, "The safe
// state and fatal errors"): whatever ends the process -- a fatal signal, an
// uncaught exception on any thread, running out of memory -- first drives
// every output to the safe state (Y off, WY 0) and says why.
//
// Two paths:
//  * the raw path, async-signal-safe, for signals: the shared-memory
//    segment registered at start gets its outputs zeroed, its state FAULT and
//    the reason, by plain atomic stores (runtime/shm_layout.h); then the
//    signal is raised again with its default action, so the exit status
//    still names it.  Retentive memory is not saved: a signal may strike
//    with any lock held and memory half written.
//  * the full path, for errors that are not signals (fatal()): the raw path
//    first, then the runtime's rescue (runtime/plc.cpp: state FAULT, outputs
//    through the whole driver chain, retentive memory saved) on a thread of
//    its own that waits for nothing the dying thread holds, then exit status 3.
//
// One process has one segment and one runtime registered at a time.
#pragma once

#include <cstdint>

#include "runtime/shm_layout.h"

namespace ldc::failsafe {

// Exit status of a run ended by fatal() (docs/runtime.md, "Running").
constexpr int kFatalExit = 3;

// Installs the handlers: fatal signals, std::terminate, the rescue thread,
// and a reserve of address space released when memory runs out.  Idempotent.
void install();

// The segment whose outputs a fatal error drives to 0 directly.
void register_segment(shm::Header* h);
// Before the segment is unmapped.  False if a fatal path has begun: then the
// segment must stay mapped (the process is ending in the fatal path).
bool unregister_segment(shm::Header* h);

// The full path's work on the runtime (runtime/plc.cpp), called once on the
// rescue thread with the reason; it must not wait without a time limit.
using Rescue = void (*)(void* ctx, const char* reason);
void set_rescue(Rescue f, void* ctx);
void clear_rescue(void* ctx);

// A publication to the segment (the shm driver writes outputs and state
// inside one): refused once a fatal path has begun, so no scan can turn an
// output on again after the fatal path turned it off.
class Publication {
 public:
  Publication();
  ~Publication();
  Publication(const Publication&) = delete;
  Publication& operator=(const Publication&) = delete;
  explicit operator bool() const { return open_; }

 private:
  bool open_;
};

// A FAULT the runtime survives (the watchdog, a failed I/O driver): its
// reason into the segment; and the segment's outputs to 0 when the driver
// chain could not do it.
void note_fault(const char* reason);
void zero_segment_outputs();

// Ends the process after a fatal error that is not a signal: `what` is the
// cause ("out of memory (std::bad_alloc) on task 'main'").  Never returns.
[[noreturn]] void fatal(const char* what);

// LDC_FAULT_INJECT=WHERE:WHAT[@N], the test hook of docs/faults.md: the Nth
// time (default 1) the point WHERE is reached, do WHAT.  Points: "http" (a
// request parsed by the monitor's server thread), "modbus" (a connection
// accepted by the Modbus server thread), "io" (the shared-memory driver
// publishing outputs).  WHAT: "throw" (std::runtime_error), "bad_alloc"
// (throw std::bad_alloc), "oom" (allocate 64 MiB blocks until an allocation
// fails: a real std::bad_alloc under an address-space limit).  The variable
// is read once; without it, inject() does nothing.
void inject(const char* where);

}  // namespace ldc::failsafe
