// runtime/runtime.h -- running a program scan by scan: engines, input traces,
// watched outputs (docs/format.md, section "Traces").
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "ir/ir.h"

namespace ldc {

struct Image;  // loader/loader.h

// What one scan cost on a simulated processor (the C40 engines, docs/c40.md):
// counted cycles and instructions, and the processor's cycle time.
struct ScanCost {
  uint64_t cycles = 0;
  uint64_t instructions = 0;
  double ns_per_cycle = 0;
  double us() const { return double(cycles) * ns_per_cycle / 1000.0; }
};

// Something that runs one scan over the memory image.
class Engine {
 public:
  virtual ~Engine() = default;
  // One scan over `mem`.  Only the guarded storage of ir.h is taken: native
  // code finds its call table below the image and faults past either end,
  // so no path can hand an engine a plain vector or pointer
  // (tests/runtime/native_type_test.cpp).
  virtual void scan(ImageBytes& mem) = 0;
  // The cost of the last scan on a simulated processor; nullopt for an engine
  // that runs on this machine (its time is measured, not counted).
  virtual std::optional<ScanCost> last_cost() const { return std::nullopt; }
  // Bytes [off, off + len) of the image were written between scans by
  // someone else (a trace row, a client, forcing).  Every host that writes
  // the image says so: the change-driven engine (runtime/change_driven.h)
  // runs what depends on them; the others need not know.
  virtual void written(uint32_t off, uint32_t len) { (void)off, (void)len; }
  // The whole image may have changed (a cold restart, retentive memory put
  // back): the same for every byte.
  virtual void written_all() {}
  // Does written() matter to this engine (so a host compares before it copies)?
  virtual bool tracks_writes() const { return false; }
};

// The reference interpreter over an image's binary IL.
std::unique_ptr<Engine> make_interp_engine(std::vector<uint8_t> il, const Layout& layout);

// The fast interpreter (runtime/fastinterp.h): the same binary IL, decoded
// once into type-specialized records with resolved offsets, threaded dispatch.
std::unique_ptr<Engine> make_fast_interp_engine(std::span<const uint8_t> il, const Layout& layout);

// Native x86-64 code that passed the loader's code check, in the memory it
// runs from: map_checked_code copies the bytes into a fresh mapping, runs
// check_x86_code (loader.h) on that copy, the bytes that will run, and only
// then makes the mapping read+execute.  Its constructor is private and
// map_checked_code is the one function that makes one, so the native engine,
// which takes nothing else, never runs bytes the check has not seen (a plain
// vector does not convert: tests/runtime/native_type_test.cpp).
class CheckedRegions;
class CheckedCode {
 public:
  CheckedCode(CheckedCode&& o) noexcept;
  CheckedCode& operator=(CheckedCode&& o) noexcept;
  CheckedCode(const CheckedCode&) = delete;
  CheckedCode& operator=(const CheckedCode&) = delete;
  ~CheckedCode();
  uint32_t entry() const { return entry_; }
  size_t size() const { return size_; }

 private:
  friend CheckedCode map_checked_code(std::span<const uint8_t> code, uint32_t entry, const Layout& layout);
  friend CheckedRegions map_checked_regions(std::span<const uint8_t> code, std::span<const uint32_t> start,
                                            std::span<const uint32_t> size, const Layout& layout);
  friend class NativeEngine;
  friend class NativeRegionEngine;
  CheckedCode(void* base, size_t mapped, size_t size, uint32_t entry) : base_(base), mapped_(mapped), size_(size), entry_(entry) {}
  void* base_ = nullptr;  // read+execute
  size_t mapped_ = 0, size_ = 0;
  uint32_t entry_ = 0;
};
// Throws std::runtime_error ("native code refused: at code offset 0x..: why")
// if the check refuses the code, or if it cannot be mapped.
CheckedCode map_checked_code(std::span<const uint8_t> code, uint32_t entry, const Layout& layout);

// The native code of a change-driven scan (runtime/change_driven.h): one
// scan function per region, region i's bytes [start[i], start[i] + size[i])
// of `code` with its entry at start[i], in ascending order without overlap
// (the bytes between are never run).  Each passes the code check on its own
// bytes, so no branch leaves its region; the mapping is made executable only
// then.  Throws std::runtime_error ("native code refused: region N: ...").
class CheckedRegions {
 public:
  size_t regions() const { return start_.size(); }
  const CheckedCode& code() const { return code_; }

