// loader/image_kinds.cpp -- the table of image kinds (loader.h): each kind of
// machine code an image can hold, with the code check read_image applies;
// and OffsetBits, the set of instruction starts a check gives back.
#include <algorithm>
#include <array>
#include <bit>

#include "loader/c40_check.h"
#include "loader/checks.h"
#include "loader/loader.h"

namespace ldc {

namespace {

// The C40 check (c40_check.h); every word is an instruction.
std::string check_c40(std::span<const uint8_t> code, uint32_t entry, const Layout& layout, OffsetBits* starts) {
  std::string why = check_c40_code(code, entry, layout);
  if (why.empty() && starts) {
    *starts = OffsetBits(code.size());
    for (uint32_t off = 0; off < code.size(); off += 4) starts->add(off);
  }
  return why;
}

constexpr std::array kKinds = {
    ImageKind{ImageTarget::X86_64, "x86-64", 1, detail::check_x86},
    ImageKind{ImageTarget::C40, "C40", 4, check_c40},
};

}  // namespace

std::span<const ImageKind> image_kinds() { return kKinds; }

int64_t OffsetBits::before(uint64_t off) const {
  if (off == 0 || size_ == 0) return -1;
  uint64_t last = std::min<uint64_t>(off, size_) - 1;  // the first candidate
  size_t w = size_t(last / 64);
  uint64_t word = bits_[w] & (~uint64_t(0) >> (63 - last % 64));
  while (!word) {
    if (w == 0) return -1;
    word = bits_[--w];
  }
  return int64_t(w * 64 + 63 - size_t(std::countl_zero(word)));
}

bool OffsetBits::meets(const OffsetBits& o) const {
  for (size_t w = 0; w < bits_.size() && w < o.bits_.size(); w++)
    if (bits_[w] & o.bits_[w]) return true;
  return false;
}

const ImageKind* find_image_kind(uint8_t id) {
  for (const ImageKind& k : kKinds)
    if (uint8_t(k.id) == id) return &k;
  return nullptr;
}

}  // namespace ldc
