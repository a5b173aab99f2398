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
void check_rows_with_gnu_as(bool printed) {
  std::string why;
  ASSERT_TRUE(binutils_available(&why)) << why;
  auto rows = load_rows();
  ASSERT_FALSE(rows.empty());
  std::string src = ".intel_syntax noprefix\n.text\n";
  std::vector<uint8_t> ours;
  std::vector<size_t> starts;
  for (size_t i = 0; i < rows.size(); ++i) {
    x86::Instruction in = x86::parse(rows[i].text);
    std::string label = ".Lrow" + std::to_string(i);
    // Numeric branch targets are relative to the row: those rows go through
    // the printer, which writes them as `.LrowN+0x12`.
    bool branch = in.num_operands && in.ops[0].kind == x86::OperandKind::Address;
    std::string text = printed || branch ? x86::print(in, false, label) : rows[i].text;
    src += label + ":\n\t" + text + "\n";
    starts.push_back(ours.size());
    auto b = from_hex(rows[i].hex);
    ours.insert(ours.end(), b.begin(), b.end());
  }
  std::string err;
  std::vector<uint8_t> theirs = gnu_assemble(src, &err);
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
                    << "\n  ours: " << to_hex(a) << "\n  as:   " << to_hex(b)
                    << " (rows after this one are not compared)";
      return;
    }
  }
  EXPECT_EQ(ours.size(), theirs.size());
}

TEST(GnuAs, EveryRowAssemblesToTheSameBytes) { check_rows_with_gnu_as(false); }

TEST(GnuAs, PrintedRowsAssembleToTheSameBytes) { check_rows_with_gnu_as(true); }

// Thousands of register/memory/immediate variants of the rows.
TEST(GnuAs, RowVariantsAssembleToTheSameBytes) {
  std::string why;
  ASSERT_TRUE(binutils_available(&why)) << why;
  auto all = all_row_variants();
  std::string src = ".intel_syntax noprefix\n.text\n";
  std::vector<uint8_t> ours;
  std::vector<size_t> starts;
  for (const auto& in : all) {
    src += "\t" + x86::print(in) + "\n";
    starts.push_back(ours.size());
    auto b = x86::encode_at(in, 0);
    ours.insert(ours.end(), b.begin(), b.end());
  }
  starts.push_back(ours.size());
  std::string err;
  auto theirs = gnu_assemble(src, &err);
  ASSERT_TRUE(err.empty()) << err;
  for (size_t i = 0; i < all.size(); ++i) {
    size_t n = starts[i + 1] - starts[i];
    if (starts[i] + n > theirs.size() ||
        !std::equal(ours.begin() + long(starts[i]), ours.begin() + long(starts[i + 1]),
                    theirs.begin() + long(starts[i]))) {
      size_t e = std::min(theirs.size(), starts[i] + n);
      ADD_FAILURE() << x86::print(all[i]) << "\n  ours: "
                    << to_hex({ours.begin() + long(starts[i]), ours.begin() + long(starts[i + 1])})
                    << "\n  as:   "
                    << to_hex({theirs.begin() + long(std::min(starts[i], e)), theirs.begin() + long(e)})
                    << " (later instructions are not compared)";
      return;
    }
  }
  EXPECT_EQ(ours.size(), theirs.size());
  std::printf("%zu variants match GNU as\n", all.size());
}

void compare_with_objdump(const std::vector<uint8_t>& code) {
  auto ours = x86::disassemble(code);
  ASSERT_FALSE(ours.error) << ours.error->message << " at " << ours.error->offset;
  std::string err;
  auto theirs = objdump_intel(code, &err);
  ASSERT_TRUE(err.empty()) << err;
  ASSERT_EQ(theirs.size(), ours.insts.size());
  size_t failures = 0;
  for (size_t i = 0; i < theirs.size() && failures < 20; ++i) {
    const auto& mine = ours.insts[i];
    SCOPED_TRACE("objdump: " + theirs[i].text + "   ours: " + x86::print(mine.inst));
    ASSERT_EQ(theirs[i].address, mine.offset) << "instruction boundaries differ";
    x86::Instruction a = mine.inst, b;
    try {
      b = x86::parse(normalize_objdump(theirs[i].text));
    } catch (const AsmError& e) {
      ADD_FAILURE() << "cannot read objdump's text: " << e.what();
      ++failures;
      continue;
    }
    // objdump does not show {disp32}; the boundary check covers it.
    a.long_branch = b.long_branch = false;
    if (!(a == b)) {
      ADD_FAILURE() << "objdump's text parses as " << x86::print(b);
      ++failures;
    }
  }
}

TEST(GnuAs, ObjdumpAgreesOnRowVariants) {
  std::string why;
  ASSERT_TRUE(binutils_available(&why)) << why;
  std::vector<uint8_t> code;
  for (const auto& in : all_row_variants()) {
    auto b = x86::encode_at(in, 0);
    code.insert(code.end(), b.begin(), b.end());
  }
  compare_with_objdump(code);
}

TEST(GnuAs, ObjdumpAgreesWithOurDisassembler) {
  std::string why;
  ASSERT_TRUE(binutils_available(&why)) << why;
  std::vector<uint8_t> code;
  for (const Row& r : load_rows()) {
    // Branch rows are written for address 0; move them to where they sit.
    x86::Instruction in = x86::parse(r.text);
    if (in.num_operands && in.ops[0].kind == x86::OperandKind::Address)
      in.ops[0].imm += int64_t(code.size());
    auto b = x86::encode_at(in, code.size());
    code.insert(code.end(), b.begin(), b.end());
  }
  compare_with_objdump(code);
}

}  // namespace
