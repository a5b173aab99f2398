// runtime/online_carry.h -- what an online download carries from the running
// program's memory into the new one's, by identity and not by position
// (docs/runtime.md, "What a download carries").
//
//   devices          by address: X Y M K S D F T C keep their values (timers
//                    and counters with their hidden state: TI, the done bits)
//   named variables  by name (the image's `vars` section as wholes, and its
//                    aliases outside them): a variable the new program
//                    places elsewhere is moved there; one whose type changed is
//                    reset to its initial value; a new one starts from its
//                    initial value where its cells belonged to another variable
//                    or the new program initialises them
//   edge slots       by the element they belong to: the same element of an
//                    unchanged rung (wherever it moved), then of a rung with the
//                    same title, then the remaining slots reading the same
//                    device (or counting the same counter) in program order
//
// plan_carry works on the two images alone (off the task's thread);
// apply_carry does the copies at the scan boundary.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "loader/loader.h"

namespace ldc::plc {

// What a download did with the running program's state, item by item.
struct CarryReport {
  size_t edges_kept = 0;                 // edge slots carried (also those that kept their slot number)
  size_t vars_kept = 0;                  // named variables carried (also those that did not move)
  std::vector<std::string> moved;        // variables and edge slots carried to another place: "level D0 -> D1"
  std::vector<std::string> added;        // new items, started as at a fresh start: "edge [P X3] (line 2)"
  std::vector<std::string> reset;        // carried items that could not be: "x (INT -> REAL)"
  std::vector<std::string> dropped;      // items of the running program the new one does not have
  // "carried 4 edges, 3 variables (moved: ...); new: ...; reset: ...; dropped: ..."
  std::string text() const;
};

struct CarryPlan {
  // A byte range moved from the old memory to the new one (after the copy by
  // address); `shared` ranges (M, K) live in the global image.
  struct Copy {
    bool shared;
    uint32_t from, to, size;
  };
  // A variable's initial value (written before the copies).
  struct Fill {
    bool shared;
    uint32_t off;
    std::vector<uint8_t> bytes;
  };
  std::vector<std::pair<uint32_t, uint32_t>> edges;  // {new slot, old slot}
  std::vector<Copy> copies;
  std::vector<Fill> fills;
  CarryReport report;
  bool touches_shared() const {
    for (const Copy& c : copies)
      if (c.shared) return true;
    for (const Fill& f : fills)
      if (f.shared) return true;
    return false;
  }
};

// The plan for switching from `old_img` to `new_img` (both checked images:
// read_image's checks hold).
CarryPlan plan_carry(const Image& old_img, const Image& new_img);

// Makes the new program's memory from the running one's: every area but the
// edge memory by address, then the plan's edge slots (slots without a match
// start at 0, as at a fresh start), its fills (initial values), then its
// copies (moved variables; the old values are read before anything is
// written).  `global` is the
// global image (the caller holds its lock), where shared copies read and
// write, the new memory getting the same bytes; null: both in the memories.
void apply_carry(const CarryPlan& plan, const Layout& old_layout, const uint8_t* old_mem, const Layout& new_layout,
                 uint8_t* new_mem, uint8_t* global);

// The new program's initial memory: zero, then its first-scan initialisation
// (the rungs made of `LOAD S1` and moves of constants: typed variables'
// initial values, a ladder `[S1]--(MOV 8 D1)`).
std::vector<uint8_t> initial_memory(const Image& img);

}  // namespace ldc::plc
