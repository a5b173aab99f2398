// tests/backend-c40sim/gen/c40model.cpp -- the C40 semantic model and its precision check
// (c40model.h).  Operand decoding and the INT32, bit, timer and counter rules
// follow ir/interp.cpp (docs/il.md); REAL goes through c40gen.h's functions.
#include "tests/backend-c40sim/gen/c40model.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>

#include "backend-c40sim/gen/c40gen.h"
#include "backend-c40sim/machine/mathrom.h"

namespace ldc::c40gen {

uint32_t CheckReport::ulps_for(Op op) {
  return op_info(op).klass == OpClass::Special && rom_of(op_info(op).fn) != RomFn::Count ? kUlpsRom : kUlpsArith;
}

uint64_t CheckReport::total_checked() const {
  uint64_t n = 0;
  for (uint64_t v : checked) n += v;
  return n;
}
uint64_t CheckReport::total_outside() const {
  uint64_t n = 0;
  for (uint64_t v : outside) n += v;
  return n;
}
uint64_t CheckReport::total_rounding() const {
  uint64_t n = 0;
  for (uint64_t v : rounding) n += v;
  return n;
}

uint32_t ulp_distance(float a, float b) {
  if (a == b) return 0;
  auto key = [](float f) {  // monotone integer order of the finite floats
    int32_t i;
    std::memcpy(&i, &f, 4);
    return i < 0 ? int64_t(INT32_MIN) - int64_t(i) : int64_t(i);
  };
  int64_t d = key(a) - key(b);
  d = d < 0 ? -d : d;
  return d > UINT32_MAX ? UINT32_MAX : uint32_t(d);
}

namespace {

namespace fp = c40sim::fp;
constexpr int32_t kMin = std::numeric_limits<int32_t>::min();
constexpr int32_t kMax = std::numeric_limits<int32_t>::max();

float to_float(uint32_t u) {
  float f;
  std::memcpy(&f, &u, 4);
  return f;
}
uint32_t to_bits(float f) {
  uint32_t u;
  std::memcpy(&u, &f, 4);
  return u;
}
bool in_format(float f) { return f == 0.0f || std::isnormal(f); }
bool exact_float(int32_t i) { return double(float(i)) == double(i); }

struct Val {
  uint8_t* addr = nullptr;  // nullptr for constants
  bool real = false;
  int32_t i = 0;
  uint32_t bits = 0;  // REAL: the IEEE word
  uint32_t index = 0;
  float f() const { return to_float(bits); }
  float ieee() const { return real ? f() : int_to_real(i); }
  Ext c40() const { return real ? real_from_ieee(bits) : real_from_int(i); }
};

uint32_t rd16(const uint8_t* p) { return p[0] | (p[1] << 8); }
uint32_t rd32(const uint8_t* p) { return p[0] | (p[1] << 8) | (p[2] << 16) | (uint32_t(p[3]) << 24); }

enum class Fmt : uint8_t { In, Outside, Rounding };

class Run {
 public:
  Run(const std::vector<uint8_t>& il, const Layout& L, uint8_t* mem, C40Model::Mode mode, CheckReport& rep,
      uint64_t scan)
      : code_(il.data()), size_(uint32_t(il.size())), L_(L), mem_(mem), check_(mode == C40Model::Mode::Check),
        rep_(rep), scan_(scan) {}
  void run();

 private:
  const uint8_t* code_;
  uint32_t size_;
  uint32_t pc_ = 0, at_ = 0;  // at_: offset of the instruction being run
  const Layout& L_;
  uint8_t* mem_;
  bool check_;
  CheckReport& rep_;
  uint64_t scan_;
  uint32_t stack_ = 0;
  bool end_ = false;
  Op op_{};

