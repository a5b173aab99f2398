// runtime/write_shadow.cpp -- see write_shadow.h.
#include "runtime/write_shadow.h"

#include <algorithm>
#include <bit>
#include <cstring>

namespace ldc::plc {

void apply_element(const ElementWrite& w, uint8_t* mem, const Layout& L) {
  uint8_t* at = mem + L.addr(w.area, w.index);
  if (area_is_bit(w.area)) {
    *at = uint8_t(w.value & 1);
    return;
  }
  uint32_t old;
  std::memcpy(&old, at, 4);
  uint32_t now = (old & ~w.mask) | (w.value & w.mask);
  std::memcpy(at, &now, 4);
}

namespace {
uint64_t key_of(const ElementWrite& w) { return uint64_t(w.area) << 32 | w.index; }
// A bit element's write replaces it whole: its mask says nothing.
ElementWrite normalised(ElementWrite w) {
  if (area_is_bit(w.area)) w.value &= 1, w.mask = 1;
  return w;
}
}  // namespace

WriteShadow::WriteShadow(size_t capacity) : capacity_(std::max<size_t>(capacity, 1)) {
  writes_.reserve(capacity_);
  index_.assign(std::bit_ceil(4 * capacity_), Slot{0, 0, 0});
}

void WriteShadow::clear_index() {
  writes_.clear();
  if (++gen_ == 0) {  // the stamps wrapped: every slot is stale in fact, say so
    for (Slot& s : index_) s.gen = 0;
    gen_ = 1;
  }
}

// Linear probing from a multiplicative hash; the table is never more than
// half full (merge grows it), so a free slot is always found.
WriteShadow::Slot& WriteShadow::slot_of(uint64_t key) {
  size_t mask = index_.size() - 1;
  size_t i = size_t((key * 0x9E3779B97F4A7C15ull) >> 20) & mask;
  while (index_[i].gen == gen_ && index_[i].key != key) i = (i + 1) & mask;
  return index_[i];
}

// put_back may hold more than `capacity` elements for a while: the table then
// doubles, so that it stays at most half full.
void WriteShadow::grow() {
  std::vector<Slot> old(index_.size() * 2, Slot{0, 0, 0});
  old.swap(index_);
  gen_ = 1;
  for (uint32_t pos = 0; pos < writes_.size(); pos++) slot_of(key_of(writes_[pos])) = Slot{key_of(writes_[pos]), pos, gen_};
}

void WriteShadow::merge(const ElementWrite& in) {
  ElementWrite w = normalised(in);
  if (2 * (writes_.size() + 1) > index_.size()) grow();
  Slot& s = slot_of(key_of(w));
  if (s.gen != gen_) {
    s = Slot{key_of(w), uint32_t(writes_.size()), gen_};
    writes_.push_back(w);
    return;
  }
  ElementWrite& e = writes_[s.pos];
  e.value = (e.value & ~w.mask) | (w.value & w.mask);
  e.mask |= w.mask;
}

// The distinct elements of `writes` the shadow does not hold yet.
size_t WriteShadow::fresh_elements(std::span<const ElementWrite> writes) {
  std::vector<uint64_t> keys;
  keys.reserve(writes.size());
  for (const ElementWrite& w : writes)
    if (slot_of(key_of(w)).gen != gen_) keys.push_back(key_of(w));
  std::sort(keys.begin(), keys.end());
  return size_t(std::unique(keys.begin(), keys.end()) - keys.begin());
}

uint64_t WriteShadow::post(std::span<const ElementWrite> writes) {
  std::lock_guard<std::mutex> l(mu_);
  // A request that surely fits is merged at once; else its new elements are
  // counted first, so that a refused request merges nothing.
  if (writes_.size() + writes.size() > capacity_ && writes_.size() + fresh_elements(writes) > capacity_) return 0;
  for (const ElementWrite& w : writes) merge(w);
  return ++ticket_;
}

bool WriteShadow::take(Batch& b) {
  b.writes.clear();
  std::unique_lock<std::mutex> l(mu_, std::try_to_lock);
  if (!l.owns_lock()) return false;
  b.ticket = ticket_;
  if (writes_.empty()) return true;
  b.writes.swap(writes_);
  clear_index();
  return true;
}

void WriteShadow::put_back(const Batch& b) {
  if (b.empty()) return;
  std::lock_guard<std::mutex> l(mu_);
  std::vector<ElementWrite> since;
  since.swap(writes_);
  clear_index();
  for (const ElementWrite& w : b.writes) merge(w);
  for (const ElementWrite& w : since) merge(w);
}

size_t WriteShadow::size() const {
  std::lock_guard<std::mutex> l(mu_);
  return writes_.size();
}

uint64_t WriteShadow::last_ticket() const {
  std::lock_guard<std::mutex> l(mu_);
  return ticket_;
}

}  // namespace ldc::plc
