// runtime/fastinterp.cpp -- the fast interpreter (fastinterp.h): pre-decoded,
// type-specialized handlers, threaded dispatch.  The meaning of every handler is
// the reference interpreter's (ir/interp.cpp, docs/il.md), instruction by
// instruction; only the decoding moved from run time to load time.
#include "runtime/fastinterp.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <optional>
#include <stdexcept>
#include <utility>

#include "ir/typed.h"

#if defined(__GNUC__) && !defined(LDC_FASTINTERP_SWITCH)
#define LDC_FAST_GOTO 1
#else
#define LDC_FAST_GOTO 0
#endif

namespace ldc {
namespace {

constexpr int32_t kMin = std::numeric_limits<int32_t>::min();
constexpr int32_t kMax = std::numeric_limits<int32_t>::max();

// Value operand kinds (2 bits): where the 32-bit field points or what it holds.
enum : unsigned { kIntMem = 0, kRealMem = 1, kIntConst = 2, kRealConst = 3 };
// Destination kinds (1 bit).
enum : unsigned { kDstInt = 0, kDstReal = 1 };

// The handlers.  _MM: two INT32 words; _MK: a word and a constant; _KM: a
// constant and a word (destination an INT32 word).  _F: REAL words; _FF, _FK:
// compares of two REAL words, of a REAL word and a REAL constant.
#define LDC_INT3(X, N) X(N##_MM) X(N##_MK) X(N##_KM)
#define LDC_FAST_OPS(X)                                                                                  \
  X(HALT) X(LD) X(LDN) X(AND) X(ANDN) X(OR) X(ORN) X(LDP) X(LDF) X(TRUE) X(PUSH0) X(ANDB) X(ORB)        \
  X(MPS) X(MRD) X(MPP) X(OUT) X(OUTN) X(SET) X(RST)                                                     \
  X(EQ_MM) X(NE_MM) X(LT_MM) X(LE_MM) X(GT_MM) X(GE_MM)                                                 \
  X(EQ_MK) X(NE_MK) X(LT_MK) X(LE_MK) X(GT_MK) X(GE_MK)                                                 \
  X(EQ_FF) X(NE_FF) X(LT_FF) X(LE_FF) X(GT_FF) X(GE_FF)                                                 \
  X(EQ_FK) X(NE_FK) X(LT_FK) X(LE_FK) X(GT_FK) X(GE_FK) X(CMP_F)                                        \
  X(MOVK) X(MOV32) X(MOVI2F) X(MOVF2I)                                                                  \
  LDC_INT3(X, ADD) LDC_INT3(X, SUB) LDC_INT3(X, MUL) LDC_INT3(X, DIV) LDC_INT3(X, MOD)                  \
  LDC_INT3(X, WAND) LDC_INT3(X, WOR) LDC_INT3(X, WXOR) LDC_INT3(X, SHL) LDC_INT3(X, SHR)                \
  X(ADD_F) X(SUB_F) X(MUL_F) X(DIV_F) X(WNOT_M)                                                         \
  X(SIN_F) X(COS_F) X(TAN_F) X(EXP_F) X(LN_F) X(SQRT_F) X(ABS_F) X(GEN)                                 \
  X(TON_K) X(TON_M) X(TOF_K) X(TOF_M) X(TP_K) X(TP_M) X(RSTT)                                           \
  X(MTON_K) X(MTON_M) X(MTOF_K) X(MTOF_M) X(MTP_K) X(MTP_M)                                             \
  X(CTU_K) X(CTU_M) X(CTD_K) X(CTD_M) X(RSTC) X(JMP) X(END) X(LOOP)                                           \
  LDC_TYPED_OPS(X)

// The typed handlers (docs/il.md, "Typed instructions").  A move class says how
// a value goes from cell to cell: B a bit device; S8 U8 S16 U16 one cell, its
// low 8 / 16 bits sign- or zero-extended; W32 one cell as it is (DINT UDINT
// DWORD REAL); W64 two cells.  TGEN / TGCMP: any other typed instruction,
// through a routine of its op (TypedGeneric).  Arithmetic of INT (S16), of the
// one-cell 32-bit integers (W32) and of the 64-bit ones (W64), REAL (F32) and
// LREAL (F64): _MM, _MK, _KM as above (a 64-bit constant's field is its index in
// the constant pool).  Compares: signed 16, 32, 64 bits and the REALs, _MM and _MK.
#define LDC_MCLASSES(X, N) X(N##_B) X(N##_S8) X(N##_U8) X(N##_S16) X(N##_U16) X(N##_W32) X(N##_W64)
#define LDC_TARITH(X, C) LDC_INT3(X, TADD_##C) LDC_INT3(X, TSUB_##C) LDC_INT3(X, TMUL_##C)
#define LDC_TCMP1(X, C, F) X(TEQ_##C##_##F) X(TNE_##C##_##F) X(TLT_##C##_##F) X(TLE_##C##_##F) X(TGT_##C##_##F) X(TGE_##C##_##F)
#define LDC_TCMP(X, C) LDC_TCMP1(X, C, MM) LDC_TCMP1(X, C, MK)
#define LDC_TYPED_OPS(X)                                                                                 \
  X(TGEN) X(TGCMP) X(TMOVK32) X(TMOVK64) X(TMOVKB)                                                       \
  LDC_MCLASSES(X, TMOV) LDC_MCLASSES(X, TLDX) LDC_MCLASSES(X, TSTX) X(TIDX_S16) X(TIDX_S32)              \
  LDC_TARITH(X, S16) LDC_TARITH(X, W32) LDC_TARITH(X, W64)                                               \
  LDC_TARITH(X, F32) LDC_INT3(X, TDIV_F32) LDC_TARITH(X, F64) LDC_INT3(X, TDIV_F64)                      \
  LDC_TCMP(X, S16) LDC_TCMP(X, S32) LDC_TCMP(X, S64) LDC_TCMP(X, F32) LDC_TCMP(X, F64)

enum FOp : uint16_t {
#define LDC_ENUM(n) F_##n,
  LDC_FAST_OPS(LDC_ENUM)
#undef LDC_ENUM
  F_Count
};

// The compare handlers of each operand form run in the order of ops.def's REL
// table (F_EQ_MM + Rel), the REAL function handlers in that of its FN table
// (F_SIN_F + RealFn).
constexpr bool follows_rel_order(FOp eq, FOp ne, FOp lt, FOp le, FOp gt, FOp ge) {
  return ne == eq + int(Rel::Ne) && lt == eq + int(Rel::Lt) && le == eq + int(Rel::Le) && gt == eq + int(Rel::Gt) &&
         ge == eq + int(Rel::Ge) && eq + int(Rel::Eq) == eq;
}
static_assert(follows_rel_order(F_EQ_MM, F_NE_MM, F_LT_MM, F_LE_MM, F_GT_MM, F_GE_MM));
static_assert(follows_rel_order(F_EQ_MK, F_NE_MK, F_LT_MK, F_LE_MK, F_GT_MK, F_GE_MK));
static_assert(follows_rel_order(F_EQ_FF, F_NE_FF, F_LT_FF, F_LE_FF, F_GT_FF, F_GE_FF));
static_assert(follows_rel_order(F_EQ_FK, F_NE_FK, F_LT_FK, F_LE_FK, F_GT_FK, F_GE_FK));
static_assert(F_COS_F == F_SIN_F + int(RealFn::Cos) && F_TAN_F == F_SIN_F + int(RealFn::Tan) &&
              F_EXP_F == F_SIN_F + int(RealFn::Exp) && F_LN_F == F_SIN_F + int(RealFn::Ln) &&
              F_SQRT_F == F_SIN_F + int(RealFn::Sqrt) && F_ABS_F == F_SIN_F + int(RealFn::Abs) &&
              F_SIN_F + int(RealFn::Sin) == F_SIN_F);

inline int32_t ld_i(const uint8_t* m, uint32_t off) { int32_t v; std::memcpy(&v, m + off, 4); return v; }
inline float ld_f(const uint8_t* m, uint32_t off) { float v; std::memcpy(&v, m + off, 4); return v; }
inline void st_i(uint8_t* m, uint32_t off, int32_t v) { std::memcpy(m + off, &v, 4); }
inline void st_f(uint8_t* m, uint32_t off, float v) { std::memcpy(m + off, &v, 4); }
inline float bits_f(uint32_t u) { float f; std::memcpy(&f, &u, 4); return f; }
inline uint32_t f_bits(float f) { uint32_t u; std::memcpy(&u, &f, 4); return u; }

// A value operand as REAL / as INT32, as the reference's as_real / Val::i
// (Val::i of a REAL operand is 0; valid IL never asks for it).
inline float get_f(const uint8_t* m, unsigned k, uint32_t v) {
  switch (k) {
    case kIntMem: return int_to_real(ld_i(m, v));
    case kRealMem: return ld_f(m, v);
    case kIntConst: return int_to_real(int32_t(v));
    default: return bits_f(v);
  }
}
inline int32_t get_i(const uint8_t* m, unsigned k, uint32_t v) {
  return k == kIntMem ? ld_i(m, v) : k == kIntConst ? int32_t(v) : 0;
}
inline void store_int(uint8_t* m, unsigned dk, uint32_t off, int32_t x) {
  if (dk == kDstReal) st_f(m, off, int_to_real(x));
  else st_i(m, off, x);
}
inline void store_real(uint8_t* m, unsigned dk, uint32_t off, float x) {
  if (dk == kDstReal) st_f(m, off, x);
  else st_i(m, off, real_to_int(x));
}

inline int32_t i_add(int32_t x, int32_t y) { return int32_t(uint32_t(x) + uint32_t(y)); }
inline int32_t i_sub(int32_t x, int32_t y) { return int32_t(uint32_t(x) - uint32_t(y)); }
inline int32_t i_mul(int32_t x, int32_t y) { return int32_t(uint32_t(x) * uint32_t(y)); }
inline int32_t i_shl(int32_t x, int32_t n) { return n < 0 || n > 31 ? 0 : int32_t(uint32_t(x) << n); }
inline int32_t i_shr(int32_t x, int32_t n) { return n < 0 || n > 31 ? 0 : int32_t(uint32_t(x) >> n); }
inline int32_t i_div(int32_t x, int32_t y) { return (x == kMin && y == -1) ? kMin : x / y; }
inline int32_t i_mod(int32_t x, int32_t y) { return y == -1 ? 0 : x % y; }
inline int32_t i_abs(int32_t x) { return x == kMin ? kMin : (x < 0 ? -x : x); }

inline int32_t advance(int32_t et, int32_t dt, int32_t pt) {  // as the reference interpreter
  if (et >= pt) return pt;
  int64_t s = int64_t(et) + int64_t(dt);
  return s > pt ? pt : int32_t(s);
}
inline int32_t dt_of(const uint8_t* m) { return ld_i(m, kSysDt); }

// The application instructions without a specialized handler: any operand
// kinds.  x = IL opcode | ka << 8 | kb << 10 | kd << 12; a and b the sources,
// c the destination.  Called with power on.
__attribute__((noinline)) void generic(uint8_t* m, const FastInterpreter::Ins& in, uint32_t s0) {
  Op op = Op(in.x & 0xff);
  unsigned ka = (in.x >> 8) & 3, kb = (in.x >> 10) & 3, kd = (in.x >> 12) & 1;
  bool real = (ka | kb) & 1;
  switch (op) {
    case Op::MOV:
      if (ka & 1) store_real(m, kd, in.c, get_f(m, ka, in.a));
      else store_int(m, kd, in.c, get_i(m, ka, in.a));
      return;
    case Op::ADD: case Op::SUB: case Op::MUL:
      if (real) {
        float x = get_f(m, ka, in.a), y = get_f(m, kb, in.b);
        store_real(m, kd, in.c, op == Op::ADD ? typed::real_add(x, y) : op == Op::SUB ? typed::real_sub(x, y) : typed::real_mul(x, y));
      } else {
        int32_t x = get_i(m, ka, in.a), y = get_i(m, kb, in.b);
        store_int(m, kd, in.c, op == Op::ADD ? i_add(x, y) : op == Op::SUB ? i_sub(x, y) : i_mul(x, y));
      }
      return;
    case Op::DIV:
      if (real) {
        float y = get_f(m, kb, in.b);
        if (y == 0.0f) { m[s0] = 1; return; }
        store_real(m, kd, in.c, typed::real_div(get_f(m, ka, in.a), y));
      } else {
        int32_t y = get_i(m, kb, in.b);
        if (y == 0) { m[s0] = 1; return; }
        store_int(m, kd, in.c, i_div(get_i(m, ka, in.a), y));
      }
      return;
    case Op::MOD: {
      int32_t y = get_i(m, kb, in.b);
      if (y == 0) { m[s0] = 1; return; }
      store_int(m, kd, in.c, i_mod(get_i(m, ka, in.a), y));
      return;
    }
    case Op::WAND: case Op::WOR: case Op::WXOR: case Op::SHL: case Op::SHR: {
      int32_t x = get_i(m, ka, in.a), y = get_i(m, kb, in.b);
      int32_t r = op == Op::WAND ? x & y : op == Op::WOR ? x | y : op == Op::WXOR ? x ^ y
                : op == Op::SHL ? i_shl(x, y) : i_shr(x, y);
      store_int(m, kd, in.c, r);
      return;
    }
    case Op::WNOT: store_int(m, kd, in.c, ~get_i(m, ka, in.a)); return;
    case Op::SIN: case Op::COS: case Op::TAN: case Op::SQRT: case Op::EXP: case Op::LN: case Op::ABS: {
      const RealFn fn = op_info(op).fn;
      if (real_fn_info(fn).ints && !(ka & 1)) store_int(m, kd, in.c, i_abs(get_i(m, ka, in.a)));
      else store_real(m, kd, in.c, apply_real_fn(fn, get_f(m, ka, in.a)));
      return;
    }
    default: break;
  }
}

// A REAL compare: x = ka | kb << 2 | Rel << 4.
__attribute__((noinline)) bool compare_real(const uint8_t* m, const FastInterpreter::Ins& in) {
  float x = get_f(m, in.x & 3, in.a), y = get_f(m, (in.x >> 2) & 3, in.b);
  return rel_holds(Rel(in.x >> 4), x, y);
}


// ---- typed instructions (ir/typed.h defines each)
inline uint32_t ld_u(const uint8_t* m, uint32_t off) { uint32_t v; std::memcpy(&v, m + off, 4); return v; }
inline uint64_t ld_u64(const uint8_t* m, uint32_t off) { uint64_t v; std::memcpy(&v, m + off, 8); return v; }
inline double ld_d(const uint8_t* m, uint32_t off) { double v; std::memcpy(&v, m + off, 8); return v; }
inline void st_u(uint8_t* m, uint32_t off, uint32_t v) { std::memcpy(m + off, &v, 4); }
inline void st_u64(uint8_t* m, uint32_t off, uint64_t v) { std::memcpy(m + off, &v, 8); }
inline void st_d(uint8_t* m, uint32_t off, double v) { std::memcpy(m + off, &v, 8); }
inline double bits_d(uint64_t u) { double d; std::memcpy(&d, &u, 8); return d; }
// A cell's 32 bits made canonical for a one-cell move class (typed::load, then
// the 32 bits typed::store writes).
inline uint32_t n_S8(uint32_t v) { return uint32_t(int32_t(int8_t(uint8_t(v)))); }
inline uint32_t n_U8(uint32_t v) { return v & 0xffu; }
inline uint32_t n_S16(uint32_t v) { return uint32_t(int32_t(int16_t(uint16_t(v)))); }
inline uint32_t n_U16(uint32_t v) { return v & 0xffffu; }
inline uint32_t n_W32(uint32_t v) { return v; }
template <uint32_t (*N)(uint32_t)>
inline void move_cell(uint8_t* d, const uint8_t* p) { st_u(d, 0, N(ld_u(p, 0))); }

using TGen = FastInterpreter::TypedGeneric;
using TOpnd = FastInterpreter::TypedOperand;
inline uint64_t tget(const uint8_t* m, const TOpnd& o, Ty t) { return o.konst ? o.k : typed::load(t, m + o.off); }

// The routine of typed instruction `op` (not a compare), as the reference
// interpreter's exec_typed: called with power on.
template <Op op>
bool run_typed(uint8_t* m, const TGen& g, uint32_t& xr, typed::StrArgs& args) {
  constexpr const OpInfo& oi = kOps[int(op)];
  const Ty t = g.t, u = g.u;
  if (typed::is_string_instr(op, t, u)) {  // the string section: ir/typed.h runs it
    uint8_t* o[3] = {};
    uint64_t k[3] = {};
    for (int i = 0; i < oi.nopd; i++) o[i] = g.o[i].konst ? nullptr : m + g.o[i].off, k[i] = g.o[i].k;
    if (typed::str_exec(op, t, u, o, k, args)) m[g.s0] = 1;
    return false;
  }
  if constexpr (oi.klass != OpClass::Typed || oi.push == 1) {
    return false;  // compares go to typed_compare; untyped ops have handlers of their own
  } else if constexpr (op == Op::TIDX) {
    uint64_t i = tget(m, g.o[0], t);
    int32_t lo = int32_t(g.o[1].k), hi = int32_t(g.o[2].k);
    if (typed::index_ok(t, i, lo, hi)) { xr = uint32_t(int64_t(i) - lo); return false; }
    write_scan_fault(m, kFaultIndex, g.at, i);
    return true;
  } else if constexpr (op == Op::TLDX) {
    typed::store(t, m + g.o[2].off, typed::load(t, m + g.o[0].off + size_t(xr) * g.o[1].k));
  } else if constexpr (op == Op::TSTX) {
    typed::store(t, m + g.o[1].off + size_t(xr) * g.o[2].k, tget(m, g.o[0], t));
  } else if constexpr (oi.nopd == 2) {  // MOVE, NOT, the functions, CONV, TRUNC
    uint64_t a = tget(m, g.o[0], u != Ty::None ? u : t);
    uint64_t r = op == Op::TMOVE ? a
               : op == Op::TNOT ? typed::logic(op, t, a, 0)
               : op == Op::TCONV ? typed::conv(t, u, a)
               : op == Op::TTRUNC ? typed::trunc(t, u, a)
               : typed::unary(op, t, a);
    typed::store(t, m + g.o[1].off, r);
  } else {  // the two-operand ones
    uint64_t a = tget(m, g.o[0], t), b = tget(m, g.o[1], u != Ty::None ? u : t);
    bool error = false;
    uint64_t r = (op == Op::TAND || op == Op::TOR || op == Op::TXOR) ? typed::logic(op, t, a, b)
               : (op == Op::TSHL || op == Op::TSHR || op == Op::TROL || op == Op::TROR) ? typed::shift(op, t, a, u, b)
               : typed::arith(op, t, a, b, error);
    if (error) m[g.s0] = 1;
    typed::store(t, m + g.o[2].off, r);
  }
  return false;
}
using TypedRoutine = bool (*)(uint8_t*, const TGen&, uint32_t&, typed::StrArgs&);
// The routine of every op, by opcode (nullptr for the untyped ones).
template <size_t... I>
constexpr std::array<TypedRoutine, kOpCount> typed_routines(std::index_sequence<I...>) {
  return {{(kOps[I].klass == OpClass::Typed ? &run_typed<Op(I)> : nullptr)...}};
}
constexpr std::array<TypedRoutine, kOpCount> kTypedRoutines = typed_routines(std::make_index_sequence<kOpCount>());
__attribute__((noinline)) bool typed_compare(const uint8_t* m, const TGen& g) {
  if (g.t == Ty::STRING) return typed::str_compare(op_info(g.op).rel, typed::str_load(m + g.o[0].off), typed::str_load(m + g.o[1].off));
  return typed::compare(op_info(g.op).rel, g.t, tget(m, g.o[0], g.t), tget(m, g.o[1], g.t));
}

}  // namespace

// ------------------------------------------------------------------ decoding

namespace {

using Ins = FastInterpreter::Ins;

Ins ins(FOp op, uint32_t a = 0, uint32_t b = 0, uint32_t c = 0, uint16_t x = 0) { return Ins{uint16_t(op), x, a, b, c}; }

// Decodes IL instructions into handler calls: one member function per
// instruction group; `special` says whether the last one got a specialized
// handler (not the generic one).
struct Decoder {
  const Layout& L;
  const std::vector<uint32_t>& starts;  // instruction starts, so jump targets (byte offsets) become indices
  std::vector<uint64_t>& k64;            // the 64-bit constant pool
  std::vector<FastInterpreter::TypedGeneric>& generic;
  uint32_t s0;                           // byte offset of S0
  bool special = true;
  uint32_t at = 0;                       // the IL byte offset of the instruction being decoded

