// runtime/net/modbus.h -- a Modbus TCP server for the soft-PLC runtime
// (`ldrun --modbus HOST:PORT`, docs/runtime.md "Modbus TCP").
//
// Two parts: the protocol -- serve(), a pure function from the bytes a client
// sent to the reply and the writes a request asks for, over a read-only view
// of the memory (fuzzed by tests/fuzz/fuzz_modbus.cpp) -- and the server, an
// IoDriver decorator with a network thread of its own: the writes are merged
// into a shadow per task (runtime/write_shadow.h) that the scan takes at its
// boundary, and a snapshot of the view is taken after each scan.  Its limits
// (connections, per address, frame deadline, idle time, pending writes, log
// lines) are in docs/faults.md, "Modbus TCP".
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "ir/ir.h"
#include "runtime/plc.h"
#include "runtime/write_shadow.h"

namespace ldc::modbus {

// ---------------------------------------------------------------- the map
// Coils (FC 1, 5, 15): Y, then M, then K.  Discrete inputs (FC 2): X, then
// the timers' and counters' done bits.  Input registers (FC 4): WX, one
// register per word, then the timers' elapsed ms and the counters' values,
// two registers per word, the high half first.  Holding registers (FC 3, 6,
// 16): WY one register per word, then D and F two registers per word, the
// high half first.  Timers and counters are the unit's task's, read-only.
constexpr uint32_t kCoilY = 0, kCoilM = 8192, kCoilK = 16384, kCoilEnd = 24576;
constexpr uint32_t kDiscreteX = 0, kDiscreteT = 8192, kDiscreteC = kDiscreteT + 256, kDiscreteEnd = kDiscreteC + 256;
constexpr uint32_t kInputWX = 0, kInputT = 1024, kInputC = kInputT + 2 * 256, kInputEnd = kInputC + 2 * 256;
constexpr uint32_t kHoldWY = 0, kHoldD = 1024, kHoldF = kHoldD + 2 * 8192, kHoldEnd = kHoldF + 2 * 1024;

// Named variables (--modbus-map FILE, docs/runtime.md "Modbus TCP"): an
// unlocated variable of the first task's program at an address the file
// gives, past the device map so that it never hides a device: a BOOL is a
// coil from kCoilEnd on, any other elementary type but STRING holding
// registers from kHoldEnd on, one register up to 16 bits, two for 32, four
// for 64, the most significant first.
struct NamedPoint {
  std::string name;
  bool coil = false;
  uint32_t address = 0;  // its first register, or its coil
  Area area = Area::D;   // where it lives: M for a BOOL, D or F
  uint32_t index = 0;
  Ty ty = Ty::None;
};
uint32_t registers_of(Ty t);  // 1, 2 or 4
// Reads a map file: `NAME coil ADDRESS` or `NAME holding ADDRESS` a line, `#`
// comments; NAME resolved in `aliases`.  Throws std::runtime_error
// "file:line:col: error: ..." for a bad line, an unknown or located name, an
// address inside the device map, past 65535, or overlapping another.
std::vector<NamedPoint> read_map(std::string_view text, const std::string& file, const std::vector<Alias>& aliases);

// Function codes and exception codes (Modbus Application Protocol V1.1b3).
enum Function : uint8_t {
  kReadCoils = 1, kReadDiscreteInputs = 2, kReadHoldingRegisters = 3, kReadInputRegisters = 4,
  kWriteSingleCoil = 5, kWriteSingleRegister = 6, kWriteMultipleCoils = 15, kWriteMultipleRegisters = 16,
};
enum Exception : uint8_t {
  kIllegalFunction = 1, kIllegalDataAddress = 2, kIllegalDataValue = 3, kServerBusy = 6, kGatewayTargetFailed = 0x0B,
};
constexpr size_t kMbapSize = 7;        // transaction, protocol, length, unit
constexpr size_t kMaxPdu = 253;
constexpr size_t kMaxAdu = kMbapSize - 1 + 1 + kMaxPdu;  // 260

// What reads see: the shared areas (X Y M K WX WY) in `global`, the private
// ones (D F, the timers' and counters' TQ CQ TW CW) in each task's memory,
// all at the standard layout's offsets.
struct View {
  const Layout* layout = nullptr;
  const uint8_t* global = nullptr;
  std::vector<const uint8_t*> tasks;  // at least one
  const std::vector<NamedPoint>* named = nullptr;  // --modbus-map, served for task 0's units
};

// One element changed by a write request: element = (element & ~mask) |
// (value & mask).  Bits: value 0/1, mask 1.  Words: INT32 halves or whole.
// Applied by plc::apply_element.
using Write = plc::ElementWrite;

struct Outcome {
  enum Kind { NeedMore, Reply, Close } kind = NeedMore;
  size_t consumed = 0;           // bytes of the request (Reply, Close: all there is)
  std::vector<uint8_t> reply;    // the whole reply frame (MBAP header and PDU)
  size_t task = 0;               // the task whose memory the request addresses (unit identifier)
  std::vector<Write> writes;     // a write request's changes, applied all at once; empty otherwise
  std::string error;             // Close: why
};

// Serves the first request of `buf` (a TCP byte stream): NeedMore if it is
// incomplete; Close if it is not Modbus (protocol identifier not 0, length
// field outside 2..254); else the reply -- data, an echo of a write, or an
// exception.  Unit identifiers 0, 255 and 1 address task 0, 2..n task 1..n-1;
// others get exception 0x0B.  Never reads outside the view.
Outcome serve(std::span<const uint8_t> buf, const View& view);

// ---------------------------------------------------------------- the server
struct ServerOptions {
  std::string host = "127.0.0.1";
  uint16_t port = 502;           // 0: any free port (logged)
  size_t tasks = 1;              // the runtime's task count (unit identifiers)
  // Connections open at a time; a newcomer beyond it takes the place of the
  // idlest connection (no write pending, longest since its last request),
  // or is closed at once if every one has a write pending.
  size_t max_connections = 16;
  // Connections from one address; a newcomer beyond it takes the place of
  // that address's idlest connection (or is closed), never another's.
  size_t max_per_address = 8;
  int idle_timeout_ms = 60000;   // no request for that long: closed
  int frame_timeout_ms = 2000;   // a frame begun and not complete by then: closed (slowloris)
  int write_timeout_ms = 1000;   // a write no scan took by then: exception 06, not applied
  // Distinct elements (coils, register words) merged and not yet taken by a
  // scan, per task: what one scan applies at most.  A write that does not
  // fit gets exception 06 at once.  At least 1968 (the largest request).
  size_t pending_writes = 8192;
  size_t log_burst = 5;          // log lines per cause per window, then one summary
  int log_window_ms = 10000;
  int accept_backoff_ms = 250;   // the listener rests that long after accept fails (EMFILE)
  std::function<void(const std::string&)> log;
  std::function<void(const std::string&)> listening;  // told the address bound, "127.0.0.1:5020" (ldrun's banner)
  std::vector<NamedPoint> named;  // --modbus-map
};

// Open files the server holds at most: its connections, one newcomer being
// admitted, the listener, its wake-up eventfd and the spare descriptor kept
// for EMFILE (ldrun checks RLIMIT_NOFILE against it).
size_t descriptors_needed(const ServerOptions& o);

// "HOST:PORT", ":PORT", "PORT", "[V6]:PORT" into host and port (the host
// defaults to 127.0.0.1); throws std::runtime_error with the reason.
void parse_address(const std::string& text, ServerOptions& o);

// The decorator: forwards every call to `inner`; binds and listens now
// (throws std::runtime_error if it cannot), serves from attach() to detach().
std::unique_ptr<plc::IoDriver> make_modbus_driver(std::unique_ptr<plc::IoDriver> inner, ServerOptions o);

}  // namespace ldc::modbus
