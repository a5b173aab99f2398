// runtime/fastinterp.cpp -- the fast interpreter (fastinterp.h): pre-decoded,
// type-specialized handlers, threaded dispatch.  The meaning of every handler is
// the reference interpreter's (ir/interp.cpp, docs/il.md), instruction by
// instruction; only the decoding moved from run time to load time.
#include "runtime/fastinterp.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>

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
  X(CTU_K) X(CTU_M) X(CTD_K) X(CTD_M) X(RSTC) X(JMP) X(END)

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
        store_real(m, kd, in.c, op == Op::ADD ? x + y : op == Op::SUB ? x - y : x * y);
      } else {
        int32_t x = get_i(m, ka, in.a), y = get_i(m, kb, in.b);
        store_int(m, kd, in.c, op == Op::ADD ? i_add(x, y) : op == Op::SUB ? i_sub(x, y) : i_mul(x, y));
      }
      return;
    case Op::DIV:
      if (real) {
        float y = get_f(m, kb, in.b);
        if (y == 0.0f) { m[s0] = 1; return; }
        store_real(m, kd, in.c, get_f(m, ka, in.a) / y);
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
  bool special = true;

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
};

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
  Decoder dec{L, starts};
  code_.reserve(instrs.size() + 1);
  for (const Instr& in : instrs) {
    code_.push_back(dec.decode(in));
    specialized_ += dec.special;
  }
  code_.push_back(Ins{F_HALT, 0, 0, 0, 0});
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
  HANDLER(ADD_F) { if (st & 1u) st_f(m, ip->c, ld_f(m, ip->a) + ld_f(m, ip->b)); NEXT(); }
  HANDLER(SUB_F) { if (st & 1u) st_f(m, ip->c, ld_f(m, ip->a) - ld_f(m, ip->b)); NEXT(); }
  HANDLER(MUL_F) { if (st & 1u) st_f(m, ip->c, ld_f(m, ip->a) * ld_f(m, ip->b)); NEXT(); }
  HANDLER(DIV_F) {
    if (st & 1u) { float y = ld_f(m, ip->b); if (y == 0.0f) m[s0] = 1; else st_f(m, ip->c, ld_f(m, ip->a) / y); }
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

  // ---- flow
  HANDLER(JMP) {
    if (st & 1u) { ip = base + ip->a; DISPATCH(); }
    NEXT();
  }
  HANDLER(END) {
    if (st & 1u) return;
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
