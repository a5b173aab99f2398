// loader/build.cpp -- an image from a program and its assembled code
// (loader.h: make_image, retentive_ranges).
#include <algorithm>

#include "loader/loader.h"

namespace ldc {

std::vector<RetentiveRange> retentive_ranges(const Program& p) {
  std::vector<RetentiveRange> r = {{Area::K, 0, device_count(Dev::K)}};
  std::vector<uint32_t> words;
  for (const DeviceRef& d : p.retain) words.push_back(d.index);
  std::sort(words.begin(), words.end());
  words.erase(std::unique(words.begin(), words.end()), words.end());
  for (size_t i = 0; i < words.size(); i++) {
    if (i && words[i] == words[i - 1] + 1) r.back().count++;
    else r.push_back({Area::D, words[i], 1});
  }
  return r;
}

namespace {

// Everything of the image but its code bytes.
Image image_without_code(ImageTarget target, const Program& p, const as::Result& code,
                         const std::vector<std::vector<uint32_t>>& il_items, std::span<const uint32_t> rung_blocks) {
  Image img;
  img.target = target;
  img.source = p.source;
  img.layout = p.layout();
  img.entry = 0;
  BinaryIl bin = encode_il(p);
  img.il = std::move(bin.code);  // bin.instr_offset is still read below
  img.aliases = p.aliases;
  img.retentive = retentive_ranges(p);
  size_t k = 0;
  img.rung_titles.reserve(p.rungs.size());
  img.lines.reserve(bin.instr_offset.size());
  for (size_t r = 0; r < p.rungs.size(); r++) {
    img.rung_titles.push_back(p.rungs[r].title);
    uint32_t b = rung_blocks[r];
    const auto& items = code.items[b];
    uint32_t block_end = b + 1 < code.block_offsets.size() ? code.block_offsets[b + 1] : uint32_t(code.code.size());
    for (size_t i = 0; i < p.rungs[r].code.size(); i++, k++) {
      const Instr& in = p.rungs[r].code[i];
      uint32_t at = il_items[r][i];  // an instruction that emitted nothing at the rung's end: the block's end
      img.lines.push_back({at < items.size() ? items[at].offset : block_end, bin.instr_offset[k],
                           in.loc.line ? in.loc.line : p.rungs[r].line, uint32_t(r)});
    }
  }
  return img;
}

}  // namespace

Image make_image(ImageTarget target, const Program& p, const as::Result& code,
                 const std::vector<std::vector<uint32_t>>& il_items, std::span<const uint32_t> rung_blocks) {
  Image img = image_without_code(target, p, code, il_items, rung_blocks);
  img.code = code.code;
  return img;
}

Image make_image(ImageTarget target, const Program& p, as::Result&& code,
                 const std::vector<std::vector<uint32_t>>& il_items, std::span<const uint32_t> rung_blocks) {
  Image img = image_without_code(target, p, code, il_items, rung_blocks);
  img.code = std::move(code.code);
  return img;
}

}  // namespace ldc
