// tests/backend-c40sim/gen/c40typed_test.cpp -- the typed instructions (issue 25)
// on the C40 (docs/c40.md, "Typed instructions"):
//   * every typed instruction on the types that fit a 32-bit word that the C40
//     compiles, native at -O0, -O1 and -O2, is bit-exact with the reference
//     interpreter (ir/typed.h is the definition) after every scan, on inputs
//     at the limits of every type (wrap, extension, division by zero, MIN / -1,
//     rounding ties, shifts by big and negative counts, NaN, infinities,
//     -0, denormals) and random words;
//   * IDX / LDX / STX likewise, faults included (the record in Sys, the scan
//     ending at the IDX), and the loader's C40 code check accepts the checked
//     indexed access and refuses it tampered with;
//   * what the C40 refuses, it refuses by name: the 64-bit types and the REAL
//     functions (ldc --target=c40), every typed instruction in the C40-hosted
//     interpreter (at load).
#include <gtest/gtest.h>

#include <iostream>

#include <cmath>
#include <cstring>
#include <random>
#include <set>
#include <sstream>

#include "assembler/c40.h"
#include "backend-c40sim/gen/c40gen.h"
#include "driver/c40_target.h"
#include "ir/typed.h"
#include "loader/c40_check.h"
#include "loader/loader.h"
#include "runtime/runtime.h"

