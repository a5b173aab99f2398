// Helpers shared by the loader tests: a tiny valid image built by hand.
#pragma once

#include <string>
#include <vector>

#include "assembler/x86.h"
#include "loader/loader.h"

namespace ldc::test {

// Assembles lines one after the other (branch operands are absolute offsets).
inline std::vector<uint8_t> assemble(const std::vector<std::string>& lines) {
  std::vector<uint8_t> code;
  for (const std::string& l : lines) {
    auto b = as::x86::encode_at(as::x86::parse(l), code.size());
    code.insert(code.end(), b.begin(), b.end());
  }
  return code;
}

// A scan function: the canonical -O0 prologue (8 bytes), the body, the
// epilogue.  Branch operands in the body are offsets from the body's start.
inline std::vector<uint8_t> framed(const std::vector<std::string>& body) {
  std::vector<uint8_t> code;
  for (const auto& in : as::x86::scan_prologue(false)) {
    auto b = as::x86::encode_at(in, code.size());
    code.insert(code.end(), b.begin(), b.end());
  }
  const size_t base = code.size();
  for (const std::string& l : body) {
    as::x86::Instruction in = as::x86::parse(l);
    if (in.num_operands && in.ops[0].kind == as::x86::OperandKind::Address) in.ops[0].imm += int64_t(base);
    auto b = as::x86::encode_at(in, code.size());
    code.insert(code.end(), b.begin(), b.end());
  }
  for (const auto& in : as::x86::scan_epilogue(false)) {
    auto b = as::x86::encode_at(in, code.size());
    code.insert(code.end(), b.begin(), b.end());
  }
  return code;
}

inline std::string disp(uint32_t v) {
  char buf[16];
  std::snprintf(buf, sizeof buf, "0x%x", v);
  return buf;
}

// `LOAD X0 / OUT Y0` as IL and as x86-64 code, with every optional field set.
inline Image tiny_image() {
  Program p = parse_il_text(".rung line 1 \"copy\"\nLOAD X0\nOUT Y0\n.end\n", "t.il");
  BinaryIl bil = encode_il(p);
  Image im;
  im.source = "t.ld";
  im.layout = p.layout();
  uint32_t x0 = im.layout.addr(Area::X, 0), y0 = im.layout.addr(Area::Y, 0);
  im.code = framed({"movzx eax, byte ptr [rbx+" + disp(x0) + "]", "mov byte ptr [rbx+" + disp(y0) + "], al"});
  im.entry = 0;
  im.il = bil.code;
  // movzx starts after the 8-byte prologue, the mov after it at 8+4.
  im.lines = {{8, bil.instr_offset.at(0), 2, 0}, {12, bil.instr_offset.at(1), 2, 0}};
  im.rung_titles = {"copy"};
  im.aliases = {{"start", {Dev::X, 0}}, {"lamp", {Dev::Y, 0}}, {"count", {Dev::C, 255}}};
  im.retentive = {{Area::K, 0, 8192}, {Area::CW, 3, 2}};
  return im;
}

inline uint32_t get32(const std::vector<uint8_t>& b, size_t at) {
  return uint32_t(b[at]) | uint32_t(b[at + 1]) << 8 | uint32_t(b[at + 2]) << 16 | uint32_t(b[at + 3]) << 24;
}
inline void put32(std::vector<uint8_t>& b, size_t at, uint32_t v) {
  for (int i = 0; i < 4; i++) b[at + i] = uint8_t(v >> (8 * i));
}
// Recomputes the header checksum after a test has edited the bytes.
inline void reseal(std::vector<uint8_t>& b) {
  put32(b, 24, 0);
  put32(b, 24, crc32(b));
}

// Offsets of the format (docs/image-format.md).
constexpr size_t kSectionTable = 168;
inline size_t entry_at(int i) { return kSectionTable + 12 * size_t(i); }
// Index of the section table entry with the given id.
inline int find_section(const std::vector<uint8_t>& b, uint32_t id) {
  uint32_t n = get32(b, 20);
  for (uint32_t i = 0; i < n; i++)
    if (get32(b, entry_at(int(i))) == id) return int(i);
  return -1;
}

}  // namespace ldc::test
