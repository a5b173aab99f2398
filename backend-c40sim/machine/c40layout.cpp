// backend-c40sim/machine/c40layout.cpp -- the C40 word image (c40layout.h).
#include "backend-c40sim/machine/c40layout.h"

#include <cstring>

namespace ldc::c40gen {

void bytes_to_words(const Layout& l, const C40Layout& w, const uint8_t* bytes, uint32_t* words) {
  std::memset(words + w.offset[int(Area::Sys)], 0, kSysWords * 4);
  std::memcpy(words + kSysDtWord, bytes + kSysDt, 4);
  std::memcpy(words + kSysScanWord, bytes + kSysScan, 4);
  std::memcpy(words + kSysFaultWord, bytes + kSysFault, 16);  // kind, at, the index's two words
  for (int i = 1; i < kAreaCount; i++) {
    Area a = Area(i);
    const uint8_t* src = bytes + l.offset[i];
    uint32_t* dst = words + w.offset[i];
    if (area_is_bit(a) || a == Area::E) {
      for (uint32_t k = 0; k < l.count[i]; k++) dst[k] = src[k] != 0;
    } else {
      std::memcpy(dst, src, size_t(l.count[i]) * 4);  // little-endian host, as the byte image
    }
  }
}

void words_to_bytes(const Layout& l, const C40Layout& w, const uint32_t* words, uint8_t* bytes) {
  std::memcpy(bytes + kSysDt, words + kSysDtWord, 4);
  std::memcpy(bytes + kSysScan, words + kSysScanWord, 4);
  std::memcpy(bytes + kSysFault, words + kSysFaultWord, 16);
  for (int i = 1; i < kAreaCount; i++) {
    Area a = Area(i);
    const uint32_t* src = words + w.offset[i];
    uint8_t* dst = bytes + l.offset[i];
    if (area_is_bit(a) || a == Area::E) {
      for (uint32_t k = 0; k < l.count[i]; k++) dst[k] = src[k] <= 1 ? uint8_t(src[k]) : 0xEE;
    } else {
      std::memcpy(dst, src, size_t(l.count[i]) * 4);
    }
  }
}

}  // namespace ldc::c40gen
