// ldobjdump -- an objdump-style listing of an ldc image: address, bytes and
// instruction, with each rung's source line and IL interleaved.
#include <cstdio>
#include <map>
#include <string>

#include "driver/c40_driver.h"
#include "driver/driver.h"
#include "driver/version.h"

using namespace ldc;

static const char kUsage[] = "usage: ldobjdump IMAGE.bin|IMAGE.hex\n";

static std::string x86_listing(const Image& img, const std::string& path) {
  std::string out;
  char buf[64];
  out += "\n" + path + ":     file format ldc-x86-64 (image of " + img.source + ")\n\n";
  out += "Disassembly of section .code:\n\n";
  std::snprintf(buf, sizeof buf, "%016x <scan>:\n", img.entry);
  out += buf;
  // what to print before the instruction at each code offset
  std::multimap<uint32_t, std::string> notes;
  uint32_t last_rung = UINT32_MAX;
  for (const LineEntry& e : img.lines) {
    if (e.rung != last_rung) {
      std::string t = "; rung " + std::to_string(e.rung + 1) + ", line " + std::to_string(e.line);
      if (e.rung < img.rung_titles.size() && !img.rung_titles[e.rung].empty()) t += " \"" + img.rung_titles[e.rung] + "\"";
      notes.emplace(e.code_offset, t);
      last_rung = e.rung;
    }
    Instr in;
    decode_instr(img.il, e.il_offset, in);
    notes.emplace(e.code_offset, ";   " + instr_text(in));
  }
  as::x86::Disassembly d = as::x86::disassemble(img.code);
  for (const auto& di : d.insts) {
    auto [lo, hi] = notes.equal_range(di.offset);
    for (auto it = lo; it != hi; ++it) out += it->second + "\n";
    std::snprintf(buf, sizeof buf, "%8x:\t", di.offset);
    out += buf;
    std::string bytes;
    for (uint32_t i = 0; i < di.length; i++) {
      std::snprintf(buf, sizeof buf, "%02x ", img.code[di.offset + i]);
      bytes += buf;
    }
    if (bytes.size() < 21) bytes.resize(21, ' ');
    out += bytes + "\t" + as::x86::print(di.inst) + "\n";
  }
  if (d.error) out += "  (cannot decode at offset " + std::to_string(d.error->offset) + ": " + d.error->message + ")\n";
  // Branch sites: each conditional or unconditional jump is a place the branch
  // predictor may have to remember (docs/x86.md, "Branch sites").
  size_t jcc = 0, jmp = 0, call = 0;
  for (const auto& di : d.insts) {
    jcc += di.inst.mnemonic == as::x86::Mnemonic::Jcc;
    jmp += di.inst.mnemonic == as::x86::Mnemonic::Jmp;
    call += di.inst.mnemonic == as::x86::Mnemonic::Call;
  }
  out += "\n; " + std::to_string(img.code.size()) + " bytes, " + std::to_string(d.insts.size()) + " instructions, " +
         std::to_string(img.lines.size()) + " IL; branch sites: " + std::to_string(jcc) + " jcc, " + std::to_string(jmp) +
         " jmp, " + std::to_string(call) + " call\n";
  return out;
}

namespace {

int ldobjdump_main(int argc, char** argv) {
  if (argc == 2 && std::string(argv[1]) == "--version") return print_version("ldobjdump");
  if (argc != 2 || argv[1][0] == '-') {
    std::fputs(kUsage, argc == 2 && std::string(argv[1]) == "--help" ? stdout : stderr);
    return argc == 2 && std::string(argv[1]) == "--help" ? 0 : 1;
  }
  Image img = load_image_file(argv[1]);
  std::string out = img.target == ImageTarget::C40 ? c40_objdump(img, argv[1]) : x86_listing(img, argv[1]);
  std::fwrite(out.data(), 1, out.size(), stdout);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return run_tool("ldobjdump", [&] { return ldobjdump_main(argc, argv); });
}
