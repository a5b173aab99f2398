// Helpers shared by the assembler tests.
#ifndef LDC_TESTS_ASSEMBLER_TEST_UTIL_H
#define LDC_TESTS_ASSEMBLER_TEST_UTIL_H

#include <string>
#include <vector>

#include "assembler/assembler.h"
#include "assembler/x86.h"

namespace ldc::as::test {

// One row of tests/assembler/x86_encode.rows.
struct Row {
  int line = 0;     // in the file
  std::string hex;  // "-" if not filled in yet
  std::string text;
};

std::vector<Row> loadRows(const std::string& path = LDC_X86_ROWS);
// Rewrites the hex column of the rows file from `hexes` (same order).
void rewriteRows(const std::vector<std::string>& hexes, const std::string& path = LDC_X86_ROWS);

std::string toHex(const std::vector<uint8_t>& bytes);
std::vector<uint8_t> fromHex(const std::string& hex);

// Variants of an instruction: each operand swept on its own over every
// register of its class, memory bases/indexes/scales/displacements and
// boundary immediates. Only those that encode are returned (deduplicated).
std::vector<x86::Instruction> variants(const x86::Instruction& in);
// All variants of all golden rows.
std::vector<x86::Instruction> allRowVariants();

// A program from text. Each block is lines of: `name:` (local label),
// `name::` (global label), `# text` (comment item) or an instruction.
struct BlockText {
  int line;
  std::string text;
};
x86::X86Program buildProgram(std::vector<std::string> globals, const std::vector<BlockText>& blocks);

// GNU binutils. These fail the current test (ADD_FAILURE) with a clear
// message if the tools are missing or report errors, and return an empty
// result then.
bool binutilsAvailable(std::string* why);
std::vector<uint8_t> gnuAssemble(const std::string& source, std::string* error);

struct ObjdumpInsn {
  uint64_t address = 0;
  std::string text;  // mnemonic and operands as objdump prints them
};
std::vector<ObjdumpInsn> objdumpIntel(const std::vector<uint8_t>& code, std::string* error);

// objdump's text in our parser's syntax.
std::string normalizeObjdump(const std::string& text);

}  // namespace ldc::as::test

#endif
