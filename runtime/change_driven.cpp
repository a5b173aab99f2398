// runtime/change_driven.cpp -- the change-driven scan (runtime/change_driven.h).
#include "runtime/change_driven.h"

#include <algorithm>
#include <bit>
#include <chrono>
#include <cstring>
#include <stdexcept>
#include <string>

namespace ldc {

namespace {

constexpr uint32_t kReads = 0x80000000u;
constexpr uint32_t kNoUnit = 0xffffffffu;
// the adaptive choice: scans a probe settles, then measures; full scans
// before the next probe, doubled by each probe the regions lose
constexpr uint64_t kSettle = 3, kProbe = 12, kMinWait = 256, kMaxWait = 16384;
constexpr double kKeep = 0.9;

}  // namespace

ChangeDrivenEngine::ChangeDrivenEngine(const RegionPlan& plan, const Layout& layout, std::vector<std::unique_ptr<Engine>> parts,
                                       std::unique_ptr<Engine> full)
    : full_(std::move(full)) {
  if (parts.size() != plan.regions.size()) throw std::invalid_argument("change-driven scan: one engine per region");
  const size_t n = parts.size(), size = layout.size;
  // per byte: who reads it, who writes it (counted, then placed)
  std::vector<uint32_t> count(size + 1, 0);
  std::vector<uint8_t> written_by_any(size, 0), read_by_any(size, 0);
  for (size_t r = 0; r < n; r++) {
    const Region& g = plan.regions[r];
    for (const std::vector<Span>* v : {&g.reads, &g.writes})
      for (const Span& s : *v)
        if (uint64_t(s.off) + s.len > size)
          throw std::invalid_argument("change-driven scan: region " + std::to_string(r) + "'s memory reaches past the image");
    for (const Span& s : g.reads)
      for (uint32_t b = s.off; b < s.off + s.len && b < size; b++) count[b]++, read_by_any[b] = 1;
    for (const Span& s : g.writes)
      for (uint32_t b = s.off; b < s.off + s.len && b < size; b++) count[b]++, written_by_any[b] = 1;
  }
  // per byte, then bytes in a row with the same list made one unit (a word's
  // four bytes, an array), so a changed word marks its regions once
  std::vector<uint32_t> at(size + 1, 0), list;
  for (size_t b = 0; b < size; b++) at[b + 1] = at[b] + count[b];
  list.resize(at[size]);
  std::vector<uint32_t> fill(at.begin(), at.end() - 1);
  for (size_t r = 0; r < n; r++) {
    const Region& g = plan.regions[r];
    for (const Span& s : g.reads)
      for (uint32_t b = s.off; b < s.off + s.len && b < size; b++) list[fill[b]++] = uint32_t(r) | kReads;
    for (const Span& s : g.writes)
      for (uint32_t b = s.off; b < s.off + s.len && b < size; b++) list[fill[b]++] = uint32_t(r);
  }
  auto same = [&](size_t a, size_t b) {
    return at[a + 1] - at[a] == at[b + 1] - at[b] && std::equal(list.begin() + at[a], list.begin() + at[a + 1], list.begin() + at[b]);
  };
  unit_of_.assign(size, kNoUnit);
  touch_at_.push_back(0);
  for (size_t b = 0; b < size; b++) {
    if (at[b + 1] == at[b]) continue;
    if (b == 0 || unit_of_[b - 1] == kNoUnit || !same(b - 1, b)) {
      touch_.insert(touch_.end(), list.begin() + at[b], list.begin() + at[b + 1]);
      touch_at_.push_back(uint32_t(touch_.size()));
    }
    unit_of_[b] = uint32_t(touch_at_.size() - 2);
  }
  external_byte_.assign(size, 0);
  for (uint32_t b = 0; b < size; b++) {
    if (!read_by_any[b] || written_by_any[b]) continue;
    external_byte_[b] = 1;
    if (!external_.empty() && external_.back().off + external_.back().len == b) external_.back().len++;
    else external_.push_back({b, 1});
  }
  size_t ext = 0;
  for (const Span& s : external_) ext += s.len;
  shadow_.resize(ext);
  for (size_t r = 0; r < n; r++)
    parts_.push_back(Part{std::move(parts[r]), observed_writes(plan.regions[r].writes, r), plan.regions[r].uses_time,
                          plan.regions[r].time_always, plan.regions[r].il_offset});
  size_t most = 0;
  for (const Part& p : parts_) {
    size_t k = 0;
    for (const Span& s : p.writes) k += s.len;
    most = std::max(most, k);
  }
  snap_.assign(most, 0);
  dirty_.assign((n + 63) / 64, 0);
}

// The bytes of region r's writes whose change marks some region: read by
// any region (r too), or written by another.  A change of the others (a
// coil nothing in the program reads) marks nothing, so it is not looked for.
std::vector<Span> ChangeDrivenEngine::observed_writes(const std::vector<Span>& writes, size_t r) const {
  std::vector<Span> out;
  for (const Span& s : writes)
    for (uint32_t b = s.off; b < s.off + s.len; b++) {
      const uint32_t u = unit_of_[b];
      bool seen = false;
      for (uint32_t k = touch_at_[u]; k < touch_at_[u + 1] && !seen; k++) seen = (touch_[k] & ~kReads) != r || (touch_[k] & kReads);
      if (!seen) continue;
      if (!out.empty() && out.back().off + out.back().len == b) out.back().len++;
      else out.push_back({b, 1});
    }
  return out;
}

// Copies and compares of the few bytes a region writes: a call to memcpy
// or memcmp costs more than the bytes.
namespace {
void copy_small(uint8_t* to, const uint8_t* from, uint32_t n) {
  switch (n) {
    case 1: *to = *from; return;
    case 4: std::memcpy(to, from, 4); return;
    case 8: std::memcpy(to, from, 8); return;
    default: std::memcpy(to, from, n);
  }
}
bool same_small(const uint8_t* a, const uint8_t* b, uint32_t n) {
  switch (n) {
    case 1: return *a == *b;
    case 4: { uint32_t x, y; std::memcpy(&x, a, 4), std::memcpy(&y, b, 4); return x == y; }
    case 8: { uint64_t x, y; std::memcpy(&x, a, 8), std::memcpy(&y, b, 8); return x == y; }
    default: return std::memcmp(a, b, n) == 0;
  }
}
}  // namespace

void ChangeDrivenEngine::written(uint32_t off, uint32_t len) {
  if (full_ && in_full_) return;  // a probe marks every region
  last_unit_ = kNoUnit;
  for (uint64_t b = off; b < uint64_t(off) + len && b < unit_of_.size(); b++)
    if (!external_byte_[b]) mark_byte(uint32_t(b), SIZE_MAX);  // the external bytes: compared before the scan
}

void ChangeDrivenEngine::mark_all() { all_ = true; }

void ChangeDrivenEngine::mark_byte(uint32_t b, size_t self) {
  const uint32_t u = unit_of_[b];
  if (u == kNoUnit || u == last_unit_) return;
  last_unit_ = u;
  for (uint32_t k = touch_at_[u]; k < touch_at_[u + 1]; k++) {
    const uint32_t t = touch_[k];
    const size_t r = t & ~kReads;
    if (r != self || (t & kReads)) set(r);
  }
}

size_t ChangeDrivenEngine::next_dirty(size_t pos) const {
  for (size_t w = pos >> 6; w < dirty_.size(); w++) {
    uint64_t bits = dirty_[w];
    if (w == pos >> 6) bits &= ~uint64_t(0) << (pos & 63);
    if (bits) return w * 64 + size_t(std::countr_zero(bits));
  }
  return SIZE_MAX;
}

// No vptr check on the call of a region's engine: UBSan's check, on a type it
// has not seen, probes memory with pipe2 and write, which the sandbox's child
// (runtime/sandbox.cpp, ldrun --sandbox) refuses.
__attribute__((no_sanitize("vptr"))) void ChangeDrivenEngine::run(size_t r, uint8_t* m) {
  Part& p = parts_[r];
  size_t k = 0;
  for (const Span& s : p.writes) copy_small(snap_.data() + k, m + s.off, s.len), k += s.len;
  ran_++;
  p.engine->scan(*image_);
  k = 0;
  last_unit_ = kNoUnit;
  for (const Span& s : p.writes) {
    if (!same_small(snap_.data() + k, m + s.off, s.len))
      for (uint32_t i = 0; i < s.len; i++)
        if (snap_[k + i] != m[s.off + i]) mark_byte(s.off + i, r);
    k += s.len;
  }
}

void ChangeDrivenEngine::scan(ImageBytes& mem) {
  if (!full_) return walk(mem);
  // every 8th scan is timed, and every scan of a probe's first kProbe
  const bool timed = scans_++ % 8 == 0 || (!in_full_ && since_ < kProbe);
  const auto t0 = timed ? std::chrono::steady_clock::now() : std::chrono::steady_clock::time_point();
  if (in_full_) {
    full_->scan(mem);
    ran_ = SIZE_MAX;
  } else {
    walk(mem);
  }
  since_++;
  if (timed) choose(double(std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now() - t0).count()));
  else choose(-1);
}

