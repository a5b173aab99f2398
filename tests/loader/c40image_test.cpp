// tests/loader/c40image_test.cpp -- ImageTarget::C40 images: what ldc writes
// reads back, and the loader's C40 code check refuses what it must
// (docs/image-format.md, "The C40 code check").
#include <gtest/gtest.h>

#include <cstring>
#include <fstream>
#include <sstream>

#include "bench/ldgen.h"
#include "driver/c40_target.h"
#include "frontend/frontend.h"
#include "loader/c40_check.h"
#include "loader/loader.h"
#include "runtime/runtime.h"
#include "backend-c40sim/machine/c40machine.h"

namespace {

using namespace ldc;
using namespace ldc::as::c40;

std::string read(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

Image example_image(const std::string& name, int opt_level = 0) {
  Program p = lower_to_il(parse_ld(read(std::string(LDC_EXAMPLES_DIR) + "/" + name + ".ld"), name + ".ld"));
  return make_c40_image(p, build_c40(p, name + ".ld", opt_level));
}

void put(Image& img, uint32_t word_index, uint32_t w) { std::memcpy(img.code.data() + 4 * word_index, &w, 4); }
uint32_t get(const Image& img, uint32_t word_index) {
  uint32_t w;
  std::memcpy(&w, img.code.data() + 4 * word_index, 4);
  return w;
}
uint32_t enc(const std::string& text, int64_t at = 0) { return encode_at(parse(text), at); }

// the first word of a mnemonic in the code
uint32_t find(const Image& img, Mnemonic m, Cond c = Cond::U) {
  for (uint32_t i = 0; i < img.code.size() / 4; i++) {
    auto in = decode_word(get(img, i), i);
    if (in && in->mnemonic == m && (!has_cond(m) || in->cond == c)) return i;
  }
  return UINT32_MAX;
}

std::string refusal(const Image& img) {
  try {
    read_image(write_image(img), "t.bin");
  } catch (ImageError& e) {
    return e.what();
  }
  return "";
}

// at every level: -O1 and -O2 set DP once per scan, the loader's flow
// analysis still finds it on every path
TEST(C40Image, EveryExampleReadsBack) {
  for (const char* n : {"motor", "realmath", "sorter", "jumps", "timers", "edges", "wordlogic"}) {
    for (int opt = 0; opt <= 2; opt++) {
      Image img = example_image(n, opt);
      EXPECT_EQ(check_c40_code(img.code, img.entry, img.layout), "") << n << " -O" << opt;
      Image back = read_image(write_image(img), "t.bin");
      EXPECT_EQ(back, img) << n;
      EXPECT_EQ(back.target, ImageTarget::C40);
      std::vector<uint8_t> hex = read_intel_hex(write_intel_hex(write_image(img)), "t.hex");
      EXPECT_EQ(read_image(hex, "t.hex"), img) << n;
    }
  }
  // a far edge slot: its LDPK and the data page back, inside a rung without its own LDPK
  Program p = parse_il_text(".edges 30001\n.rung line 1\n    LOAD X2\n    LOADP X1 E30000\n    ORBLK\n    OUT Y0\n.end\n", "t.il");
  for (int opt = 0; opt <= 2; opt++) {
    Image img = make_c40_image(p, build_c40(p, "t.il", opt));
    EXPECT_EQ(check_c40_code(img.code, img.entry, img.layout), "") << "far edge -O" << opt;
  }
}

// Random programs of every element class at every level pass the loader's
// check: -O1/-O2 delay slots hold no control instruction and stay inside the
// code, DP is known on every path.
TEST(C40Image, RandomProgramsAtEveryLevelPassTheCodeCheck) {
  for (uint64_t seed = 300; seed < 340; seed++) {
    GenOptions o;
    o.rungs = 40;
    o.max_depth = 2 + int(seed % 4);
    Program p = lower_to_il(parse_ld(generate_ld(seed, o), "r.ld"));
    for (int opt = 0; opt <= 2; opt++) {
      Image img = make_c40_image(p, build_c40(p, "r.ld", opt));
      EXPECT_EQ(check_c40_code(img.code, img.entry, img.layout), "") << "seed " << seed << " -O" << opt;
    }
  }
}

TEST(C40Image, RefusesAWordThatDoesNotDecode) {
  Image img = example_image("motor");
  put(img, 5, 0xFFFFFFFFu);
  std::string why = refusal(img);
  EXPECT_NE(why.find("at word 0x5: word 0xffffffff does not decode"), std::string::npos) << why;
  EXPECT_NE(why.find("section 'code'"), std::string::npos) << why;
}

TEST(C40Image, RefusesDirectOperandsOutsideTheImage) {
  Image img = example_image("motor");
  uint32_t i = find(img, Mnemonic::Ldpk);
  ASSERT_NE(i, UINT32_MAX);
  put(img, i, enc("LDPK 090h"));
  std::string why = refusal(img);
  EXPECT_NE(why.find("is outside the memory image"), std::string::npos) << why;
  // the last word of the image is fine, one past it is not
  Program p = parse_il_text(".rung line 1\n    LOAD X1\n    OUT Y0\n.end\n", "t.il");
  Image ok = make_c40_image(p, build_c40(p, "t.il"));
  uint32_t out = find(ok, Mnemonic::Sti);
  c40gen::C40Layout w = c40gen::C40Layout::of(p.layout());
  uint32_t last = (c40gen::kDataBase + w.words - 1) & 0xFFFF;
  put(ok, out, enc("STI R0, @" + std::to_string(last)));
  EXPECT_EQ(check_c40_code(ok.code, ok.entry, ok.layout), "");
  put(ok, out, enc("STI R0, @" + std::to_string(last + 1)));
  EXPECT_NE(check_c40_code(ok.code, ok.entry, ok.layout).find("outside the memory image"), std::string::npos);
}

TEST(C40Image, RefusesDirectOperandsWithoutAKnownDataPage) {
  Image img = example_image("motor");
  uint32_t i = find(img, Mnemonic::Ldpk);
  put(img, i, enc("NOP"));
  std::string why = refusal(img);
  EXPECT_NE(why.find("data page not set by LDPK on every path"), std::string::npos) << why;
  // DP written by another instruction is unknown too
  img = example_image("motor");
  put(img, i, enc("LDI 0, DP"));
  EXPECT_NE(refusal(img).find("data page not set"), std::string::npos);
}

TEST(C40Image, RefusesIndirectOperandsAndRegisterBranches) {
  Image img = example_image("motor");
  uint32_t i = find(img, Mnemonic::Sti);
  put(img, i, enc("STI R0, *+AR1(3)"));
  EXPECT_NE(refusal(img).find("indirect memory operand"), std::string::npos);
  img = example_image("motor");
  put(img, i, enc("BU R0"));
  EXPECT_NE(refusal(img).find("through a register"), std::string::npos);
}

TEST(C40Image, RefusesBranchTargetsOutsideTheCode) {
  Image img = example_image("jumps");
  uint32_t n = uint32_t(img.code.size() / 4);
  uint32_t i = find(img, Mnemonic::Br);
  ASSERT_NE(i, UINT32_MAX);
  put(img, i, encode_at(make(Mnemonic::Br, {as::c40::Operand::a(n + 5)}), i));
  std::string why = refusal(img);
  EXPECT_NE(why.find("outside the code"), std::string::npos) << why;
  // calls may go to the math ROM's entries, and nowhere else outside
  img = example_image("realmath");
  i = find(img, Mnemonic::Call);
  ASSERT_NE(i, UINT32_MAX);
  EXPECT_EQ(refusal(img), "");
  for (uint32_t k = i; k < img.code.size() / 4; k++) {
    auto in = decode_word(get(img, k), k);
    if (in->mnemonic == Mnemonic::Call && in->ops[0].imm >= int64_t(c40gen::kRomBase)) {
      put(img, k, encode_at(make(Mnemonic::Call, {as::c40::Operand::a(c40gen::kRomBase + 1)}), k));
      break;
    }
  }
  EXPECT_NE(refusal(img).find("outside the code"), std::string::npos);
}

TEST(C40Image, RefusesControlInDelaySlots) {
  Program p = parse_il_text(".rung line 1\n    LOAD X1\n    DIV D0 D1 D2\n.end\n", "t.il");
  Image img = make_c40_image(p, build_c40(p, "t.il"));
  EXPECT_EQ(refusal(img), "");
  uint32_t i = find(img, Mnemonic::Dbcd);
  ASSERT_NE(i, UINT32_MAX);
  put(img, i + 1, enc("RETSU"));
  EXPECT_NE(refusal(img).find("in the delay slot"), std::string::npos);
}

// The C40 check lets backward branches through (the division routines loop),
// so the simulator's per-scan cycle budget is what stops a looping image: a
// branch to itself passes the check and its first scan stops at the budget.
TEST(C40Image, ALoopStopsAtTheScanCycleBudget) {
  Program p = parse_il_text(".rung line 1\n    LOAD X1\n    OUT Y0\n.end\n", "t.il");
  Image img = make_c40_image(p, build_c40(p, "t.il"));
  put(img, img.entry / 4, encode_at(make(Mnemonic::Br, {as::c40::Operand::a(img.entry / 4)}), img.entry / 4));
  ASSERT_EQ(refusal(img), "");
  auto eng = make_c40sim_engine(img.code, img.entry, img.layout);
  Memory m(img.layout);
  try {
    eng->scan(m.data());
    ADD_FAILURE() << "a scan that branches to itself ended";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("cycle limit"), std::string::npos) << e.what();
  }
}

// Code ldc makes stays far inside that budget: every example at every level,
// over scans with changing inputs, uses less than a tenth of it.
TEST(C40Image, ExamplesStayFarBelowTheCycleBudget) {
  for (const char* n : {"motor", "timers", "realmath", "wordlogic", "sorter", "traffic", "updown", "jumps"})
    for (int opt : {0, 1, 2}) {
      Image img = example_image(n, opt);
      uint64_t budget = c40gen::C40Machine::kBudgetBase + c40gen::C40Machine::kBudgetPerWord * (img.code.size() / 4);
      auto eng = make_c40sim_engine(img.code, img.entry, img.layout);
      Memory m(img.layout);
      uint64_t worst = 0;
      for (int k = 0; k < 40; k++) {
        for (uint32_t x = 0; x < 16; x++) m.set_bit(Area::X, x, ((k * 7 + x * 3) % 5) < 2);
        for (uint32_t d = 0; d < 8; d++) m.set_int(Area::D, d, k * 977 - int32_t(d) * 3001);
        std::memcpy(m.data() + kSysDt, &k, 4);
        eng->scan(m.data());
        worst = std::max(worst, eng->last_cost()->cycles);
      }
      EXPECT_LT(worst * 10, budget) << n << " -O" << opt << ": " << worst << " cycles, budget " << budget;
    }
}

}  // namespace
