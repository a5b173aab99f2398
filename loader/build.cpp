// loader/build.cpp -- an image from a program and its assembled code
// (loader.h: make_image, retentive_ranges).
#include <algorithm>
#include <stdexcept>

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

void append_line_offsets(std::vector<uint32_t>& out, std::span<const as::ItemLayout> items, uint32_t block_end,
                         std::span<const uint32_t> starts) {
  for (uint32_t at : starts)  // an instruction that emitted nothing at the rung's end: the block's end
    out.push_back(at < items.size() ? items[at].offset : block_end);
}

std::vector<uint32_t> line_offsets(const as::Result& code, const std::vector<std::vector<uint32_t>>& il_items,
                                   std::span<const uint32_t> rung_blocks) {
  std::vector<uint32_t> out;
  for (size_t r = 0; r < il_items.size(); r++) {
    uint32_t b = rung_blocks[r];
    uint32_t block_end = b + 1 < code.block_offsets.size() ? code.block_offsets[b + 1] : uint32_t(code.code.size());
    append_line_offsets(out, code.items[b], block_end, il_items[r]);
  }
  return out;
}

Image make_image(ImageTarget target, const Program& p, std::vector<uint8_t> code, std::span<const uint32_t> offsets) {
  Image img;
  img.target = target;
  img.source = p.source;
  img.layout = p.layout();
  img.entry = 0;
  BinaryIl bin = encode_il(p);
  if (offsets.size() != bin.instr_offset.size())
    throw std::invalid_argument("make_image: " + std::to_string(offsets.size()) + " code offsets for " +
                                std::to_string(bin.instr_offset.size()) + " IL instructions");
  img.il = std::move(bin.code);
  img.aliases = p.aliases;
  img.vars = p.vars;
  img.retentive = retentive_ranges(p);
  size_t k = 0;
  img.rung_titles.reserve(p.rungs.size());
  img.lines.reserve(bin.instr_offset.size());
  for (size_t r = 0; r < p.rungs.size(); r++) {
    img.rung_titles.push_back(p.rungs[r].title);
    for (const Instr& in : p.rungs[r].code) {
      img.lines.push_back({offsets[k], bin.instr_offset[k], in.loc.line ? in.loc.line : p.rungs[r].line, uint32_t(r)});
      k++;
    }
  }
  img.code = std::move(code);
  return img;
}

Image make_image(ImageTarget target, const Program& p, const as::Result& code,
                 const std::vector<std::vector<uint32_t>>& il_items, std::span<const uint32_t> rung_blocks) {
  return make_image(target, p, code.code, line_offsets(code, il_items, rung_blocks));
}

Image make_image(ImageTarget target, const Program& p, as::Result&& code,
                 const std::vector<std::vector<uint32_t>>& il_items, std::span<const uint32_t> rung_blocks) {
  std::vector<uint32_t> offsets = line_offsets(code, il_items, rung_blocks);
  return make_image(target, p, std::move(code.code), offsets);
}

}  // namespace ldc