// After a timed scan (ns), or an untimed one (ns < 0).
void ChangeDrivenEngine::choose(double ns) {
  if (fixed_full_ || fixed_walk_) {
    if (since_ < (in_full_ ? fixed_full_ : fixed_walk_)) return;
    in_full_ = !in_full_, since_ = 0;
    if (!in_full_) all_ = true;
    return;
  }
  // a mode's first timed scan after a switch (cold code, the probe's marked
  // regions) is left out; a mode is judged by the median of its last 16
  // timed scans (a scan the system interrupted does not decide)
  auto add = [&](double x) {
    if (timed_seen_++ == 0) return;
    times_.push_back(x);
    if (times_.size() > 16) times_.erase(times_.begin());
  };
  auto median = [&] {
    std::vector<double> v = times_;
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    return v[v.size() / 2];
  };
  auto switch_to = [&](bool full) {
    in_full_ = full, since_ = 0;
    times_.clear(), timed_seen_ = 0;
  };
  if (in_full_) {
    if (ns >= 0) add(ns);
    if (since_ < wait_ || times_.size() < 2) return;
    full_ns_ = median();
    switch_to(false);
    all_ = true;  // nothing is known of the regions after full scans
    return;
  }
  if (ns < 0 || since_ <= kSettle) return;
  add(ns);
  if (times_.size() < 3) return;
  const double walk = median();
  // walking must win by a margin (kKeep) to be kept: the two are measured
  // at different times; a probe decides after kProbe scans, or at once if the
  // walk is clearly slower
  if (walk > 2 * full_ns_ || (since_ >= kProbe && walk > kKeep * full_ns_)) {
    switch_to(true);
    wait_ = std::min<uint64_t>(wait_ * 2, kMaxWait);
  } else if (since_ >= kProbe) {
    wait_ = kMinWait;  // the next time the regions lose, a probe comes soon again
  }
}

