// runtime/change_driven.h -- the change-driven scan (issue 28,
// docs/change-driven.md): a program cut into regions (ir/regions.h), each run
// only when something it reads or writes changed since it last ran.
//
// The record it keeps: a dirty bit per region.  Every region runs on the
// first scan.  After a region runs, each byte of its writes that changed
// marks every region that reads or writes that byte (not the region itself
// for a byte it only writes): a later one runs in this scan, an earlier one
// (or itself) in the next.  Before each scan the bytes that regions read and
// none writes (inputs, S1) are compared with their values at the last scan,
// and a change marks their readers; whoever else writes the image between
// scans (a client, forcing, a download) says so with `written` or
// `mark_all`.  A region that reads dt runs again in the next scan if dt was
// 0 in this one (a timer that is timing changes its elapsed word with every
// dt > 0, which marks it; with dt = 0 nothing would), and after every scan
// it ran in if one of its timers has a second writer in it (time_always).  A region that ends
// the scan with a fault (Sys kSysFault) stays dirty and the walk stops, as
// the full scan stops there.
//
// The result of every scan is the full scan's; the regions' own engines (the
// reference interpreter's, or checked native code's) do the work.
//
// Adaptive (`full` given): when most regions run anyway, walking them costs
// more than the full scan's code.  The engine starts with `full`, measured,
// and after `wait_` full scans probes the regions: a scan with every region
// marked (nothing is known after full scans), two more to settle, then scans
// that measure (8, fewer if the regions are clearly slower).  It keeps the
// regions while the median of their last 16 timed scans stays under 0.9
// times the full scan's (timed: every 8th scan, and every scan of a probe);
// each probe that loses doubles the wait for the next (256 up to 16384 full
// scans).
// Either way the scan's result is the full scan's.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "ir/regions.h"
#include "runtime/runtime.h"

namespace ldc {

class ChangeDrivenEngine : public Engine {
 public:
  // parts[i] runs plan.regions[i] (region_program) over the whole image.
  ChangeDrivenEngine(const RegionPlan& plan, const Layout& layout, std::vector<std::unique_ptr<Engine>> parts,
                     std::unique_ptr<Engine> full = nullptr);
  void scan(ImageBytes& mem) override;
  // Bytes [off, off + len) changed between scans by someone else.
  void written(uint32_t off, uint32_t len) override;
  // Every region runs in the next scan (a download, a restart).
  void mark_all();
  void written_all() override { mark_all(); }
  bool tracks_writes() const override { return true; }
  size_t regions() const { return parts_.size(); }
  size_t ran_last_scan() const { return ran_; }  // SIZE_MAX: the last scan ran `full`
  bool walking() const { return !full_ || !in_full_; }  // the next scan walks the regions
  // Tests: instead of measuring, alternate `full_scans` full scans and
  // `walk_scans` walking ones (the switches are what is tested).
  void alternate(uint64_t full_scans, uint64_t walk_scans) { fixed_full_ = full_scans, fixed_walk_ = walk_scans; }

 private:
  void mark_byte(uint32_t b, size_t self);
  void set(size_t r) { dirty_[r >> 6] |= uint64_t(1) << (r & 63); }
  size_t next_dirty(size_t pos) const;
  void run(size_t r, uint8_t* m);
  void walk(ImageBytes& mem);
  std::vector<Span> observed_writes(const std::vector<Span>& writes, size_t r) const;
  void choose(double ns);

  struct Part {
    std::unique_ptr<Engine> engine;
    std::vector<Span> writes;  // the bytes whose change marks some region (observed_writes)
    bool uses_time = false, time_always = false;
    uint32_t il_offset = 0;  // its IL's place in the program's: a fault record names the program's offset
  };
  std::vector<Part> parts_;
  std::vector<uint64_t> dirty_;
  // per image byte its unit (bytes in a row that the same regions touch),
  // or ~0; per unit u: [touch_at_[u], touch_at_[u + 1]) in touch_, each a
  // region that reads (top bit set) or only writes it
  std::vector<uint32_t> unit_of_, touch_at_, touch_;
  uint32_t last_unit_ = ~0u;  // the unit marked last (a span's bytes mark it once)
  std::vector<Span> external_;        // read by a region, written by none
  std::vector<uint8_t> external_byte_;  // per image byte: in external_
  std::vector<uint8_t> shadow_, snap_;
  ImageBytes* image_ = nullptr;  // during scan()
  // the adaptive choice (above)
  std::unique_ptr<Engine> full_;
  bool in_full_ = true;             // the first scans run `full`, measured
  uint64_t scans_ = 0, since_ = 0;  // scans, and scans since the last switch
  uint64_t wait_ = 256;             // full scans before the next probe (kMinWait)
  double full_ns_ = 0;         // the last full phase's median scan time
  std::vector<double> times_;  // this mode's last 16 timed scans (not its first)
  uint64_t timed_seen_ = 0;
  uint64_t fixed_full_ = 0, fixed_walk_ = 0;  // alternate(): 0 = measure
  bool all_ = true;
  size_t ran_ = 0;
};

}  // namespace ldc