  Val operand() {
    Val v;
    uint8_t tag = code_[pc_];
    switch (tag) {
      case 1: v.i = int32_t(rd32(code_ + pc_ + 1)); pc_ += 5; return v;
      case 2: v.bits = rd32(code_ + pc_ + 1); v.real = true; pc_ += 5; return v;
      case 3: case 4: v.index = rd32(code_ + pc_ + 1); pc_ += 5; return v;
      default: {
        Area a = Area(tag - 0x10);
        v.index = rd16(code_ + pc_ + 1);
        v.addr = mem_ + L_.addr(a, v.index);
        v.real = area_is_real(a);
        if (area_is_word(a)) {
          if (v.real) std::memcpy(&v.bits, v.addr, 4);
          else std::memcpy(&v.i, v.addr, 4);
        }
        pc_ += 3;
        return v;
      }
    }
  }
  void skip(int n) { for (int k = 0; k < n; k++) operand(); }
  bool top() const { return stack_ & 1; }
  void push(bool b) { stack_ = (stack_ << 1) | (b ? 1u : 0u); }
  bool bit(const Val& v) const { return *v.addr != 0; }
  void set_error() { mem_[L_.addr(Area::S, kBitError)] = 1; }
  int32_t dt() const { int32_t d; std::memcpy(&d, mem_ + kSysDt, 4); return d; }

  void put_int(const Val& d, int32_t x) { std::memcpy(d.addr, &x, 4); }
  void put_bits(const Val& d, uint32_t x) { std::memcpy(d.addr, &x, 4); }

  void violation(const std::string& what) {
    rep_.violations++;
    if (rep_.first_violations.size() < 10) {
      char buf[160];
      std::snprintf(buf, sizeof buf, "scan %llu, IL offset %u, %s: ", (unsigned long long)scan_, at_,
                    op_info(op_).name);
      rep_.first_violations.push_back(buf + what);
    }
  }
  Fmt inputs(std::initializer_list<const Val*> vs) const {
    Fmt r = Fmt::In;
    for (const Val* v : vs) {
      if (v->real) {
        if (!in_format(v->f())) return Fmt::Outside;
      } else if (!exact_float(v->i)) {
        r = Fmt::Rounding;
      }
    }
    return r;
  }
  bool count(Fmt f) {
    if (f == Fmt::Outside) rep_.outside[int(op_)]++;
    else if (f == Fmt::Rounding) rep_.rounding[int(op_)]++;
    else rep_.checked[int(op_)]++;
    return f == Fmt::In;
  }

  // A REAL result: `ieee` as the reference computes it, `c` as the C40 does.
  void store_real(const Val& d, float ieee, Ext c, Fmt fmt) {
    if (!check_) {
      if (d.real) put_bits(d, real_to_ieee(c));
      else put_int(d, real_to_int32(c));
      return;
    }
    if (fmt == Fmt::In && !in_format(ieee)) fmt = Fmt::Outside;
    if (count(fmt)) {
      uint32_t k = CheckReport::ulps_for(op_);
      float cf = to_float(real_to_ieee(c));
      uint32_t u = ulp_distance(ieee, cf);
      if (u > rep_.max_ulps[int(op_)]) rep_.max_ulps[int(op_)] = u;
      char buf[160];
      if (u > k) {
        std::snprintf(buf, sizeof buf, "REAL %.9g, C40 %.9g: %u ulps (bound %u)", double(ieee), double(cf), u, k);
        violation(buf);
      }
      if (!d.real) {
        // the C40 truncates its 40-bit value: within k + 1 ulps of the IEEE one
        float lo = ieee, hi = ieee;
        for (uint32_t s = 0; s <= k; s++) {
          lo = std::nextafter(lo, -INFINITY);
          hi = std::nextafter(hi, INFINITY);
        }
        int32_t ci = real_to_int32(c), a = real_to_int(lo), b = real_to_int(hi);
        if (ci < std::min(a, b) || ci > std::max(a, b)) {
          std::snprintf(buf, sizeof buf, "INT32 %d from REAL %.9g, C40 %d", real_to_int(ieee), double(ieee), ci);
          violation(buf);
        }
      }
    }
    if (d.real) put_bits(d, to_bits(ieee));
    else put_int(d, real_to_int(ieee));
  }
  // An INT32 result, converted to REAL for an F destination.
  void store_int(const Val& d, int32_t x) {
    if (!d.real) return put_int(d, x);
    store_real(d, int_to_real(x), real_from_int(x), Fmt::In);
  }

