// backend-c/cgen.cpp -- IL -> C.  One C statement per IL instruction; the bit
// stack entry at depth d is the local s<d % 32> (a rung never has more than 32
// live entries, and what lies deeper is never read again, as with the
// interpreter's 32-bit shift register).
#include "backend-c/backend_c.h"

#include "backend-c/c_typed.h"

#include <cinttypes>
#include <cstdio>
#include <cstring>
#include <stdexcept>

namespace ldc {
namespace {

// The run-time helpers: exactly the rules of docs/il.md, as the interpreter has them.
const char kPrelude[] = R"(#include <stdint.h>
#include <string.h>
#include <math.h>

typedef unsigned char u8;
static inline int32_t rd_i(const u8 *m, uint32_t a) { int32_t v; memcpy(&v, m + a, 4); return v; }
static inline float rd_f(const u8 *m, uint32_t a) { float v; memcpy(&v, m + a, 4); return v; }
static inline void wr_i(u8 *m, uint32_t a, int32_t v) { memcpy(m + a, &v, 4); }
static inline void wr_f(u8 *m, uint32_t a, float v) { memcpy(m + a, &v, 4); }
static inline float f_of(uint32_t u) { float f; memcpy(&f, &u, 4); return f; }
/* a NaN result r of x op y (a function: y = x): the first NaN operand quieted, else the
   default NaN (docs/il.md "NaN results", typed::nan_rule); the C compiler may swap x and y */
static inline float ldc_nanf(float r, float x, float y) {
  uint32_t u;
  if (r == r) return r;
  if (x == x) x = y;
  if (x == x) u = 0xffc00000u; else { memcpy(&u, &x, 4); u |= 0x00400000u; }
  memcpy(&r, &u, 4);
  return r;
}
static inline int32_t r2i(float f) {
  if (f != f) return 0;
  if (f >= 2147483648.0f) return INT32_MAX;
  if (f < -2147483648.0f) return INT32_MIN;
  return (int32_t)f;
}
static inline int32_t i_add(int32_t a, int32_t b) { return (int32_t)((uint32_t)a + (uint32_t)b); }
static inline int32_t i_sub(int32_t a, int32_t b) { return (int32_t)((uint32_t)a - (uint32_t)b); }
static inline int32_t i_mul(int32_t a, int32_t b) { return (int32_t)((uint32_t)a * (uint32_t)b); }
static inline int32_t i_shl(int32_t a, int32_t n) { return n < 0 || n > 31 ? 0 : (int32_t)((uint32_t)a << n); }
static inline int32_t i_shr(int32_t a, int32_t n) { return n < 0 || n > 31 ? 0 : (int32_t)((uint32_t)a >> n); }
static inline int32_t i_abs(int32_t a) { return a == INT32_MIN ? INT32_MIN : (a < 0 ? -a : a); }
typedef float (*realfn)(float);
static inline float call_fn(const u8 *m, int32_t slot, float x) { realfn f; memcpy(&f, m + slot, sizeof f); return f(x); }
static inline int32_t adv(int32_t et, int32_t dt, int32_t pt) {
  if (et >= pt) return pt;
  int64_t s = (int64_t)et + dt;
  return s > pt ? pt : (int32_t)s;
}
static inline int32_t pre(int32_t pt) { return pt < 0 ? 0 : pt; }
static inline void ton(u8 *m, uint32_t tw, uint32_t tq, uint32_t ti, int32_t pt, int in) {
  pt = pre(pt);
  if (in) {
    int32_t et = m[ti] ? adv(rd_i(m, tw), rd_i(m, 0), pt) : 0;
    wr_i(m, tw, et);
    m[tq] = et >= pt;
  } else {
    wr_i(m, tw, 0);
    m[tq] = 0;
  }
  m[ti] = (u8)in;
}
static inline void tof(u8 *m, uint32_t tw, uint32_t tq, uint32_t ti, int32_t pt, int in) {
  pt = pre(pt);
  if (in) { m[tq] = 1; wr_i(m, tw, 0); }
  else if (m[ti]) { wr_i(m, tw, 0); m[tq] = pt > 0; }
  else if (m[tq]) { int32_t et = adv(rd_i(m, tw), rd_i(m, 0), pt); wr_i(m, tw, et); m[tq] = et < pt; }
  m[ti] = (u8)in;
}
static inline void tp(u8 *m, uint32_t tw, uint32_t tq, uint32_t ti, int32_t pt, int in) {
  pt = pre(pt);
  if (m[tq]) { int32_t et = adv(rd_i(m, tw), rd_i(m, 0), pt); wr_i(m, tw, et); if (et >= pt) m[tq] = 0; }
  else if (in && !m[ti]) { m[tq] = pt > 0; wr_i(m, tw, 0); }
  else if (!in) wr_i(m, tw, 0);
  m[ti] = (u8)in;
}
static inline void mton(u8 *m, uint32_t tw, uint32_t tq, uint32_t ti, int32_t pt, int in) {
  pt = pre(pt);
  if (!in || !m[ti]) { wr_i(m, tw, 0); m[tq] = 0; }
  else if (!m[tq]) { int32_t et = adv(rd_i(m, tw), rd_i(m, 0), pt); wr_i(m, tw, et); m[tq] = et >= pt; }
  m[ti] = (u8)in;
}
static inline void mtof(u8 *m, uint32_t tw, uint32_t tq, uint32_t ti, int32_t pt, int in) {
  pt = pre(pt);
  if (in || m[ti]) { m[tq] = 1; wr_i(m, tw, 0); }
  else if (m[tq]) { int32_t et = adv(rd_i(m, tw), rd_i(m, 0), pt); wr_i(m, tw, et); m[tq] = et < pt; }
  m[ti] = (u8)in;
}
static inline void mtp(u8 *m, uint32_t tw, uint32_t tq, uint32_t ti, int32_t pt, int in) {
  pt = pre(pt);
  if (m[tq]) { int32_t et = adv(rd_i(m, tw), rd_i(m, 0), pt); wr_i(m, tw, et); if (et >= pt) m[tq] = 0; }
  else if (in && !m[ti]) { m[tq] = 1; wr_i(m, tw, 0); }
  if (!m[tq] && !in) wr_i(m, tw, 0);
  m[ti] = (u8)in;
}
static inline void ctu(u8 *m, uint32_t cw, uint32_t cq, uint32_t e, int32_t pv, int in) {
  int32_t cv = rd_i(m, cw);
  if (in && !m[e] && cv != INT32_MAX) cv++;
  wr_i(m, cw, cv);
  m[cq] = cv >= pv;
  m[e] = (u8)in;
}
static inline void ctd(u8 *m, uint32_t cw, uint32_t cq, uint32_t e, int32_t pv, int in) {
  (void)pv;
  int32_t cv = rd_i(m, cw);
  if (in && !m[e] && cv != INT32_MIN) cv--;
  wr_i(m, cw, cv);
  m[cq] = cv <= 0;
  m[e] = (u8)in;
}
)";

class CGen {
 public:
  CGen(const Layout& l, std::string indent = "  ") : L_(l), ind_(std::move(indent)) {}
  std::string out;

