// Helpers shared by the assembler tests.
#pragma once

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

std::vector<Row> load_rows(const std::string& path = LDC_X86_ROWS);
// Rewrites the hex column of the rows file from `hexes` (same order).
void rewrite_rows(const std::vector<std::string>& hexes, const std::string& path = LDC_X86_ROWS);

std::string to_hex(const std::vector<uint8_t>& bytes);
std::vector<uint8_t> from_hex(const std::string& hex);

// Variants of an instruction: each operand swept on its own over every
// register of its class, memory bases/indexes/scales/displacements and
// boundary immediates. Only those that encode are returned (deduplicated).
std::vector<x86::Instruction> variants(const x86::Instruction& in);
// All variants of all golden rows.
std::vector<x86::Instruction> all_row_variants();

// A program from text. Each block is lines of: `name:` (local label),
// `name::` (global label), `# text` (comment item) or an instruction.
struct BlockText {
  int line;
  std::string text;
};
x86::X86Program build_program(std::vector<std::string> globals, const std::vector<BlockText>& blocks);

// GNU binutils. These fail the current test (ADD_FAILURE) with a clear
// message if the tools are missing or report errors, and return an empty
// result then.
bool binutils_available(std::string* why);
std::vector<uint8_t> gnu_assemble(const std::string& source, std::string* error);

struct ObjdumpInsn {
  uint64_t address = 0;
  std::string text;  // mnemonic and operands as objdump prints them
};
std::vector<ObjdumpInsn> objdump_intel(const std::vector<uint8_t>& code, std::string* error);

// objdump's text in our parser's syntax.
std::string normalize_objdump(const std::string& text);

}  // namespace ldc::as::test

