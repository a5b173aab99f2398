// ir/sfc.cpp -- a sequential function chart becomes IL (docs/sfc.md).
// One scan: the initial step is entered on the first scan; then each scope
// (the main sequence first) copies its steps' active flags into their run bits
// and visits its steps in source order.  A step whose run bit is set runs its
// timer, S/R bits, P body (first scan only), N body, the scopes of a
// simultaneous sequence, and then tests its transitions in priority order: the
// first that holds leaves the step, enters its target and ends the step.
// Last, every `N bit` becomes the OR of its steps' flags.  backend-c's
// generate_sfc_c visits the same things in the same order.
#include "ir/ir.h"

namespace ldc {
namespace {

Operand mbit(uint32_t i) { return Operand{OpdKind::Bit, Area::M, i}; }

Instr ins(Op op, int line, Operand a = {}, Operand b = {}) {
  Instr in;
  in.op = op;
  in.a[0] = a;
  in.a[1] = b;
  in.loc = {line, 1};
  return in;
}

Operand label(const std::string& name) {
  Operand o{OpdKind::Label};
  o.label = name;
  return o;
}

struct ChartLowering {
  const Chart& c;
  Program p;
  std::vector<std::string> pending;  // labels of the next rung

  void rung(int line, std::string title, std::vector<Instr> code) {
    Rung r;
    r.labels = std::move(pending);
    pending.clear();
    r.line = line;
    r.title = std::move(title);
    r.code = std::move(code);
    p.rungs.push_back(std::move(r));
  }
  void body(const SfcBody& b) {
    for (const Rung& r : b.rungs) {
      p.rungs.push_back(r);
      auto& labels = p.rungs.back().labels;
      labels.insert(labels.begin(), pending.begin(), pending.end());
      pending.clear();
    }
    pending.insert(pending.end(), b.end_labels.begin(), b.end_labels.end());
  }

  void enter(std::vector<Instr>& code, uint32_t s, int line) {
    code.push_back(ins(Op::SET, line, mbit(c.flag(s))));
    if (!c.steps[s].parallel) code.push_back(ins(Op::SET, line, mbit(c.entry(s))));
    for (uint32_t b : c.steps[s].branches) enter(code, c.scopes[b].first, line);
  }

  void scope(uint32_t sc) {
    for (uint32_t s : c.scopes[sc].steps)
      rung(c.steps[s].line, "", {ins(Op::LOAD, c.steps[s].line, mbit(c.flag(s))), ins(Op::OUT, c.steps[s].line, mbit(c.run(s)))});
    for (uint32_t s : c.scopes[sc].steps) step(s);
  }

  void step(uint32_t s) {
    const SfcStep& st = c.steps[s];
    int ln = st.line;
    std::string end = "sfc_end_" + std::to_string(s);
    rung(ln, (st.parallel ? "simultaneous sequence " : "step ") + st.name,
         {ins(Op::LOADN, ln, mbit(c.run(s))), ins(Op::JMP, ln, label(end))});
    if (st.timer >= 0) {
      Operand t{OpdKind::Timer};
      t.index = uint32_t(st.timer);
      Operand pt{OpdKind::ConstInt};
      pt.ival = INT32_MAX;
      rung(ln, "", {ins(Op::LOAD, ln, mbit(c.entry(s))), ins(Op::RSTT, ln, t)});
      rung(ln, "", {ins(Op::TRUE, ln), ins(Op::TON, ln, t, pt)});
    }
    if (!st.bits.empty()) {
      std::vector<Instr> code{ins(Op::TRUE, ln)};
      code.insert(code.end(), st.bits.begin(), st.bits.end());
      rung(ln, "", code);
    }
    if (!st.on_entry.rungs.empty()) {
      std::string skip = "sfc_entered_" + std::to_string(s);
      rung(ln, "", {ins(Op::LOADN, ln, mbit(c.entry(s))), ins(Op::JMP, ln, label(skip))});
      body(st.on_entry);
      pending.push_back(skip);
    }
    if (!st.parallel) rung(ln, "", {ins(Op::TRUE, ln), ins(Op::RST, ln, mbit(c.entry(s)))});
    body(st.body);
    for (uint32_t b : st.branches) scope(b);
    for (const SfcTransition& t : st.out) {
      std::vector<Instr> code = t.cond;
      for (uint32_t b : st.branches) code.push_back(ins(Op::AND, t.line, mbit(c.run(c.scopes[b].last))));
      code.push_back(ins(Op::RST, t.line, mbit(c.flag(s))));
      for (uint32_t b : st.branches) code.push_back(ins(Op::RST, t.line, mbit(c.flag(c.scopes[b].last))));
      enter(code, t.target, t.line);
      code.push_back(ins(Op::JMP, t.line, label(end)));
      rung(t.line, "transition " + t.text, code);
    }
    pending.push_back(end);
  }
};

}  // namespace

Program lower_chart(const Chart& c) {
  ChartLowering l{c, {}, {}};
  l.p.source = c.source;
  l.p.aliases = c.aliases;
  l.p.edge_slots = c.edge_slots;
  int ln = c.steps[c.initial].line;
  std::vector<Instr> init{ins(Op::LOAD, ln, Operand{OpdKind::Bit, Area::S, kBitFirstScan})};
  l.enter(init, c.initial, ln);
  l.rung(ln, "initial step " + c.steps[c.initial].name, init);
  l.scope(0);
  for (const SfcNBit& n : c.nbits) {
    int nl = c.steps[n.steps[0]].line;
    std::vector<Instr> code{ins(Op::LOAD, nl, mbit(c.flag(n.steps[0])))};
    for (size_t i = 1; i < n.steps.size(); i++) code.push_back(ins(Op::OR, nl, mbit(c.flag(n.steps[i]))));
    code.push_back(ins(Op::OUT, nl, n.bit));
    l.rung(nl, "N " + operand_text(n.bit), code);
  }
  l.p.end_labels = std::move(l.pending);
  return l.p;
}

}  // namespace ldc