void ChangeDrivenEngine::walk(ImageBytes& mem) {
  uint8_t* m = mem.data();
  image_ = &mem;
  size_t k = 0;
  if (all_) {
    std::fill(dirty_.begin(), dirty_.end(), ~uint64_t(0));
    if (parts_.size() % 64) dirty_.back() = (uint64_t(1) << (parts_.size() % 64)) - 1;
    for (const Span& s : external_) std::memcpy(shadow_.data() + k, m + s.off, s.len), k += s.len;
    all_ = false;
  } else {
    last_unit_ = kNoUnit;
    for (const Span& s : external_) {
      if (std::memcmp(shadow_.data() + k, m + s.off, s.len) != 0)
        for (uint32_t i = 0; i < s.len; i++)
          if (shadow_[k + i] != m[s.off + i]) shadow_[k + i] = m[s.off + i], mark_byte(s.off + i, SIZE_MAX);
      k += s.len;
    }
  }
  int32_t dt;
  std::memcpy(&dt, m + kSysDt, 4);
  ran_ = 0;
  for (size_t pos = 0;;) {
    const size_t r = next_dirty(pos);
    if (r == SIZE_MAX) break;
    dirty_[r >> 6] &= ~(uint64_t(1) << (r & 63));
    // a fault kind left from before this region (a host that did not clear
    // it) is not this region's: it is put back unless the region faults
    uint32_t before = 0, fault = 0;
    std::memcpy(&before, m + kSysFault, 4);
    std::memset(m + kSysFault, 0, 4);
    run(r, m);
    if (parts_[r].time_always || (parts_[r].uses_time && dt == 0)) set(r);
    std::memcpy(&fault, m + kSysFault, 4);
    if (fault == kFaultNone) {
      std::memcpy(m + kSysFault, &before, 4);
      pos = r + 1;
      continue;
    }
    uint32_t at;
    std::memcpy(&at, m + kSysFaultAt, 4);
    at += parts_[r].il_offset;
    std::memcpy(m + kSysFaultAt, &at, 4);
    set(r);  // it did not finish: it runs again
    break;
  }
  image_ = nullptr;
}

}  // namespace ldc