  uint32_t index_of(uint32_t target) const {  // target == il.size(): the HALT
    auto it = std::lower_bound(starts.begin(), starts.end(), target);
    if (it != starts.end() && *it != target) throw std::invalid_argument("fast interpreter: jump inside an instruction");
    return uint32_t(it - starts.begin());
  }
  uint32_t where(const Operand& o) const {  // byte offset of a device or edge slot
    if (o.kind == OpdKind::Edge) return L.addr(Area::E, o.index);
    return L.addr(o.area, o.index);
  }
  // A value operand: its kind and its 32-bit field.
  uint32_t value(const Operand& o, unsigned& kind) const {
    switch (o.kind) {
      case OpdKind::ConstInt: kind = kIntConst; return uint32_t(o.ival);
      case OpdKind::ConstReal: kind = kRealConst; return f_bits(o.fval);
      case OpdKind::Real: kind = kRealMem; return where(o);
      default: kind = kIntMem; return where(o);
    }
  }
  uint32_t dest(const Operand& o, unsigned& kind) const {
    kind = o.kind == OpdKind::Real ? kDstReal : kDstInt;
    return where(o);
  }
  Ins gen(Op op, unsigned ka, uint32_t a, unsigned kb, uint32_t b, unsigned kd, uint32_t c) {
    special = false;
    return ins(F_GEN, a, b, c, uint16_t(unsigned(op) | ka << 8 | kb << 10 | kd << 12));
  }

