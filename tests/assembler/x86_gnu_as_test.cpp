// Independent check of the golden rows with GNU binutils: `as` must produce
// the same bytes for every row, and `objdump -d -M intel` must see the same
// instructions as our disassembler. binutils is a required test dependency:
// these tests fail (never skip) when it is missing.
#include <gtest/gtest.h>

#include "test_util.h"

using namespace ldc::as;
using namespace ldc::as::test;

namespace {

// Assembles the rows with GNU as, each at its own label, and compares.
// printed=false feeds the row text itself, printed=true our printer's text.
void checkRowsWithGnuAs(bool printed) {
  std::string why;
  ASSERT_TRUE(binutilsAvailable(&why)) << why;
  auto rows = loadRows();
  ASSERT_FALSE(rows.empty());
  std::string src = ".intel_syntax noprefix\n.text\n";
  std::vector<uint8_t> ours;
  std::vector<size_t> starts;
  for (size_t i = 0; i < rows.size(); ++i) {
    x86::Instruction in = x86::parse(rows[i].text);
    std::string label = ".Lrow" + std::to_string(i);
    // Numeric branch targets are relative to the row: those rows go through
    // the printer, which writes them as `.LrowN+0x12`.
    bool branch = in.numOperands && in.ops[0].kind == x86::OperandKind::Address;
    std::string text = printed || branch ? x86::print(in, false, label) : rows[i].text;
    src += label + ":\n\t" + text + "\n";
    starts.push_back(ours.size());
    auto b = fromHex(rows[i].hex);
    ours.insert(ours.end(), b.begin(), b.end());
  }
  std::string err;
  std::vector<uint8_t> theirs = gnuAssemble(src, &err);
  ASSERT_TRUE(err.empty()) << err;
  starts.push_back(ours.size());
  for (size_t i = 0; i < rows.size(); ++i) {
    if (starts[i] >= theirs.size()) {
      ADD_FAILURE() << "as output ends before row " << rows[i].line;
      return;
    }
    size_t n = starts[i + 1] - starts[i];
    std::vector<uint8_t> a(ours.begin() + long(starts[i]), ours.begin() + long(starts[i + 1]));
    std::vector<uint8_t> b(theirs.begin() + long(starts[i]),
                           theirs.begin() + long(std::min(theirs.size(), starts[i] + n)));
    if (a != b) {
      ADD_FAILURE() << "x86_encode.rows:" << rows[i].line << ": " << rows[i].text
                    << "\n  ours: " << toHex(a) << "\n  as:   " << toHex(b)
                    << " (rows after this one are not compared)";
      return;
    }
  }
  EXPECT_EQ(ours.size(), theirs.size());
}

TEST(GnuAs, EveryRowAssemblesToTheSameBytes) { checkRowsWithGnuAs(false); }

TEST(GnuAs, PrintedRowsAssembleToTheSameBytes) { checkRowsWithGnuAs(true); }

TEST(GnuAs, ObjdumpAgreesWithOurDisassembler) {
  std::string why;
  ASSERT_TRUE(binutilsAvailable(&why)) << why;
  std::vector<uint8_t> code;
  for (const Row& r : loadRows()) {
    // Branch rows are at address 0 in the file; move them to where they sit.
    x86::Instruction in = x86::parse(r.text);
    if (in.numOperands && in.ops[0].kind == x86::OperandKind::Address)
      in.ops[0].imm += int64_t(code.size());
    auto b = x86::encodeAt(in, code.size());
    code.insert(code.end(), b.begin(), b.end());
  }
  auto ours = x86::disassemble(code);
  ASSERT_FALSE(ours.error) << ours.error->message << " at " << ours.error->offset;
  std::string err;
  auto theirs = objdumpIntel(code, &err);
  ASSERT_TRUE(err.empty()) << err;
  ASSERT_EQ(theirs.size(), ours.insts.size());
  for (size_t i = 0; i < theirs.size(); ++i) {
    const auto& mine = ours.insts[i];
    SCOPED_TRACE("objdump: " + theirs[i].text + "   ours: " + x86::print(mine.inst));
    ASSERT_EQ(theirs[i].address, mine.offset) << "instruction boundaries differ";
    x86::Instruction a = mine.inst, b;
    try {
      b = x86::parse(normalizeObjdump(theirs[i].text));
    } catch (const AsmError& e) {
      ADD_FAILURE() << "cannot read objdump's text: " << e.what();
      continue;
    }
    // objdump does not show {disp32}; the length check above covers it.
    a.longBranch = b.longBranch = false;
    EXPECT_TRUE(a == b) << "objdump's text parses as " << x86::print(b);
  }
}

}  // namespace
