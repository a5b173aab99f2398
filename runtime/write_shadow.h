// runtime/write_shadow.h -- writes from network clients on their way to a
// scan (docs/faults.md, "Network writes and the scan").
//
// A client may send writes faster than a task scans, or while the PLC is
// stopped.  Queued one per request, they cost the next scan in proportion to
// their number (and a queue searched per element, quadratically), and a
// backlog can trip the watchdog.  A shadow instead merges them as they arrive,
// on the network thread: one entry per element written, the last write of an
// element winning bit by bit, in request order.  The scan takes the whole
// shadow at its boundary with one swap (it never waits: the network side's
// lock is only try-locked) and applies it in O(elements written), however
// many requests wrote them.  The shadow holds at most `capacity` distinct
// elements; a request that would need more is refused whole (the server
// answers "busy"), so the copy a scan makes is bounded too.
#pragma once

#include <cstddef>
#include <cstdint>
#include <mutex>
#include <span>
#include <vector>

#include "ir/ir.h"

namespace ldc::plc {

// One element changed by a client: element = (element & ~mask) | (value &
// mask).  Bit elements (area_is_bit) take value & 1 and ignore the mask.
struct ElementWrite {
  Area area;
  uint32_t index;
  uint32_t value, mask;
  bool operator==(const ElementWrite&) const = default;
};

// Applies one element write to a memory image of layout `L` (the caller has
// checked the element is inside it).
void apply_element(const ElementWrite& w, uint8_t* mem, const Layout& L);

class WriteShadow {
 public:
  // What a scan took: the merged writes in the order their elements were
  // first written, and the ticket of the last request merged into them.
  struct Batch {
    std::vector<ElementWrite> writes;
    uint64_t ticket = 0;
    bool empty() const { return writes.empty(); }
  };

  explicit WriteShadow(size_t capacity = 8192);

  // Network side: merges one request's writes, all or none.  Returns its
  // ticket (1, 2, ...; a later request has a larger one), or 0 -- merging
  // nothing -- if the shadow would then hold more than `capacity` elements.
  uint64_t post(std::span<const ElementWrite> writes);

  // Scan side: moves everything merged so far into `b` (whose old writes are
  // dropped) and leaves the shadow empty.  Never waits: returns false, taking
  // nothing, while the network side holds the lock (the next scan takes it).
  // `b.ticket` is then the newest ticket the batch includes.
  bool take(Batch& b);

  // A batch taken but not applied goes back in front of what was merged
  // since (which still wins), whatever the capacity: posts are refused
  // until a scan has taken the shadow again.
  void put_back(const Batch& b);

  size_t size() const;            // distinct elements merged and not taken
  size_t capacity() const { return capacity_; }
  uint64_t last_ticket() const;   // of the newest request merged

 private:
  struct Slot {
    uint64_t key;
    uint32_t pos;  // into writes_
    uint32_t gen;  // the slot is in use only if gen == gen_
  };
  void merge(const ElementWrite& w);  // with mu_ held
  void clear_index();                 // with mu_ held: O(1) but on wrap
  void grow();                        // with mu_ held: twice the slots
  Slot& slot_of(uint64_t key);        // with mu_ held: its slot, or a free one
  size_t fresh_elements(std::span<const ElementWrite> writes);  // with mu_ held

  size_t capacity_;
  mutable std::mutex mu_;
  std::vector<ElementWrite> writes_;
  std::vector<Slot> index_;  // open addressing, at least 4 x capacity slots, at most half full
  uint32_t gen_ = 1;
  uint64_t ticket_ = 0;
};

}  // namespace ldc::plc