  // The binary IL's instruction offsets, in program order (an IDX's fault
  // record names its offset); without them typed IDX is refused.
  void set_il_offsets(const std::vector<uint32_t>* offsets) { offsets_ = offsets; }

  void code(const std::vector<Instr>& c) {
    depth_ = 0;
    for (const Instr& in : c) {
      instr(in);
      n_++;
    }
  }
  // rungs with their labels and titles, then labels after the last rung
  void rungs(const std::vector<Rung>& rs, const std::vector<std::string>& end_labels) {
    for (const Rung& r : rs) {
      for (const auto& l : r.labels) out += "lbl_" + l + ":;\n";
      std::string title = r.title;
      for (size_t at; (at = title.find("*/")) != std::string::npos;) title.replace(at, 2, "* /");
      out += ind_ + "/* rung, line " + std::to_string(r.line) + (title.empty() ? "" : ": " + title) + " */\n";
      code(r.code);
    }
    for (const auto& l : end_labels) out += "lbl_" + l + ":;\n";
  }

 private:
  const Layout& L_;
  std::string ind_;
  int depth_ = 0;
  const std::vector<uint32_t>* offsets_ = nullptr;
  size_t n_ = 0;  // instructions translated so far

  static std::string u(uint32_t v) { return std::to_string(v) + "u"; }
  // LOOP (docs/il.md "Loops"): a back edge counted in Sys kSysLoops; the
  // budget's last one writes the loop fault and ends the scan
  std::string loop(const std::string& label) const {
    if (!offsets_) throw std::logic_error("C backend: LOOP without the IL offsets of its fault record");
    return "if (" + top() + ") { uint32_t n_ = (uint32_t)rd_i(m, " + u(kSysLoops) + ") + 1u; wr_i(m, " + u(kSysLoops) +
           ", (int32_t)n_); if (n_ >= " + u(kLoopBudget) +
           ") { uint32_t k_ = " + u(kFaultLoop) + ", a_ = " + u((*offsets_)[n_]) + "; uint64_t v_ = " + u(kLoopBudget) +
           "; memcpy(m + " + u(kSysFault) + ", &k_, 4); memcpy(m + " + u(kSysFaultAt) + ", &a_, 4); memcpy(m + " +
           u(kSysFaultValue) + ", &v_, 8); return; } goto lbl_" + label + "; }";
  }
  std::string s(int d) const { return "s" + std::to_string(((d % 32) + 32) % 32); }
  std::string top() const { return s(depth_ - 1); }

