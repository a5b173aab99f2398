// loader/image_kinds.cpp -- the table of image kinds (loader.h): each kind of
// machine code an image can hold, with the code check read_image applies.
#include <array>

#include "loader/c40_check.h"
#include "loader/checks.h"
#include "loader/loader.h"

namespace ldc {

namespace {

// The C40 check (c40_check.h); every word is an instruction.
std::string check_c40(std::span<const uint8_t> code, uint32_t entry, const Layout& layout,
                      std::vector<uint32_t>* starts) {
  std::string why = check_c40_code(code, entry, layout);
  if (why.empty() && starts)
    for (uint32_t off = 0; off < code.size(); off += 4) starts->push_back(off);
  return why;
}

constexpr std::array kKinds = {
    ImageKind{ImageTarget::X86_64, "x86-64", 1, detail::check_x86},
    ImageKind{ImageTarget::C40, "C40", 4, check_c40},
};

}  // namespace

std::span<const ImageKind> image_kinds() { return kKinds; }

const ImageKind* find_image_kind(uint8_t id) {
  for (const ImageKind& k : kKinds)
    if (uint8_t(k.id) == id) return &k;
  return nullptr;
}

}  // namespace ldc