namespace {

using namespace ldc;

// The scans of each run.  The sanitizer build (Debug + ASan + UBSan) runs the
// simulator about 50 times slower, so there every run takes a fifth of its
// scans (the programs are the same; the normal build runs them all).
#ifdef LDC_SANITIZED
constexpr int kScanDivisor = 5;
#else
constexpr int kScanDivisor = 1;
#endif

// The types that fit the C40's word (types.def: at most 32 bits).
const Ty kFit[] = {Ty::BOOL, Ty::SINT, Ty::INT, Ty::DINT, Ty::USINT, Ty::UINT, Ty::UDINT,
                   Ty::BYTE, Ty::WORD, Ty::DWORD, Ty::REAL};

uint32_t fbits(float f) {
  uint32_t u;
  std::memcpy(&u, &f, 4);
  return u;
}

// Words at the limits of every 8-, 16- and 32-bit type, counts around the
// widths, and REAL bit patterns: ties (x.5), around the integer ranges, NaNs,
// infinities, -0, denormals, the largest values.
std::vector<uint32_t> edge_words() {
  std::vector<uint32_t> w;
  for (int32_t v : {0, 1, 2, 3, 5, 7, 8, 9, 15, 16, 17, 31, 32, 33, 63, 64, 100, 1000, 70000, -1, -2, -3, -7, -8, -9,
                    -31, -32, -33, -100, -1000, 0x7F, 0x80, 0x81, 0xFF, 0x100, 0x7FFF, 0x8000, 0x8001, 0xFFFF,
                    0x10000, 0x12345678, INT32_MAX, INT32_MIN, INT32_MIN + 1, -128, -129, -32768, -32769})
    w.push_back(uint32_t(v));
  for (uint32_t v : {0x80000000u, 0xFFFFFF80u, 0xFFFF8000u, 0xFFFFFFFFu, 0xDEADBEEFu}) w.push_back(v);
  for (float f : {0.0f, -0.0f, 0.5f, 1.5f, 2.5f, -0.5f, -1.5f, -2.5f, 0.49999997f, 3.4999998f, 1.0f, 0.75f, 5.5f,
                  6.5f, 127.5f, 128.5f, -128.5f, 255.5f, 32767.5f, 65535.5f, 8388607.5f, 16777216.0f, 16777218.0f,
                  1e10f, -1e10f, 2147483648.0f, -2147483648.0f, 4294967040.0f, 4294967296.0f, 1e20f, -1e20f,
                  9.2233720e18f, 1.8446744e19f, 3.4e38f, -3.4e38f, 1e-30f, 123.456f})
    w.push_back(fbits(f));
  for (uint32_t v : {0x7F800000u, 0xFF800000u, 0x7FC00000u, 0xFFC00000u, 0x7F800001u, 0x7FBFFFFFu, 0x00000001u,
                     0x80000001u, 0x007FFFFFu, 0x00800000u, 0x7F7FFFFFu})
    w.push_back(v);
  return w;
}

std::string dev(const char* area, int n) { return std::string(area) + std::to_string(n); }

// A program that holds every typed instruction the C40 compiles, `copies`
// times with operands drawn at random: sources from WX0..47 (X0..15 for
// BOOL) or constants, destinations a D word (M bit) of their own.  Each one
// in a rung of its own, its power from an X input or TRUE; a compare's push
// goes to an M bit.  `refused` collects what the C40 refuses.
std::string all_ops_program(std::mt19937& rng, int copies, std::vector<std::string>* refused) {
  const std::vector<uint32_t> edges = edge_words();
  std::ostringstream il;
  int line = 1, d = 0, m = 100;
  auto pick = [&](int n) { return int(rng() % uint32_t(n)); };
  auto source = [&](Ty t) -> std::string {
    if (pick(4) == 0) {  // a constant of t, unless a REAL that is NaN or infinite (no text for them)
      uint64_t v = typed::norm(t, uint64_t(int64_t(int32_t(edges[size_t(pick(int(edges.size())))]))));
      if (!(typed::is_real(t) && !std::isfinite(typed::f32(v)))) return typed_const_text(t, v);
    }
    return t == Ty::BOOL ? dev("X", pick(16)) : dev("WX", pick(48));
  };
  auto dest = [&](Ty t) { return t == Ty::BOOL ? dev("M", m++) : dev("D", d++); };
  for (int op = 0; op < kOpCount; op++) {
    const OpInfo& oi = op_info(Op(op));
    if (oi.klass != OpClass::Typed || Op(op) == Op::TIDX || Op(op) == Op::TLDX || Op(op) == Op::TSTX) continue;
    for (Ty t : kFit) {
      for (Ty u : kFit) {
        if (oi.typed == 1 && u != Ty::BOOL) continue;  // once
        Ty src = oi.typed == 2 ? u : Ty::None;
        if (!op_takes(Op(op), t, src)) continue;
        if (typed::is_string_instr(Op(op), t, src)) continue;  // ARGS: a string instruction, refused by name
        Instr probe;
        probe.op = Op(op), probe.ty = t, probe.src = src;
        if (!c40gen::c40_typed_refusal(probe).empty()) {
          if (refused) refused->push_back(op_spelling(probe));
          continue;
        }
        for (int k = 0; k < copies; k++) {
          il << ".rung line " << line++ << "\n";
          std::string head = op_spelling(probe);
          if (oi.push) {
            il << head << " " << source(t) << " " << source(t) << "\nOUT " << dev("M", m++) << "\n";
            continue;
          }
          il << (pick(3) == 0 ? std::string("TRUE") : "LOAD " + dev("X", pick(16))) << "\n" << head;
          for (const char* s = oi.operands; *s; s++)
            il << " " << (*s == 's' ? source(t) : *s == 'x' ? source(src) : dest(t));
          il << "\n";
        }
      }
    }
  }
  il << ".end\n";
  return il.str();
}

// Arrays: `rungs` rungs, each an IDX of an integer type that fits (its index
// from WX<k> for rung k), then an LDX or STX of a type that fits, at strides
// 1..3, bounds lo -2..0 and hi >= 2 (so the indices 0..2 are inside every
// array), arrays of words from D1000 and of bits from M1000.
std::string array_program(std::mt19937& rng, int rungs) {
  const Ty idx_types[] = {Ty::SINT, Ty::INT, Ty::DINT, Ty::USINT, Ty::UINT, Ty::UDINT};
  std::ostringstream il;
  int d = 0, m = 100;
  for (int k = 0; k < rungs; k++) {
    Ty it = idx_types[rng() % 6], t = kFit[rng() % std::size(kFit)];
    bool store = rng() & 1;
    int lo = -int(rng() % 3), n = 3 - lo + int(rng() % 6), stride = 1 + int(rng() % 3);
    int hi = lo + n - 1;
    std::string base = t == Ty::BOOL ? dev("M", 1000 + 40 * k) : dev("D", 1000 + 40 * k);
    il << ".rung line " << k + 1 << "\n" << (rng() % 4 ? "TRUE" : "LOAD X" + std::to_string(rng() % 16)) << "\n";
    il << "IDX." << ty_info(it).name << " WX" << k << " " << lo << " " << hi << "\n";
    if (store)
      il << "STX." << ty_info(t).name << " " << (t == Ty::BOOL ? dev("X", int(rng() % 16)) : dev("WX", 16 + int(rng() % 32)))
         << " " << base << " " << stride << "\n";
    else
      il << "LDX." << ty_info(t).name << " " << base << " " << stride << " " << (t == Ty::BOOL ? dev("M", m++) : dev("D", d++))
         << "\n";
  }
  il << ".end\n";
  return il.str();
}

// What ldc --target=c40 -O`opt` makes of the program, read back through the
// loader (its C40 code check included), on the simulated board.
std::unique_ptr<Engine> c40_engine(const Program& p, int opt) {
  Image img = make_c40_image(p, build_c40(p, "typed.il", opt));
  Image back = read_image(write_image(img), "typed.bin");
  return make_c40sim_engine(back.code, back.entry, back.layout);
}

std::string where(const Layout& l, size_t off) {
  for (int a = kAreaCount - 1; a >= 0; a--)
    if (off >= l.offset[a] && l.count[a])
      return std::string(area_name(Area(a))) + std::to_string((off - l.offset[a]) / l.elem_size(Area(a))) +
             " (byte " + std::to_string(off) + ")";
  return "byte " + std::to_string(off);
}

// Runs the program `scans` scans on the reference interpreter and on native
// C40 code at every -O level, from the same image, with the same inputs each
// scan (X0..15 random bits; WX0..47 drawn by `input`), comparing the whole
// image after every scan.  Returns the scans whose IDX faulted (the fault record set).
template <class Input>
int run_against_reference(const std::string& text, int scans, uint32_t seed, Input input) {
  scans /= kScanDivisor;
  Program p = parse_il_text(text, "typed.il");
  BinaryIl bin = encode_il(p);
  EXPECT_EQ(validate_il(bin.code, p.layout()), "");
  Interpreter ref(bin.code, p.layout());
  const Layout& L = p.layout();
  int faults = 0;
  for (int opt = 0; opt <= 2; opt++) {
    std::unique_ptr<Engine> c40 = c40_engine(p, opt);
    ImageBytes a(L.size), b(L.size);
    std::mt19937 rng(seed);
    const std::vector<uint32_t> edges = edge_words();
    for (uint32_t i = 0; i < L.count[int(Area::D)]; i++) {  // D: edge and random words to start with
      uint32_t w = rng() % 2 ? edges[rng() % edges.size()] : uint32_t(rng());
      std::memcpy(a.data() + L.addr(Area::D, i), &w, 4);
    }
    for (int s = 1; s <= scans; s++) {
      for (uint32_t i = 0; i < 16; i++) a[L.addr(Area::X, i)] = uint8_t(rng() & 1);
      for (uint32_t i = 0; i < 48; i++) {
        uint32_t w = input(rng);
        std::memcpy(a.data() + L.addr(Area::WX, i), &w, 4);
      }
      uint32_t zero = 0;
      std::memcpy(a.data() + kSysFault, &zero, 4);  // as the runtime would after a fault: a fresh record
      std::memcpy(b.data(), a.data(), L.size);
      ref.scan(a.data());
      c40->scan(b);
      uint32_t kind;
      std::memcpy(&kind, a.data() + kSysFault, 4);
      faults += opt == 0 && kind == kFaultIndex;
      if (std::memcmp(a.data(), b.data(), L.size) == 0) continue;
      for (size_t off = 0; off < L.size; off++) {
        if (a[off] == b[off]) continue;
        ADD_FAILURE() << "-O" << opt << " scan " << s << ": " << where(L, off) << " is " << int(b[off])
                      << " on the C40, " << int(a[off]) << " in the reference interpreter";
        return faults;
      }
    }
  }
  return faults;
}

TEST(C40Typed, EveryInstructionThatFitsIsBitExactWithTheReference) {
  const std::vector<uint32_t> edges = edge_words();
  for (uint32_t seed : {1u, 2u, 3u}) {
    std::mt19937 rng(seed);
    std::vector<std::string> refused;
    std::string text = all_ops_program(rng, 3, &refused);
    // inputs: an edge word, or (one time in three) a random one
    run_against_reference(text, 30, seed * 7919, [&](std::mt19937& r) {
      return r() % 3 == 0 ? uint32_t(r()) : edges[r() % edges.size()];
    });
    if (::testing::Test::HasFailure()) {
      std::cerr << text.substr(0, 4000);
      return;
    }
    // what was left out is the REAL functions, nothing else
    std::set<std::string> left(refused.begin(), refused.end());
    EXPECT_EQ(left, (std::set<std::string>{"EXPT.REAL", "SQRT.REAL",
                                           "LN.REAL", "LOG.REAL", "EXP.REAL", "SIN.REAL", "COS.REAL", "TAN.REAL",
                                           "ASIN.REAL", "ACOS.REAL", "ATAN.REAL"}));
  }
}

TEST(C40Typed, ArraysAndIndexFaultsAreBitExactWithTheReference) {
  int faults = 0;
  const std::vector<uint32_t> edges = edge_words();
  for (uint32_t seed = 11; seed < 19; seed++) {
    std::mt19937 rng(seed);
    std::string text = array_program(rng, 16);
    // indices: 0..2 (inside every array) 19 times in 20, else -6..14 or an edge word
    faults += run_against_reference(text, 40, seed, [&](std::mt19937& r) {
      if (r() % 20) return uint32_t(r() % 3);
      return r() % 2 ? edges[r() % edges.size()] : uint32_t(int32_t(r() % 21) - 6);
    });
    if (::testing::Test::HasFailure()) {
      std::cerr << text;
      return;
    }
  }
  const int scans = 8 * 40 / kScanDivisor;
  std::cout << faults << " of " << scans << " scans ended by an index fault\n";
  EXPECT_GT(faults, scans / 10) << "the inputs should make some IDX fault";
  EXPECT_LT(faults, scans * 9 / 10) << "and many scans run to the end";
}

// REAL ADD SUB MUL DIV, which the C40 computes as IEEE binary32 in integer
// code (its own floating point is not IEEE), on inputs that make their
// rounding work: per scan a common exponent with operands within a few
// binades of it (cancellation, alignment by 0..3 places, ties from mantissas
// with few bits), denormals, the edge words, and random words.
TEST(C40Typed, RealArithmeticIsIeeeBinary32) {
  std::ostringstream il;
  const char* ops[] = {"ADD", "SUB", "MUL", "DIV"};
  int d = 0;
  for (int k = 0; k < 96; k++) {
    il << ".rung line " << k + 1 << "\nTRUE\n" << ops[k % 4] << ".REAL WX" << (k * 7) % 48 << " WX" << (k * 13 + 5) % 48
       << " D" << d++ << "\n";
  }
  il << ".end\n";
  const std::vector<uint32_t> edges = edge_words();
  uint32_t scan_exp = 127;
  int word = 0;
  run_against_reference(il.str(), 300, 99, [&](std::mt19937& r) {
    if (word++ % 48 == 0) scan_exp = 1 + r() % 254;  // a new common exponent each scan
    uint32_t sign = (r() & 1) << 31;
    uint32_t mant = r() & 0x7FFFFF;
    switch (r() % 9) {
      case 0: return edges[r() % edges.size()];
      case 8: {  // 7..30 binades below: aligned past the 6 guard bits (sticky)
        int e = std::max(1, int(scan_exp) - 7 - int(r() % 24));
        return sign | uint32_t(e) << 23 | mant;
      }
      case 1: return uint32_t(r());
      case 2: return sign | (r() % 4 ? mant >> (r() % 23) : 1u);  // a denormal
      case 3: mant &= 0x7FFFFF << (r() % 23); [[fallthrough]];   // few mantissa bits: exact ties
      default: {
        int e = int(scan_exp) + int(r() % 7) - 3;
        e = e < 1 ? 1 : e > 254 ? 254 : e;
        return sign | uint32_t(e) << 23 | mant;
      }
    }
  });
}

// The C40 refuses by name what it cannot compute bit for bit.
TEST(C40Typed, SixtyFourBitTypesAndRealFunctionsAreRefusedByName) {
  struct Case {
    const char* line;
    const char* says;
  };
  const Case cases[] = {
      {"ADD.LINT D0 D2 D4", "the C40 cannot compile ADD.LINT: 64-bit types"},
      {"MOVE.ULINT D0 D2", "the C40 cannot compile MOVE.ULINT: 64-bit types"},
      {"AND.LWORD D0 D2 D4", "the C40 cannot compile AND.LWORD: 64-bit types"},
      {"MUL.LREAL D0 D2 D4", "the C40 cannot compile MUL.LREAL: 64-bit types"},
      {"ADD.TIME D0 D2 D4", "the C40 cannot compile ADD.TIME: 64-bit types"},
      {"MOVE.DT D0 D2", "the C40 cannot compile MOVE.DT: 64-bit types"},
      {"CONV.DINT.LREAL D0 D4", "the C40 cannot compile CONV.DINT.LREAL: 64-bit types"},
      {"CONV.TIME.DINT D0 D4", "the C40 cannot compile CONV.TIME.DINT: 64-bit types"},
      {"SIN.REAL D0 D2", "the C40 cannot compile SIN.REAL: the REAL functions are C's double functions"},
      {"SQRT.REAL D0 D2", "the C40 cannot compile SQRT.REAL: the REAL functions are C's double functions"},
      {"EXPT.REAL D0 D1 D2", "the C40 cannot compile EXPT.REAL: the REAL functions are C's double functions"},
  };
  for (const Case& c : cases) {
    Program p = parse_il_text(std::string(".rung line 1\nTRUE\n") + c.line + "\n.end\n", "r.il");
    for (int opt = 0; opt <= 2; opt++) {
      try {
        build_c40(p, "r.il", opt);
        ADD_FAILURE() << c.line << " compiled at -O" << opt;
      } catch (const CompileError& e) {
        EXPECT_NE(std::string(e.what()).find(c.says), std::string::npos) << e.what();
        EXPECT_EQ(e.line, 3) << c.line;  // the instruction's line
      }
    }
  }
}

TEST(C40Typed, TheC40HostedInterpreterRefusesTypedInstructionsByName) {
  Program p = parse_il_text(".rung line 1\nTRUE\nMOVE.INT 5 D0\nCONV.DINT.REAL D1 D2\n.end\n", "i.il");
  BinaryIl bin = encode_il(p);
  try {
    make_c40interp_engine(bin.code, p.layout());
    ADD_FAILURE() << "loaded";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("cannot run MOVE.INT (IL offset 1)"), std::string::npos) << e.what();
  }
}