  uint32_t addr(const Operand& o) const {
    switch (o.kind) {
      case OpdKind::Edge: return L_.addr(Area::E, o.index);
      case OpdKind::Timer: return L_.addr(Area::TW, o.index);
      case OpdKind::Counter: return L_.addr(Area::CW, o.index);
      default: return L_.addr(o.area, o.index);
    }
  }
  std::string bit(const Operand& o) const { return "m[" + u(addr(o)) + "]"; }
  static std::string int_const(int32_t v) {
    return v == INT32_MIN ? "(-2147483647 - 1)" : "(" + std::to_string(v) + ")";
  }
  // the value of o as an INT32 or REAL C expression, converted when asked
  std::string val(const Operand& o, bool as_real) const {
    std::string e;
    bool real = o.is_real();
    if (o.kind == OpdKind::ConstInt) e = int_const(o.ival);
    else if (o.kind == OpdKind::ConstReal) {
      uint32_t bits;
      std::memcpy(&bits, &o.fval, 4);
      e = "f_of(" + u(bits) + ")";
    } else if (real) e = "rd_f(m, " + u(addr(o)) + ")";
    else e = "rd_i(m, " + u(addr(o)) + ")";
    if (as_real && !real) return "(float)" + e;
    if (!as_real && real) return "r2i(" + e + ")";
    return e;
  }
  // store an expression of the given type into d
  std::string store(const Operand& d, const std::string& e, bool real) const {
    bool dreal = d.kind == OpdKind::Real;
    if (dreal) return "wr_f(m, " + u(addr(d)) + ", " + (real ? e : "(float)(" + e + ")") + ");";
    return "wr_i(m, " + u(addr(d)) + ", " + (real ? "r2i(" + e + ")" : e) + ");";
  }
  void line(const std::string& l) { out += ind_ + l + "\n"; }
  void guarded(const std::string& body) { line("if (" + top() + ") { " + body + " }"); }

