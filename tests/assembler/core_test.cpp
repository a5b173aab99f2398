// The target-independent core, driven through the x86-64 target and a toy
// word-addressed target shaped like the TMS320C40.
#include <gtest/gtest.h>

#include <algorithm>

#include "test_util.h"

using namespace ldc::as;
using namespace ldc::as::test;
using x86::X86Program;

namespace {

std::string nops(int n) {
  std::string s;
  for (int i = 0; i < n; ++i) s += "nop\n";
  return s;
}

// Size of the item at (block, item).
uint32_t size_at(const Result& r, size_t b, size_t i) { return r.items[b][i].size; }

std::string errors_of(const Result& r) {
  std::string s;
  for (const Error& e : r.errors)
    s += "block " + std::to_string(e.block) + " line " + std::to_string(e.line) + ": " + e.message + "\n";
  return s;
}

TEST(Core, ForwardJumpShortUpTo127) {
  for (int n : {0, 1, 126, 127, 128, 129, 300}) {
    SCOPED_TRACE(n);
    for (const char* j : {"jmp", "je"}) {
      auto p = build_program({}, {{10, std::string(j) + " L\n" + nops(n) + "L:\nret"}});
      Result r = assemble(x86::target(), p);
      ASSERT_TRUE(r.ok()) << errors_of(r);
      uint32_t long_size = std::string(j) == "jmp" ? 5 : 6;
      EXPECT_EQ(size_at(r, 0, 0), n <= 127 ? 2u : long_size);
      // The displacement reaches the label.
      auto d = x86::disassemble(r.code);
      ASSERT_FALSE(d.error);
      EXPECT_EQ(d.insts[0].inst.ops[0].imm, int64_t(r.items[0][size_t(n) + 1].offset));
    }
  }
}

TEST(Core, BackwardJumpShortDownToMinus128) {
  for (int n : {0, 125, 126, 127, 128}) {
    SCOPED_TRACE(n);
    auto p = build_program({}, {{1, "L:\n" + nops(n) + "jne L"}});
    Result r = assemble(x86::target(), p);
    ASSERT_TRUE(r.ok()) << errors_of(r);
    // disp = -(n + 2) for the short form.
    EXPECT_EQ(size_at(r, 0, size_t(n) + 1), n <= 126 ? 2u : 6u);
    auto d = x86::disassemble(r.code);
    ASSERT_FALSE(d.error);
    EXPECT_EQ(d.insts.back().inst.ops[0].imm, 0);
  }
}

TEST(Core, GrowingOneJumpCanPushAnotherOutOfRange) {
  // j1 reaches A only while j2 is short; j2 must grow (B is 128 bytes past
  // it), which then pushes A out of j1's reach: two rounds of growth.
  auto p = build_program({}, {{1, "jmp A\n" + nops(124) + "jmp B\nA:\n" + nops(128) + "B:\nret"}});
  Result r = assemble(x86::target(), p);
  ASSERT_TRUE(r.ok()) << errors_of(r);
  EXPECT_EQ(size_at(r, 0, 0), 5u);
  EXPECT_EQ(size_at(r, 0, 125), 5u);
  EXPECT_GE(r.stats.relax_passes, 3u);
  auto d = x86::disassemble(r.code);
  ASSERT_FALSE(d.error) << d.error->message;
  EXPECT_EQ(d.insts[0].inst.ops[0].imm, int64_t(r.items[0][126].offset));
}

X86Program rungs() {
  return build_program({"rung0", "rung1", "rung2", "done"},
                      {{100, "rung0::\n"
                             "cmp eax, 0x1\n"
                             "je skip\n"
                             "jmp rung2\n"
                             "skip:\n"
                             "jne rung1\n"
                             "# fall through\n"},
                       {110, "rung1::\n"
                             "test eax, eax\n"
                             "jne skip\n"
                             "call rung0\n"
                             "skip:\n"
                             "jmp done\n"},
                       {120, "rung2::\n"
                             "jmp rung1\n"
                             "done::\n"
                             "ret\n"}});
}

TEST(Core, GlobalJumpsAreRel32AndResolvedAcrossBlocks) {
  X86Program p = rungs();
  Result r = assemble(x86::target(), p);
  ASSERT_TRUE(r.ok()) << errors_of(r);
  ASSERT_EQ(r.global_addresses.size(), 4u);
  EXPECT_EQ(r.global_addresses[0], 0);
  EXPECT_EQ(r.global_addresses[1], r.block_offsets[1]);
  EXPECT_EQ(r.global_addresses[2], r.block_offsets[2]);
  auto d = x86::disassemble(r.code);
  ASSERT_FALSE(d.error) << d.error->message;
  // Every branch to a global label is a rel32 form to the right address.
  std::vector<std::pair<std::string, int64_t>> want = {
      {"je", -1}, {"jmp", r.global_addresses[2]}, {"jne", r.global_addresses[1]},
      {"jne", -1}, {"call", r.global_addresses[0]}, {"jmp", r.global_addresses[3]},
      {"jmp", r.global_addresses[1]}};
  size_t k = 0;
  for (const auto& di : d.insts) {
    std::string mn(x86::mnemonic_name(di.inst.mnemonic, di.inst.cond));
    if (di.inst.ops[0].kind != x86::OperandKind::Address) continue;
    ASSERT_LT(k, want.size());
    EXPECT_EQ(mn, want[k].first);
    if (want[k].second >= 0) {
      EXPECT_EQ(di.inst.ops[0].imm, want[k].second) << mn;
      EXPECT_GE(di.length, 5u) << mn << " to a global label must be rel32";
    } else {
      EXPECT_EQ(di.length, 2u) << "local jump stays short";
    }
    ++k;
  }
  EXPECT_EQ(k, want.size());
  EXPECT_EQ(r.stats.global_fixups, 5u);
}

TEST(Core, LocalLabelsWithTheSameNameInDifferentBlocks) {
  X86Program p = rungs();  // both rung0 and rung1 define "skip"
  for (Mode mode : {Mode::Blockwise, Mode::WholeProgram}) {
    Result r = assemble(x86::target(), p, mode);
    ASSERT_TRUE(r.ok()) << errors_of(r);
    auto d = x86::disassemble(r.code);
    ASSERT_FALSE(d.error);
    // je skip (block 0) -> block 0's skip; jne skip (block 1) -> block 1's.
    EXPECT_EQ(d.insts[1].inst.ops[0].imm, int64_t(r.items[0][4].offset));
    size_t b1 = 0;
    while (d.insts[b1].offset < r.block_offsets[1]) ++b1;
    EXPECT_EQ(d.insts[b1 + 1].inst.ops[0].imm, int64_t(r.items[1][4].offset));
  }
}

TEST(Core, BlockAndItemOffsets) {
  X86Program p = rungs();
  Result r = assemble(x86::target(), p);
  ASSERT_TRUE(r.ok());
  ASSERT_EQ(r.block_offsets.size(), 3u);
  EXPECT_EQ(r.block_offsets[0], 0u);
  // rung0: cmp(3) je(2) jmp(5) jne(6) = 16 bytes.
  EXPECT_EQ(r.block_offsets[1], 16u);
  EXPECT_EQ(r.items[0][1].offset, 0u);
  EXPECT_EQ(r.items[0][2].offset, 3u);
  EXPECT_EQ(r.items[0][3].offset, 5u);
  EXPECT_EQ(r.items[0][4].offset, 10u);  // the label skip
  EXPECT_EQ(r.items[0][5].offset, 10u);
  EXPECT_TRUE(r.items[0][3].long_form);
  EXPECT_FALSE(r.items[0][2].long_form);
  std::string lst = x86::listing(p, r);
  EXPECT_NE(lst.find("{disp32} jmp rung2"), std::string::npos) << lst;
  EXPECT_NE(lst.find("# fall through"), std::string::npos) << lst;
  EXPECT_NE(lst.find("line 110"), std::string::npos) << lst;
}

struct ErrCase {
  const char* what;
  std::vector<std::string> globals;
  std::vector<BlockText> blocks;
  int block;
  int line;
  const char* message;
};

TEST(Core, ErrorsCarryBlockLineAndLabel) {
  std::vector<ErrCase> cases = {
      {"undefined local", {}, {{5, "ret"}, {7, "jmp nowhere"}}, 1, 7, "undefined label 'nowhere'"},
      {"undefined global", {"g"}, {{5, "call g"}}, 0, 5, "undefined label 'g'"},
      {"duplicate local", {}, {{3, "a:\nnop\na:\nret"}}, 0, 3, "duplicate label 'a'"},
      {"local clashes with global", {"a"}, {{1, "a::\nret"}, {9, "a:\nret"}}, 1, 9,
       "local label 'a' clashes with a global label"},
      {"global defined twice", {"g"}, {{1, "g::\nret"}, {4, "g::\nret"}}, 1, 4,
       "duplicate global label 'g'"},
      {"duplicate declaration", {"g", "g"}, {{1, "g::\nret"}}, -1, 0, "duplicate global label 'g'"},
      {"undeclared global", {}, {{8, "h::\nret"}}, 0, 8, "global label 'h' is not declared"},
      {"bad operands", {}, {{6, "nop\nmov eax, rbx"}}, 0, 6, "item 1: invalid operands"},
  };
  for (const ErrCase& c : cases) {
    SCOPED_TRACE(c.what);
    X86Program p = build_program(c.globals, c.blocks);
    for (Mode mode : {Mode::Blockwise, Mode::WholeProgram}) {
      Result r = assemble(x86::target(), p, mode);
      ASSERT_EQ(r.errors.size(), 1u) << errors_of(r);
      EXPECT_EQ(r.errors[0].block, c.block);
      EXPECT_EQ(r.errors[0].line, c.line);
      EXPECT_NE(r.errors[0].message.find(c.message), std::string::npos) << r.errors[0].message;
    }
  }
}

TEST(Core, ErrorsDoNotStopTheOtherBlocks) {
  X86Program p = build_program({"g"}, {{1, "jmp x\n"}, {2, "g::\nret"}, {3, "jmp y\njmp g"}});
  Result r = assemble(x86::target(), p);
  EXPECT_EQ(r.errors.size(), 2u);
  EXPECT_EQ(r.global_addresses[0], int64_t(r.block_offsets[1]));
  auto d = x86::disassemble(r.code);
  ASSERT_FALSE(d.error);
  EXPECT_EQ(d.insts.back().inst.ops[0].imm, r.global_addresses[0]);
}

// A pseudo-random program: many rungs with local and global jumps.
X86Program big_program(int blocks, uint32_t seed) {
  auto rnd = [&] {
    seed = seed * 1103515245u + 12345u;
    return (seed >> 16) & 0x7fff;
  };
  std::vector<std::string> globals;
  for (int b = 0; b < blocks; ++b) globals.push_back("rung" + std::to_string(b));
  globals.push_back("end");
  std::vector<BlockText> bt;
  const char* fill[] = {"mov eax, dword ptr [rbx+0x10]", "add eax, 0x1", "movzx ecx, byte ptr [rbx+0x200]",
                        "test byte ptr [rbx+0x3], 0x4", "setne byte ptr [rbx+0x5]", "nop",
                        "lea rax, [rbx+rcx*4+0x100]", "cvtsi2ss xmm0, eax", "imul eax, ecx, 0x3e8"};
  for (int b = 0; b < blocks; ++b) {
    std::string t = "rung" + std::to_string(b) + "::\n";
    int labels = 1 + int(rnd() % 4);
    for (int l = 0; l < labels; ++l) {
      int n = int(rnd() % 40);
      for (int i = 0; i < n; ++i) t += std::string(fill[rnd() % 9]) + "\n";
      t += "jne L" + std::to_string(rnd() % labels) + "\n";
      if (rnd() % 3 == 0) t += "je rung" + std::to_string(rnd() % blocks) + "\n";
      t += "L" + std::to_string(l) + ":\n";
    }
    t += b + 1 < blocks ? "jmp rung" + std::to_string(b + 1) + "\n" : "jmp end\n";
    bt.push_back({1000 + b * 10, t});
  }
  bt.push_back({99999, "end::\nret"});
  return build_program(globals, bt);
}

TEST(Core, BlockwiseAndWholeProgramGiveIdenticalBytes) {
  X86Program p = big_program(60, 7);
  Result bw = assemble(x86::target(), p, Mode::Blockwise);
  Result wp = assemble(x86::target(), p, Mode::WholeProgram);
  ASSERT_TRUE(bw.ok()) << errors_of(bw);
  ASSERT_TRUE(wp.ok()) << errors_of(wp);
  EXPECT_EQ(bw.code, wp.code);
  EXPECT_EQ(bw.block_offsets, wp.block_offsets);
  EXPECT_EQ(bw.global_addresses, wp.global_addresses);
  // The blockwise tables are smaller: globals plus one block's locals.
  EXPECT_LT(bw.stats.peak_label_entries, wp.stats.peak_label_entries);
  EXPECT_EQ(wp.stats.peak_label_entries, p.globals.size() + [&] {
    size_t n = 0;
    for (const auto& b : p.blocks)
      for (const auto& it : b.items) n += it.kind == ItemKind::Label && !it.global;
    return n;
  }());
  EXPECT_LE(bw.stats.peak_label_entries, p.globals.size() + 4);
  EXPECT_EQ(bw.stats.units, p.blocks.size());
  EXPECT_EQ(wp.stats.units, 1u);
  EXPECT_GE(bw.stats.relax_passes, p.blocks.size());
  auto d = x86::disassemble(bw.code);
  EXPECT_FALSE(d.error);
}

// The streaming assembler (one block at a time, each copy dropped after add)
// gives assemble()'s result on the same blocks.
Result streamed(const X86Program& p) {
  Assembler<x86::Instruction> a(x86::target(), p.globals);
  for (const auto& b : p.blocks) {
    Block<x86::Instruction> copy = b;  // dies right after add: nothing may point into it
    a.add(copy);
  }
  return a.finish();
}

TEST(Core, StreamingGivesTheBlockwiseResult) {
  X86Program p = big_program(200, 11);
  Result bw = assemble(x86::target(), p, Mode::Blockwise);
  Result st = streamed(p);
  ASSERT_TRUE(bw.ok() && st.ok()) << errors_of(bw) << errors_of(st);
  EXPECT_EQ(bw.code, st.code);
  EXPECT_EQ(bw.block_offsets, st.block_offsets);
  EXPECT_EQ(bw.global_addresses, st.global_addresses);
  ASSERT_EQ(bw.items.size(), st.items.size());
  for (size_t b = 0; b < bw.items.size(); b++) {
    ASSERT_EQ(bw.items[b].size(), st.items[b].size());
    for (size_t i = 0; i < bw.items[b].size(); i++) {
      EXPECT_EQ(bw.items[b][i].offset, st.items[b][i].offset);
      EXPECT_EQ(bw.items[b][i].size, st.items[b][i].size);
      EXPECT_EQ(bw.items[b][i].long_form, st.items[b][i].long_form);
    }
  }
  EXPECT_EQ(bw.stats.peak_label_entries, st.stats.peak_label_entries);
  EXPECT_EQ(bw.stats.encode_calls, st.stats.encode_calls);
}

// With Items::LastOnly each block's item layout is there right after its
// add() (last_items, code_size its end) and no block's stays in the result.
TEST(Core, StreamingLastItemsAreEachBlocksLayout) {
  X86Program p = big_program(200, 13);
  Result bw = assemble(x86::target(), p, Mode::Blockwise);
  using Asm = Assembler<x86::Instruction>;
  Asm a(x86::target(), p.globals, Asm::Items::LastOnly);
  for (size_t b = 0; b < p.blocks.size(); b++) {
    a.add(p.blocks[b]);
    std::span<const ItemLayout> last = a.last_items();
    ASSERT_EQ(last.size(), bw.items[b].size()) << "block " << b;
    for (size_t i = 0; i < last.size(); i++) {
      EXPECT_EQ(last[i].offset, bw.items[b][i].offset) << "block " << b << " item " << i;
      EXPECT_EQ(last[i].size, bw.items[b][i].size);
      EXPECT_EQ(last[i].long_form, bw.items[b][i].long_form);
    }
    EXPECT_EQ(a.code_size(), b + 1 < p.blocks.size() ? bw.block_offsets[b + 1] : bw.code.size());
  }
  Result st = a.finish();
  ASSERT_TRUE(bw.ok() && st.ok()) << errors_of(bw) << errors_of(st);
  EXPECT_EQ(bw.code, st.code);
  EXPECT_EQ(bw.block_offsets, st.block_offsets);
  EXPECT_TRUE(st.items.empty());
}

TEST(Core, StreamingReportsTheSameErrors) {
  // undefined local and global labels, an undeclared and a twice-defined
  // global, a clash, a duplicate local: every kind, the labels named after
  // their blocks are gone
  X86Program p = build_program({"g", "h", "never"}, {{1, "jmp x\ng::\n"}, {2, "g::\nret\njmp never"},
                                                   {3, "u::\nh:\njmp h"}, {4, "a:\na:\njmp a"}, {5, "jmp zz"}});
  Result bw = assemble(x86::target(), p, Mode::Blockwise);
  Result st = streamed(p);
  auto sorted = [](const Result& r) {
    std::vector<std::string> v;
    for (const Error& e : r.errors) v.push_back(std::to_string(e.block) + ":" + std::to_string(e.line) + ": " + e.message);
    std::sort(v.begin(), v.end());
    return v;
  };
  EXPECT_GE(bw.errors.size(), 6u) << errors_of(bw);
  EXPECT_EQ(sorted(bw), sorted(st));
  EXPECT_EQ(bw.code, st.code);
}

// Reports the two modes' cost on a large program (1000 rungs).
TEST(Core, ModeStatsOnALargeProgram) {
  X86Program p = big_program(1000, 99);
  Result bw = assemble(x86::target(), p, Mode::Blockwise);
  Result wp = assemble(x86::target(), p, Mode::WholeProgram);
  ASSERT_TRUE(bw.ok() && wp.ok());
  EXPECT_EQ(bw.code, wp.code);
  EXPECT_LT(bw.stats.peak_label_entries, wp.stats.peak_label_entries);
  for (const auto* r : {&bw, &wp}) {
    std::printf("%-13s %zu bytes, peak label entries %zu, passes %zu, encodes %zu, %.3f ms\n",
                r == &bw ? "blockwise" : "whole-program", r->code.size(),
                r->stats.peak_label_entries, r->stats.relax_passes, r->stats.encode_calls,
                double(r->stats.elapsed_ns) / 1e6);
  }
}

// ------------------------------------------------------------ toy target
// Shaped like the TMS320C40: every instruction is one 32-bit word; branch
// displacements count words from the instruction after the branch (or three
// after, for delayed branches) and live in the low 16 or 24 bits.

struct WordInst {
  uint32_t word = 0;
  std::string label;
  uint16_t kind = 0;  // which fixup kind the label uses
};

enum : uint16_t { Disp16, Disp24, Delayed16, Abs24, Field8At16 };
constexpr FixupKind kWordKinds[] = {
    {"disp16", 4, 0, 16, true, true, PcBase::InstructionStart, 1, 4, -1},
    {"disp24", 4, 0, 24, true, true, PcBase::InstructionStart, 1, 4, -1},
    {"delayed16", 4, 0, 16, true, true, PcBase::InstructionStart, 3, 4, -1},
    {"abs24", 4, 0, 24, false, false, PcBase::InstructionStart, 0, 4, -1},
    {"field8at16", 4, 16, 8, true, true, PcBase::InstructionStart, 1, 4, -1},
};

void encode_word(const WordInst& in, bool, Encoding& out) {
  out.put32(in.word);
  if (!in.label.empty()) out.add_fixup(Fixup{0, in.kind, in.label, 0});
}

const Target<WordInst>& word_target() {
  static const Target<WordInst> t = [] {
    Target<WordInst> t;
    t.name = "toy-c40";
    t.fixup_kinds = kWordKinds;
    t.encode = encode_word;
    return t;
  }();
  return t;
}

uint32_t word_at(const Result& r, size_t i) {
  return uint32_t(r.code[4 * i]) | uint32_t(r.code[4 * i + 1]) << 8 |
         uint32_t(r.code[4 * i + 2]) << 16 | uint32_t(r.code[4 * i + 3]) << 24;
}

TEST(Core, WordAddressedTargetUsesScaledBitFields) {
  using I = Item<WordInst>;
  Program<WordInst> p;
  p.globals = {"far"};
  Block<WordInst> b0;
  b0.source_line = 1;
  b0.items = {I::label_def("top"),
              I::instr({0x60000000, "next", Disp16}),     // word 0 -> next (word 3): 3-1 = 2
              I::instr({0x61000000, "top", Disp24}),      // word 1 -> top (0): 0-2 = -2
              I::instr({0x62000000, "next", Delayed16}),  // word 2 -> 3: 3-5 = -2
              I::label_def("next"),
              I::instr({0x63000000, "far", Abs24}),       // word 3 -> far (word 5)
              I::instr({0xAB00CDEF, "top", Field8At16})}; // word 4 -> 0: 0-5 = -5
  Block<WordInst> b1;
  b1.source_line = 2;
  b1.items = {I::label_def("far", true), I::instr({0x08000000, "", 0})};
  p.blocks = {b0, b1};
  Result r = assemble(word_target(), p);
  ASSERT_TRUE(r.ok()) << errors_of(r);
  ASSERT_EQ(r.code.size(), 24u);
  EXPECT_EQ(word_at(r, 0), 0x60000002u);
  EXPECT_EQ(word_at(r, 1), 0x61FFFFFEu);
  EXPECT_EQ(word_at(r, 2), 0x6200FFFEu);
  EXPECT_EQ(word_at(r, 3), 0x63000005u);
  EXPECT_EQ(word_at(r, 4), 0xABFBCDEFu);  // only bits 16..23 changed
  ASSERT_EQ(r.relocations.size(), 1u);   // the absolute field
  EXPECT_EQ(r.relocations[0].offset, 12u);
  EXPECT_EQ(r.global_addresses[0], 20);
}

TEST(Core, OutOfRangeFieldWithoutLongerFormIsAnError) {
  using I = Item<WordInst>;
  Program<WordInst> p;
  Block<WordInst> b;
  b.source_line = 42;
  b.items.push_back(I::instr({0, "there", Field8At16}));
  for (int i = 0; i < 200; ++i) b.items.push_back(I::instr({0, "", 0}));
  b.items.push_back(I::label_def("there"));
  p.blocks = {b};
  Result r = assemble(word_target(), p);
  ASSERT_EQ(r.errors.size(), 1u);
  EXPECT_EQ(r.errors[0].line, 42);
  EXPECT_NE(r.errors[0].message.find("label 'there' out of range for fixup field8at16"),
            std::string::npos)
      << r.errors[0].message;
}

TEST(Core, InvalidFixupFromAnEncoderIsAnError) {
  using I = Item<WordInst>;
  Program<WordInst> p;
  Block<WordInst> b;
  b.source_line = 7;
  b.items = {I::label_def("x"), I::instr({0, "x", 99})};
  p.blocks = {b};
  Result r = assemble(word_target(), p);
  ASSERT_EQ(r.errors.size(), 1u);
  EXPECT_EQ(r.errors[0].line, 7);
  EXPECT_NE(r.errors[0].message.find("invalid fixup"), std::string::npos);
}

TEST(Core, FixupHelpers) {
  const FixupKind& k = kWordKinds[Disp16];
  int64_t v = 0;
  EXPECT_TRUE(fixup_value(k, 400, 0, 100, 4, v));
  EXPECT_EQ(v, 74);  // (400 - (100 + 4)) / 4
  EXPECT_FALSE(fixup_value(k, 402, 0, 100, 4, v));  // not word aligned
  EXPECT_TRUE(fixup_fits(k, 32767));
  EXPECT_FALSE(fixup_fits(k, 32768));
  EXPECT_TRUE(fixup_fits(k, -32768));
  EXPECT_FALSE(fixup_fits(k, -32769));
  EXPECT_FALSE(fixup_fits(kWordKinds[Abs24], -1));
  EXPECT_TRUE(fixup_fits(kWordKinds[Abs24], 0xFFFFFF));
  std::vector<uint8_t> code = {0xFF, 0xFF, 0xFF, 0xFF};
  apply_fixup(kWordKinds[Field8At16], code, 0, 0x12);
  EXPECT_EQ(code, (std::vector<uint8_t>{0xFF, 0xFF, 0x12, 0xFF}));
}

}  // namespace
