// The -O2 base registers pointed region by region (docs/x86.md, "Compact
// addressing"): programs whose rungs move from one group of devices to the
// next, with jumps over regions that point the registers elsewhere, run on the
// native code at every level and on the reference interpreter; the memory
// images must agree after every scan, the loader must accept the images, and
// the -O2 code must really point the registers again inside the body.
#include <gtest/gtest.h>

#include <cstring>
#include <sstream>

#include "assembler/x86.h"
#include "driver/x86_target.h"
#include "ir/ir.h"
#include "runtime/runtime.h"

using namespace ldc;
namespace x86 = ldc::as::x86;

namespace {

// Groups of rungs, each group on its own devices (D, M, Y 1-2 KiB apart, more
// operands than a region holds); X inputs decide the jumps: one over the
// second group to a label, a second jump to the same label from the third
// group, one to the end.  After each label the code goes on with the devices
// of the code falling through to it, so the registers would keep their K there
// but for the jumps, which bring other K.
std::string program() {
  std::ostringstream s;
  int line = 1;
  auto rung = [&](const std::string& body) { s << ".rung line " << line++ << "\n" << body; };
  auto group = [&](int d, int m, int y, int rungs) {
    for (int i = 0; i < rungs; i++) {
      std::string di = "D" + std::to_string(d + i % 24), dj = "D" + std::to_string(d + (i * 7) % 24);
      rung("    LOAD X" + std::to_string(8 + i % 8) + "\n    AND M" + std::to_string(m + i % 40) + "\n    OUT Y" +
           std::to_string(y + i % 30) + "\n    ADD " + di + " " + dj + " " + di + "\n    LDGT " + dj + " 50\n    OUT M" +
           std::to_string(m + (i + 3) % 40) + "\n");
    }
  };
  s << "; base registers region by region\n";
  group(0, 0, 0, 12);
  rung("    LOAD X0\n    JMP far\n");
  group(100, 200, 120, 12);
  rung("    LOAD X1\n    JMP near\n");
  group(200, 400, 200, 12);
  s << ".label near\n";
  group(200, 400, 200, 4);  // the devices of the code falling through: only the jump differs
  group(60, 100, 60, 6);
  rung("    LOAD X2\n    JMP far\n");
  group(150, 300, 160, 12);
  s << ".label far\n";
  group(150, 300, 160, 4);
  group(0, 0, 0, 6);  // the first group's devices again
  group(200, 400, 200, 6);
  rung("    LOAD X3\n    JMP fin\n");
  group(100, 200, 120, 6);
  s << ".label fin\n";
  group(60, 100, 60, 4);
  s << ".end\n";
  return s.str();
}

struct Rng {
  uint64_t s;
  uint64_t next() {
    uint64_t z = (s += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
};

// "" if the native code at `level` and the reference interpreter agree on
// every byte after each of `scans` scans with random inputs.
std::string compare(const Program& p, int level, uint64_t seed, int scans) {
  Layout L = p.layout();
  NativeBuild nb = build_x86(p, p.source, as::Mode::Blockwise, level, false);
  read_image(write_image(make_x86_image(p, nb)), "regions.bin");  // throws if the loader refuses it
  auto native = make_native_engine(map_checked_code(nb.asm_result.code, 0, L));
  auto ref = make_interp_engine(encode_il(p).code, L);
  Memory a(L), b(L);
  Rng r{seed};
  for (uint32_t i = 0; i < 256; i++) {  // devices that differ, so that a wrong address shows
    int32_t v = int32_t(r.next() % 101);
    a.set_int(Area::D, i, v);
    b.set_int(Area::D, i, v);
  }
  for (uint32_t i = 0; i < 512; i++) {
    bool v = r.next() & 1;
    a.set_bit(Area::M, i, v);
    b.set_bit(Area::M, i, v);
  }
  for (int k = 1; k <= scans; k++) {
    for (int i = 0; i < 16; i++) {
      bool v = r.next() & 1;
      a.set_bit(Area::X, i, v);
      b.set_bit(Area::X, i, v);
    }
    ref->scan(a.bytes);
    native->scan(b.bytes);
    for (uint32_t off = 0; off < L.size; off++)
      if (a.bytes[off] != b.bytes[off])
        return "-O" + std::to_string(level) + " seed " + std::to_string(seed) + " scan " + std::to_string(k) +
               ": image byte " + std::to_string(off) + " differs";
  }
  return "";
}

TEST(BaseRegions, JumpsOverRegionsMatchTheInterpreter) {
  Program p = parse_il_text(program(), "regions.il");
  for (int level : {0, 1, 2})
    for (uint64_t seed = 1; seed <= 8; seed++) EXPECT_EQ(compare(p, level, seed, 12), "");
}

// The program above is not covered by one K per register: the -O2 body points
// them again (leas after the prologue's), and operands go through all three.
TEST(BaseRegions, TheBodyPointsTheRegistersAgain) {
  Program p = parse_il_text(program(), "regions.il");
  NativeBuild nb = build_x86(p, p.source, as::Mode::Blockwise, 2, false);
  x86::Disassembly d = x86::disassemble(nb.asm_result.code);
  ASSERT_FALSE(d.error);
  int leas = 0;
  bool through[x86::kNumBases] = {};
  for (const x86::Decoded& di : d.insts) {
    const x86::Instruction& in = di.inst;
    for (int b = 0; b < x86::kNumBases; b++) {
      if (in.mnemonic == x86::Mnemonic::Lea && in.ops[0].kind == x86::OperandKind::Reg &&
          in.ops[0].reg == x86::r64(x86::kBaseRegs[b])) {
        leas++;
        EXPECT_GE(in.ops[1].mem.disp, 128);
        EXPECT_LE(in.ops[1].mem.disp, int32_t(p.layout().size) - 135);
      }
      for (unsigned k = 0; k < in.num_operands; k++)
        if (in.ops[k].kind == x86::OperandKind::Mem && in.ops[k].mem.base == x86::r64(x86::kBaseRegs[b])) {
          through[b] = true;
          EXPECT_GE(in.ops[k].mem.disp, -128);
          EXPECT_LE(in.ops[k].mem.disp, 127);
        }
    }
  }
  EXPECT_GT(leas, x86::kNumBases + 3);  // the prologue's three and more
  for (int b = 0; b < x86::kNumBases; b++) EXPECT_TRUE(through[b]) << x86::reg_name(x86::r64(x86::kBaseRegs[b]));
}

}  // namespace
