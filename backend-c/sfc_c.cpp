// backend-c/sfc_c.cpp -- a sequential function chart as the C of paper 001:
// `switch (step_status)` over the steps of a scope, one case per step running
// its actions, testing its transitions and moving to the next step.  A
// simultaneous sequence is a case whose body holds one switch per branch and
// then the join.  The state lives in the memory image (the step flags of
// docs/sfc.md), so each switch variable is read from the flags when its scope
// starts; the visiting order is exactly lower_chart's (ir/sfc.cpp).
#include <string>

#include "backend-c/backend_c.h"
#include "backend-c/c_typed.h"

namespace ldc {
namespace {

struct SfcC {
  const Chart& c;
  const Layout& L;
  std::string out;

  static std::string u(uint32_t v) { return std::to_string(v) + "u"; }
  std::string m(uint32_t mindex) const { return "m[" + u(L.addr(Area::M, mindex)) + "]"; }
  std::string var(uint32_t sc) const { return sc == 0 ? "step_status" : "branch" + std::to_string(sc); }
  static std::string comment(std::string s) {
    for (size_t at; (at = s.find("*/")) != std::string::npos;) s.replace(at, 2, "* /");
    return "/* " + s + " */";
  }

  void enter(const std::string& ind, uint32_t s) {
    out += ind + m(c.flag(s)) + " = 1;";
    if (!c.steps[s].parallel) out += " " + m(c.entry(s)) + " = 1;";
    out += " " + comment("enter " + c.steps[s].name) + "\n";
    for (uint32_t b : c.steps[s].branches) enter(ind, c.scopes[b].first);
  }

  void scope(uint32_t sc, const std::string& ind) {
    const SfcScope& scope = c.scopes[sc];
    for (uint32_t s : scope.steps) out += ind + m(c.run(s)) + " = " + m(c.flag(s)) + ";\n";
    std::string v = var(sc);
    out += ind + "int " + v + " = ";
    for (uint32_t s : scope.steps) out += m(c.flag(s)) + " ? " + std::to_string(s) + " : ";
    out += "-1;\n";
    out += ind + "switch (" + v + ") {\n";
    for (uint32_t s : scope.steps) step(s, ind);
    out += ind + "default:\n" + ind + "  break;\n" + ind + "}\n";
  }

  void step(uint32_t s, const std::string& ind) {
    const SfcStep& st = c.steps[s];
    std::string in = ind + "  ";
    out += ind + "case " + std::to_string(s) + ": { " +
           comment((st.parallel ? "simultaneous sequence " : "step ") + st.name + ", line " + std::to_string(st.line)) +
           "\n";
    if (st.timer >= 0) {
      uint32_t n = uint32_t(st.timer);
      out += in + "if (" + m(c.entry(s)) + ") { wr_i(m, " + u(L.addr(Area::TW, n)) + ", 0); m[" +
             u(L.addr(Area::TQ, n)) + "] = 0; m[" + u(L.addr(Area::TI, n)) + "] = 0; }  " +
             comment("T" + std::to_string(n) + ": time in the step") + "\n";
      out += in + "ton(m, " + u(L.addr(Area::TW, n)) + ", " + u(L.addr(Area::TQ, n)) + ", " + u(L.addr(Area::TI, n)) +
             ", 2147483647, 1);\n";
    }
    for (const Instr& b : st.bits)
      out += in + "m[" + u(L.addr(b.a[0].area, b.a[0].index)) + "] = " + (b.op == Op::SET ? "1" : "0") + ";  " +
             comment(instr_text(b)) + "\n";
    if (!st.on_entry.rungs.empty()) {
      out += in + "if (" + m(c.entry(s)) + ") {  " + comment("P: on the step's first scan") + "\n";
      out += c_rungs(st.on_entry.rungs, st.on_entry.end_labels, L, in + "  ");
      out += in + "}\n";
    }
    if (!st.parallel) out += in + m(c.entry(s)) + " = 0;\n";
    if (!st.body.rungs.empty() || !st.body.end_labels.empty()) {
      out += in + comment("N: every scan while active") + "\n";
      out += c_rungs(st.body.rungs, st.body.end_labels, L, in);
    }
    for (uint32_t b : st.branches) {
      out += in + comment("branch") + "\n";
      scope(b, in);
    }
    for (const SfcTransition& t : st.out) {
      out += in + comment("transition, line " + std::to_string(t.line) + ": " + t.text) + "\n";
      out += c_code(t.cond, L, in);
      std::string test = "s0";
      for (uint32_t b : st.branches) test += " && " + var(b) + " == " + std::to_string(c.scopes[b].last);
      out += in + "if (" + test + ") {\n";
      out += in + "  " + m(c.flag(s)) + " = 0;\n";
      for (uint32_t b : st.branches) out += in + "  " + m(c.flag(c.scopes[b].last)) + " = 0;\n";
      enter(in + "  ", t.target);
      out += in + "  break;\n" + in + "}\n";
    }
    out += in + "break;\n" + ind + "}\n";
  }
};

}  // namespace

// Does the chart hold a typed instruction (its C then needs their helpers)?
static bool chart_has_typed(const Chart& c) {
  auto typed = [](const std::vector<Instr>& code) {
    for (const Instr& in : code)
      if (op_info(in.op).klass == OpClass::Typed) return true;
    return false;
  };
  auto body = [&](const SfcBody& b) {
    for (const Rung& r : b.rungs)
      if (typed(r.code)) return true;
    return false;
  };
  for (const SfcStep& st : c.steps) {
    if (typed(st.bits) || body(st.on_entry) || body(st.body)) return true;
    for (const SfcTransition& t : st.out)
      if (typed(t.cond)) return true;
  }
  return false;
}

std::string generate_sfc_c(const Chart& c, const Layout& layout) {
  SfcC g{c, layout, {}};
  const bool typed = chart_has_typed(c);
  g.out = "/* ldc: " + c.source + ", a sequential function chart as C (paper 001). */\n" + c_prelude() +
          (typed ? c_typed_prelude() : "") + "\n" + c_scan_head() +
          (typed ? "  uint32_t xr = 0; /* the index register: IDX sets it */\n  (void)xr;\n"
                   "  int64_t sl_ = 0, sp_ = 0; /* the string-argument registers: ARGS sets them */\n  (void)sl_; (void)sp_;\n" : "");
  const SfcStep& init = c.steps[c.initial];
  g.out += "  if (m[" + SfcC::u(layout.addr(Area::S, kBitFirstScan)) + "]) {  " + SfcC::comment("first scan") + "\n";
  g.enter("    ", c.initial);
  g.out += "  }\n";
  (void)init;
  g.scope(0, "  ");
  for (const SfcNBit& n : c.nbits) {
    g.out += "  m[" + SfcC::u(layout.addr(n.bit.area, n.bit.index)) + "] = ";
    for (size_t i = 0; i < n.steps.size(); i++) g.out += (i ? " | " : "") + g.m(c.flag(n.steps[i]));
    g.out += ";  " + SfcC::comment("N " + operand_text(n.bit)) + "\n";
  }
  g.out += "  (void)s0;\n}\n";
  return g.out;
}

}  // namespace ldc
