// The typed instructions (ir/typed.h, docs/x86.md "Typed instructions") on
// native x86-64 code at -O0, -O1 and -O2 against the reference interpreter,
// scan by scan: every typed op with every type it takes (CONV with every pair),
// its operands in devices that the test fills before each scan with values
// at the limits (the extremes of each width, wrap points, NaN, the
// infinities, ties, 2^63 and 2^64, negative and oversized shift counts ...)
// or random bits, and with constants of the same kinds; the power of each
// instruction on or off; arrays through IDX / LDX / STX with strides of 0 to
// 3 cells and index faults.  The expected values are the interpreter's:
// ir/typed.h defines each instruction, and every byte of the image must agree
// after every scan (the fault record in Sys included).
#include <gtest/gtest.h>

#include <cstring>
#include <functional>
#include <limits>
#include <random>
#include <sstream>

#include "backend-x86/backend_x86.h"
#include "driver/x86_target.h"
#include "ir/ir.h"
#include "ir/scanopt.h"
#include "ir/typed.h"
#include "runtime/runtime.h"

using namespace ldc;

namespace {

// Inputs: 64 slots of two D words each (D0..D127), bits M0..M63 (the typed
// BOOL operands, which may hold any byte), and the power bits M100..M163.
constexpr uint32_t kSlots = 64, kPowerBase = 100, kOutBase = 1000, kOutBits = 2000;

Operand dev(Area a, uint32_t index) {
  Operand o;
  o.area = a;
  o.index = index;
  o.kind = area_is_bit(a) ? OpdKind::Bit : area_is_real(a) ? OpdKind::Real : OpdKind::Int;
  return o;
}
Operand k32(int32_t v) {
  Operand o;
  o.kind = OpdKind::ConstInt;
  o.ival = v;
  return o;
}

// Values at the limits, as 64 bits (a narrow type reads the low bits; a
// REAL the low 32 bits).
std::vector<uint64_t> limit_values() {
  std::vector<uint64_t> v = {0, 1, 2, 3, 7, 8, 15, 16, 31, 32, 33, 63, 64, 65, 100, 127, 128, 255, 256, 32767, 32768, 65535,
                             65536, 0x7fffffff, 0x80000000, 0xffffffff, 0x100000000ull, 0x7fffffffffffffffull,
                             0x8000000000000000ull, 0xffffffffffffffffull, 0xfffffffffffffffeull, 0xffffffffffffff80ull,
                             0xffffffffffff8000ull, 0xffffffff80000000ull, 0x00000001ffffff7full, 86400000000000ull,
                             0xfffffb1ae4d6e001ull /* -5e15: a DT before 1970 */, 1000000, 999999, 0xfffffffffff0bdc1ull};
  for (double d : {0.5, 1.5, 2.5, -0.5, -1.5, -2.5, 3.0, -7.0, 0.1, -0.0, 1e300, -1e300, 1e-310, 9.2233720368547758e18,
                   1.8446744073709552e19, 1.9e19, -9.2233720368547758e18, -9.3e18, 4294967295.5, 4294967296.0,
                   2147483647.5, -2147483648.5, 32767.5, 65535.5, 255.5, 1e10, -1e10, 1e6, 86400000.25,
                   std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity(),
                   std::numeric_limits<double>::quiet_NaN(), -std::numeric_limits<double>::quiet_NaN(), 2.0, 0.25, 1.0,
                   -1.0, 0.75})
    v.push_back(typed::bits_of(d));
  for (float f : {0.5f, 1.5f, 2.5f, -0.5f, -2.5f, 3.0f, -0.0f, 1e30f, -1e30f, 1e-40f, 3.4e38f, 2147483648.0f, 4294967296.0f,
                  9.3e18f, 1.9e19f, 65535.5f, 255.5f, std::numeric_limits<float>::infinity(),
                  -std::numeric_limits<float>::infinity(), std::numeric_limits<float>::quiet_NaN(), 2.0f, 0.1f})
    v.push_back(typed::bits_of(f) | (uint64_t(0xdeadbeef) << 32));  // junk above: REAL reads the low word only
  return v;
}

class Inputs {
 public:
  explicit Inputs(uint64_t seed) : rng_(seed), limits_(limit_values()) {}
  uint64_t value() {
    switch (rng_() % 4) {
      case 0: return rng_();
      case 1: return uint64_t(int64_t(int32_t(rng_() % 200) - 100));
      default: return limits_[rng_() % limits_.size()];
    }
  }
  // this scan's inputs, the same into both images
  void fill(ImageBytes& a, ImageBytes& b, const Layout& l, double power_on) {
    for (uint32_t s = 0; s < kSlots; s++) {
      uint64_t v = value();
      std::memcpy(a.data() + l.addr(Area::D, 2 * s), &v, 8);
      std::memcpy(b.data() + l.addr(Area::D, 2 * s), &v, 8);
    }
    for (uint32_t m = 0; m < kSlots; m++) {
      static const uint8_t kBytes[] = {0, 1, 0, 1, 2, 255};
      uint8_t v = kBytes[rng_() % 6];
      a[l.addr(Area::M, m)] = b[l.addr(Area::M, m)] = v;
      uint8_t p = std::uniform_real_distribution<double>(0, 1)(rng_) < power_on ? 1 : 0;
      a[l.addr(Area::M, kPowerBase + m)] = b[l.addr(Area::M, kPowerBase + m)] = p;
    }
  }
  std::mt19937_64& rng() { return rng_; }

 private:
  std::mt19937_64 rng_;
  std::vector<uint64_t> limits_;
};

// A program of one rung per typed instruction (rung: `LOAD M1xx` or `TRUE`,
// the instruction, and `OUT M2xxx` after a compare).
class Builder {
 public:
  explicit Builder(uint64_t seed) : rng_(seed), limits_(limit_values()) {}

