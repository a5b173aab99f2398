// Helpers shared by the C40 tests.
#pragma once

#include <string>
#include <vector>

#include "assembler/c40.h"

namespace ldc::as::c40::test {

// One row of tests/assembler/c40_encode.rows: `<hex word>  <instruction>  ; source`.
struct Row {
  int line = 0;     // in the file
  std::string hex;  // "-" if not filled in yet
  std::string text;  // the instruction, without the comment
  std::string source;
};
std::vector<Row> load_rows(const std::string& path = LDC_C40_ROWS);
// Rewrites the hex column of the rows file (same order as load_rows).
void rewrite_rows(const std::vector<std::string>& hexes, const std::string& path = LDC_C40_ROWS);
std::string hex_word(uint32_t w);

// A program from text: each block is lines of `name:` (local label),
// `name::` (global label), `; text` (comment item) or an instruction.
struct BlockText {
  int line;
  std::string text;
};
C40Program build_program(std::vector<std::string> globals, const std::vector<BlockText>& blocks);

// The tic4x GNU tools (tests/assembler/build_tic4x_tools.sh builds them from
// Debian's binutils-source). Empty string and ADD_FAILURE if missing.
std::string tic4x_tool(const std::string& name);

// Runs a shell command; returns its exit status and fills *out with stdout
// and stderr.
int run_command(const std::string& cmd, std::string* out);
std::string temp_dir();

}  // namespace ldc::as::c40::test