 private:
  friend CheckedRegions map_checked_regions(std::span<const uint8_t> code, std::span<const uint32_t> start,
                                            std::span<const uint32_t> size, const Layout& layout);
  friend class NativeRegionEngine;
  CheckedRegions(CheckedCode c, std::vector<uint32_t> s) : code_(std::move(c)), start_(std::move(s)) {}
  CheckedCode code_;
  std::vector<uint32_t> start_;
};
CheckedRegions map_checked_regions(std::span<const uint8_t> code, std::span<const uint32_t> start,
                                   std::span<const uint32_t> size, const Layout& layout);
// One engine per region, each calling its scan function in the shared mapping.
std::vector<std::unique_ptr<Engine>> make_native_region_engines(std::shared_ptr<const CheckedRegions> code);

// Native x86-64 scan code, called as void scan(uint8_t* image).  The image must
// live in ImageBytes (ir.h): the code calls the REAL functions through the
// read-only table below it.
std::unique_ptr<Engine> make_native_engine(CheckedCode code);
// A scan function `void symbol(uint8_t* image)` in a shared object (the C route).
std::unique_ptr<Engine> make_shared_object_engine(const std::string& path, const std::string& symbol);

// A device named in a trace column or a --watch list.
struct Probe {
  std::string name;  // as the user wrote it
  Area area;         // T and C name their word (elapsed ms, current value)
  uint32_t index;
  Ty ty = Ty::None;  // a typed alias's type: read and written at it (docs/il.md)
};
// Resolves a variable's name (an alias: `motor`, `tank.level`, `c[2].v`,
// `a[1, 2]`; blanks, case and enclosing double quotes do not matter), else a
// device spelling or IEC address; throws std::runtime_error.  A program's name
// wins over a device of the same spelling.
Probe resolve_probe(std::string_view name, const std::vector<Alias>& aliases);
// A CSV line's cells, trimmed, each with its 1-based column: commas inside
// [...] (an element a[1,2]) and inside quotes ('text', "name") do not split.
std::vector<std::pair<std::string, int>> split_cells(std::string_view line);
// A name as an output header cell: in double quotes if it holds a comma
// ("a[1,2]"), which split_cells and resolve_probe read back.
std::string csv_name(const std::string& name);
// A --watch list's names, split as a CSV line.
std::vector<std::string> split_names(std::string_view list);

struct Trace {
  std::vector<Probe> columns;
  int dt_column = -1;
  // one row per scan; std::nullopt-like empty string = keep the previous value
  std::vector<std::vector<std::string>> rows;
  std::vector<int> row_line;  // source line of each row, for messages
  int header_line = 0;          // the line naming the columns
  std::vector<int> column_col;  // each column's name: its column on that line
};
// Reads the CSV input trace; errors are "file:line:col: error: ...".
Trace read_trace(std::string_view text, const std::string& file, const std::vector<Alias>& aliases);
// A trace cell's integer (decimal, or hex with 0x; `end` as strtoll's), and a
// non-empty cell written into the memory image at `base`.
long long trace_cell_int(const std::string& v, char** end = nullptr);
void put_trace_cell(uint8_t* base, const Layout& L, const Probe& p, const std::string& v);
// How many bytes from L.addr(p.area, p.index) a cell of p writes.
uint32_t probe_width(const Probe& p, const Layout& L);
// Why a cell cannot be a typed column's value ("" if it can, or the column is untyped).
std::string check_trace_cell(const Probe& p, const std::string& v);
// Why a non-empty cell cannot be written to p ("" if it can): a typed
// column's value, else a bit 0/1, an INT32, a REAL (F).
std::string trace_cell_problem(const Probe& p, const std::string& v);

struct RunOptions {
  int scans = -1;          // -1: as many as the trace has rows (1 without a trace)
  int32_t period_ms = 10;  // dt when the trace has no dt column
  std::vector<Probe> watch;
  bool continue_after_fault = false;  // ldrun --fault=continue: a faulted scan's row is written and the scans go on
};

// A fault that ended a scan (an array index outside its bounds): the record
// every engine writes at Sys+8 (docs/il.md, "Index faults").
struct ScanFault {
  uint32_t kind = kFaultNone;
  uint32_t il_offset = 0;  // the IL byte offset of the faulting instruction
  int64_t value = 0;       // the index
  int scan = 0;            // the scan it ended (run_trace)
};
std::optional<ScanFault> read_scan_fault(const uint8_t* mem);
// "index 11 outside 1..10 at prog.st:12 (rung 3 "POU main")", from the
// image's IL and line map where it has them (img may be null).
std::string describe_scan_fault(const ScanFault& f, const Image* img);

// Runs the scans and writes the CSV of watched values to `out`.  Throws
// std::runtime_error with a located message on a bad trace value.  A scan
// that faults ends the run (its row is not written) unless
// opt.continue_after_fault; the faults are returned.
std::vector<ScanFault> run_trace(Engine& engine, const Layout& layout, const Trace* trace, const std::string& trace_file,
                                   const RunOptions& opt, std::string& out);

// Value of a probe, formatted as ldrun prints it (bits 0/1, INT32 decimal, REAL %g).
std::string format_probe(const Memory& mem, const Probe& p);
// The same, for a probe of the memory image at `base` laid out as `layout`.
std::string format_probe(const uint8_t* base, const Layout& layout, const Probe& p);

}  // namespace ldc

