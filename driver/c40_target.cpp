// driver/c40_target.cpp -- the C40 row of the table of targets (targets.h):
// backend-c40sim's code generator, the assembler's C40 target, the C40 code
// check, and the engines on the simulated board (c40_engine.cpp).
#include "driver/c40_target.h"

#include <cstdio>

#include "driver/targets.h"

namespace ldc {

C40Build build_c40(const Program& p, const std::string& source_name, int opt_level) {
  C40Build b;
  b.gen = c40gen::generate_c40(p, p.layout(), opt_level);
  b.asm_result = assemble_or_throw(as::c40::target(), b.gen.program, source_name);
  return b;
}

Image make_c40_image(const Program& p, const C40Build& b) {
  return make_image(ImageTarget::C40, p, b.asm_result, b.gen.il_items, rung_blocks(b.gen));
}

namespace {

TargetCode generate(const Program& p, const std::string& source_name, int opt_level, bool /*notes: always*/) {
  C40Build b = build_c40(p, source_name, opt_level);
  return target_code(std::move(b.gen), std::move(b.asm_result));
}

std::string gnu_as(const Program& p, const std::string& source_name, int opt_level) {
  return "; ldc " + source_name + ": TMS320C40, GNU as syntax (tic4x, as -mcpu=40), -O" + std::to_string(opt_level) +
         "\n" + as::c40::to_gnu_as(c40gen::generate_c40(p, p.layout(), opt_level).program);
}

std::string listing(const Program& p, const std::string& source_name, int opt_level) {
  C40Build b = build_c40(p, source_name, opt_level);
  return as::c40::listing(b.gen.program, b.asm_result);
}

// Word addresses, word and instruction, with the rungs and IL interleaved.
std::string disassemble(const Image& img) {
  std::string out = "Disassembly of section .code (32-bit words, word addresses):\n\n";
  char buf[96];
  std::snprintf(buf, sizeof buf, "%08x <scan>:\n", img.entry / 4);
  out += buf;
  std::multimap<uint32_t, std::string> notes = line_notes(img, 4);
  as::c40::Disassembly d = as::c40::disassemble_bytes(img.code);
  for (const auto& di : d.insts) {
    auto [lo, hi] = notes.equal_range(uint32_t(di.address));
    for (auto it = lo; it != hi; ++it) out += it->second + "\n";
    std::snprintf(buf, sizeof buf, "%8llx:\t%08x\t", (unsigned long long)di.address, di.word);
    out += buf + as::c40::print(di.inst) + "\n";
  }
  for (const auto& e : d.errors) out += "  (cannot decode the word at " + std::to_string(e.address) + ": " + e.message + ")\n";
  return out;
}

const as::TargetInfo& assembler() { return as::c40::target(); }

const TargetEngine kEngines[] = {
    {"c40sim", true, [](const Image& img) { return make_c40sim_engine(img.code, img.entry, img.layout); }},
    {"c40interp", false, [](const Image& img) { return make_c40interp_engine(img.il, img.layout); }},
};

}  // namespace

const Target& c40_target() {
  static const Target t{
      .name = "c40",
      .title = "C40",
      .an_image = "a C40 image",
      .image_kind = ImageTarget::C40,
      .host = false,
      .assembler = assembler,
      .generate = generate,
      .gnu_as = gnu_as,
      .listing = listing,
      .disassemble = disassemble,
      .engines = kEngines,
  };
  return t;
}

}  // namespace ldc
