// driver/targets.cpp -- the table of targets (targets.h).  A target is one
// row here; its data and hooks live in driver/NAME_target.cpp.
#include "driver/targets.h"

#include <fstream>

#include "driver/driver.h"

namespace ldc {

const Target& x86_64_target();  // driver/x86_target.cpp
const Target& c40_target();     // driver/c40_target.cpp

std::span<const Target> targets() {
  static const Target table[] = {
      x86_64_target(),
      c40_target(),
  };
  return table;
}

const Target* find_target(std::string_view name) {
  for (const Target& t : targets())
    if (t.name == name) return &t;
  return nullptr;
}

const Target& target_of(ImageTarget kind) {
  for (const Target& t : targets())
    if (t.image_kind == kind) return t;
  throw std::logic_error("an image kind without a target: " + std::to_string(int(kind)));
}

const Target& host_target() {
  for (const Target& t : targets())
    if (t.host) return t;
  throw std::logic_error("no target runs on this machine");
}

const Target* image_file_target(const std::string& path) {
  if (!is_image_file(path)) return nullptr;
  std::ifstream f(path, std::ios::binary);
  uint8_t head[16] = {};
  f.read(reinterpret_cast<char*>(head), sizeof head);
  uint8_t kind = 0;
  if (std::optional<uint8_t> k = peek_image_target(std::span(head, size_t(f.gcount())))) {
    kind = *k;
  } else {
    try {  // Intel HEX: the image behind it
      kind = uint8_t(load_image_file(path).target);
    } catch (...) {
      return nullptr;
    }
  }
  for (const Target& t : targets())
    if (uint8_t(t.image_kind) == kind) return &t;
  return nullptr;
}

std::string or_list(const std::vector<std::string>& names) {
  std::string s;
  for (size_t i = 0; i < names.size(); i++) s += (i == 0 ? "" : i + 1 == names.size() ? " or " : ", ") + names[i];
  return s;
}

std::string target_names() {
  std::vector<std::string> n;
  for (const Target& t : targets()) n.emplace_back(t.name);
  return or_list(n);
}

std::vector<std::string> engine_names(bool host) {
  std::vector<std::string> n;
  for (const Target& t : targets())
    if (t.host == host)
      for (const TargetEngine& e : t.engines) n.emplace_back(e.name);
  return n;
}

FoundEngine find_engine(std::string_view name) {
  for (const Target& t : targets())
    for (const TargetEngine& e : t.engines)
      if (e.name == name) return {&t, &e};
  return {nullptr, nullptr};
}

Image target_image(const Target& t, const Program& p, const std::string& source_name, int opt_level) {
  TargetCode c = t.generate(p, source_name, opt_level, /*notes=*/false);
  return make_image(t.image_kind, p, std::move(c.assembled.code), c.line_offsets);
}

void throw_assembly_errors(const as::Result& r, const std::string& source_name) {
  if (r.ok()) return;
  std::string msg;
  for (const auto& e : r.errors)
    msg += (msg.empty() ? "" : "\n") + source_name + ":" + std::to_string(e.line) + ":1: error: " + e.message;
  throw UserError(msg);
}

// The lines of the image's source file, if it can be read from here (as
// objdump -S shows what it finds); none otherwise.
static std::vector<std::string> source_lines(const Image& img) {
  std::vector<std::string> lines;
  std::string text;
  try {
    text = read_file(img.source);
  } catch (const std::exception&) {
    return lines;
  }
  size_t at = 0;
  while (at <= text.size() && lines.size() < (1u << 22)) {
    size_t nl = text.find('\n', at);
    std::string l = text.substr(at, nl == std::string::npos ? std::string::npos : nl - at);
    if (!l.empty() && l.back() == '\r') l.pop_back();
    lines.push_back(std::move(l));
    if (nl == std::string::npos) break;
    at = nl + 1;
  }
  return lines;
}

std::multimap<uint32_t, std::string> line_notes(const Image& img, uint32_t unit) {
  std::multimap<uint32_t, std::string> notes;
  const std::vector<std::string> src = source_lines(img);
  uint32_t last_rung = UINT32_MAX;
  int32_t last_line = -1;
  for (const LineEntry& e : img.lines) {
    if (e.rung != last_rung) {
      std::string t = "; rung " + std::to_string(e.rung + 1) + ", line " + std::to_string(e.line);
      if (e.rung < img.rung_titles.size() && !img.rung_titles[e.rung].empty()) t += " \"" + img.rung_titles[e.rung] + "\"";
      notes.emplace(e.code_offset / unit, t);
      last_rung = e.rung;
    }
    if (e.line != last_line && e.line >= 1 && size_t(e.line) <= src.size()) {  // the source line, when it changes
      notes.emplace(e.code_offset / unit, "; " + std::to_string(e.line) + ": " + src[size_t(e.line) - 1]);
      last_line = e.line;
    }
    Instr in;
    decode_instr(img.il, e.il_offset, in);
    notes.emplace(e.code_offset / unit, ";   " + instr_text(in));
  }
  return notes;
}

}  // namespace ldc