  void instr(const Instr& in) {
    const Operand *a = in.a;
    out += ind_ + "/* " + instr_text(in) + " */\n";
    auto push = [&](const std::string& e) { line(s(depth_) + " = " + e + ";"); depth_++; };
    if (op_info(in.op).klass == OpClass::Typed) {
      CTyped c = c_typed(in, L_, offsets_ && n_ < offsets_->size() ? int64_t((*offsets_)[n_]) : -1);
      return c.push ? push(c.text) : guarded(c.text);
    }
    bool real = a[0].is_real() || a[1].is_real();
    switch (in.op) {
      case Op::LOAD: return push(bit(a[0]));
      case Op::LOADN: return push("!" + bit(a[0]));
      case Op::AND: return line(top() + " &= " + bit(a[0]) + ";");
      case Op::ANDN: return line(top() + " &= !" + bit(a[0]) + ";");
      case Op::OR: return line(top() + " |= " + bit(a[0]) + ";");
      case Op::ORN: return line(top() + " |= !" + bit(a[0]) + ";");
      case Op::LOADP: case Op::LOADF: {
        std::string b = bit(a[0]), e = bit(a[1]);
        push(in.op == Op::LOADP ? "(" + b + " && !" + e + ")" : "(!" + b + " && " + e + ")");
        return line(e + " = " + b + ";");
      }
      case Op::TRUE: return push("1");
      case Op::ANDBLK: depth_--; return line(top() + " &= " + s(depth_) + ";");
      case Op::ORBLK: depth_--; return line(top() + " |= " + s(depth_) + ";");
      case Op::MPS: return push(top());
      case Op::MRD: return line(top() + " = " + s(depth_ - 2) + ";");
      case Op::MPP: depth_--; return;
      case Op::OUT: return line(bit(a[0]) + " = (u8)" + top() + ";");
      case Op::OUTN: return line(bit(a[0]) + " = (u8)!" + top() + ";");
      case Op::SET: return line("if (" + top() + ") " + bit(a[0]) + " = 1;");
      case Op::RST: return line("if (" + top() + ") " + bit(a[0]) + " = 0;");
      case Op::LDEQ: case Op::LDNE: case Op::LDLT: case Op::LDLE: case Op::LDGT: case Op::LDGE:
        return push("(" + val(a[0], real) + " " + rel_info(op_info(in.op).rel).c + " " + val(a[1], real) + ")");
      case Op::MOV: return guarded(store(a[1], val(a[0], a[0].is_real()), a[0].is_real()));
      case Op::ADD: case Op::SUB: case Op::MUL: {
        if (real) {
          const char* op = in.op == Op::ADD ? " + " : in.op == Op::SUB ? " - " : " * ";
          return guarded("float a_ = " + val(a[0], true) + ", b_ = " + val(a[1], true) + "; " +
                         store(a[2], std::string("ldc_nanf(a_") + op + "b_, a_, b_)", true));
        }
        const char* fn = in.op == Op::ADD ? "i_add(" : in.op == Op::SUB ? "i_sub(" : "i_mul(";
        return guarded(store(a[2], fn + val(a[0], false) + ", " + val(a[1], false) + ")", false));
      }
      case Op::DIV:
        if (real)
          return guarded("float a_ = " + val(a[0], true) + ", b_ = " + val(a[1], true) + "; if (b_ == 0.0f) m[" +
                         u(L_.addr(Area::S, kBitError)) + "] = 1; else " + store(a[2], "ldc_nanf(a_ / b_, a_, b_)", true));
        return guarded("int32_t a_ = " + val(a[0], false) + ", b_ = " + val(a[1], false) + "; if (b_ == 0) m[" +
                       u(L_.addr(Area::S, kBitError)) + "] = 1; else " +
                       store(a[2], "(b_ == -1 ? i_sub(0, a_) : a_ / b_)", false));
      case Op::MOD:
        return guarded("int32_t a_ = " + val(a[0], false) + ", b_ = " + val(a[1], false) + "; if (b_ == 0) m[" +
                       u(L_.addr(Area::S, kBitError)) + "] = 1; else " +
                       store(a[2], "(b_ == -1 ? 0 : a_ % b_)", false));
      case Op::WAND: case Op::WOR: case Op::WXOR: {
        const char* op = in.op == Op::WAND ? " & " : in.op == Op::WOR ? " | " : " ^ ";
        return guarded(store(a[2], "(" + val(a[0], false) + op + val(a[1], false) + ")", false));
      }
      case Op::WNOT: return guarded(store(a[1], "(~" + val(a[0], false) + ")", false));
      case Op::SHL: case Op::SHR:
        return guarded(store(a[2], std::string(in.op == Op::SHL ? "i_shl(" : "i_shr(") + val(a[0], false) + ", " +
                                       val(a[1], false) + ")", false));
      case Op::SIN: case Op::COS: case Op::TAN: case Op::SQRT: case Op::EXP: case Op::LN: case Op::ABS: {
        const RealFn fn = op_info(in.op).fn;
        if (real_fn_info(fn).ints && !a[0].is_real()) return guarded(store(a[1], "i_abs(" + val(a[0], false) + ")", false));
        // the called ones through the image's table, as native code: the same libm as the interpreter
        if (real_fn_info(fn).called)
          return guarded(store(a[1], "call_fn(m, " + std::to_string(call_slot_disp(fn)) + ", " + val(a[0], true) + ")", true));
        return guarded(store(a[1], std::string(real_fn_info(fn).libm) + "(" + val(a[0], true) + ")", true));
      }
      case Op::TON: case Op::TOF: case Op::TP: case Op::MTON: case Op::MTOF: case Op::MTP: {
        uint32_t n = a[0].index;
        const char* fn = in.op == Op::TON ? "ton" : in.op == Op::TOF ? "tof" : in.op == Op::TP ? "tp"
                       : in.op == Op::MTON ? "mton" : in.op == Op::MTOF ? "mtof" : "mtp";
        return line(std::string(fn) + "(m, " + u(L_.addr(Area::TW, n)) + ", " + u(L_.addr(Area::TQ, n)) + ", " +
                    u(L_.addr(Area::TI, n)) + ", " + val(a[1], false) + ", " + top() + ");");
      }
      case Op::RSTT: {
        uint32_t n = a[0].index;
        return guarded("wr_i(m, " + u(L_.addr(Area::TW, n)) + ", 0); m[" + u(L_.addr(Area::TQ, n)) + "] = 0; m[" +
                       u(L_.addr(Area::TI, n)) + "] = 0;");
      }
      case Op::CTU: case Op::CTD: {
        uint32_t n = a[0].index;
        return line(std::string(in.op == Op::CTU ? "ctu" : "ctd") + "(m, " + u(L_.addr(Area::CW, n)) + ", " +
                    u(L_.addr(Area::CQ, n)) + ", " + u(addr(a[2])) + ", " + val(a[1], false) + ", " + top() + ");");
      }
      case Op::RSTC: {
        uint32_t n = a[0].index;
        return guarded("wr_i(m, " + u(L_.addr(Area::CW, n)) + ", 0); m[" + u(L_.addr(Area::CQ, n)) + "] = 0;");
      }
      case Op::JMP: return line("if (" + top() + ") goto lbl_" + a[0].label.str() + ";");
      case Op::END: return line("if (" + top() + ") return;");
      case Op::LOOP: return line(loop(a[0].label.str()));
      case Op::Count: break;
      default: break;  // the typed instructions, translated above
    }
    throw std::logic_error(std::string("C backend: no translation for ") + op_info(in.op).name);
  }
};

}  // namespace

