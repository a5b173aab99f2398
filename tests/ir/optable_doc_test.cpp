// docs/il.md against ir/ops.def: the page's op table lists exactly the rows of
// the table (every column), its REL and FN tables exactly those of ops.def, and
// the sections on the instructions name every mnemonic.  Also the facts of the
// REL and FN tables that the code relies on.
#include <gtest/gtest.h>

#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "ir/ir.h"

using namespace ldc;

namespace {

std::string il_md() {
  std::ifstream f(LDC_DOCS_DIR "/il.md");
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

std::string trim(std::string s) {
  size_t a = s.find_first_not_of(" \t"), b = s.find_last_not_of(" \t");
  return a == std::string::npos ? "" : s.substr(a, b - a + 1);
}
std::string unquote(std::string s) {  // `x` -> x
  if (s.size() >= 2 && s.front() == '`' && s.back() == '`') return s.substr(1, s.size() - 2);
  return s;
}

// The rows of the markdown table whose header row starts with `| head`,
// each as its trimmed cells (backquotes removed); the header and rule rows not included.
std::vector<std::vector<std::string>> table_after(const std::string& md, const std::string& head) {
  std::vector<std::vector<std::string>> rows;
  size_t at = md.find("\n| " + head);
  if (at == std::string::npos) return rows;
  std::istringstream in(md.substr(at + 1));
  std::string line;
  std::getline(in, line);  // header
  std::getline(in, line);  // |---|
  while (std::getline(in, line) && !line.empty() && line[0] == '|') {
    std::vector<std::string> cells;
    std::string cell;
    for (size_t i = 1; i < line.size(); i++) {
      if (line[i] == '|') {
        cells.push_back(unquote(trim(cell)));
        cell.clear();
      } else {
        cell += line[i];
      }
    }
    rows.push_back(cells);
  }
  return rows;
}


TEST(OpTable, DocsListTheTable) {
  auto rows = table_after(il_md(), "opcode | mnemonic |");
  ASSERT_EQ(rows.size(), size_t(kOpCount)) << "docs/il.md, the op table: one row per OP of ir/ops.def";
  for (int i = 0; i < kOpCount; i++) {
    const OpInfo& o = op_info(Op(i));
    const auto& r = rows[i];
    ASSERT_EQ(r.size(), 10u) << "row " << i;
    EXPECT_EQ(r[0], std::to_string(i));
    EXPECT_EQ(r[1], o.name) << "row " << i;
    EXPECT_EQ(r[2], *o.operands ? o.operands : "–") << o.name;
    EXPECT_EQ(r[3], std::to_string(o.push)) << o.name;
    EXPECT_EQ(r[4], std::to_string(o.pop)) << o.name;
    std::string klass = op_class_name(o.klass);
    klass[0] = char(std::toupper(klass[0]));
    EXPECT_EQ(r[5], klass) << o.name;
    EXPECT_EQ(r[6], o.rel == Rel::None ? "–" : rel_info(o.rel).name) << o.name;
    EXPECT_EQ(r[7], o.fn == RealFn::None ? "–" : real_fn_info(o.fn).name) << o.name;
    EXPECT_EQ(r[8], std::to_string(o.typed)) << o.name;
    std::string types = *o.types ? o.types : "–";
    if (size_t bar = types.find('|'); bar != std::string::npos) types.replace(bar, 1, " / ");  // a table cell has no |
    EXPECT_EQ(r[9], types) << o.name;
  }
}

TEST(OpTable, DocsListTheRelations) {
  auto rows = table_after(il_md(), "rel | C |");
  ASSERT_EQ(rows.size(), size_t(Rel::None));
  for (int i = 0; i < int(Rel::None); i++) {
    const RelInfo& r = rel_info(Rel(i));
    ASSERT_EQ(rows[i].size(), 5u);
    EXPECT_EQ(rows[i][0], r.name);
    EXPECT_EQ(rows[i][1], r.c) << r.name;
    EXPECT_EQ(rows[i][2], r.ld) << r.name;
    EXPECT_EQ(rows[i][3], rel_info(r.negation).name) << r.name;
    EXPECT_EQ(rows[i][4], rel_info(r.swapped).name) << r.name;
  }
}

TEST(OpTable, DocsListTheRealFunctions) {
  auto rows = table_after(il_md(), "fn | libm |");
  ASSERT_EQ(rows.size(), size_t(RealFn::None));
  for (int i = 0; i < int(RealFn::None); i++) {
    const RealFnInfo& f = real_fn_info(RealFn(i));
    ASSERT_EQ(rows[i].size(), 4u);
    EXPECT_EQ(rows[i][0], f.name);
    EXPECT_EQ(rows[i][1], f.libm) << f.name;
    EXPECT_EQ(rows[i][2], f.called ? "yes" : "no") << f.name;
    EXPECT_EQ(rows[i][3], f.ints ? "yes" : "no") << f.name;
  }
}

// Every mnemonic is named as a word of a `code span` in the sections on the
// instructions (from "## Instructions" to the op table).
TEST(OpTable, DocsDescribeEveryMnemonic) {
  std::string md = il_md();
  size_t from = md.find("\n## Instructions"), to = md.find("\n## The op table");
  ASSERT_NE(from, std::string::npos);
  ASSERT_NE(to, std::string::npos);
  std::string text = md.substr(from, to - from);
  std::set<std::string> words;
  for (size_t p = text.find('`'); p != std::string::npos; p = text.find('`', p)) {
    size_t q = text.find('`', p + 1);
    if (q == std::string::npos) break;
    std::istringstream span(text.substr(p + 1, q - p - 1));
    for (std::string w; span >> w;) words.insert(w), words.insert(w.substr(0, w.find('.')));  // ADD.INT: ADD
    p = q + 1;
  }
  for (int i = 0; i < kOpCount; i++) {
    const OpInfo& o = op_info(Op(i));
    const char* spelled = o.typed ? o.name + 1 : o.name;  // a typed op's tag is T + its spelling
    EXPECT_TRUE(words.count(spelled)) << spelled << " is not described";
  }
}

TEST(OpTable, RelationsAreConsistent) {
  for (int i = 0; i < int(Rel::None); i++) {
    Rel r = Rel(i);
    EXPECT_EQ(negate(negate(r)), r);
    EXPECT_EQ(swap_operands(swap_operands(r)), r);
    EXPECT_EQ(op_info(compare_op(r)).rel, r);
    for (int32_t x : {-2, 0, 3})
      for (int32_t y : {-2, 0, 3}) {
        EXPECT_NE(rel_holds(r, x, y), rel_holds(negate(r), x, y)) << rel_info(r).name;
        EXPECT_EQ(rel_holds(r, x, y), rel_holds(swap_operands(r), y, x)) << rel_info(r).name;
      }
  }
}

TEST(OpTable, SpecialsHaveAFunctionAndComparesARelation) {
  for (int i = 0; i < kOpCount; i++) {
    const OpInfo& o = op_info(Op(i));
    EXPECT_EQ(o.klass == OpClass::Compare || (o.klass == OpClass::Typed && o.push == 1), o.rel != Rel::None) << o.name;
    EXPECT_EQ(o.klass == OpClass::Special, o.fn != RealFn::None) << o.name;
  }
  for (int f = 0; f < int(RealFn::None); f++)
    EXPECT_EQ(real_fn(RealFn(f))(0.5f), apply_real_fn(RealFn(f), 0.5f)) << real_fn_info(RealFn(f)).name;
}

}  // namespace
