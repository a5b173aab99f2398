// tests/loader/c40_hostile.h -- hand-built hostile C40 images (issue 24, item 11):
// code that tries to leave the checked code through the stack, a computed
// branch or a store into the code.  Shared by c40image_test.cpp and the
// mutant fuzzer's C40 stack shapes.
#pragma once

#include <cstring>
#include <string>
#include <vector>

#include "assembler/c40.h"
#include "loader/c40_map.h"
#include "loader/loader.h"

namespace ldc::test {

// Assembles TI-syntax lines one word each at word addresses 0, 1, ...;
// branch operands are absolute word addresses.
inline std::vector<uint8_t> c40_words(const std::vector<std::string>& lines) {
  std::vector<uint8_t> code;
  for (size_t i = 0; i < lines.size(); i++) {
    uint32_t w = as::c40::encode_at(as::c40::parse(lines[i]), int64_t(i));
    for (int k = 0; k < 4; k++) code.push_back(uint8_t(w >> (8 * k)));
  }
  return code;
}

inline std::string c40_hex(uint32_t v) {
  char b[16];
  std::snprintf(b, sizeof b, "0%xh", v);
  return b;
}

// A C40 image of the program `LOAD X0 / OUT Y1` (it writes Y1 only) whose
// code is `lines`: the IL, layout and sections stay valid, so only the code
// check decides.
inline Image c40_image_with_code(const std::vector<std::string>& lines) {
  Program p = parse_il_text(".rung line 1\n    LOAD X0\n    OUT Y1\n.end\n", "t.il");
  Image im;
  im.target = ImageTarget::C40;
  im.source = "t.il";
  im.layout = p.layout();
  im.il = encode_il(p).code;
  im.code = c40_words(lines);
  im.entry = 0;
  return im;
}

// Word address of a device element on the board, and its 16-bit direct offset.
inline uint32_t c40_addr(const Image& im, Area a, uint32_t i) { return c40map::C40Layout::of(im.layout).addr(a, i); }

// The walk-around of issue 24 (item 11).  PUSH of D0's address, then RETSU:
// control goes to the memory image, where D0 and D1 (values the trace
// supplies) run.  D0 = `STI R1, *AR0` rewrites word kVictim (the check saw
// RETSU there) into `STI R2, @Y0`; D1 = `BU R3` branches to it; Y0 becomes 1
// and the rewritten word's RETSU-successor returns.  The checked code has no
// store to Y0.
struct StackAttack {
  static constexpr uint32_t kVictim = 12, kPush = 10;
  Image image;
  uint32_t d0_word, d1_word;  // what the trace puts into D0 and D1
};

inline StackAttack c40_push_retsu_attack(const std::string& push = "PUSH R0", const std::string& ret = "RETSU") {
  StackAttack a;
  Image probe = c40_image_with_code({"RETSU"});
  const uint32_t d0 = c40_addr(probe, Area::D, 0), y0 = c40_addr(probe, Area::Y, 0);
  const uint32_t sti_y0 = as::c40::encode_at(as::c40::parse("STI R2, @" + c40_hex(y0 & 0xFFFF)), 0);
  std::vector<std::string> code = {
      "LDPK 080h",                                         // 0
      "LDI 1, R2",                                         // 1
      "LDI " + std::to_string(StackAttack::kVictim) + ", AR0",  // 2
      "LDI " + std::to_string(StackAttack::kVictim) + ", R3",   // 3
      "LDHI " + c40_hex(sti_y0 >> 16) + ", R1",            // 4
      "OR " + c40_hex(sti_y0 & 0xFFFF) + ", R1",           // 5: R1 = the word of STI R2, @Y0
      "LDHI " + c40_hex(d0 >> 16) + ", R0",                // 6
      "OR " + c40_hex(d0 & 0xFFFF) + ", R0",               // 7: R0 = D0's address
      "NOP",                                               // 8
      "NOP",                                               // 9
      push,                                                // 10 (kPush)
      ret,                                                 // 11
      "RETSU",                                             // 12 (kVictim): rewritten
      "RETSU",                                             // 13
  };
  a.image = c40_image_with_code(code);
  a.d0_word = as::c40::encode_at(as::c40::parse("STI R1, *AR0"), d0);
  a.d1_word = as::c40::encode_at(as::c40::parse("BU R3"), d0 + 1);
  return a;
}

}  // namespace ldc::test