std::string c_prelude() { return kPrelude; }

std::string c_scan_head() {
  std::string s = "void " + std::string(kCScanSymbol) + "(u8 *m) {\n  int s0";
  for (int i = 1; i < 32; i++) s += ", s" + std::to_string(i);
  return s + ";\n";
}

std::string c_rungs(const std::vector<Rung>& rungs, const std::vector<std::string>& end_labels, const Layout& layout,
                    const std::string& indent) {
  CGen g(layout, indent);
  g.rungs(rungs, end_labels);
  return g.out;
}

std::string c_code(const std::vector<Instr>& code, const Layout& layout, const std::string& indent) {
  CGen g(layout, indent);
  g.code(code);
  return g.out;
}

// A rung's stack lives in C locals whose places are counted from the rung's
// first push, so a program where a rung reads what an earlier one left (IL
// text can say that) is refused where it does so.
void refuse_shared_stack(const Program& p) {
  for (const Rung& r : p.rungs)
    if (int i = foreign_stack_use(r.code); i >= 0) {
      const Instr& in = r.code[size_t(i)];
      throw CompileError(in.loc.line, in.loc.col,
                         std::string("the C route cannot compile ") + op_info(in.op).name +
                             " here: it uses a stack entry an earlier rung left (native code and the interpreters can)");
    }
}

static bool has_typed(const Program& p) {
  for (const Rung& r : p.rungs)
    for (const Instr& in : r.code)
      if (op_info(in.op).klass == OpClass::Typed) return true;
  return false;
}

std::string generate_c(const Program& p, const Layout& layout) {
  refuse_shared_stack(p);
  const bool typed = has_typed(p), loops = has_loop(p);
  std::vector<uint32_t> offsets;
  if (typed || loops) offsets = encode_il(p).instr_offset;
  CGen g(layout, "  ");
  g.set_il_offsets(typed || loops ? &offsets : nullptr);
  g.rungs(p.rungs, p.end_labels);
  return std::string("/* ldc: ") + p.source + " as C (the C route). */\n" + kPrelude + (typed ? c_typed_prelude() : "") +
         "\n" + c_scan_head() + (loops ? "  wr_i(m, " + std::to_string(kSysLoops) + "u, 0); /* no loop taken yet */\n" : "") +
         (typed ? "  uint32_t xr = 0; /* the index register: IDX sets it */\n"
                  "  int64_t sl_ = 0, sp_ = 0; /* the string-argument registers: ARGS sets them */\n" : "") + g.out +
         "  (void)s0;\n" + (typed ? "  (void)xr; (void)sl_; (void)sp_;\n" : "") + "}\n";
}

}  // namespace ldc
