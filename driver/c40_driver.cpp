// driver/c40_driver.cpp -- the C40 route of ldc and ldobjdump (c40_driver.h).
#include "driver/c40_driver.h"

#include <cstdio>
#include <fstream>
#include <map>

namespace ldc {

C40Build build_c40(const Program& p, const std::string& source_name, int opt_level) {
  C40Build b;
  b.gen = c40gen::generate_c40(p, p.layout(), opt_level);
  b.asm_result = as::assemble(as::c40::target(), b.gen.program, as::Mode::Blockwise);
  if (!b.asm_result.ok()) {
    std::string msg;
    for (const auto& e : b.asm_result.errors)
      msg += (msg.empty() ? "" : "\n") + source_name + ":" + std::to_string(e.line) + ":1: error: " + e.message;
    throw UserError(msg);
  }
  return b;
}

Image make_c40_image(const Program& p, const C40Build& b) {
  std::vector<uint32_t> blocks;
  for (size_t r = 0; r < b.gen.il_items.size(); r++) blocks.push_back(c40gen::C40Code::rung_block(r));
  return make_image(ImageTarget::C40, p, b.asm_result, b.gen.il_items, blocks);
}

std::string c40_output(const Program& p, const std::string& input, const std::string& emit, bool to_file,
                       int opt_level) {
  if (emit == "asm")
    return "; ldc " + input + ": TMS320C40, GNU as syntax (tic4x, as -mcpu=40), -O" + std::to_string(opt_level) + "\n" +
           as::c40::toGnuAs(c40gen::generate_c40(p, p.layout(), opt_level).program);
  C40Build b = build_c40(p, input, opt_level);
  if (emit == "listing") return as::c40::listing(b.gen.program, b.asm_result);
  std::vector<uint8_t> bin = write_image(make_c40_image(p, b));
  if (emit == "hex") return write_intel_hex(bin);
  if (!to_file) throw UserError("ldc: error: an image needs -o FILE (or --emit=hex for text on stdout)");
  return std::string(bin.begin(), bin.end());
}

std::string c40_objdump(const Image& img, const std::string& path) {
  std::string out;
  char buf[96];
  out += "\n" + path + ":     file format ldc-c40 (image of " + img.source + ")\n\n";
  out += "Disassembly of section .code (32-bit words, word addresses):\n\n";
  std::snprintf(buf, sizeof buf, "%08x <scan>:\n", img.entry / 4);
  out += buf;
  std::multimap<uint32_t, std::string> notes;  // by word address
  uint32_t last_rung = UINT32_MAX;
  for (const LineEntry& e : img.lines) {
    if (e.rung != last_rung) {
      std::string t = "; rung " + std::to_string(e.rung + 1) + ", line " + std::to_string(e.line);
      if (e.rung < img.rung_titles.size() && !img.rung_titles[e.rung].empty()) t += " \"" + img.rung_titles[e.rung] + "\"";
      notes.emplace(e.code_offset / 4, t);
      last_rung = e.rung;
    }
    Instr in;
    decode_instr(img.il, e.il_offset, in);
    notes.emplace(e.code_offset / 4, ";   " + instr_text(in));
  }
  as::c40::Disassembly d = as::c40::disassembleBytes(img.code);
  for (const auto& di : d.insts) {
    auto [lo, hi] = notes.equal_range(uint32_t(di.address));
    for (auto it = lo; it != hi; ++it) out += it->second + "\n";
    std::snprintf(buf, sizeof buf, "%8llx:\t%08x\t", (unsigned long long)di.address, di.word);
    out += buf + as::c40::print(di.inst) + "\n";
  }
  for (const auto& e : d.errors) out += "  (cannot decode the word at " + std::to_string(e.address) + ": " + e.message + ")\n";
  return out;
}

bool is_c40_image(const std::string& path) {
  if (!is_image_file(path)) return false;
  std::ifstream f(path, std::ios::binary);
  char head[12] = {};
  f.read(head, 12);
  if (f.gcount() == 12 && std::string(head, 6) == "LDCIMG") return uint8_t(head[10]) == uint8_t(ImageTarget::C40);
  try {  // Intel HEX: the image behind it
    return load_image_file(path).target == ImageTarget::C40;
  } catch (...) {
    return false;
  }
}

}  // namespace ldc