  void compare(Rel rel) {
    Val a = operand(), b = operand();
    if (!a.real && !b.real) return push(rel_holds(rel, a.i, b.i));
    bool c = rel_holds(rel, real_compare(a.c40(), b.c40()), 0);
    if (!check_) return push(c);
    bool r = rel_holds(rel, a.ieee(), b.ieee());
    if (count(inputs({&a, &b})) && r != c) violation(std::string("compare: REAL ") + (r ? "true" : "false"));
    push(r);
  }

  void arith();
  void divmod();
  void special();
  void timer();
  void counter();
};

int32_t wrap(uint32_t u) { return int32_t(u); }
int32_t advance(int32_t et, int32_t dt, int32_t pt) {
  if (et >= pt) return pt;
  int64_t s = int64_t(et) + int64_t(dt);
  return s > pt ? pt : int32_t(s);
}

void Run::arith() {
  if (!top()) return skip(3);
  Val a = operand(), b = operand(), d = operand();
  if (a.real || b.real) {
    float x = a.ieee(), y = b.ieee();
    Ext cx = a.c40(), cy = b.c40();
    Fmt fmt = inputs({&a, &b});
    switch (op_) {
      case Op::ADD: return store_real(d, x + y, real_add(cx, cy), fmt);
      case Op::SUB: return store_real(d, x - y, real_sub(cx, cy), fmt);
      default: return store_real(d, x * y, real_mul(cx, cy), fmt);
    }
  }
  switch (op_) {
    case Op::ADD: return store_int(d, wrap(uint32_t(a.i) + uint32_t(b.i)));
    case Op::SUB: return store_int(d, wrap(uint32_t(a.i) - uint32_t(b.i)));
    default: return store_int(d, wrap(uint32_t(a.i) * uint32_t(b.i)));
  }
}

void Run::divmod() {
  if (!top()) return skip(3);
  Val a = operand(), b = operand(), d = operand();
  if (op_ == Op::DIV && (a.real || b.real)) {
    float x = a.ieee(), y = b.ieee();
    Ext cx = a.c40(), cy = b.c40();
    bool czero = fp::is_zero(cy), rzero = y == 0.0f;
    if (!check_) {
      if (czero) return set_error();
      return store_real(d, 0, real_div(cx, cy), Fmt::In);
    }
    Fmt fmt = inputs({&a, &b});
    if (fmt == Fmt::In && czero != rzero) violation("division by zero test differs");
    if (rzero) {
      count(fmt);
      return set_error();
    }
    return store_real(d, x / y, czero ? fp::kZero : real_div(cx, cy), fmt);
  }
  if (b.i == 0) return set_error();
  if (op_ == Op::DIV) store_int(d, (a.i == kMin && b.i == -1) ? kMin : a.i / b.i);
  else store_int(d, b.i == -1 ? 0 : a.i % b.i);
}

void Run::special() {
  if (!top()) return skip(2);
  Val a = operand(), d = operand();
  if (op_ == Op::ABS) {
    if (!a.real) return store_int(d, a.i == kMin ? kMin : (a.i < 0 ? -a.i : a.i));
    if (d.real) return put_bits(d, a.bits & 0x7FFFFFFFu);  // fabsf, exact on both
    return store_real(d, std::fabs(a.f()), fp::abs(a.c40()).v, inputs({&a}));
  }
  RomFn fn = rom_of(op_info(op_).fn);
  store_real(d, rom_host(fn, a.ieee()), rom_result(fn, a.c40()), inputs({&a}));
}

void Run::timer() {
  Val tv = operand();
  uint32_t n = tv.index;
  uint8_t* et = mem_ + L_.addr(Area::TW, n);
  uint8_t* q = mem_ + L_.addr(Area::TQ, n);
  uint8_t* ti = mem_ + L_.addr(Area::TI, n);
  auto get_et = [&] { int32_t v; std::memcpy(&v, et, 4); return v; };
  auto set_et = [&](int32_t v) { std::memcpy(et, &v, 4); };
  if (op_ == Op::RSTT) {
    if (!top()) return;
    set_et(0);
    *q = 0;
    *ti = 0;
    return;
  }
  Val p = operand();
  int32_t pt = p.i < 0 ? 0 : p.i;
  bool in = top();
  if (op_ == Op::TON) {
    if (in) {
      int32_t e = *ti ? advance(get_et(), dt(), pt) : 0;
      set_et(e);
      *q = e >= pt;
    } else {
      set_et(0);
      *q = 0;
    }
  } else if (op_ == Op::TOF) {
    if (in) {
      *q = 1;
      set_et(0);
    } else if (*ti) {
      set_et(0);
      *q = pt > 0;
    } else if (*q) {
      int32_t e = advance(get_et(), dt(), pt);
      set_et(e);
      *q = e < pt;
    }
  } else if (op_ == Op::TP) {
    if (*q) {
      int32_t e = advance(get_et(), dt(), pt);
      set_et(e);
      if (e >= pt) *q = 0;
    } else if (in && !*ti) {
      *q = pt > 0;
      set_et(0);
    } else if (!in) {
      set_et(0);
    }
  } else if (op_ == Op::MTON) {
    if (!in || !*ti) {
      set_et(0);
      *q = 0;
    } else if (!*q) {
      int32_t e = advance(get_et(), dt(), pt);
      set_et(e);
      *q = e >= pt;
    }
  } else if (op_ == Op::MTOF) {
    if (in || *ti) {
      *q = 1;
      set_et(0);
    } else if (*q) {
      int32_t e = advance(get_et(), dt(), pt);
      set_et(e);
      *q = e < pt;
    }
  } else {  // MTP
    if (*q) {
      int32_t e = advance(get_et(), dt(), pt);
      set_et(e);
      if (e >= pt) *q = 0;
    } else if (in && !*ti) {
      *q = 1;
      set_et(0);
    }
    if (!*q && !in) set_et(0);
  }
  *ti = in;
}

void Run::counter() {
  uint32_t n = operand().index;
  uint8_t* cvp = mem_ + L_.addr(Area::CW, n);
  uint8_t* cq = mem_ + L_.addr(Area::CQ, n);
  if (op_ == Op::RSTC) {
    if (!top()) return;
    std::memset(cvp, 0, 4);
    *cq = 0;
    return;
  }
  int32_t pv = operand().i;
  uint8_t* e = mem_ + L_.addr(Area::E, operand().index);
  int32_t cv;
  std::memcpy(&cv, cvp, 4);
  bool in = top();
  if (in && !*e) {
    if (op_ == Op::CTU && cv != kMax) cv++;
    if (op_ == Op::CTD && cv != kMin) cv--;
  }
  std::memcpy(cvp, &cv, 4);
  *cq = op_ == Op::CTU ? cv >= pv : cv <= 0;
  *e = in;
}

void Run::run() {
  while (pc_ < size_ && !end_) {
    at_ = pc_;
    op_ = Op(code_[pc_++]);
    switch (op_) {
      case Op::LOAD: push(bit(operand())); break;
      case Op::LOADN: push(!bit(operand())); break;
      case Op::AND: if (!bit(operand())) stack_ &= ~1u; break;
      case Op::ANDN: if (bit(operand())) stack_ &= ~1u; break;
      case Op::OR: if (bit(operand())) stack_ |= 1u; break;
      case Op::ORN: if (!bit(operand())) stack_ |= 1u; break;
      case Op::LOADP: case Op::LOADF: {
        bool b = bit(operand());
        uint8_t* e = mem_ + L_.addr(Area::E, operand().index);
        push(op_ == Op::LOADP ? b && !*e : !b && *e);
        *e = b;
        break;
      }
      case Op::TRUE: push(true); break;
      case Op::ANDBLK: { uint32_t a = stack_ & 1; stack_ >>= 1; stack_ &= ~1u | a; break; }
      case Op::ORBLK: { uint32_t a = stack_ & 1; stack_ >>= 1; stack_ |= a; break; }
      case Op::MPS: push(top()); break;
      case Op::MRD: stack_ = (stack_ & ~1u) | ((stack_ >> 1) & 1u); break;
      case Op::MPP: stack_ >>= 1; break;
      case Op::OUT: *operand().addr = top(); break;
      case Op::OUTN: *operand().addr = !top(); break;
      case Op::SET: { Val w = operand(); if (top()) *w.addr = 1; break; }
      case Op::RST: { Val w = operand(); if (top()) *w.addr = 0; break; }
      case Op::LDEQ: case Op::LDNE: case Op::LDLT: case Op::LDLE: case Op::LDGT: case Op::LDGE:
        compare(op_info(op_).rel);
        break;
      case Op::MOV: {
        if (!top()) { skip(2); break; }
        Val a = operand(), d = operand();
        if (a.real == d.real) {
          if (a.real) put_bits(d, a.bits);
          else put_int(d, a.i);
        } else if (a.real) {
          store_real(d, a.f(), a.c40(), inputs({&a}));
        } else {
          store_int(d, a.i);
        }
        break;
      }
      case Op::ADD: case Op::SUB: case Op::MUL: arith(); break;
      case Op::DIV: case Op::MOD: divmod(); break;
      case Op::WAND: case Op::WOR: case Op::WXOR: case Op::SHL: case Op::SHR: {
        if (!top()) { skip(3); break; }
        Val a = operand(), b = operand(), d = operand();
        int32_t x = a.i, y = b.i, r;
        if (op_ == Op::WAND) r = x & y;
        else if (op_ == Op::WOR) r = x | y;
        else if (op_ == Op::WXOR) r = x ^ y;
        else if (y < 0 || y > 31) r = 0;
        else r = op_ == Op::SHL ? wrap(uint32_t(x) << y) : wrap(uint32_t(x) >> y);
        store_int(d, r);
        break;
      }
      case Op::WNOT: {
        if (!top()) { skip(2); break; }
        Val a = operand(), d = operand();
        store_int(d, ~a.i);
        break;
      }
      case Op::SIN: case Op::COS: case Op::TAN: case Op::SQRT: case Op::EXP: case Op::LN: case Op::ABS:
        special();
        break;
      case Op::TON: case Op::TOF: case Op::TP: case Op::RSTT: case Op::MTON: case Op::MTOF: case Op::MTP: timer(); break;
      case Op::CTU: case Op::CTD: case Op::RSTC: counter(); break;
      case Op::JMP: { uint32_t t = operand().index; if (top()) pc_ = t; break; }
      case Op::END: if (top()) end_ = true; break;
      case Op::Count: break;
      default:  // the typed instructions: this model checks the untyped code generator only (tests/typed checks them)
        std::fprintf(stderr, "c40model: %s is not modelled\n", op_info(op_).name);
        std::abort();
    }
  }
}

}  // namespace

C40Model::C40Model(std::span<const uint8_t> il, const Layout& layout, Mode mode)
    : il_(il.begin(), il.end()), layout_(layout), mode_(mode) {}

void C40Model::scan(uint8_t* mem) {
  Run r(il_, layout_, mem, mode_, report_, ++scans_);
  r.run();
}

}  // namespace ldc::c40gen