  Operand source(Ty t) {
    if (rng_() % 5 == 0) return Operand::typed_const(typed::norm(t, limits_[rng_() % limits_.size()]));
    if (t == Ty::BOOL) return dev(Area::M, uint32_t(rng_() % kSlots));
    return dev(Area::D, 2 * uint32_t(rng_() % kSlots));
  }
  Operand dest(Ty t) {
    if (t == Ty::BOOL) return dev(Area::M, kOutBits + next_bit_++);
    Operand d = dev(Area::D, kOutBase + next_word_);
    next_word_ += 2;
    return d;
  }
  void rung(std::vector<Instr> code) {
    Rung r;
    r.line = int(p_.rungs.size()) + 1;
    Instr power;
    if (rng_() % 4 == 0) power.op = Op::TRUE;
    else power.op = Op::LOAD, power.a[0] = dev(Area::M, kPowerBase + uint32_t(rng_() % kSlots));
    r.code.push_back(power);
    for (Instr& in : code) r.code.push_back(in);
    p_.rungs.push_back(std::move(r));
  }
  // one instruction of op with types t, u, its operands drawn
  void instr(Op op, Ty t, Ty u) {
    const OpInfo& oi = op_info(op);
    Instr in;
    in.op = op, in.ty = t, in.src = oi.typed == 2 ? u : Ty::None;
    for (int i = 0; i < oi.nopd; i++) {
      char sig = oi.operands[i];
      in.a[i] = sig == 's' ? source(t) : sig == 'x' ? source(u) : dest(t);
    }
    std::vector<Instr> code{in};
    if (oi.push) {
      Instr out;
      out.op = Op::OUT;
      out.a[0] = dev(Area::M, kOutBits + next_bit_++);
      code.push_back(out);
    }
    rung(code);
  }
  std::mt19937_64& rng() { return rng_; }
  Program take() { return std::move(p_); }

