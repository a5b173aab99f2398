// The C40 target through the blockwise core: labels, global fixups,
// displacement limits, delayed-branch bias, both modes.
#include <gtest/gtest.h>

#include <set>

#include "c40_test_util.h"

using namespace ldc::as;
using namespace ldc::as::c40;
using namespace ldc::as::c40::test;

namespace {

std::string errors_of(const Result& r) {
  std::string s;
  for (const Error& e : r.errors) s += "[" + std::to_string(e.line) + "] " + e.message + "\n";
  return s;
}

uint32_t word_at(const Result& r, size_t i) { return words_of(r.code).at(i); }

C40Program sample() {
  return build_program({"main", "rung1", "done", "table"},
                      {{10, R"(main::
LDPK 0x8000
LDI @0x1, R0
AND R11, R0
LSH -1, R10
OR R0, R10
BNE skip
CALL rung1
skip:
BR rung1
)"},
                       {20, R"(rung1::
LDI R10, R0
; a comment item
loop:
SUBI 1, R0
BNED loop
NOP
NOP
NOP
DBU AR0, loop
BU done
skip:
BR done
)"},
                       {30, R"(done::
RETSU
table::
.word main
.word rung1
.word skip
skip:
NOP
)"}});
}

TEST(C40Core, MultiBlockProgramInBothModes) {
  C40Program p = sample();
  Result a = assemble(target(), p, Mode::Blockwise);
  ASSERT_TRUE(a.ok()) << errors_of(a);
  Result b = assemble(target(), p, Mode::WholeProgram);
  ASSERT_TRUE(b.ok()) << errors_of(b);
  EXPECT_EQ(a.code, b.code);
  auto w = words_of(a.code);
  ASSERT_EQ(w.size(), 22u);
  // block 0 at word 0
  EXPECT_EQ(hex_word(w[0]), "1f708000");  // LDPK 0x8000
  EXPECT_EQ(hex_word(w[1]), "08200001");  // LDI @0x1, R0
  EXPECT_EQ(hex_word(w[5]), "6a060001");  // BNE skip (word 7): 7 - 5 - 1
  EXPECT_EQ(hex_word(w[6]), "62000001");  // CALL rung1 (word 8): 8 - 6 - 1
  EXPECT_EQ(hex_word(w[7]), "60000000");  // BR rung1: 8 - 7 - 1
  // block 1 at word 8: loop = word 9
  EXPECT_EQ(hex_word(w[10]), "6a26fffc");  // BNED loop: 9 - 10 - 3 = -4
  EXPECT_EQ(hex_word(w[14]), "6e00fffa");  // DBU AR0, loop: 9 - 14 - 1 = -6
  EXPECT_EQ(hex_word(w[15]), "6a000001");  // BU done (17): 17 - 15 - 1
  EXPECT_EQ(hex_word(w[16]), "60000000");  // BR done: 17 - 16 - 1
  // block 2 at word 17
  EXPECT_EQ(hex_word(w[17]), "78800000");
  EXPECT_EQ(w[18], 0u);   // .word main
  EXPECT_EQ(w[19], 8u);   // .word rung1
  EXPECT_EQ(w[20], 21u);  // .word skip (the local one of block 2)
  ASSERT_EQ(a.relocations.size(), 3u);
  std::set<uint32_t> relocs;
  for (const Relocation& rl : a.relocations) {
    relocs.insert(rl.offset);
    EXPECT_EQ(rl.kind, Abs32);
  }
  EXPECT_EQ(relocs, (std::set<uint32_t>{18 * 4, 19 * 4, 20 * 4}));
  EXPECT_EQ(a.global_addresses, (std::vector<int64_t>{0, 32, 68, 72}));  // bytes
  EXPECT_EQ(a.block_offsets, (std::vector<uint32_t>{0, 32, 68}));
  // Blockwise keeps one block's locals; the whole program keeps them all.
  EXPECT_LT(a.stats.peak_label_entries, b.stats.peak_label_entries);
  // The disassembly reproduces the instructions (labels become addresses).
  Disassembly d = disassemble_bytes(std::span(a.code).first(18 * 4));
  EXPECT_TRUE(d.errors.empty());
  ASSERT_EQ(d.insts.size(), 18u);
  EXPECT_EQ(print(d.insts[5].inst), "BNE 0x7");
  EXPECT_EQ(print(d.insts[10].inst), "BNED 0x9");
  std::string lst = listing(p, a);
  EXPECT_NE(lst.find("000005  6a060001  \tBNE skip"), std::string::npos) << lst;
  EXPECT_NE(lst.find("; a comment item"), std::string::npos);
  std::string gas = to_gnu_as(p);
  EXPECT_NE(gas.find(".L0_skip:"), std::string::npos) << gas;
  EXPECT_NE(gas.find("\tBR rung1"), std::string::npos);
  EXPECT_NE(gas.find(".L2_skip"), std::string::npos);
}

// A block with `before` NOPs, the branch, `after` NOPs and labels at both
// ends: the branch targets `fwd` or `back`.
C40Program limit_program(const std::string& branch, int before, int after) {
  C40Program p;
  Block<Instruction> b;
  b.source_line = 7;
  b.items.push_back(Item<Instruction>::label_def("back"));
  for (int i = 0; i < before; ++i) b.items.push_back(Item<Instruction>::instr(parse("NOP")));
  b.items.push_back(Item<Instruction>::instr(parse(branch)));
  for (int i = 0; i < after; ++i) b.items.push_back(Item<Instruction>::instr(parse("NOP")));
  b.items.push_back(Item<Instruction>::label_def("fwd"));
  b.items.push_back(Item<Instruction>::instr(parse("RETSU")));
  p.blocks.push_back(std::move(b));
  return p;
}

TEST(C40Core, DisplacementLimits) {
  for (Mode mode : {Mode::Blockwise, Mode::WholeProgram}) {
    // forward: target = 0 + 1 + 32767
    Result r = assemble(target(), limit_program("BU fwd", 0, 32767), mode);
    ASSERT_TRUE(r.ok()) << errors_of(r);
    EXPECT_EQ(hex_word(word_at(r, 0)), "6a007fff");
    r = assemble(target(), limit_program("BU fwd", 0, 32768), mode);
    ASSERT_EQ(r.errors.size(), 1u);
    EXPECT_EQ(r.errors[0].line, 7);
    EXPECT_NE(r.errors[0].message.find("label 'fwd' out of range for fixup disp16"), std::string::npos)
        << r.errors[0].message;
    // backward: the branch at 32767 reaches 0 = 32767 + 1 - 32768
    r = assemble(target(), limit_program("BEQ back", 32767, 0), mode);
    ASSERT_TRUE(r.ok()) << errors_of(r);
    EXPECT_EQ(hex_word(word_at(r, 32767)), "6a058000");
    r = assemble(target(), limit_program("BEQ back", 32768, 0), mode);
    EXPECT_EQ(r.errors.size(), 1u);
    // delayed: target = address + 3 + disp, so 32769 words ahead still fits
    r = assemble(target(), limit_program("BUD fwd", 0, 32769), mode);
    ASSERT_TRUE(r.ok()) << errors_of(r);
    EXPECT_EQ(hex_word(word_at(r, 0)), "6a207fff");
    r = assemble(target(), limit_program("BUD fwd", 0, 32770), mode);
    EXPECT_EQ(r.errors.size(), 1u);
    r = assemble(target(), limit_program("BUD back", 32765, 0), mode);
    ASSERT_TRUE(r.ok()) << errors_of(r);
    EXPECT_EQ(hex_word(word_at(r, 32765)), "6a208000");  // 0 - 32765 - 3
    r = assemble(target(), limit_program("BUD back", 32766, 0), mode);
    EXPECT_EQ(r.errors.size(), 1u);
  }
}

TEST(C40Core, DelayedAndStandardBias) {
  C40Program p = build_program({}, {{1, R"(
BU a
a:
BUD b
NOP
NOP
b:
NOP
BRD c
NOP
NOP
NOP
c:
CALL c
DBUD AR1, c
)"}});
  Result r = assemble(target(), p);
  ASSERT_TRUE(r.ok()) << errors_of(r);
  EXPECT_EQ(hex_word(word_at(r, 0)), "6a000000");  // 1 - 0 - 1
  EXPECT_EQ(hex_word(word_at(r, 1)), "6a200000");  // b = 4: 4 - 1 - 3
  EXPECT_EQ(hex_word(word_at(r, 5)), "61000001");  // c = 9: 9 - 5 - 3
  EXPECT_EQ(hex_word(word_at(r, 9)), "62ffffff");  // 9 - 9 - 1
  EXPECT_EQ(hex_word(word_at(r, 10)), "6e60fffc");  // 9 - 10 - 3
}

TEST(C40Core, ErrorsCarryTheBlockLine) {
  C40Program p = build_program({"g"}, {{11, "BU nowhere\n"}, {12, "g::\nBR g\n"}, {13, "BR missing\n"}});
  Result r = assemble(target(), p);
  ASSERT_EQ(r.errors.size(), 2u) << errors_of(r);
  EXPECT_EQ(r.errors[0].line, 11);
  EXPECT_NE(r.errors[0].message.find("undefined label 'nowhere'"), std::string::npos);
  EXPECT_EQ(r.errors[1].line, 13);
}

}  // namespace