// ---- the loader's check of the checked indexed access

uint32_t word_at(const Image& img, uint32_t i) {
  uint32_t w;
  std::memcpy(&w, img.code.data() + 4 * i, 4);
  return w;
}
void put(Image& img, uint32_t i, uint32_t w) { std::memcpy(img.code.data() + 4 * i, &w, 4); }
uint32_t indirect_word(const Image& img) {
  for (uint32_t i = 0; i < img.code.size() / 4; i++) {
    auto in = as::c40::decode_word(word_at(img, i), i);
    if (in && in->num_operands == 2 &&
        (in->ops[0].kind == as::c40::OperandKind::Ind || in->ops[1].kind == as::c40::OperandKind::Ind))
      return i;
  }
  return UINT32_MAX;
}

TEST(C40Typed, TheLoaderAcceptsTheCheckedAccessAndRefusesItTamperedWith) {
  Program p = parse_il_text(".rung line 1\nLOAD X0\nIDX.INT WX0 0 9\nSTX.DINT WX1 D100 2\n.end\n", "a.il");
  for (int opt = 0; opt <= 2; opt++) {
    Image img = make_c40_image(p, build_c40(p, "a.il", opt));
    ASSERT_EQ(check_c40_code(img.code, img.entry, img.layout), "") << "-O" << opt;
    uint32_t acc = indirect_word(img);
    ASSERT_NE(acc, UINT32_MAX);
    auto refused = [&](uint32_t at, uint32_t w, const char* says) {
      Image bad = img;
      put(bad, at, w);
      std::string why = check_c40_code(bad.code, bad.entry, bad.layout);
      EXPECT_NE(why.find(says), std::string::npos) << "-O" << opt << ": " << why;
    };
    using as::c40::encode_at;
    using as::c40::parse;
    // the limit (word 2: OR lo, R1) past the image; the base (word 6) below it
    refused(acc - 6, encode_at(parse("OR 0FFFFh, R1"), acc - 6), "is not inside the memory image");
    refused(acc - 7, encode_at(parse("LDHI 0FFh, R1"), acc - 7), "is not inside the memory image");
    refused(acc - 3, encode_at(parse("LDHI 07Fh, AR0"), acc - 3), "is not inside the memory image");
    // the clamp gone (CMPI or LDIHI replaced), the add of another register
    refused(acc - 5, encode_at(parse("NOP"), acc - 5), "not preceded by its bounds check");
    refused(acc - 4, encode_at(parse("LDILO R1, R0"), acc - 4), "not preceded by its bounds check");
    refused(acc - 1, encode_at(parse("ADDI R1, AR0"), acc - 1), "not preceded by its bounds check");
    // another mode, another register
    refused(acc, encode_at(parse("STI R2, *AR0++"), acc), "only *AR0 without an update");
    refused(acc, encode_at(parse("STI R2, *AR1"), acc), "only *AR0 without an update");
    refused(acc, encode_at(parse("ADDI *AR0, R2"), acc), "only LDI *AR0, Rn and STI Rn, *AR0");
    // a branch past the bounds check: the power test's BEQ (before the access) retargeted
    bool retargeted = false;
    for (uint32_t i = acc; i-- > 0 && !retargeted;) {
      auto in = as::c40::decode_word(word_at(img, i), i);
      if (in && in->mnemonic == as::c40::Mnemonic::Bc) {
        refused(i, encode_at(parse("BEQ " + std::to_string(acc)), i), "inside a checked indexed access");
        retargeted = true;
      }
    }
    EXPECT_TRUE(retargeted) << "-O" << opt << ": no conditional branch before the access";
  }
}

}  // namespace