 private:
  std::mt19937_64 rng_;
  std::vector<uint64_t> limits_;
  Program p_;
  uint32_t next_word_ = 0, next_bit_ = 0;
};

// Every typed op but IDX / LDX / STX with every type (pair) it takes, `copies` times.
Program every_op(uint64_t seed, int copies) {
  Builder b(seed);
  for (int c = 0; c < copies; c++)
    for (int o = 0; o < kOpCount; o++) {
      Op op = Op(o);
      if (op_info(op).klass != OpClass::Typed || op == Op::TIDX || op == Op::TLDX || op == Op::TSTX) continue;
      for (int t = 0; t < kTyCount; t++)
        for (int u = 0; u < (op_info(op).typed == 2 ? kTyCount : 1); u++)
          if (op_takes(op, Ty(t), op_info(op).typed == 2 ? Ty(u) : Ty::None) && !typed::is_string_instr(op, Ty(t), Ty(u)))
            b.instr(op, Ty(t), Ty(u));  // STRING: refused by native code (x86gen refuse_strings)
    }
  Program p = b.take();
  p.source = "typed_every_op";
  return p;
}

std::unique_ptr<Engine> interp(const Program& p) {
  BinaryIl bin = encode_il(p);
  std::string why = validate_il(bin.code, p.layout());
  if (!why.empty()) throw std::runtime_error("IL " + why);
  return make_interp_engine(bin.code, p.layout());
}
std::unique_ptr<Engine> native(const Program& p, int opt) {
  NativeBuild nb = build_x86(p, p.source, as::Mode::Blockwise, opt);
  return make_native_engine(map_checked_code(nb.asm_result.code, 0, p.layout()));
}

// The first byte where the images differ, described, or "".
std::string differ(const Program& p, const ImageBytes& ref, const ImageBytes& got) {
  const Layout l = p.layout();
  for (uint32_t i = 0; i < l.size; i++) {
    if (ref[i] == got[i]) continue;
    std::ostringstream s;
    s << "image offset " << i;
    for (int a = 0; a < kAreaCount; a++)
      if (i >= l.offset[a] && i < l.offset[a] + l.count[a] * l.elem_size(Area(a)))
        s << " (" << area_name(Area(a)) << (i - l.offset[a]) / l.elem_size(Area(a)) << ")";
    s << ": interpreter " << int(ref[i]) << ", native " << int(got[i]);
    // the instruction that writes there, if an output
    for (const Rung& r : p.rungs)
      for (const Instr& in : r.code)
        for (int k = 0; k < in.nopd(); k++)
          if ((in.a[k].kind == OpdKind::Int || in.a[k].kind == OpdKind::Real || in.a[k].kind == OpdKind::Bit) &&
              l.addr(in.a[k].area, in.a[k].index) / 8 == i / 8 && k == in.nopd() - 1)
            s << "\n  written by line " << r.line << ": " << instr_text(in);
    return s.str();
  }
  return "";
}

// Runs `scans` scans on the interpreter and on native code at `opt`, the same
// inputs before each; "" or where they first differ.
std::string compare(const Program& p, int opt, int scans, uint64_t seed, double power_on,
                    const std::function<void(ImageBytes&, ImageBytes&, std::mt19937_64&)>& extra = nullptr) {
  const Layout l = p.layout();
  auto ref = interp(p);
  auto nat = native(p, opt);
  ImageBytes a(l.size), b(l.size);
  Inputs in(seed);
  for (int s = 1; s <= scans; s++) {
    in.fill(a, b, l, power_on);
    if (extra) extra(a, b, in.rng());
    ref->scan(a);
    nat->scan(b);
    if (!(a == b)) return "-O" + std::to_string(opt) + ", scan " + std::to_string(s) + ": " + differ(p, a, b);
    if (!b.slack_intact()) return "-O" + std::to_string(opt) + ": native code wrote past the image";
  }
  return "";
}

// compare() at every -O level from `first` on, each its own seed.
void expect_levels(const Program& p, int first, int scans, uint64_t seed, double power_on,
                   const std::function<void(ImageBytes&, ImageBytes&, std::mt19937_64&)>& extra = nullptr) {
  for (int opt = first; opt <= 2; opt++) {
    std::string why = compare(p, opt, scans, seed + uint64_t(opt), power_on, extra);
    EXPECT_TRUE(why.empty()) << why;
  }
}

// Inputs for the held-value tests: each index cell D<d> drawn from 0..below-1,
// and M0..M7 made 0 or 1 (the bit instructions read them too, as bit devices).
std::function<void(ImageBytes&, ImageBytes&, std::mt19937_64&)> index_inputs(const Layout& l,
                                                                            std::vector<std::pair<uint32_t, uint32_t>> cells) {
  return [l, cells](ImageBytes& a, ImageBytes& b, std::mt19937_64& rng) {
    for (auto [d, below] : cells) {
      const int32_t v = int32_t(rng() % below);
      std::memcpy(a.data() + l.addr(Area::D, d), &v, 4);
      std::memcpy(b.data() + l.addr(Area::D, d), &v, 4);
    }
    for (uint32_t m = 0; m < 8; m++) a[l.addr(Area::M, m)] = b[l.addr(Area::M, m)] = a[l.addr(Area::M, m)] != 0;
  };
}

TEST(TypedNative, EveryOpEveryTypeAtTheLimits) {
  Program p = every_op(20261128, 3);
  ASSERT_GT(p.rungs.size(), 800u);
  for (int opt = 0; opt <= 2; opt++) {
    std::string why = compare(p, opt, 150, 7 + opt, 0.8);
    EXPECT_TRUE(why.empty()) << why;
  }
}

// Operands that are the same device, and the power off more often.
TEST(TypedNative, SameOperandsAndPowerOff) {
  Builder b(99);
  for (int o = 0; o < kOpCount; o++) {
    Op op = Op(o);
    if (op_info(op).klass != OpClass::Typed || op == Op::TIDX || op == Op::TLDX || op == Op::TSTX || op_info(op).typed == 2)
      continue;
    for (int t = 0; t < kTyCount; t++) {
      if (!op_takes(op, Ty(t), Ty::None) || typed::is_string_instr(op, Ty(t), Ty::None)) continue;
      Instr in;
      in.op = op, in.ty = Ty(t);
      const Operand same = Ty(t) == Ty::BOOL ? dev(Area::M, 5) : dev(Area::D, 10);
      for (int i = 0; i < op_info(op).nopd; i++) in.a[i] = op_info(op).operands[i] == 'r' ? b.dest(Ty(t)) : same;
      b.rung({in});
    }
  }
  Program p = b.take();
  p.source = "typed_same";
  for (int opt = 0; opt <= 2; opt++) {
    std::string why = compare(p, opt, 40, 3, 0.5);
    EXPECT_TRUE(why.empty()) << why;
  }
}

// Arrays: IDX of every index type, LDX / STX of every element type, strides
// 0 to 3 cells; a scan in four makes one index leave its bounds (the fault
// record, and the scan ends there).
Program arrays(uint64_t seed, std::vector<std::pair<int32_t, int32_t>>& bounds) {
  Builder b(seed);
  std::mt19937_64& rng = b.rng();
  const Ty index_types[] = {Ty::SINT, Ty::INT, Ty::DINT, Ty::LINT, Ty::USINT, Ty::UINT, Ty::UDINT, Ty::ULINT};
  uint32_t slot = 0;
  for (int n = 0; n < int(kSlots); n++) {  // one index slot each
    Ty it = index_types[n % 8];
    Ty et = Ty(rng() % kTyCount);
    if (et == Ty::STRING) et = Ty::DINT;  // no STRING arrays in the typed IL
    int32_t lo = int32_t(rng() % 7) - 3;
    if (!typed::is_signed(it) && lo < 0 && n % 3) lo = 0;
    const int32_t hi = lo + int32_t(rng() % 9);
    bounds.push_back({lo, hi});
    int32_t stride = int32_t(rng() % 4);
    Instr idx;
    idx.op = Op::TIDX, idx.ty = it;
    idx.a[0] = dev(Area::D, 2 * (slot++ % kSlots));
    idx.a[1] = k32(lo), idx.a[2] = k32(hi);
    Instr acc;
    acc.ty = et;
    const bool bits = et == Ty::BOOL;
    const Operand base = bits ? dev(Area::M, 3000 + 40 * uint32_t(n)) : dev(Area::D, 3000 + 40 * uint32_t(n));
    if (n % 2) {
      acc.op = Op::TLDX;
      acc.a[0] = base, acc.a[1] = k32(stride), acc.a[2] = b.dest(et);
    } else {
      acc.op = Op::TSTX;
      acc.a[0] = b.source(et), acc.a[1] = base, acc.a[2] = k32(stride);
    }
    b.rung({idx, acc});
  }
  Program p = b.take();
  p.source = "typed_arrays";
  return p;
}

TEST(TypedNative, ArraysAndIndexFaults) {
  std::vector<std::pair<int32_t, int32_t>> bounds;
  Program p = arrays(5, bounds);
  const Layout l = p.layout();
  // the index slots: inside the bounds, but in one scan of four one of them outside
  auto indices = [&](ImageBytes& a, ImageBytes& b, std::mt19937_64& rng) {
    const size_t bad = rng() % 4 == 0 ? rng() % bounds.size() : SIZE_MAX;
    for (size_t n = 0; n < bounds.size(); n++) {
      auto [lo, hi] = bounds[n];
      int64_t v = lo + int64_t(rng() % uint64_t(hi - lo + 1));
      if (n == bad) {
        static const int64_t kOutside[] = {-1000, -129, 1000, 70000, INT64_MIN, INT64_MAX, -1};
        v = rng() % 2 ? (rng() % 2 ? hi + 1 : lo - 1) : kOutside[rng() % 7];
      }
      if (n % 8 == 7 || n % 8 == 3) {  // LINT / ULINT: also the 64-bit values
        std::memcpy(a.data() + l.addr(Area::D, 2 * uint32_t(n % kSlots)), &v, 8);
        std::memcpy(b.data() + l.addr(Area::D, 2 * uint32_t(n % kSlots)), &v, 8);
      } else {
        uint32_t w = uint32_t(v);
        if (n % 8 == 4) w &= 0xff, w |= rng() % 2 ? 0xab00 : 0;  // USINT reads its low byte: junk above
        std::memcpy(a.data() + l.addr(Area::D, 2 * uint32_t(n % kSlots)), &w, 4);
        std::memcpy(b.data() + l.addr(Area::D, 2 * uint32_t(n % kSlots)), &w, 4);
      }
    }
  };
  for (int opt = 0; opt <= 2; opt++) {
    std::string why = compare(p, opt, 300, 11 + opt, 0.9, indices);
    EXPECT_TRUE(why.empty()) << why;
  }
}

// -O2 drops a typed instruction whose destination holds its result already
// (ir/scanopt.h, kHeld): identical instructions again with power on and off,
// and beside them every write that must keep one (a source or the
// destination written, typed or not, gated or not, an STX that may reach
// it, a jump landing between), IDXs that end one scan in five before or
// between them (the fault record and the words left as the interpreter
// leaves them).  ScanFacts.ATypedResultTheDestinationHoldsNeedsNoCode holds
// which are dropped.
TEST(TypedNative, InstructionsWhoseDestinationHoldsTheResult) {
  Program p = parse_il_text(
      ".rung line 1\nTRUE\nADD.INT D0 D2 D1000\nMUL.LREAL D4 D6 D1002\nCONV.DINT.LREAL D4 D1004\nMIN.LINT D8 D10 D1006\n"
      "DIV.LREAL D4 D6 D1008\nSHL.WORD.INT D12 D14 D1010\nMOVE.BOOL M0 Y5\nDIV.INT D16 D18 D1012\n"
      ".rung line 2\nLOAD M100\nADD.INT D0 D2 D1000\nMUL.LREAL D4 D6 D1002\nMOVE.BOOL M0 Y5\nDIV.INT D16 D18 D1012\n"
      ".rung line 3\nTRUE\nIDX.INT D20 0 3\nSTX.LREAL D4 D1020 2\n"
      ".rung line 4\nTRUE\nCONV.DINT.LREAL D4 D1004\nMIN.LINT D8 D10 D1006\nMOVE.LREAL D1022 D1030\n"
      ".rung line 5\nLOAD M101\nMOVE.LINT D40 D8\nMOV 7 D2\n"
      ".rung line 6\nTRUE\nADD.INT D0 D2 D1000\nMIN.LINT D8 D10 D1006\nDIV.LREAL D4 D6 D1008\nSHL.WORD.INT D12 D14 D1010\n"
      ".rung line 7\nLOAD M102\nJMP L1\n"
      ".rung line 8\nTRUE\nMOVE.INT D0 D1040\n"
      ".rung line 9\nTRUE\nIDX.INT D22 0 3\nSTX.LREAL D6 D1020 2\nMOVE.LREAL D1022 D1030\nADD.INT D0 D2 D1000\n"
      ".label L1\n.rung line 10\nTRUE\nMOVE.INT D0 D1040\nMUL.LREAL D4 D6 D1002\nMOVE.BOOL M0 Y5\n.end\n",
      "held.il");
  p.source = "typed_held";
  const Layout l = p.layout();
  ScanFacts f = scan_facts(p, l, 3);
  ASSERT_GE(f.count(kHeld), 6u) << "the program must hold the case it tests";
  auto indices = [&](ImageBytes& a, ImageBytes& b, std::mt19937_64& rng) {
    for (uint32_t d : {20u, 22u}) {
      const int32_t v = int32_t(rng() % 5);  // 4: outside 0..3, the scan ends there
      std::memcpy(a.data() + l.addr(Area::D, d), &v, 4);
      std::memcpy(b.data() + l.addr(Area::D, d), &v, 4);
    }
  };
  for (int opt = 0; opt <= 2; opt++) {
    std::string why = compare(p, opt, 400, 21 + opt, 0.5, indices);
    EXPECT_TRUE(why.empty()) << why;
  }
}

// -O2 keeps a typed value in the register it was stored from or loaded into
// and reads it from there (docs/x86.md, "Values held in registers").  Random
// rungs of chains over a few cells -- each instruction reading what the ones
// before wrote, in several types over the same bytes -- with everything that
// must end a held value between them: a store of another width over the same
// bytes (a LINT over two DINT cells, an INT into half of it), an indexed STX,
// the bit instructions' OUT / SET / RST / OUTN on a BOOL cell, the bit stack
// writing a slot register, a jump and its label; an indexed BOOL store into
// the bit cells, a call (SIN), a timer (its scratch registers), which also end
// a byte read back from a register (BytesFromRegisters).  The interpreter's
// images are the expected values.
std::string chains_program(uint64_t seed) {
  std::mt19937_64 rng(seed);
  auto pick = [&](std::initializer_list<const char*> l) { return std::string(l.begin()[rng() % l.size()]); };
  auto word = [&] { return "D" + std::to_string(rng() % 12); };  // D0..D11 (a 64-bit type takes D11 and D12)
  auto bit = [&] { return "M" + std::to_string(rng() % 8); };
  auto src = [&](const std::string& t) {
    const bool sgn = t == "INT" || t == "SINT" || t == "DINT" || t == "LINT";
    if (rng() % 6 == 0) return t == "BOOL" ? std::string(rng() % 2 ? "1" : "0") : std::to_string(int(rng() % 100) - (sgn ? 50 : 0));
    return t == "BOOL" ? bit() : word();
  };
  std::ostringstream il;
  il << ".edges 4\n";
  int label = 0;
  std::vector<int> pending;  // labels jumped to, placed at a later rung
  for (int r = 1; r <= 60; r++) {
    if (!pending.empty() && rng() % 2) il << ".label L" << pending.back() << "\n", pending.pop_back();
    il << ".rung line " << r << "\n" << (rng() % 3 ? "TRUE" : "LOAD M" + std::to_string(100 + rng() % 8)) << "\n";
    for (int n = int(3 + rng() % 10); n > 0; n--) {
      const std::string t = pick({"BOOL", "BOOL", "INT", "SINT", "USINT", "UINT", "DINT", "UDINT", "WORD", "BYTE", "LINT", "ULINT"});
      switch (rng() % 12) {
        case 0: il << "MOVE." << t << " " << src(t) << " " << (t == "BOOL" ? bit() : word()) << "\n"; break;
        case 1: case 2: {  // logic on the bit strings, arithmetic on the numbers
          const std::string b = pick({"BOOL", "BYTE", "WORD", "DWORD", "LWORD"});
          if (t == "BOOL" || rng() % 3 == 0)
            il << pick({"AND", "OR", "XOR"}) << "." << b << " " << src(b) << " " << src(b) << " " << (b == "BOOL" ? bit() : word()) << "\n";
          else {
            const std::string n = pick({"INT", "SINT", "USINT", "UINT", "DINT", "UDINT", "LINT", "ULINT"});
            il << pick({"ADD", "SUB", "MUL"}) << "." << n << " " << src(n) << " " << src(n) << " " << word() << "\n";
          }
          break;
        }
        case 3: {
          const std::string b = pick({"BOOL", "BOOL", "BYTE", "WORD", "DWORD", "LWORD"});
          il << "NOT." << b << " " << src(b) << " " << (b == "BOOL" ? bit() : word()) << "\n";
          break;
        }
        case 4:  // a compare onto the bit stack, its result into a BOOL cell by a bit instruction
          il << (t == "BOOL" ? pick({"EQ", "NE"}) : pick({"EQ", "NE", "LT", "GE"})) << "." << t << " " << src(t) << " " << src(t) << "\n"
             << pick({"OUT", "OUT", "SET", "RST", "OUTN"}) << " " << bit() << "\nMPP\n";
          break;
        case 5:  // the bit stack reads a BOOL cell (a held one from its register), writes one
          il << pick({"LOAD", "LOADN"}) << " " << bit() << "\n" << pick({"AND", "OR", "ANDN", "ORN"}) << " " << bit() << "\n"
             << pick({"OUT", "SET", "RST"}) << " " << bit() << "\nMPP\n";
          break;
        case 6:  // an edge (LOADP writes its slot) into a BOOL cell
          il << pick({"LOADP", "LOADF"}) << " " << bit() << " E" << rng() % 4 << "\nOUT " << bit() << "\nMPP\n";
          break;
        case 7:  // an indexed store into the cells (D20 holds 0..9; 9 is outside, the scan ends there)
          il << "IDX.INT D20 0 8\nSTX." << (t == "BOOL" ? "DINT" : t) << " " << word() << " D0 1\n";
          break;
        case 9:  // an indexed store into the bit cells (M0..M7; D20's 8 and 9 are outside: the scan ends there)
          il << "IDX.INT D20 0 7\nSTX.BOOL " << src("BOOL") << " M0 1\n";
          break;
        case 10:  // a call (libm), which may write every scratch register
          il << "SIN.LREAL " << word() << " D14\n";
          break;
        case 11:  // a timer, whose code takes scratch registers (esi, ecx, edx, r10, r11)
          il << "LOAD " << bit() << "\nMTON T" << rng() % 2 << " " << 1 + rng() % 3 << "\nMPP\nMOVE.BOOL T" << rng() % 2 << " " << bit() << "\n";
          break;
        default:
          if (rng() % 2) il << "LOAD M" << 100 + rng() % 8 << "\nJMP L" << label << "\nMPP\n", pending.push_back(label++);
          else {
            const std::string from = pick({"INT", "DINT", "LINT", "BOOL", "USINT", "UDINT", "ULINT"});
            const std::string to = rng() % 3 ? t : pick({"REAL", "LREAL"});  // from UDINT: a 64-bit conversion of a held word
            il << "CONV." << to << "." << from << " " << (from == "BOOL" ? bit() : word()) << " " << (to == "BOOL" ? bit() : word()) << "\n";
          }
          break;
      }
    }
  }
  for (int l : pending) il << ".label L" << l << "\n";
  il << ".rung line 61\nTRUE\n.end\n";
  return il.str();
}

TEST(TypedNative, ChainsThroughHeldRegisters) {
  for (uint64_t seed = 1; seed <= 24; seed++) {
    const std::string text = chains_program(seed);
    Program p = parse_il_text(text, "chains.il");
    p.source = "typed_chains";
    auto index = index_inputs(p.layout(), {{20, 10}});
    for (int opt = 1; opt <= 2; opt++) {
      std::string why = compare(p, opt, 200, 100 * seed + uint64_t(opt), 0.7, index);
      EXPECT_TRUE(why.empty()) << "seed " << seed << ": " << why << "\n" << text;
    }
  }
}

// Each way a held value ends, in a rung of its own (the random chains above
// meet them too, but rarely in the order that tells): a jump over the store
// (the typed run's power test, its label), an indexed store over the cell,
// a wider store over part of it, a bit instruction that changes the slot
// register holding it (ANDN's seta), one that writes the cell (SET, RST), an
// indexed store of a held LINT over its own upper half; and an IDX taken again
// from r11 ends when its index cell is written (then 9, outside: the scan ends
// at the second IDX) or r11 is (MTON's scratch).
TEST(TypedNative, HeldValuesEndWhereTheyMust) {
  Program p = parse_il_text(
      ".rung line 1\nLOAD M100\nMOVE.INT D0 D1\nTRUE\nADD.INT D1 1 D30\nMPP\nMPP\n"
      ".rung line 2\nLOAD M0\nOUT M5\nIDX.INT D20 0 8\nSTX.BOOL M6 M1 1\nMOVE.BOOL M5 M7\nMPP\n"
      ".rung line 3\nTRUE\nMOVE.DINT D6 D7\nMOVE.LINT D8 D6\nADD.DINT D7 1 D32\nMOVE.INT D9 D7\nADD.DINT D7 0 D33\n"
      ".rung line 4\nLOAD M0\nOUT M5\nANDN M6\nTRUE\nMOVE.BOOL M5 M7\nMPP\nOUT M11\nMPP\n"
      ".rung line 6\nTRUE\nIDX.INT D20 0 8\nSTX.LINT D4 D0 1\nADD.LINT D4 1 D34\n"
      ".rung line 7\nTRUE\nIDX.INT D20 0 8\nLDX.DINT D0 1 D35\nMOVE.INT D21 D20\nIDX.INT D20 0 8\nLDX.DINT D0 1 D36\n"
      "LOAD M2\nMTON T1 D22\nMPP\nIDX.INT D20 0 8\nLDX.DINT D0 1 D37\nIDX.INT D20 0 8\nLDX.DINT D0 1 D38\n"
      ".rung line 5\nTRUE\nMOVE.BOOL M1 M8\nLOAD M2\nSET M8\nMPP\nMOVE.BOOL M8 M9\nLOAD M3\nRST M8\nMPP\nMOVE.BOOL M8 M10\n"
      // r10 = r11 * 12 kept for the next element of that stride, not another's,
      // nor after r11 is written (an IDX of a changed cell) or a call
      ".rung line 8\nTRUE\nIDX.INT D20 0 8\nLDX.DINT D40 3 D39\nIDX.INT D20 0 8\nLDX.DINT D41 3 D50\n"
      "IDX.INT D20 0 8\nLDX.DINT D42 5 D56\nMOVE.INT D21 D20\nIDX.INT D20 0 8\nLDX.DINT D40 3 D51\n"
      "LOAD M2\nMTON T2 D22\nMPP\nIDX.INT D20 0 8\nLDX.DINT D42 3 D52\nIDX.INT D21 0 9\nLDX.DINT D40 3 D53\n"
      ".end\n",
      "held_ends.il");
  p.source = "held_ends";
  expect_levels(p, 0, 300, 31, 0.5, index_inputs(p.layout(), {{20, 9}, {21, 10}}));  // 9 is outside 0..8: the scan ends there
}

// The store cuts a narrow result to its type unless the operation cannot
// leave it: a constant shift left (cut), right (of a zero-extended value: not
// cut), an AND with a constant of the type (not cut), OR / XOR of the raw cell
// (cut).  D0 holds random 64-bit cells, not canonical for these types.
TEST(TypedNative, NarrowResultsCutWhereTheyMayOverflow) {
  Program p = parse_il_text(
      ".rung line 1\nTRUE\nSHL.WORD.INT D0 1 D1000\nSHL.BYTE.INT D0 3 D1001\nSHR.WORD.INT D0 1 D1002\n"
      "SHR.BYTE.DINT D0 2 D1003\nAND.WORD D0 65535 D1004\nAND.WORD D0 255 D1005\nAND.BYTE D0 127 D1006\n"
      "OR.WORD D0 1 D1007\nXOR.BYTE D0 255 D1008\nSHL.WORD.INT D0 15 D1009\n.end\n",
      "narrow_cut.il");
  p.source = "narrow_cut";
  expect_levels(p, 0, 200, 41, 1.0);
}

// The sum of count(instruction) over the code of p at -O`opt`.
template <class Count>
size_t count_in_code(const Program& p, int opt, Count count) {
  X86Code code = generate_x86(p, p.layout(), opt, /*notes=*/false);
  size_t n = 0;
  for (const auto& b : code.program.blocks)
    for (const auto& it : b.items)
      if (it.kind == as::ItemKind::Instruction) n += count(it.inst);
  return n;
}

// The registers are read: in the -O2 code of a chain of BOOL temporaries no
// byte is loaded back from memory (M100, whose register eax took D4 for the
// next compare, is read from a spare register: BytesFromRegisters); -O1 loads
// every one.
size_t byte_loads(const Program& p, int opt) {
  return count_in_code(p, opt, [](const as::x86::Instruction& in) {
    size_t n = 0;
    for (unsigned k = 0; k < in.num_operands; k++) {
      const as::x86::Operand& o = in.ops[k];
      const bool read = k > 0 || in.mnemonic == as::x86::Mnemonic::Cmp || in.mnemonic == as::x86::Mnemonic::Test;
      if (o.kind == as::x86::OperandKind::Mem && o.mem.size == as::x86::Size::Byte && read) n++;
    }
    return n;
  });
}

// Stores to memory in the -O2 code of p (an operand the form writes whole).
size_t memory_stores(const Program& p) {
  return count_in_code(p, 2, [](const as::x86::Instruction& in) {
    return size_t(in.num_operands > 0 && in.ops[0].kind == as::x86::OperandKind::Mem &&
                  as::x86::effects(in).ops[0] == as::x86::Use::W);
  });
}

// -O2 drops a store that the same straight line writes over before anything
// may read it (DeadStores, docs/x86.md "Stores nothing reads"): a chain of
// three results into D10 stores once.  Each rung after the first tempts it
// where the store must stay, and the image after every scan is compared
// with the interpreter's: a read of the cell between the two stores (rung 2),
// a read of a wider operand that overlaps it at another address (3), a second
// store that covers only half of the first (4), a jump that skips the second
// store (5); rung 6, a timer whose preset is the cell, reads it from a
// register.  Rung 7: a label between the stores does not keep the first
// (every path from it reaches the second).  A call or any use of the stack
// between the two also keeps the first store (a routine may read any cell):
// no rung here makes such a call.
TEST(TypedNative, StoresDroppedOnlyWhereNothingReadsThem) {
  Program chain = parse_il_text(
      ".rung line 1\nTRUE\nMUL.LREAL D0 0.5 D10\nMUL.LREAL D10 0.25 D10\nADD.LREAL D10 1.0 D10\n.end\n", "chain.il");
  EXPECT_EQ(memory_stores(chain), 1u);
  Program p = parse_il_text(
      ".rung line 1\nTRUE\nMUL.LREAL D0 0.5 D10\nMUL.LREAL D10 0.25 D10\nADD.LREAL D10 1.0 D10\n"
      ".rung line 2\nTRUE\nADD.DINT D1 1 D2\nMOVE.DINT D5 D6\nADD.DINT D7 D2 D8\nMOVE.DINT D9 D2\n"
      ".rung line 3\nTRUE\nADD.DINT D11 1 D12\nMOVE.LINT D11 D30\nMOVE.DINT D9 D12\n"
      ".rung line 4\nTRUE\nMOVE.LINT D40 D14\nMOVE.DINT D16 D14\nADD.DINT D15 0 D17\n"
      ".rung line 5\nTRUE\nADD.DINT D18 1 D19\nLOAD M0\nJMP over\nMPP\nMOVE.DINT D5 D19\n"
      ".label over\n.rung line 6\nTRUE\nADD.DINT D20 3 D22\nLOAD M2\nMTON T1 D22\nMPP\nMOVE.DINT D5 D22\n"
      ".rung line 7\nLOAD M3\nADD.DINT D23 1 D24\nMPP\nTRUE\nMOVE.DINT D5 D24\n"
      ".end\n",
      "dead_stores.il");
  p.source = "dead_stores";
  // D20, rung 6's input, kept small (a preset that times out now and then); M0..M7 made bits
  expect_levels(p, 0, 300, 61, 0.5, index_inputs(p.layout(), {{20, 40}}));
}

// Memory operands read in the -O2 code of p (loads and read operands alike).
size_t memory_reads(const Program& p) {
  return count_in_code(p, 2, [](const as::x86::Instruction& in) {
    const as::x86::Effects e = as::x86::effects(in);
    size_t n = 0;
    for (unsigned k = 0; k < in.num_operands; k++)
      if (in.ops[k].kind == as::x86::OperandKind::Mem && as::x86::reads_operand(e.ops[k])) n++;
    return n;
  });
}

// An operation whose second operand is the result xmm0 holds (stored by the
// instruction before) reads it from xmm0 by way of xmm1, in the operands'
// order (WordInEax, docs/x86.md "a word kept in eax"): SUB and DIV give
// other values swapped, MIN and MAX of a NaN and of signed zeros (the
// random cells hold NaNs and zeros of both signs) another.  The operands
// read from memory: D2, D0 / D4, D6 / D8, D9 and D20 (MAX's first, which
// xmm0 no longer holds) / D30, D32; never the result just stored.  Rungs 5
// and 6: an LDX's element, held in a general register, is the second operand
// (`movd xmm1, eax` / `movq xmm1, rax`): their reads are the index, the
// element and the first operand, 3 each (Gen::real_src).
TEST(TypedNative, SecondOperandHeldInXmm0KeepsItsPlace) {
  Program p = parse_il_text(
      ".rung line 1\nTRUE\nMUL.LREAL D2 0.5 D10\nSUB.LREAL D0 D10 D12\n"
      ".rung line 2\nTRUE\nMUL.LREAL D4 -0.0 D14\nMIN.LREAL D6 D14 D16\n"
      ".rung line 3\nTRUE\nADD.REAL D8 0.0 D20\nDIV.REAL D9 D20 D21\nMAX.REAL D20 D21 D22\n"
      ".rung line 4\nTRUE\nSUB.LREAL D30 0.5 D34\nMAX.LREAL D32 D34 D36\n"
      ".rung line 5\nTRUE\nIDX.INT D60 0 3\nLDX.REAL D40 1 D50\nSUB.REAL D51 D50 D52\n"
      ".rung line 6\nTRUE\nIDX.INT D60 0 3\nLDX.LREAL D42 2 D54\nDIV.LREAL D56 D54 D58\n.end\n",
      "second_xmm0.il");
  p.source = "second_xmm0";
  EXPECT_EQ(memory_reads(p), 15u);
  expect_levels(p, 0, 300, 71, 1.0, index_inputs(p.layout(), {{60, 4}}));
}

TEST(TypedNative, HeldBoolsAreNotLoadedBack) {
  Program p = parse_il_text(
      ".rung line 1\nTRUE\nEQ.DINT D4 2\nOUT M99\nMPP\nMOVE.BOOL M99 M100\nEQ.DINT D4 3\nOUT M101\nMPP\n"
      "MOVE.BOOL M101 M102\nOR.BOOL M100 M102 M5\nLOADN M5\nOUT Y0\nMPP\n.end\n",
      "held_bools.il");
  p.source = "held_bools";
  EXPECT_EQ(byte_loads(p, 2), 0u);
  EXPECT_GE(byte_loads(p, 1), 5u);
  expect_levels(p, 0, 100, 5, 0.7);
}

// REAL and LREAL constants used more than once live in xmm8..xmm15 at -O2
// (RealConsts, docs/x86.md "Constants in registers"): every use reads the
// register, which must hold its constant after a call into the C library
// (SIN, EXPT, which may write every xmm register), at a label a JMP skips to,
// and in the rounding of CONV to an integer (0.5 and the sign bit).  The
// interpreter's values are ir/typed.h's.
TEST(TypedNative, ConstantsInRegistersSurviveCallsAndJumps) {
  Program p = parse_il_text(
      ".rung line 1\nTRUE\nMUL.LREAL D0 0.0125 D1000\nADD.LREAL D2 2.5 D1002\nGT.LREAL D4 2.5\nOUT Y0\nMPP\n"
      "MUL.REAL D6 1.5 D1004\nCONV.INT.LREAL D8 D1005\nCONV.UDINT.LREAL D10 D1006\n"
      "SIN.LREAL D12 D1008\nMUL.LREAL D1008 0.0125 D1010\nSUB.REAL D1004 1.5 D1012\nCONV.DINT.LREAL D14 D1013\n"
      "EXPT.LREAL D16 D18 D1014\nLT.LREAL 2.5 D1014\nOUT Y1\nMPP\nMAX.LREAL D20 0.0125 D1016\n"
      "LOAD M100\nJMP skip\n"
      ".rung line 2\nTRUE\nSIN.LREAL D22 D1018\n"
      ".label skip\n.rung line 3\nTRUE\nDIV.LREAL D24 2.5 D1020\nCONV.LINT.LREAL D26 D1022\nADD.REAL D28 1.5 D1024\n"
      "MIN.LREAL 0.0125 D30 D1026\nCONV.SINT.LREAL D32 D1028\n.end\n",
      "consts.il");
  p.source = "consts";
  X86Code code = generate_x86(p, p.layout(), 2, /*notes=*/false);
  size_t reads = 0;
  for (const auto& b : code.program.blocks)
    for (const auto& it : b.items)
      if (it.kind == as::ItemKind::Instruction)
        for (unsigned k = 1; k < it.inst.num_operands; k++)
          if (it.inst.ops[k].kind == as::x86::OperandKind::Reg && it.inst.ops[k].reg.cls == as::x86::RegClass::Xmm &&
              it.inst.ops[k].reg.num >= 8)
            reads++;
  EXPECT_GE(reads, 15u);  // the constants' uses, and CONV's 0.5 and sign bit
  expect_levels(p, 0, 300, 11, 0.5);
}

// Hand-written: the examples of docs/il.md run to the same images, and an IDX
// fault's record names the IDX's IL offset (encode_il's instr_offset).
TEST(TypedNative, FaultRecordNamesTheIdx) {
  Program p = parse_il_text(
      ".rung line 1\nTRUE\nMOVE.INT 32767 D0\nADD.INT D0 1 D1\nCONV.INT.REAL 2.5 D4\n"
      ".rung line 2\nTRUE\nIDX.INT D9 1 10\nLDX.INT D20 1 D16\n"
      ".rung line 3\nTRUE\nMOVE.DINT 7 D30\n.end\n",
      "fault.il");
  const Layout l = p.layout();
  BinaryIl bin = encode_il(p);
  for (int opt = 0; opt <= 2; opt++) {
    auto nat = native(p, opt);
    ImageBytes m(l.size);
    int32_t idx = 11;  // outside 1..10
    std::memcpy(m.data() + l.addr(Area::D, 9), &idx, 4);
    nat->scan(m);
    auto word = [&](uint32_t at) { int32_t v; std::memcpy(&v, m.data() + at, 4); return v; };
    EXPECT_EQ(word(l.addr(Area::D, 1)), -32768) << "32767 + 1 wraps at 16 bits";
    EXPECT_EQ(word(l.addr(Area::D, 4)), 2) << "2.5 rounds to even";
    EXPECT_EQ(word(kSysFault), int32_t(kFaultIndex));
    EXPECT_EQ(uint32_t(word(kSysFaultAt)), bin.instr_offset[5]) << "the IDX is the program's sixth instruction";
    int64_t v;
    std::memcpy(&v, m.data() + kSysFaultValue, 8);
    EXPECT_EQ(v, 11);
    EXPECT_EQ(word(l.addr(Area::D, 30)), 0) << "the scan ended at the IDX";
  }
}

}  // namespace

namespace {

// An LDX that the IL's validator accepts right after an IDX of the rung
// before: native code keeps the index in a register within a rung, so it
// refuses the program by name instead of reading another element.
TEST(TypedNative, LdxInTheRungAfterItsIdxIsRefusedByName) {
  Program p = parse_il_text(".rung line 1\nTRUE\nIDX.INT D9 1 10\n.rung line 2\nLDX.INT D20 1 D16\n.end\n", "split.il");
  BinaryIl bin = encode_il(p);
  EXPECT_EQ(validate_il(bin.code, p.layout()), "");
  try {
    build_x86(p, p.source, as::Mode::Blockwise, 0);
    ADD_FAILURE() << "compiled";
  } catch (const CompileError& e) {
    EXPECT_EQ(e.line, 5);  // the LDX's line in the text
    EXPECT_NE(std::string(e.what()).find("LDX.INT must follow its IDX in the same rung"), std::string::npos) << e.what();
  }
}

}  // namespace
