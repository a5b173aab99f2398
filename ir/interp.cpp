// ir/interp.cpp -- the reference interpreter: the meaning of every mnemonic.
//
// Written the way a classic PLC runs its intermediate code (paper 003, Fig. 3):
// fetch a mnemonic, dispatch to its routine through a table, and decode every
// operand with one general routine.  It is the baseline native code is measured
// against, so it is straightforward, not slowed on purpose.
#include <cmath>
#include <cstring>
#include <limits>

#include "ir/ir.h"
#include "ir/typed.h"

namespace ldc {
namespace {

constexpr int32_t kMin = std::numeric_limits<int32_t>::min();
constexpr int32_t kMax = std::numeric_limits<int32_t>::max();

struct Ctx {
  const uint8_t* code;
  uint32_t size;
  uint32_t pc;
  uint8_t* mem;
  const Layout* L;
  uint32_t stack;  // the bit stack: top = bit 0
  bool end;
  uint32_t xr = 0;   // the index register: set by IDX, used by the LDX / STX right after it
  typed::StrArgs args;  // the string-argument registers: set by ARGS, used by the MID .. REPLACE right after it
  uint32_t start = 0;  // the offset of the instruction being run
};

// A decoded operand: where it lives, or its constant value.
struct Val {
  uint8_t* addr;  // nullptr for constants
  bool real;
  int32_t i;
  float f;
  uint32_t index;  // device, timer, counter, edge slot or label target
};

uint32_t rd16(const uint8_t* p) { return p[0] | (p[1] << 8); }
uint32_t rd32(const uint8_t* p) { return p[0] | (p[1] << 8) | (p[2] << 16) | (uint32_t(p[3]) << 24); }

// The general operand decoding routine (tags: docs/il.md, "Binary form").
Val operand(Ctx& c) {
  Val v{};
  uint8_t tag = c.code[c.pc];
  switch (tag) {
    case 1: v.i = int32_t(rd32(c.code + c.pc + 1)); c.pc += 5; return v;
    case 2: { uint32_t u = rd32(c.code + c.pc + 1); std::memcpy(&v.f, &u, 4); v.real = true; c.pc += 5; return v; }
    case 3: case 4: v.index = rd32(c.code + c.pc + 1); c.pc += 5; return v;
    default: {
      Area a = Area(tag - 0x10);
      v.index = rd16(c.code + c.pc + 1);
      v.addr = c.mem + c.L->addr(a, v.index);
      v.real = area_is_real(a);
      if (area_is_word(a)) {
        if (v.real) std::memcpy(&v.f, v.addr, 4);
        else std::memcpy(&v.i, v.addr, 4);
      }
      c.pc += 3;
      return v;
    }
  }
}

bool top(const Ctx& c) { return c.stack & 1; }
void push(Ctx& c, bool b) { c.stack = (c.stack << 1) | (b ? 1u : 0u); }
uint32_t pop(Ctx& c) { uint32_t t = c.stack & 1; c.stack >>= 1; return t; }
bool bit(const Val& v) { return *v.addr != 0; }
float as_real(const Val& v) { return v.real ? v.f : int_to_real(v.i); }
int32_t dt(const Ctx& c) { int32_t d; std::memcpy(&d, c.mem + kSysDt, 4); return d; }
int32_t preset(const Val& v) { return v.i < 0 ? 0 : v.i; }
void set_error(Ctx& c) { c.mem[c.L->addr(Area::S, kBitError)] = 1; }

void store_int(const Val& d, int32_t x) {
  if (d.real) { float f = int_to_real(x); std::memcpy(d.addr, &f, 4); }
  else std::memcpy(d.addr, &x, 4);
}
void store_real(const Val& d, float x) {
  if (d.real) std::memcpy(d.addr, &x, 4);
  else { int32_t i = real_to_int(x); std::memcpy(d.addr, &i, 4); }
}
void skip_operands(Ctx& c, int n) { for (int k = 0; k < n; k++) operand(c); }

// ---- bit logic
void exec_LOAD(Ctx& c) { push(c, bit(operand(c))); }
void exec_LOADN(Ctx& c) { push(c, !bit(operand(c))); }
void exec_AND(Ctx& c) { if (!bit(operand(c))) c.stack &= ~1u; }
void exec_ANDN(Ctx& c) { if (bit(operand(c))) c.stack &= ~1u; }
void exec_OR(Ctx& c) { if (bit(operand(c))) c.stack |= 1u; }
void exec_ORN(Ctx& c) { if (!bit(operand(c))) c.stack |= 1u; }
void exec_LOADP(Ctx& c) {
  bool b = bit(operand(c));
  uint8_t* e = c.mem + c.L->addr(Area::E, operand(c).index);
  push(c, b && !*e);
  *e = b;
}
void exec_LOADF(Ctx& c) {
  bool b = bit(operand(c));
  uint8_t* e = c.mem + c.L->addr(Area::E, operand(c).index);
  push(c, !b && *e);
  *e = b;
}
void exec_TRUE(Ctx& c) { push(c, true); }
void exec_ANDBLK(Ctx& c) { uint32_t a = pop(c); c.stack &= ~1u | a; }
void exec_ORBLK(Ctx& c) { uint32_t a = pop(c); c.stack |= a; }
void exec_MPS(Ctx& c) { push(c, top(c)); }
void exec_MRD(Ctx& c) { c.stack = (c.stack & ~1u) | ((c.stack >> 1) & 1u); }
void exec_MPP(Ctx& c) { pop(c); }
void exec_OUT(Ctx& c) { *operand(c).addr = top(c); }
void exec_OUTN(Ctx& c) { *operand(c).addr = !top(c); }
void exec_SET(Ctx& c) { Val w = operand(c); if (top(c)) *w.addr = 1; }
void exec_RST(Ctx& c) { Val w = operand(c); if (top(c)) *w.addr = 0; }

// ---- compares: the relation of ops.def's rel column
template <Rel r>
void exec_compare(Ctx& c) {
  Val a = operand(c), b = operand(c);
  if (a.real || b.real) push(c, rel_holds(r, as_real(a), as_real(b)));
  else push(c, rel_holds(r, a.i, b.i));
}

// ---- application instructions (only when top is 1)
void exec_MOV(Ctx& c) {
  if (!top(c)) return skip_operands(c, 2);
  Val a = operand(c), d = operand(c);
  if (a.real) store_real(d, a.f); else store_int(d, a.i);
}
template <typename IntOp, typename RealOp>
void arith(Ctx& c, IntOp iop, RealOp rop) {
  if (!top(c)) return skip_operands(c, 3);
  Val a = operand(c), b = operand(c), d = operand(c);
  if (a.real || b.real) store_real(d, rop(as_real(a), as_real(b)));
  else store_int(d, iop(a.i, b.i));
}
int32_t wrap(uint32_t u) { return int32_t(u); }
void exec_ADD(Ctx& c) { arith(c, [](int32_t x, int32_t y) { return wrap(uint32_t(x) + uint32_t(y)); }, typed::real_add<float>); }
void exec_SUB(Ctx& c) { arith(c, [](int32_t x, int32_t y) { return wrap(uint32_t(x) - uint32_t(y)); }, typed::real_sub<float>); }
void exec_MUL(Ctx& c) { arith(c, [](int32_t x, int32_t y) { return wrap(uint32_t(x) * uint32_t(y)); }, typed::real_mul<float>); }
void exec_DIV(Ctx& c) {
  if (!top(c)) return skip_operands(c, 3);
  Val a = operand(c), b = operand(c), d = operand(c);
  if (a.real || b.real) {
    float y = as_real(b);
    if (y == 0.0f) return set_error(c);
    store_real(d, typed::real_div(as_real(a), y));  // a NaN: typed::nan_rule (docs/il.md)
  } else {
    if (b.i == 0) return set_error(c);
    store_int(d, (a.i == kMin && b.i == -1) ? kMin : a.i / b.i);
  }
}
void exec_MOD(Ctx& c) {
  if (!top(c)) return skip_operands(c, 3);
  Val a = operand(c), b = operand(c), d = operand(c);
  if (b.i == 0) return set_error(c);
  store_int(d, b.i == -1 ? 0 : a.i % b.i);
}
template <typename IntOp>
void logic(Ctx& c, IntOp iop) {
  if (!top(c)) return skip_operands(c, 3);
  Val a = operand(c), b = operand(c), d = operand(c);
  store_int(d, iop(a.i, b.i));
}
void exec_WAND(Ctx& c) { logic(c, [](int32_t x, int32_t y) { return x & y; }); }
void exec_WOR(Ctx& c) { logic(c, [](int32_t x, int32_t y) { return x | y; }); }
void exec_WXOR(Ctx& c) { logic(c, [](int32_t x, int32_t y) { return x ^ y; }); }
void exec_SHL(Ctx& c) { logic(c, [](int32_t x, int32_t n) { return n < 0 || n > 31 ? 0 : wrap(uint32_t(x) << n); }); }
void exec_SHR(Ctx& c) { logic(c, [](int32_t x, int32_t n) { return n < 0 || n > 31 ? 0 : wrap(uint32_t(x) >> n); }); }
void exec_WNOT(Ctx& c) {
  if (!top(c)) return skip_operands(c, 2);
  Val a = operand(c), d = operand(c);
  store_int(d, ~a.i);
}
// SIN ... ABS: the REAL function of ops.def's fn column
template <RealFn f>
void exec_special(Ctx& c) {
  if (!top(c)) return skip_operands(c, 2);
  Val a = operand(c), d = operand(c);
  if (real_fn_info(f).ints && !a.real) store_int(d, a.i == kMin ? kMin : (a.i < 0 ? -a.i : a.i));
  else store_real(d, apply_real_fn(f, as_real(a)));
}

// ---- timers: state of timer n = ET (TW), Q (TQ), IN memory (TI)
struct Timer {
  uint8_t* et;
  uint8_t* q;
  uint8_t* in_mem;
  int32_t get_et() const { int32_t v; std::memcpy(&v, et, 4); return v; }
  void set_et(int32_t v) const { std::memcpy(et, &v, 4); }
};
Timer timer(Ctx& c, uint32_t n) {
  return {c.mem + c.L->addr(Area::TW, n), c.mem + c.L->addr(Area::TQ, n), c.mem + c.L->addr(Area::TI, n)};
}
int32_t advance(int32_t et, int32_t dt, int32_t pt) {  // et >= pt ? pt : min(et + dt, pt), exactly
  if (et >= pt) return pt;
  int64_t s = int64_t(et) + int64_t(dt);
  return s > pt ? pt : int32_t(s);
}
void exec_TON(Ctx& c) {
  Timer t = timer(c, operand(c).index);
  int32_t pt = preset(operand(c));
  bool in = top(c);
  if (in) {
    int32_t et = t.get_et();
    if (!*t.in_mem) et = 0;
    else et = advance(et, dt(c), pt);
    t.set_et(et);
    *t.q = et >= pt;
  } else {
    t.set_et(0);
    *t.q = 0;
  }
  *t.in_mem = in;
}
void exec_TOF(Ctx& c) {
  Timer t = timer(c, operand(c).index);
  int32_t pt = preset(operand(c));
  bool in = top(c);
  if (in) {
    *t.q = 1;
    t.set_et(0);
  } else if (*t.in_mem) {
    t.set_et(0);
    *t.q = pt > 0;
  } else if (*t.q) {
    int32_t et = advance(t.get_et(), dt(c), pt);
    t.set_et(et);
    *t.q = et < pt;
  }
  *t.in_mem = in;
}
void exec_TP(Ctx& c) {
  Timer t = timer(c, operand(c).index);
  int32_t pt = preset(operand(c));
  bool in = top(c);
  if (*t.q) {
    int32_t et = advance(t.get_et(), dt(c), pt);
    t.set_et(et);
    if (et >= pt) *t.q = 0;
  } else if (in && !*t.in_mem) {
    *t.q = pt > 0;
    t.set_et(0);
  } else if (!in) {
    t.set_et(0);
  }
  *t.in_mem = in;
}
// MatIEC's timers (docs/il.md, "MatIEC timers"): the same state, different rules.
void exec_MTON(Ctx& c) {
  Timer t = timer(c, operand(c).index);
  int32_t pt = preset(operand(c));
  bool in = top(c);
  if (!in || !*t.in_mem) {  // off, or the rising scan: timing starts
    t.set_et(0);
    *t.q = 0;
  } else if (!*t.q) {
    int32_t et = advance(t.get_et(), dt(c), pt);
    t.set_et(et);
    *t.q = et >= pt;
  }
  *t.in_mem = in;
}
void exec_MTOF(Ctx& c) {
  Timer t = timer(c, operand(c).index);
  int32_t pt = preset(operand(c));
  bool in = top(c);
  if (in || *t.in_mem) {
    *t.q = 1;
    t.set_et(0);
  } else if (*t.q) {
    int32_t et = advance(t.get_et(), dt(c), pt);
    t.set_et(et);
    *t.q = et < pt;
  }
  *t.in_mem = in;
}
void exec_MTP(Ctx& c) {
  Timer t = timer(c, operand(c).index);
  int32_t pt = preset(operand(c));
  bool in = top(c);
  if (*t.q) {
    int32_t et = advance(t.get_et(), dt(c), pt);
    t.set_et(et);
    if (et >= pt) *t.q = 0;
  } else if (in && !*t.in_mem) {
    *t.q = 1;
    t.set_et(0);
  }
  if (!*t.q && !in) t.set_et(0);
  *t.in_mem = in;
}
void exec_RSTT(Ctx& c) {
  Timer t = timer(c, operand(c).index);
  if (!top(c)) return;
  t.set_et(0);
  *t.q = 0;
  *t.in_mem = 0;
}

// ---- counters
template <bool Up>
void count(Ctx& c) {
  uint32_t n = operand(c).index;
  int32_t pv = operand(c).i;
  uint8_t* e = c.mem + c.L->addr(Area::E, operand(c).index);
  uint8_t* cvp = c.mem + c.L->addr(Area::CW, n);
  int32_t cv;
  std::memcpy(&cv, cvp, 4);
  bool in = top(c);
  if (in && !*e) {
    if (Up && cv != kMax) cv++;
    if (!Up && cv != kMin) cv--;
  }
  std::memcpy(cvp, &cv, 4);
  c.mem[c.L->addr(Area::CQ, n)] = Up ? cv >= pv : cv <= 0;
  *e = in;
}
void exec_CTU(Ctx& c) { count<true>(c); }
void exec_CTD(Ctx& c) { count<false>(c); }
void exec_RSTC(Ctx& c) {
  uint32_t n = operand(c).index;
  if (!top(c)) return;
  std::memset(c.mem + c.L->addr(Area::CW, n), 0, 4);
  c.mem[c.L->addr(Area::CQ, n)] = 0;
}

// ---- flow
void exec_JMP(Ctx& c) {
  uint32_t target = operand(c).index;
  if (top(c)) c.pc = target;
}
void exec_END(Ctx& c) { if (top(c)) c.end = true; }
void exec_LOOP(Ctx& c) {
  uint32_t target = operand(c).index;
  if (!top(c)) return;
  uint32_t n;
  std::memcpy(&n, c.mem + kSysLoops, 4);
  std::memcpy(c.mem + kSysLoops, &++n, 4);  // counted first: at the fault it holds the budget
  if (n < kLoopBudget) {
    c.pc = target;
    return;
  }
  write_scan_fault(c.mem, kFaultLoop, c.start, kLoopBudget);
  c.end = true;
}


// ---- typed instructions (ir/typed.h defines each)
struct TOpd {
  uint8_t* addr = nullptr;  // a device's bytes; nullptr for a constant
  Area area = Area::Sys;
  uint32_t index = 0;
  uint64_t v = 0;           // the value (of a device: loaded in the operand's type)
};
TOpd toperand(Ctx& c, Ty t) {
  TOpd o;
  uint8_t tag = c.code[c.pc];
  if (tag == 5) { o.v = rd32(c.code + c.pc + 1) | (uint64_t(rd32(c.code + c.pc + 5)) << 32); c.pc += 9; return o; }
  if (tag == 1) { o.v = uint64_t(int64_t(int32_t(rd32(c.code + c.pc + 1)))); c.pc += 5; return o; }
  o.area = Area(tag - 0x10);
  o.index = rd16(c.code + c.pc + 1);
  o.addr = c.mem + c.L->addr(o.area, o.index);
  if (t != Ty::None) o.v = typed::load(t, o.addr);
  c.pc += 3;
  return o;
}
void skip_typed(Ctx& c, int n) {
  for (int k = 0; k < n; k++) {
    uint8_t tag = c.code[c.pc];
    c.pc += tag == 5 ? 9 : tag == 1 ? 5 : 3;
  }
}
template <Op op>
void exec_typed(Ctx& c) {
  constexpr const OpInfo& oi = kOps[int(op)];
  const Ty t = Ty(c.code[c.pc++]);
  const Ty u = oi.typed == 2 ? Ty(c.code[c.pc++]) : Ty::None;
  if (t == Ty::STRING && oi.push == 1) {
    uint8_t* a = toperand(c, Ty::None).addr;
    uint8_t* b = toperand(c, Ty::None).addr;
    return push(c, typed::str_compare(oi.rel, typed::str_load(a), typed::str_load(b)));
  }
  if constexpr (oi.push == 1) {
    uint64_t a = toperand(c, t).v, b = toperand(c, t).v;
    return push(c, typed::compare(oi.rel, t, a, b));
  }
  if (!top(c)) return skip_typed(c, oi.nopd);
  if (typed::is_string_instr(op, t, u)) {
    uint8_t* o[3] = {};
    uint64_t k[3] = {};
    for (int i = 0; i < oi.nopd; i++) {
      TOpd d = toperand(c, Ty::None);
      o[i] = d.addr, k[i] = d.v;
    }
    if (typed::str_exec(op, t, u, o, k, c.args)) set_error(c);
    return;
  }
  if constexpr (op == Op::TIDX) {
    uint64_t i = toperand(c, t).v;
    int32_t lo = int32_t(toperand(c, Ty::None).v), hi = int32_t(toperand(c, Ty::None).v);
    if (typed::index_ok(t, i, lo, hi)) { c.xr = uint32_t(int64_t(i) - lo); return; }
    write_scan_fault(c.mem, kFaultIndex, c.start, i);
    c.end = true;
  } else if constexpr (op == Op::TLDX) {
    TOpd base = toperand(c, Ty::None);
    uint32_t stride = uint32_t(toperand(c, Ty::None).v);
    TOpd d = toperand(c, Ty::None);
    uint64_t v = typed::load(t, c.mem + c.L->addr(base.area, base.index + c.xr * stride));
    typed::store(t, d.addr, v);
  } else if constexpr (op == Op::TSTX) {
    uint64_t v = toperand(c, t).v;
    TOpd base = toperand(c, Ty::None);
    uint32_t stride = uint32_t(toperand(c, Ty::None).v);
    typed::store(t, c.mem + c.L->addr(base.area, base.index + c.xr * stride), v);
  } else if constexpr (oi.nopd == 2) {  // MOVE, NOT, the functions, CONV, TRUNC
    uint64_t a = toperand(c, u != Ty::None ? u : t).v;
    TOpd d = toperand(c, Ty::None);
    uint64_t r = op == Op::TMOVE ? a
               : op == Op::TNOT ? typed::logic(op, t, a, 0)
               : op == Op::TCONV ? typed::conv(t, u, a)
               : op == Op::TTRUNC ? typed::trunc(t, u, a)
               : typed::unary(op, t, a);
    typed::store(t, d.addr, r);
  } else {  // the two-operand ones
    uint64_t a = toperand(c, t).v, b = toperand(c, u != Ty::None ? u : t).v;
    TOpd d = toperand(c, Ty::None);
    bool error = false;
    uint64_t r = (op == Op::TAND || op == Op::TOR || op == Op::TXOR) ? typed::logic(op, t, a, b)
               : (op == Op::TSHL || op == Op::TSHR || op == Op::TROL || op == Op::TROR) ? typed::shift(op, t, a, u, b)
               : typed::arith(op, t, a, b, error);
    if (error) set_error(c);
    typed::store(t, d.addr, r);
  }
}

// The dispatch table, in ops.def order: a compare's routine is its relation's,
// a REAL function's its function's, every other mnemonic has its own.
using Routine = void (*)(Ctx&);
#define ROUTINE_Compare(name, rel, fn) exec_compare<Rel::rel>
#define ROUTINE_Special(name, rel, fn) exec_special<RealFn::fn>
#define ROUTINE_OWN(name, rel, fn) exec_##name
#define ROUTINE_Basic ROUTINE_OWN
#define ROUTINE_Move ROUTINE_OWN
#define ROUTINE_Arith ROUTINE_OWN
#define ROUTINE_Logic ROUTINE_OWN
#define ROUTINE_Timer ROUTINE_OWN
#define ROUTINE_Counter ROUTINE_OWN
#define ROUTINE_Flow ROUTINE_OWN
#define ROUTINE_Typed(name, rel, fn) exec_typed<Op::name>
const Routine kRoutines[kOpCount] = {
#define OP(name, opds, push, pop, klass, rel, fn, typed, types) ROUTINE_##klass(name, rel, fn),
#include "ir/ops.def"
};

}  // namespace

Interpreter::Interpreter(std::span<const uint8_t> code, const Layout& layout) : code_(code), layout_(layout) {
  Instr in;
  for (uint32_t off = 0; off < code.size() && !loops_; off = decode_instr(code, off, in)) loops_ = Op(code[off]) == Op::LOOP;
}

void Interpreter::scan(uint8_t* mem) const {
  Ctx c{code_.data(), uint32_t(code_.size()), 0, mem, &layout_, 0, false};
  if (loops_) std::memset(mem + kSysLoops, 0, 4);  // no loop taken yet
  while (c.pc < c.size && !c.end) {
    c.start = c.pc;
    uint8_t op = c.code[c.pc++];
    kRoutines[op](c);
  }
}

}  // namespace ldc