  Ins decode(const Instr& in);
  Ins bit(const Instr& in);
  Ins compare(const Instr& in);
  Ins mov(const Instr& in);
  Ins arith(const Instr& in);
  Ins unary(const Instr& in);
  Ins timer(const Instr& in);
  Ins counter(const Instr& in);
  Ins typed(const Instr& in);
  Ins typed_generic(const Instr& in);
  Ins typed_move(const Instr& in);
  std::optional<Ins> typed_arith(const Instr& in);
  Ins typed_compare(const Instr& in);
  // A typed constant's field: its low 32 bits, or (wide) its index in the pool.
  uint32_t konst(uint64_t v, bool wide) {
    if (!wide) return uint32_t(v);
    k64.push_back(v);
    return uint32_t(k64.size() - 1);
  }
};

// ---- typed instructions
enum MoveClass : unsigned { kMB, kMS8, kMU8, kMS16, kMU16, kMW32, kMW64 };
MoveClass move_class(Ty t) {
  const TyInfo& ti = ty_info(t);
  if (t == Ty::BOOL) return kMB;
  if (ti.cells == 2) return kMW64;
  if (ti.bits == 32) return kMW32;
  bool sign = typed::is_signed(t);
  if (ti.bits == 16) return sign ? kMS16 : kMU16;
  return sign ? kMS8 : kMU8;
}
constexpr FOp kMove[] = {F_TMOV_B, F_TMOV_S8, F_TMOV_U8, F_TMOV_S16, F_TMOV_U16, F_TMOV_W32, F_TMOV_W64};
constexpr FOp kLdx[] = {F_TLDX_B, F_TLDX_S8, F_TLDX_U8, F_TLDX_S16, F_TLDX_U16, F_TLDX_W32, F_TLDX_W64};
constexpr FOp kStx[] = {F_TSTX_B, F_TSTX_S8, F_TSTX_U8, F_TSTX_S16, F_TSTX_U16, F_TSTX_W32, F_TSTX_W64};
bool is_mem(const Operand& o) { return o.kind != OpdKind::ConstT && o.kind != OpdKind::ConstInt; }

// Any typed instruction: its operands resolved, its op's routine.
Ins Decoder::typed_generic(const Instr& in) {
  special = false;
  FastInterpreter::TypedGeneric g;
  g.run = kTypedRoutines[int(in.op)];
  g.op = in.op;
  g.t = in.ty;
  g.u = in.src;
  g.s0 = s0;
  g.at = at;
  for (int i = 0; i < in.nopd(); i++) {
    const Operand& o = in.a[i];
    if (o.kind == OpdKind::ConstT) g.o[i].konst = true, g.o[i].k = o.bits();
    else if (o.kind == OpdKind::ConstInt) g.o[i].konst = true, g.o[i].k = uint64_t(int64_t(o.ival));
    else g.o[i].off = where(o);
  }
  if (in.op == Op::TLDX || in.op == Op::TSTX) {  // the stride in bytes
    const int base = in.op == Op::TLDX ? 0 : 1;
    g.o[base + 1].k = uint64_t(uint32_t(in.a[base + 1].ival)) * L.elem_size(in.a[base].area);
  }
  generic.push_back(g);
  return ins(op_info(in.op).push ? F_TGCMP : F_TGEN, uint32_t(generic.size() - 1));
}

Ins Decoder::typed_move(const Instr& in) {
  const Operand& a = in.a[0];
  const uint32_t dst = where(in.a[1]);
  if (is_mem(a)) return ins(kMove[move_class(in.ty)], where(a), dst);
  const uint64_t v = a.bits();
  if (in.ty == Ty::BOOL) return ins(F_TMOVKB, dst, uint32_t(v));
  if (ty_info(in.ty).cells == 2) return ins(F_TMOVK64, dst, uint32_t(v), uint32_t(v >> 32));
  return ins(F_TMOVK32, dst, uint32_t(v));
}

// ADD SUB MUL of INT, the 32-bit and 64-bit integers; ADD SUB MUL DIV of REAL
// and LREAL.  nullopt: another type or op (the generic routine).
std::optional<Ins> Decoder::typed_arith(const Instr& in) {
  const Ty t = in.ty;
  const TyInfo& ti = ty_info(t);
  const unsigned k = in.op == Op::TADD ? 0 : in.op == Op::TSUB ? 1 : in.op == Op::TMUL ? 2 : 3;
  static constexpr FOp kF32[] = {F_TADD_F32_MM, F_TSUB_F32_MM, F_TMUL_F32_MM, F_TDIV_F32_MM};
  static constexpr FOp kF64[] = {F_TADD_F64_MM, F_TSUB_F64_MM, F_TMUL_F64_MM, F_TDIV_F64_MM};
  static constexpr FOp kS16[] = {F_TADD_S16_MM, F_TSUB_S16_MM, F_TMUL_S16_MM};
  static constexpr FOp kW32[] = {F_TADD_W32_MM, F_TSUB_W32_MM, F_TMUL_W32_MM};
  static constexpr FOp kW64[] = {F_TADD_W64_MM, F_TSUB_W64_MM, F_TMUL_W64_MM};
  FOp base;
  if (t == Ty::REAL) base = kF32[k];
  else if (t == Ty::LREAL) base = kF64[k];
  else if (k == 3) return std::nullopt;  // integer DIV: the generic routine (S0, MIN / -1)
  else if (t == Ty::INT) base = kS16[k];
  else if (ti.cells == 1 && ti.bits == 32) base = kW32[k];
  else if (ti.cells == 2) base = kW64[k];
  else return std::nullopt;
  const bool wide = ti.cells == 2;
  const Operand &a = in.a[0], &b = in.a[1];
  const uint32_t dst = where(in.a[2]);
  if (is_mem(a) && is_mem(b)) return ins(base, where(a), where(b), dst);
  if (is_mem(a)) return ins(FOp(base + 1), where(a), konst(b.bits(), wide), dst);
  if (is_mem(b)) return ins(FOp(base + 2), konst(a.bits(), wide), where(b), dst);
  return std::nullopt;  // two constants
}

// EQ..GE of INT, DINT, the signed 64-bit types, REAL and LREAL (a constant
// first is the mirrored compare; two constants are folded).
Ins Decoder::typed_compare(const Instr& in) {
  const Operand &a = in.a[0], &b = in.a[1];
  const Rel r = op_info(in.op).rel;
  if (!is_mem(a) && !is_mem(b)) return ins(typed::compare(r, in.ty, a.bits(), b.bits()) ? F_TRUE : F_PUSH0);
  const Ty t = in.ty;
  FOp base = t == Ty::INT ? F_TEQ_S16_MM : t == Ty::DINT ? F_TEQ_S32_MM : t == Ty::REAL ? F_TEQ_F32_MM
           : t == Ty::LREAL ? F_TEQ_F64_MM : (ty_info(t).cells == 2 && typed::is_signed(t)) ? F_TEQ_S64_MM : F_Count;
  if (base == F_Count) return typed_generic(in);
  const bool wide = ty_info(t).cells == 2;
  if (is_mem(a) && is_mem(b)) return ins(FOp(base + unsigned(r)), where(a), where(b));
  if (is_mem(a)) return ins(FOp(base + 6 + unsigned(r)), where(a), konst(b.bits(), wide));
  return ins(FOp(base + 6 + unsigned(swap_operands(r))), where(b), konst(a.bits(), wide));
}

Ins Decoder::typed(const Instr& in) {
  const Operand* o = in.a;
  if (typed::is_string_instr(in.op, in.ty, in.src)) return typed_generic(in);
  switch (in.op) {
    case Op::TMOVE: return typed_move(in);
    case Op::TADD: case Op::TSUB: case Op::TMUL: case Op::TDIV:
      if (auto r = typed_arith(in)) return *r;
      break;
    case Op::TEQ: case Op::TNE: case Op::TLT: case Op::TLE: case Op::TGT: case Op::TGE: return typed_compare(in);
    case Op::TIDX:
      if ((in.ty == Ty::INT || in.ty == Ty::DINT) && is_mem(o[0]))
        return ins(in.ty == Ty::INT ? F_TIDX_S16 : F_TIDX_S32, where(o[0]), uint32_t(o[1].ival), uint32_t(o[2].ival));
      break;
    case Op::TLDX:
      return ins(kLdx[move_class(in.ty)], where(o[0]), uint32_t(o[1].ival) * L.elem_size(o[0].area), where(o[2]));
    case Op::TSTX:
      if (is_mem(o[0]))
        return ins(kStx[move_class(in.ty)], where(o[0]), where(o[1]), uint32_t(o[2].ival) * L.elem_size(o[1].area));
      break;
    default: break;
  }
  return typed_generic(in);
}

// The bit instructions, and the rest that take no value operand.
Ins Decoder::bit(const Instr& in) {
  const Operand* o = in.a;
  switch (in.op) {
    case Op::LOAD: return ins(F_LD, where(o[0]));
    case Op::LOADN: return ins(F_LDN, where(o[0]));
    case Op::AND: return ins(F_AND, where(o[0]));
    case Op::ANDN: return ins(F_ANDN, where(o[0]));
    case Op::OR: return ins(F_OR, where(o[0]));
    case Op::ORN: return ins(F_ORN, where(o[0]));
    case Op::LOADP: return ins(F_LDP, where(o[0]), where(o[1]));
    case Op::LOADF: return ins(F_LDF, where(o[0]), where(o[1]));
    case Op::TRUE: return ins(F_TRUE);
    case Op::ANDBLK: return ins(F_ANDB);
    case Op::ORBLK: return ins(F_ORB);
    case Op::MPS: return ins(F_MPS);
    case Op::MRD: return ins(F_MRD);
    case Op::MPP: return ins(F_MPP);
    case Op::OUT: return ins(F_OUT, where(o[0]));
    case Op::OUTN: return ins(F_OUTN, where(o[0]));
    case Op::SET: return ins(F_SET, where(o[0]));
    case Op::RST: return ins(F_RST, where(o[0]));
    case Op::RSTT: return ins(F_RSTT, 0, 0, 0, uint16_t(o[0].index));
    case Op::RSTC: return ins(F_RSTC, 0, 0, 0, uint16_t(o[0].index));
    case Op::JMP: return ins(F_JMP, index_of(o[0].index));
    case Op::END: return ins(F_END);
    case Op::LOOP: return ins(F_LOOP, index_of(o[0].index));
    default: throw std::invalid_argument("fast interpreter: bad opcode");
  }
}

// LDEQ..LDGE: by the operands' kinds; a constant first is the mirrored compare.
Ins Decoder::compare(const Instr& in) {
  const Rel r = op_info(in.op).rel;
  const unsigned rel = unsigned(r), mirror = unsigned(swap_operands(r));  // a r b is b mirror a
  unsigned ka, kb;
  uint32_t a = value(in.a[0], ka), b = value(in.a[1], kb);
  if (ka == kRealMem && kb == kRealMem) return ins(FOp(F_EQ_FF + rel), a, b);
  if (ka == kRealMem && kb == kRealConst) return ins(FOp(F_EQ_FK + rel), a, b);
  if (ka == kRealConst && kb == kRealMem) return ins(FOp(F_EQ_FK + mirror), b, a);
  if ((ka | kb) & 1) return ins(F_CMP_F, a, b, 0, uint16_t(ka | kb << 2 | rel << 4));
  if (ka == kIntConst && kb == kIntConst) return ins(rel_holds(r, int32_t(a), int32_t(b)) ? F_TRUE : F_PUSH0);
  if (ka == kIntMem && kb == kIntMem) return ins(FOp(F_EQ_MM + rel), a, b);
  if (ka == kIntMem) return ins(FOp(F_EQ_MK + rel), a, b);
  return ins(FOp(F_EQ_MK + mirror), b, a);  // constant op word: the mirrored compare, word op constant
}

Ins Decoder::mov(const Instr& in) {
  unsigned ka, kd;
  uint32_t a = value(in.a[0], ka), dst = dest(in.a[1], kd);
  if (ka == kIntConst) return ins(F_MOVK, dst, kd == kDstReal ? f_bits(int_to_real(int32_t(a))) : a);
  if (ka == kRealConst) return ins(F_MOVK, dst, kd == kDstReal ? a : uint32_t(real_to_int(bits_f(a))));
  if ((ka == kRealMem) == (kd == kDstReal)) return ins(F_MOV32, a, dst);
  if (ka == kIntMem) return ins(F_MOVI2F, a, dst);
  return ins(F_MOVF2I, a, dst);
}

// ADD..SHR: word handlers by the operands' kinds, REAL ones for + - * /.
Ins Decoder::arith(const Instr& in) {
  unsigned ka, kb, kd;
  uint32_t a = value(in.a[0], ka), b = value(in.a[1], kb), c = dest(in.a[2], kd);
  FOp base = in.op == Op::ADD ? F_ADD_MM : in.op == Op::SUB ? F_SUB_MM : in.op == Op::MUL ? F_MUL_MM
           : in.op == Op::DIV ? F_DIV_MM : in.op == Op::MOD ? F_MOD_MM : in.op == Op::WAND ? F_WAND_MM
           : in.op == Op::WOR ? F_WOR_MM : in.op == Op::WXOR ? F_WXOR_MM : in.op == Op::SHL ? F_SHL_MM : F_SHR_MM;
  bool ints = !((ka | kb) & 1) && kd == kDstInt;
  if (ints && ka == kIntMem && kb == kIntMem) return ins(base, a, b, c);
  if (ints && ka == kIntMem && kb == kIntConst) return ins(FOp(base + 1), a, b, c);
  if (ints && ka == kIntConst && kb == kIntMem) return ins(FOp(base + 2), a, b, c);
  if (ka == kRealMem && kb == kRealMem && kd == kDstReal && unsigned(in.op) <= unsigned(Op::DIV))
    return ins(FOp(F_ADD_F + (unsigned(in.op) - unsigned(Op::ADD))), a, b, c);
  return gen(in.op, ka, a, kb, b, kd, c);
}

// WNOT and the REAL functions.
Ins Decoder::unary(const Instr& in) {
  unsigned ka, kd;
  uint32_t a = value(in.a[0], ka), dst = dest(in.a[1], kd);
  if (in.op == Op::WNOT && ka == kIntMem && kd == kDstInt) return ins(F_WNOT_M, a, dst);
  if (in.op != Op::WNOT && ka == kRealMem && kd == kDstReal) return ins(FOp(F_SIN_F + unsigned(op_info(in.op).fn)), a, dst);
  return gen(in.op, ka, a, 0, 0, kd, dst);
}

Ins Decoder::timer(const Instr& in) {
  unsigned kp;
  uint32_t pt = value(in.a[1], kp);
  FOp k = in.op == Op::TON ? F_TON_K : in.op == Op::TOF ? F_TOF_K : in.op == Op::TP ? F_TP_K
        : in.op == Op::MTON ? F_MTON_K : in.op == Op::MTOF ? F_MTOF_K : F_MTP_K;
  if (kp == kIntConst) return ins(k, uint32_t(int32_t(pt) < 0 ? 0 : int32_t(pt)), 0, 0, uint16_t(in.a[0].index));
  return ins(FOp(k + 1), pt, 0, 0, uint16_t(in.a[0].index));
}

Ins Decoder::counter(const Instr& in) {
  unsigned kp;
  uint32_t pv = value(in.a[1], kp);
  FOp k = in.op == Op::CTU ? F_CTU_K : F_CTD_K;
  return ins(kp == kIntConst ? k : FOp(k + 1), pv, where(in.a[2]), 0, uint16_t(in.a[0].index));
}

Ins Decoder::decode(const Instr& in) {
  special = true;
  if (op_info(in.op).klass == OpClass::Typed) return typed(in);
  switch (in.op) {
    case Op::LDEQ: case Op::LDNE: case Op::LDLT: case Op::LDLE: case Op::LDGT: case Op::LDGE: return compare(in);
    case Op::MOV: return mov(in);
    case Op::ADD: case Op::SUB: case Op::MUL: case Op::DIV: case Op::MOD:
    case Op::WAND: case Op::WOR: case Op::WXOR: case Op::SHL: case Op::SHR: return arith(in);
    case Op::WNOT: case Op::SIN: case Op::COS: case Op::TAN: case Op::SQRT: case Op::EXP: case Op::LN: case Op::ABS:
      return unary(in);
    case Op::TON: case Op::TOF: case Op::TP: case Op::MTON: case Op::MTOF: case Op::MTP: return timer(in);
    case Op::CTU: case Op::CTD: return counter(in);
    default: return bit(in);
  }
}

}  // namespace

FastInterpreter::FastInterpreter(std::span<const uint8_t> il, const Layout& L) {
  s0_ = L.addr(Area::S, kBitError);
  tw_ = L.offset[int(Area::TW)];
  tq_ = L.offset[int(Area::TQ)];
  ti_ = L.offset[int(Area::TI)];
  cw_ = L.offset[int(Area::CW)];
  cq_ = L.offset[int(Area::CQ)];
  std::vector<uint32_t> starts;
  std::vector<Instr> instrs;
  for (uint32_t off = 0; off < il.size();) {
    starts.push_back(off);
    instrs.emplace_back();
    off = decode_instr(il, off, instrs.back());
  }
  il_count_ = instrs.size();
  Decoder dec{L, starts, k64_, generic_, s0_};
  code_.reserve(instrs.size() + 1);
  for (size_t i = 0; i < instrs.size(); i++) {
    dec.at = starts[i];
    code_.push_back(dec.decode(instrs[i]));
    loops_ |= instrs[i].op == Op::LOOP;
    specialized_ += dec.special;
  }
  code_.push_back(Ins{F_HALT, 0, 0, 0, 0});
  il_offset_ = std::move(starts);
}

// ------------------------------------------------------------------ running

// The timers' scan step (docs/il.md): timer n of kind K (F_TON_K .. F_MTP_K),
// preset pt (already >= 0), input `in`; inlined into its handlers.
template <FOp K>
__attribute__((always_inline)) inline void timer_step(uint8_t* m, uint32_t tw, uint32_t tq, uint32_t ti, uint32_t n,
                                                      int32_t pt, uint32_t in) {
  const uint32_t et_off = tw + 4 * n;
  uint8_t* q = m + tq + n;
  uint8_t* in_mem = m + ti + n;
  if constexpr (K == F_TON_K) {
    if (in) {
      int32_t et = *in_mem ? advance(ld_i(m, et_off), dt_of(m), pt) : 0;
      st_i(m, et_off, et);
      *q = et >= pt;
    } else {
      st_i(m, et_off, 0);
      *q = 0;
    }
  } else if constexpr (K == F_TOF_K) {
    if (in) {
      *q = 1;
      st_i(m, et_off, 0);
    } else if (*in_mem) {
      st_i(m, et_off, 0);
      *q = pt > 0;
    } else if (*q) {
      int32_t et = advance(ld_i(m, et_off), dt_of(m), pt);
      st_i(m, et_off, et);
      *q = et < pt;
    }
  } else if constexpr (K == F_TP_K) {
    if (*q) {
      int32_t et = advance(ld_i(m, et_off), dt_of(m), pt);
      st_i(m, et_off, et);
      if (et >= pt) *q = 0;
    } else if (in && !*in_mem) {
      *q = pt > 0;
      st_i(m, et_off, 0);
    } else if (!in) {
      st_i(m, et_off, 0);
    }
  } else if constexpr (K == F_MTON_K) {
    if (!in || !*in_mem) {
      st_i(m, et_off, 0);
      *q = 0;
    } else if (!*q) {
      int32_t et = advance(ld_i(m, et_off), dt_of(m), pt);
      st_i(m, et_off, et);
      *q = et >= pt;
    }
  } else if constexpr (K == F_MTOF_K) {
    if (in || *in_mem) {
      *q = 1;
      st_i(m, et_off, 0);
    } else if (*q) {
      int32_t et = advance(ld_i(m, et_off), dt_of(m), pt);
      st_i(m, et_off, et);
      *q = et < pt;
    }
  } else if constexpr (K == F_MTP_K) {
    if (*q) {
      int32_t et = advance(ld_i(m, et_off), dt_of(m), pt);
      st_i(m, et_off, et);
      if (et >= pt) *q = 0;
    } else if (in && !*in_mem) {
      *q = 1;
      st_i(m, et_off, 0);
    }
    if (!*q && !in) st_i(m, et_off, 0);
  }
  *in_mem = uint8_t(in);
}


#if LDC_FAST_GOTO
#define HANDLER(name) LH_##name:
#define DISPATCH() goto* kLabels[ip->op]
#define NEXT() { ++ip; DISPATCH(); }
#else
#define HANDLER(name) case F_##name:
#define DISPATCH() continue
#define NEXT() { ++ip; continue; }
#endif

void FastInterpreter::scan(ImageBytes& mem_bytes) {
  uint8_t* mem = mem_bytes.data();
  uint8_t* const m = mem;
  const Ins* const base = code_.data();
  const Ins* ip = base;
  uint32_t st = 0;  // the bit stack, top = bit 0
  const uint32_t s0 = s0_, tw = tw_, tq = tq_, ti = ti_, cw = cw_, cq = cq_;
  const uint64_t* const kp = k64_.data();          // 64-bit constants
  const TypedGeneric* const tg = generic_.data();  // the typed instructions without a handler
  uint32_t xr = 0;                                 // the index register (IDX sets it)
  typed::StrArgs args;                             // the string-argument registers (ARGS sets them)
  if (loops_) std::memset(m + kSysLoops, 0, 4);    // no loop taken yet (docs/il.md, "Loops")

#if LDC_FAST_GOTO
  static const void* const kLabels[F_Count] = {
#define LDC_LABEL(n) &&LH_##n,
      LDC_FAST_OPS(LDC_LABEL)
#undef LDC_LABEL
  };
  DISPATCH();
#else
  for (;;) switch (ip->op) {
#endif

  HANDLER(HALT) { return; }
  // ---- bit logic (bits are 0/1 bytes)
  HANDLER(LD) { st = (st << 1) | m[ip->a]; NEXT(); }
  HANDLER(LDN) { st = (st << 1) | (m[ip->a] ^ 1u); NEXT(); }
  HANDLER(AND) { st &= ~1u | m[ip->a]; NEXT(); }
  HANDLER(ANDN) { st &= ~uint32_t(m[ip->a]); NEXT(); }
  HANDLER(OR) { st |= m[ip->a]; NEXT(); }
  HANDLER(ORN) { st |= m[ip->a] ^ 1u; NEXT(); }
  HANDLER(LDP) { uint32_t b = m[ip->a], e = m[ip->b]; st = (st << 1) | (b & (e ^ 1u)); m[ip->b] = uint8_t(b); NEXT(); }
  HANDLER(LDF) { uint32_t b = m[ip->a], e = m[ip->b]; st = (st << 1) | ((b ^ 1u) & e); m[ip->b] = uint8_t(b); NEXT(); }
  HANDLER(TRUE) { st = (st << 1) | 1u; NEXT(); }
  HANDLER(PUSH0) { st <<= 1; NEXT(); }
  HANDLER(ANDB) { uint32_t t = st & 1u; st >>= 1; st &= ~1u | t; NEXT(); }
  HANDLER(ORB) { uint32_t t = st & 1u; st >>= 1; st |= t; NEXT(); }
  HANDLER(MPS) { st = (st << 1) | (st & 1u); NEXT(); }
  HANDLER(MRD) { st = (st & ~1u) | ((st >> 1) & 1u); NEXT(); }
  HANDLER(MPP) { st >>= 1; NEXT(); }
  HANDLER(OUT) { m[ip->a] = uint8_t(st & 1u); NEXT(); }
  HANDLER(OUTN) { m[ip->a] = uint8_t((st & 1u) ^ 1u); NEXT(); }
  HANDLER(SET) { m[ip->a] |= uint8_t(st & 1u); NEXT(); }
  HANDLER(RST) { m[ip->a] &= uint8_t((st & 1u) ^ 1u); NEXT(); }

  // ---- compares
#define LDC_CMP(N, REL)                                                                                      \
  HANDLER(N##_MM) { st = (st << 1) | uint32_t(rel_holds(Rel::REL, ld_i(m, ip->a), ld_i(m, ip->b))); NEXT(); } \
  HANDLER(N##_MK) { st = (st << 1) | uint32_t(rel_holds(Rel::REL, ld_i(m, ip->a), int32_t(ip->b))); NEXT(); } \
  HANDLER(N##_FF) { st = (st << 1) | uint32_t(rel_holds(Rel::REL, ld_f(m, ip->a), ld_f(m, ip->b))); NEXT(); } \
  HANDLER(N##_FK) { st = (st << 1) | uint32_t(rel_holds(Rel::REL, ld_f(m, ip->a), bits_f(ip->b))); NEXT(); }
  LDC_CMP(EQ, Eq) LDC_CMP(NE, Ne) LDC_CMP(LT, Lt) LDC_CMP(LE, Le) LDC_CMP(GT, Gt) LDC_CMP(GE, Ge)
#undef LDC_CMP
  HANDLER(CMP_F) { st = (st << 1) | uint32_t(compare_real(m, *ip)); NEXT(); }

  // ---- application instructions: only with power
  HANDLER(MOVK) { if (st & 1u) st_i(m, ip->a, int32_t(ip->b)); NEXT(); }
  HANDLER(MOV32) { if (st & 1u) std::memcpy(m + ip->b, m + ip->a, 4); NEXT(); }
  HANDLER(MOVI2F) { if (st & 1u) st_f(m, ip->b, int_to_real(ld_i(m, ip->a))); NEXT(); }
  HANDLER(MOVF2I) { if (st & 1u) st_i(m, ip->b, real_to_int(ld_f(m, ip->a))); NEXT(); }

#define LDC_ARITH(N, FN)                                                                                   \
  HANDLER(N##_MM) { if (st & 1u) st_i(m, ip->c, FN(ld_i(m, ip->a), ld_i(m, ip->b))); NEXT(); }             \
  HANDLER(N##_MK) { if (st & 1u) st_i(m, ip->c, FN(ld_i(m, ip->a), int32_t(ip->b))); NEXT(); }             \
  HANDLER(N##_KM) { if (st & 1u) st_i(m, ip->c, FN(int32_t(ip->a), ld_i(m, ip->b))); NEXT(); }
#define LDC_DIVIDE(N, FN)                                                                                  \
  HANDLER(N##_MM) {                                                                                        \
    if (st & 1u) { int32_t y = ld_i(m, ip->b); if (y == 0) m[s0] = 1; else st_i(m, ip->c, FN(ld_i(m, ip->a), y)); } \
    NEXT();                                                                                                \
  }                                                                                                        \
  HANDLER(N##_MK) {                                                                                        \
    if (st & 1u) { int32_t y = int32_t(ip->b); if (y == 0) m[s0] = 1; else st_i(m, ip->c, FN(ld_i(m, ip->a), y)); } \
    NEXT();                                                                                                \
  }                                                                                                        \
  HANDLER(N##_KM) {                                                                                        \
    if (st & 1u) { int32_t y = ld_i(m, ip->b); if (y == 0) m[s0] = 1; else st_i(m, ip->c, FN(int32_t(ip->a), y)); } \
    NEXT();                                                                                                \
  }
#define LDC_AND(x, y) ((x) & (y))
#define LDC_OR(x, y) ((x) | (y))
#define LDC_XOR(x, y) ((x) ^ (y))
  LDC_ARITH(ADD, i_add) LDC_ARITH(SUB, i_sub) LDC_ARITH(MUL, i_mul)
  LDC_DIVIDE(DIV, i_div) LDC_DIVIDE(MOD, i_mod)
  LDC_ARITH(WAND, LDC_AND) LDC_ARITH(WOR, LDC_OR) LDC_ARITH(WXOR, LDC_XOR) LDC_ARITH(SHL, i_shl) LDC_ARITH(SHR, i_shr)
#undef LDC_ARITH
#undef LDC_DIVIDE
#undef LDC_AND
#undef LDC_OR
#undef LDC_XOR
  // REAL: a NaN result by typed::nan_rule (docs/il.md, "NaN results")
  HANDLER(ADD_F) { if (st & 1u) st_f(m, ip->c, typed::real_add(ld_f(m, ip->a), ld_f(m, ip->b))); NEXT(); }
  HANDLER(SUB_F) { if (st & 1u) st_f(m, ip->c, typed::real_sub(ld_f(m, ip->a), ld_f(m, ip->b))); NEXT(); }
  HANDLER(MUL_F) { if (st & 1u) st_f(m, ip->c, typed::real_mul(ld_f(m, ip->a), ld_f(m, ip->b))); NEXT(); }
  HANDLER(DIV_F) {
    if (st & 1u) { float y = ld_f(m, ip->b); if (y == 0.0f) m[s0] = 1; else st_f(m, ip->c, typed::real_div(ld_f(m, ip->a), y)); }
    NEXT();
  }
  HANDLER(WNOT_M) { if (st & 1u) st_i(m, ip->b, ~ld_i(m, ip->a)); NEXT(); }
#define LDC_REALFN(N, F) \
  HANDLER(N##_F) { if (st & 1u) st_f(m, ip->b, apply_real_fn(RealFn::F, ld_f(m, ip->a))); NEXT(); }
  LDC_REALFN(SIN, Sin) LDC_REALFN(COS, Cos) LDC_REALFN(TAN, Tan) LDC_REALFN(EXP, Exp) LDC_REALFN(LN, Ln)
  LDC_REALFN(SQRT, Sqrt) LDC_REALFN(ABS, Abs)
#undef LDC_REALFN
  HANDLER(GEN) { if (st & 1u) generic(m, *ip, s0); NEXT(); }

  // ---- timers: x = timer number; a = preset (K: a constant, already >= 0; M: its word)
#define LDC_TIMER(N)                                                                                           \
  HANDLER(N##_K) { timer_step<F_##N##_K>(m, tw, tq, ti, ip->x, int32_t(ip->a), st & 1u); NEXT(); }              \
  HANDLER(N##_M) {                                                                                             \
    int32_t pt = ld_i(m, ip->a);                                                                               \
    timer_step<F_##N##_K>(m, tw, tq, ti, ip->x, pt < 0 ? 0 : pt, st & 1u);                                      \
    NEXT();                                                                                                    \
  }
  LDC_TIMER(TON) LDC_TIMER(TOF) LDC_TIMER(TP) LDC_TIMER(MTON) LDC_TIMER(MTOF) LDC_TIMER(MTP)
#undef LDC_TIMER
  HANDLER(RSTT) {
    if (st & 1u) {
      const uint32_t n = ip->x;
      st_i(m, tw + 4 * n, 0);
      m[tq + n] = 0;
      m[ti + n] = 0;
    }
    NEXT();
  }

  // ---- counters: x = counter number, a = preset (K) or its word (M), b = edge slot
#define LDC_COUNTER(N, PV, UP)                                                                  \
  HANDLER(N) {                                                                                   \
    const uint32_t n = ip->x, cv_off = cw + 4 * n;                                               \
    const int32_t pv = PV;                                                                       \
    const uint32_t in = st & 1u;                                                                 \
    int32_t cv = ld_i(m, cv_off);                                                                \
    if (in && !m[ip->b]) {                                                                       \
      if (UP && cv != kMax) cv++;                                                                \
      if (!UP && cv != kMin) cv--;                                                               \
    }                                                                                            \
    st_i(m, cv_off, cv);                                                                         \
    m[cq + n] = UP ? cv >= pv : cv <= 0;                                                         \
    m[ip->b] = uint8_t(in);                                                                      \
    NEXT();                                                                                      \
  }
  LDC_COUNTER(CTU_K, int32_t(ip->a), true)
  LDC_COUNTER(CTU_M, ld_i(m, ip->a), true)
  LDC_COUNTER(CTD_K, int32_t(ip->a), false)
  LDC_COUNTER(CTD_M, ld_i(m, ip->a), false)
#undef LDC_COUNTER
  HANDLER(RSTC) {
    if (st & 1u) {
      const uint32_t n = ip->x;
      st_i(m, cw + 4 * n, 0);
      m[cq + n] = 0;
    }
    NEXT();
  }


  // ---- typed instructions: only with power, but the compares
  HANDLER(TGEN) {
    if ((st & 1u) && tg[ip->a].run(m, tg[ip->a], xr, args)) return;  // an index fault ends the scan
    NEXT();
  }
  HANDLER(TGCMP) { st = (st << 1) | uint32_t(typed_compare(m, tg[ip->a])); NEXT(); }
  HANDLER(TMOVK32) { if (st & 1u) st_u(m, ip->a, ip->b); NEXT(); }
  HANDLER(TMOVK64) { if (st & 1u) st_u64(m, ip->a, ip->b | uint64_t(ip->c) << 32); NEXT(); }
  HANDLER(TMOVKB) { if (st & 1u) m[ip->a] = uint8_t(ip->b); NEXT(); }
  // moves by class: a value from `src` to `dst` (byte pointers)
#define LDC_MOVE_B(dst, src) *(dst) = uint8_t(*(src) != 0)
#define LDC_MOVE_N(N) move_cell<N>
#define LDC_MOVES(H, DST, SRC)                                                  \
  HANDLER(H##_B) { if (st & 1u) LDC_MOVE_B(DST, SRC); NEXT(); }                  \
  HANDLER(H##_S8) { if (st & 1u) LDC_MOVE_N(n_S8)(DST, SRC); NEXT(); }           \
  HANDLER(H##_U8) { if (st & 1u) LDC_MOVE_N(n_U8)(DST, SRC); NEXT(); }           \
  HANDLER(H##_S16) { if (st & 1u) LDC_MOVE_N(n_S16)(DST, SRC); NEXT(); }         \
  HANDLER(H##_U16) { if (st & 1u) LDC_MOVE_N(n_U16)(DST, SRC); NEXT(); }         \
  HANDLER(H##_W32) { if (st & 1u) std::memcpy(DST, SRC, 4); NEXT(); }            \
  HANDLER(H##_W64) { if (st & 1u) std::memcpy(DST, SRC, 8); NEXT(); }
  // MOVE: a = src, b = dst; LDX: a = base, b = stride (bytes), c = dst; STX: a = src, b = base, c = stride
  LDC_MOVES(TMOV, m + ip->b, m + ip->a)
  LDC_MOVES(TLDX, m + ip->c, m + ip->a + size_t(xr) * ip->b)
  LDC_MOVES(TSTX, m + ip->b + size_t(xr) * ip->c, m + ip->a)
#undef LDC_MOVES
#undef LDC_MOVE_N
#undef LDC_MOVE_B
  // IDX of an INT / DINT word: a = the word, b = lo, c = hi
#define LDC_TIDX(N, LOAD)                                                                   \
  HANDLER(N) {                                                                              \
    if (st & 1u) {                                                                          \
      const int64_t i = LOAD, lo = int32_t(ip->b);                                          \
      if (i < lo || i > int32_t(ip->c)) { write_scan_fault(m, kFaultIndex, il_offset_[size_t(ip - base)], uint64_t(i)); return; } \
      xr = uint32_t(i - lo);                                                                \
    }                                                                                       \
    NEXT();                                                                                 \
  }
  LDC_TIDX(TIDX_S16, int16_t(uint16_t(ld_u(m, ip->a))))
  LDC_TIDX(TIDX_S32, ld_i(m, ip->a))
#undef LDC_TIDX
  // arithmetic: integers in their unsigned width, wrapped to the type by NORM
#define LDC_TARITH3(N, LD, KONST, ST, NORM, FN)                                                  \
  HANDLER(N##_MM) { if (st & 1u) ST(m, ip->c, NORM(FN(LD(m, ip->a), LD(m, ip->b)))); NEXT(); }    \
  HANDLER(N##_MK) { if (st & 1u) ST(m, ip->c, NORM(FN(LD(m, ip->a), KONST(ip->b)))); NEXT(); }    \
  HANDLER(N##_KM) { if (st & 1u) ST(m, ip->c, NORM(FN(KONST(ip->a), LD(m, ip->b)))); NEXT(); }
#define LDC_PLUS(x, y) ((x) + (y))
#define LDC_MINUS(x, y) ((x) - (y))
#define LDC_TIMES(x, y) ((x) * (y))
#define LDC_K32(v) (v)
#define LDC_K64(v) kp[v]
#define LDC_KF32(v) bits_f(v)
#define LDC_KF64(v) bits_d(kp[v])
#define LDC_SAME(v) (v)
#define LDC_TINT(C, LD, K, ST, NORM) \
  LDC_TARITH3(TADD_##C, LD, K, ST, NORM, LDC_PLUS) LDC_TARITH3(TSUB_##C, LD, K, ST, NORM, LDC_MINUS) \
  LDC_TARITH3(TMUL_##C, LD, K, ST, NORM, LDC_TIMES)
  LDC_TINT(S16, ld_u, LDC_K32, st_u, n_S16)
  LDC_TINT(W32, ld_u, LDC_K32, st_u, n_W32)
  LDC_TINT(W64, ld_u64, LDC_K64, st_u64, LDC_SAME)
  // REAL and LREAL: a NaN result by typed::nan_rule (docs/il.md, "NaN results")
#define LDC_TREAL(C, LD, K, ST)                                                                                  \
  LDC_TARITH3(TADD_##C, LD, K, ST, LDC_SAME, typed::real_add) LDC_TARITH3(TSUB_##C, LD, K, ST, LDC_SAME, typed::real_sub) \
  LDC_TARITH3(TMUL_##C, LD, K, ST, LDC_SAME, typed::real_mul) LDC_TARITH3(TDIV_##C, LD, K, ST, LDC_SAME, typed::real_div)
  LDC_TREAL(F32, ld_f, LDC_KF32, st_f)
  LDC_TREAL(F64, ld_d, LDC_KF64, st_d)
#undef LDC_TREAL
#undef LDC_TINT
#undef LDC_TARITH3
#undef LDC_PLUS
#undef LDC_MINUS
#undef LDC_TIMES
  // compares: a the first operand's word, b the second's (MM) or the constant (MK)
#define LDC_TCMP_ONE(N, REL, LD, K)                                                                           \
  HANDLER(N##_MM) { st = (st << 1) | uint32_t(rel_holds(Rel::REL, LD(m, ip->a), LD(m, ip->b))); NEXT(); }     \
  HANDLER(N##_MK) { st = (st << 1) | uint32_t(rel_holds(Rel::REL, LD(m, ip->a), K(ip->b))); NEXT(); }
#define LDC_TCMPS(C, LD, K)                                                                                   \
  LDC_TCMP_ONE(TEQ_##C, Eq, LD, K) LDC_TCMP_ONE(TNE_##C, Ne, LD, K) LDC_TCMP_ONE(TLT_##C, Lt, LD, K)          \
  LDC_TCMP_ONE(TLE_##C, Le, LD, K) LDC_TCMP_ONE(TGT_##C, Gt, LD, K) LDC_TCMP_ONE(TGE_##C, Ge, LD, K)
#define LDC_LD_S16(m, off) int16_t(uint16_t(ld_u(m, off)))
#define LDC_K_S16(v) int16_t(uint16_t(v))
#define LDC_LD_S64(m, off) int64_t(ld_u64(m, off))
#define LDC_K_S64(v) int64_t(kp[v])
  LDC_TCMPS(S16, LDC_LD_S16, LDC_K_S16)
  LDC_TCMPS(S32, ld_i, int32_t)
  LDC_TCMPS(S64, LDC_LD_S64, LDC_K_S64)
  LDC_TCMPS(F32, ld_f, LDC_KF32)
  LDC_TCMPS(F64, ld_d, LDC_KF64)
#undef LDC_TCMP_ONE
#undef LDC_TCMPS
#undef LDC_LD_S16
#undef LDC_K_S16
#undef LDC_LD_S64
#undef LDC_K_S64
#undef LDC_K32
#undef LDC_K64
#undef LDC_KF32
#undef LDC_KF64
#undef LDC_SAME

  // ---- flow
  HANDLER(JMP) {
    if (st & 1u) { ip = base + ip->a; DISPATCH(); }
    NEXT();
  }
  HANDLER(END) {
    if (st & 1u) return;
    NEXT();
  }
  HANDLER(LOOP) {  // docs/il.md "Loops": a back edge counted, the budget's last one a fault
    if (st & 1u) {
      uint32_t n = ld_u(m, kSysLoops) + 1;
      st_u(m, kSysLoops, n);  // counted first: at the fault it holds the budget
      if (n >= kLoopBudget) { write_scan_fault(m, kFaultLoop, il_offset_[size_t(ip - base)], kLoopBudget); return; }
      ip = base + ip->a;
      DISPATCH();
    }
    NEXT();
  }

#if !LDC_FAST_GOTO
    default: return;
  }
#endif
}

#undef HANDLER
#undef DISPATCH
#undef NEXT

std::unique_ptr<Engine> make_fast_interp_engine(std::span<const uint8_t> il, const Layout& layout) {
  return std::make_unique<FastInterpreter>(il, layout);
}

}  // namespace ldc
