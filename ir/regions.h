// ir/regions.h -- a program cut into regions for the change-driven scan
// (issue 28; docs/change-driven.md).  A region is a run of consecutive rungs
// whose result is a function of the memory it reads alone: run again with
// the same values in the cells it reads, it writes the same values into the
// cells it writes.  So a region need not run while nothing it reads or
// writes has changed since it last ran; the runtime (runtime/change_driven.cpp)
// keeps that record, and the scan's result is the full scan's.
//
// What joins rungs into one region (each a reason the rungs' effects cannot
// be told apart):
//  * a JMP and the rungs it may skip, up to its label's rung;
//  * a LOOP, the rungs it repeats, and every other rung with a LOOP between
//    (the loop budget is counted per scan);
//  * an END and every rung after it (a taken END skips them);
//  * a rung that reads the bit stack an earlier rung left, and that rung;
//  * consecutive rungs up to `max_rungs` (fewer calls, each larger).
// Timers read dt (Sys kSysDt): a region with one `uses_time` (and
// `time_always`, below).  An
// instruction whose memory this file cannot bound makes the plan one region
// (`whole` says why), which is the full scan.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "ir/ir.h"

namespace ldc {

// Bytes [off, off + len) of the memory image.
struct Span {
  uint32_t off = 0, len = 0;
  bool operator==(const Span&) const = default;
};

// What one instruction reads and writes of the memory image (edge slots,
// timers' and counters' hidden words included; the bit stack, dt and the
// Sys loop counter and fault record not).  `bounded` false: it touches
// memory the analysis cannot name.
struct Footprint {
  std::vector<Span> reads, writes;
  bool uses_time = false;
  bool bounded = true;
};
// `prev`: the instruction before `in` in its rung (an LDX/STX takes its
// IDX's bounds), or nullptr.
Footprint footprint(const Instr& in, const Instr* prev, const Layout& L);

struct Region {
  uint32_t first = 0, end = 0;       // rungs [first, end)
  std::vector<Span> reads, writes;   // sorted, disjoint, merged
  bool uses_time = false;
  // a timer of its that reads dt has another writer in the region (two
  // timer instructions, a MOV to its elapsed word): the region's result may
  // depend on dt with nothing changed, so it runs every scan
  bool time_always = false;
  uint32_t il_offset = 0;            // the binary IL offset of its first instruction (encode_il of the program)
};

struct RegionPlan {
  std::vector<Region> regions;  // in scan order, covering every rung
  std::string whole;            // why the program is one region ("" if it is cut)
};

RegionPlan plan_regions(const Program& p, const Layout& L, uint32_t max_rungs = 1);

// The program of rungs [r.first, r.end) of p, with p's edge slots (so the
// same layout), to be compiled as a scan function of its own.
Program region_program(const Program& p, const Region& r);

// The program again from an image's binary IL and each instruction's rung
// (the line map), its jumps' targets as labels "@OFFSET" on the rungs they
// land on: what plan_regions needs.  Throws std::runtime_error if a jump
// lands inside a rung.
Program program_of_il(std::span<const uint8_t> il, std::span<const uint32_t> rung_of, uint32_t edge_slots);

// Sorted, disjoint, with touching or overlapping spans merged.
std::vector<Span> merge_spans(std::vector<Span> v);

}  // namespace ldc
