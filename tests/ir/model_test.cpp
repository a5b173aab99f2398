// The typed program model (ir/model.h): literals with MatIEC's meaning, type
// sizes and places, member and element access, initial values, recursion.
// Expected values are derived by hand from the definitions named beside them.
#include <gtest/gtest.h>

#include "ir/model.h"
#include "ir/typed.h"

using namespace ldc;
using namespace ldc::model;

namespace {

Lit lit(const char* text, Ty t = Ty::None) {
  std::string why;
  auto p = parse_literal(text, why);
  EXPECT_TRUE(p) << text << ": " << why;
  if (!p) return {};
  if (t == Ty::None) return p->lit;
  auto v = literal_as(*p, t, why);
  EXPECT_TRUE(v) << text << ": " << why;
  return v ? *v : Lit{};
}
std::string refused(const char* text, Ty t = Ty::None) {
  std::string why;
  auto p = parse_literal(text, why);
  if (!p) return why;
  if (t == Ty::None) return "";
  auto v = literal_as(*p, t, why);
  return v ? "" : why;
}

TEST(Model, LiteralsHaveMatiecMeaning) {
  EXPECT_EQ(lit("INT#5").ty, Ty::INT);
  EXPECT_EQ(lit("INT#5").bits, 5u);
  EXPECT_EQ(lit("INT#-5").bits, uint64_t(-5));          // sign-extended (typed.h canonical bits)
  EXPECT_EQ(lit("16#FF", Ty::BYTE).bits, 255u);
  EXPECT_EQ(lit("2#1010_0101", Ty::BYTE).bits, 0xA5u);   // 165
  EXPECT_EQ(lit("DWORD#1").bits, 1u);
  EXPECT_EQ(lit("DWORD#16#FFFFFFFF").bits, 0xFFFFFFFFu);
  EXPECT_EQ(lit("8#17", Ty::INT).bits, 15u);
  EXPECT_EQ(lit("1_000", Ty::DINT).bits, 1000u);
  // T#1h2m3.5s = 3600 + 120 + 3.5 s = 3723.5 s = 3723500000000 ns
  EXPECT_EQ(lit("T#1h2m3.5s").bits, 3723500000000ull);
  EXPECT_EQ(lit("T#1h2m3.5s").ty, Ty::TIME);
  EXPECT_EQ(lit("TIME#-2ms").bits, uint64_t(-2000000));
  EXPECT_EQ(lit("T#3.5ms").bits, 3500000u);
  // T#5d14h12m18s3.5ms (issue 25): 5*86400 + 14*3600 + 12*60 + 18 s = 483138 s, + 3.5 ms
  EXPECT_EQ(lit("T#5D14H12M18S3.5MS").bits, 483138003500000ull);
  EXPECT_EQ(typed::f64(lit("LREAL#1e-9").bits), 1e-9);
  EXPECT_EQ(typed::f32(lit("1.5", Ty::REAL).bits), 1.5f);
  EXPECT_EQ(typed::f32(lit("3", Ty::REAL).bits), 3.0f);  // an integer literal is an ANY_NUM
  EXPECT_EQ(lit("TRUE").bits, 1u);
  EXPECT_EQ(lit("BOOL#0").bits, 0u);
  // 2024-01-31: 19753 days after 1970-01-01
  EXPECT_EQ(lit("DATE#2024-01-31").bits, 19753ull * 86400000000000ull);
  EXPECT_EQ(lit("TOD#12:30:00.5").bits, (12 * 3600 + 30 * 60) * 1000000000ull + 500000000ull);
  EXPECT_EQ(lit("DT#1970-01-02-00:00:01").bits, 86401000000000ull);
}

TEST(Model, LiteralsOutOfRangeAreRefused) {
  EXPECT_NE(refused("INT#40000"), "");
  EXPECT_NE(refused("40000", Ty::INT), "");
  EXPECT_NE(refused("-1", Ty::UINT), "");
  EXPECT_NE(refused("1.5", Ty::INT), "");
  EXPECT_NE(refused("5", Ty::TIME), "");
  EXPECT_NE(refused("INT#5", Ty::DINT), "");
  EXPECT_NE(refused("16#-1"), "");
  EXPECT_NE(refused("T#5x"), "");
  std::string why;
  EXPECT_FALSE(parse_literal("motor", why));  // a name, not a literal
  EXPECT_EQ(why, "");
}

TEST(Model, StructuresTakeBitsAndCells) {
  Model m;
  Type s;
  s.kind = TypeKind::Struct;
  s.name = "POINT";
  s.members = {{"on", m.elem(Ty::BOOL), {}, {}}, {"x", m.elem(Ty::INT), {}, {}}, {"big", m.elem(Ty::LREAL), {}, {}},
               {"off", m.elem(Ty::BOOL), {}, {}}};
  TypeId pt = m.add_type(s, {});
  EXPECT_EQ(m.type(pt).size, (Size{2, 3}));
  EXPECT_EQ(m.member(pt, "BIG")->offset, (Size{1, 1}));
  EXPECT_EQ(m.member(pt, "off")->offset, (Size{1, 3}));
  Type a;
  a.kind = TypeKind::Array;
  a.dims = {{1, 3}, {0, 1}};
  a.of = pt;
  TypeId arr = m.add_type(a, {});
  EXPECT_EQ(m.type(arr).size, (Size{12, 18}));
  m.set_area(100, 200);
  Ref r{arr, m.place(m.type(arr).size, {}), {}, true};
  EXPECT_EQ(r.at, (Place{100, 200}));
  // p[3, 1].x: element (3-1)*2 + 1 = 5 -> bits 100 + 5*2, cells 200 + 5*3, then x at cell +0
  auto c = [](int64_t v) { return std::make_pair(Operand::typed_const(uint64_t(v)), Ty::DINT); };
  Ref e = m.select_member(m.select_element(r, {c(3), c(1)}, {}), "x", {});
  EXPECT_EQ(e.at.cell, 215u);  // (an INT has no bit: only its cell is its place)
  EXPECT_EQ(m.scalar_ty(e.type), Ty::INT);
  // a variable first index: one step of stride 2 elements
  Operand i{OpdKind::Int, Area::D, 7};
  Ref v = m.select_element(r, {{i, Ty::INT}, c(0)}, {});
  ASSERT_EQ(v.steps.size(), 1u);
  EXPECT_EQ(v.steps[0].stride, (Size{4, 6}));
  EXPECT_EQ(stride_of(Ty::BOOL, v.steps[0].stride), 4);
  EXPECT_THROW(m.select_element(r, {c(4), c(0)}, {}), ModelError);   // outside 1..3
  EXPECT_THROW(m.select_element(r, {{i, Ty::REAL}, c(0)}, {}), ModelError);  // not an integer
  EXPECT_THROW(m.select_member(r, "x", {}), ModelError);                 // an array has no members
  try {
    m.select_member(m.select_element(r, {c(1), c(0)}, {}), "z", {});
    FAIL();
  } catch (const ModelError& e) {
    EXPECT_EQ(e.message, "POINT has no member 'z' (on, x, big, off)");
  }
}

TEST(Model, InitialValuesFollowListsAndMembers) {
  Model m;
  Type a;
  a.kind = TypeKind::Array;
  a.dims = {{0, 5}};
  a.of = m.elem(Ty::INT);
  TypeId arr = m.add_type(a, {});
  Init in;
  in.kind = Init::List;
  auto val = [](int64_t v) { Init i; i.kind = Init::Value; i.value.untyped_int = true; i.value.ival = v; return i; };
  in.list = {{1, val(1)}, {1, val(2)}, {3, val(7)}};  // [1, 2, 3(7)]: element 5 keeps 0
  std::vector<Model::Store> out;
  m.initial_stores(arr, {0, 10}, &in, out);
  ASSERT_EQ(out.size(), 5u);
  EXPECT_EQ(out[0].at.cell, 10u);
  EXPECT_EQ(out[4].at.cell, 14u);
  EXPECT_EQ(out[4].bits, 7u);
  in.list.push_back({2, val(0)});  // 7 values for 6 elements
  out.clear();
  EXPECT_THROW(m.initial_stores(arr, {0, 10}, &in, out), ModelError);
}

TEST(Model, RecursionIsRefusedByName) {
  Model m;
  Pou a, b;
  a.name = "A", a.kind = PouKind::FunctionBlock;
  b.name = "B", b.kind = PouKind::FunctionBlock;
  int ia = m.add_pou(a), ib = m.add_pou(b);
  EXPECT_NE(m.find_type("a"), kNoType);  // an FB is a type
  Model::expand_guard(m, {ia}, ib, {});
  try {
    Model::expand_guard(m, {ia, ib}, ia, {});
    FAIL();
  } catch (const ModelError& e) {
    EXPECT_EQ(e.message.substr(0, 22), "recursion: A -> B -> A");
  }
}

}  // namespace
