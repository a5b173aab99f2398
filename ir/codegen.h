// ir/codegen.h -- what the macro compilers (backend-x86, backend-c40sim) share,
// whatever their instruction type: the table of bit-instruction templates,
// parsed once, the dispatch of an IL instruction to the routine of its class
// (ops.def's class column), and the control shape of those routines
// (ClassGen), over the primitives each target supplies.
#pragma once

#include <map>
#include <stdexcept>
#include <span>
#include <string>
#include <vector>

#include "ir/ir.h"

namespace ldc {

// One row of a target's template table: a bit mnemonic and its code in the
// target's assembly syntax, instructions separated by ';'.  `%0` and `%1` stand
// for the IL instruction's operands 0 and 1.
struct OpTemplate {
  Op op;
  const char* text;
};

// The rows parsed with the target's `parse` (text -> Inst), after every `%k`
// became `marker(k)`: a placeholder operand the code generator recognises and
// replaces with operand k's address.
template <class Inst, class Parse, class Marker>
std::map<Op, std::vector<Inst>> parse_templates(std::span<const OpTemplate> rows, Parse parse, Marker marker) {
  std::map<Op, std::vector<Inst>> t;
  for (const OpTemplate& row : rows) {
    std::string s = row.text;
    for (int k = 0; k < 2; k++) {
      std::string key = "%" + std::to_string(k), val = marker(k);
      for (size_t p = 0; (p = s.find(key, p)) != std::string::npos; p += val.size()) s.replace(p, key.size(), val);
    }
    size_t start = 0;
    while (start < s.size()) {
      size_t semi = s.find(';', start);
      t[row.op].push_back(parse(s.substr(start, semi == std::string::npos ? std::string::npos : semi - start)));
      start = semi == std::string::npos ? s.size() : semi + 1;
    }
  }
  return t;
}

// Calls g's routine for the class of in's mnemonic: basic (the bit
// instructions), compare, move, arith (divmod for DIV and MOD, which set S0 on
// a zero divisor), logic, special, timer, counter, flow.
template <class Gen>
void gen_by_class(Gen& g, const Instr& in) {
  switch (op_info(in.op).klass) {
    case OpClass::Basic: return g.basic(in);
    case OpClass::Compare: return g.compare(in);
    case OpClass::Move: return g.move(in);
    case OpClass::Arith:
      if (in.op == Op::DIV || in.op == Op::MOD) return g.divmod(in);
      return g.arith(in);
    case OpClass::Logic: return g.logic(in);
    case OpClass::Special: return g.special(in);
    case OpClass::Timer: return g.timer(in);
    case OpClass::Counter: return g.counter(in);
    case OpClass::Flow: return g.flow(in);
    case OpClass::Typed:  // the typed instructions (ir/typed.h): a target that has no code for them refuses them
      if constexpr (requires { g.typed(in); }) return g.typed(in);
      else throw std::logic_error(std::string("no code for the typed instruction ") + op_info(in.op).name + " on this target");
  }
}

// The values of a rung's bit stack known while compiling it (-O2's constant
// folding of power): TRUE pushes 1, and the bit instructions carry what their
// operands decide (AND with a known 0 is 0, OR with a known 1 is 1, MPS copies,
// ANDBLK / ORBLK combine); every other push is unknown, and the application
// classes leave the stack alone.  A backend asks on() before an instruction:
// its power is on for certain, so the instruction needs no gate or test.
// (Inline: scan_facts and the -O2 code generators step it through every instruction.)
class KnownStack {
 public:
  bool on() const { return !v_.empty() && v_.back() == 1; }
  void reset() { v_.clear(); }  // a new rung (the storage is kept)
  void step(const Instr& in) {  // after in
    switch (in.op) {
      case Op::TRUE: v_.push_back(1); return;
      case Op::AND:
      case Op::ANDN: top() = top() == 0 ? 0 : -1; return;
      case Op::OR:
      case Op::ORN: top() = top() == 1 ? 1 : -1; return;
      case Op::MPS: v_.push_back(v_.empty() ? -1 : v_.back()); return;
      case Op::MRD: top() = v_.size() >= 2 ? v_[v_.size() - 2] : -1; return;
      case Op::ANDBLK: {
        signed char a = pop(), &t = top();
        t = (a == 0 || t == 0) ? 0 : (a == 1 && t == 1) ? 1 : -1;
        return;
      }
      case Op::ORBLK: {
        signed char a = pop(), &t = top();
        t = (a == 1 || t == 1) ? 1 : (a == 0 && t == 0) ? 0 : -1;
        return;
      }
      default: break;
    }
    const OpInfo& i = op_info(in.op);
    for (int k = 0; k < i.pop; k++) pop();
    for (int k = 0; k < i.push; k++) v_.push_back(-1);
  }

 private:
  std::vector<signed char> v_;  // bottom first: -1 unknown, 0, 1; what lies below is unknown
  signed char pop() {
    if (v_.empty()) return -1;
    signed char v = v_.back();
    v_.pop_back();
    return v;
  }
  signed char& top() {
    if (v_.empty()) v_.push_back(-1);
    return v_.back();
  }
};

// -O2: a contact pushed only to be combined later can wait for the combine.
// `LOAD a; B; ANDBLK`, where the block B (at least one push) only pushes and
// combines bits (contacts, edges, compares, TRUE, the blocks; no output, no
// MPS / MRD / MPP, no jump), computes `B; AND a`; LOADN gives ANDN, ORBLK
// gives OR / ORN.  The result is the same bit (B's reads and a's commute; an
// edge instruction in B writes only its edge slot, which no contact reads),
// in one register less and one instruction less.  partner[i] = j for such a
// contact at i and its block instruction at j, partner[j] = i; -1 elsewhere.
// A contact is looked for at most kDeferReach instructions ahead.
constexpr size_t kDeferReach = 64;
std::vector<int> deferred_contacts(const std::vector<Instr>& code);
// The contact instruction that the block instruction `blk` (ANDBLK / ORBLK)
// becomes for the deferred `contact` (LOAD / LOADN): AND ANDN OR ORN a.
Instr combined_contact(const Instr& contact, const Instr& blk);

// The labels of DIV / MOD (ClassGen::divmod), made in the target's order:
// err (zero divisor), divide (after the REAL zero test, x86), minus_one (the
// INT32 divisor -1), store (the shared store of the INT32 result, C40); a label
// a target does not use stays empty.
struct DivLabels {
  std::string err, divide, minus_one, store;
};

// The routines of gen_by_class's classes (all but basic and flow), written
// once over the primitives of the target's code generator G (CRTP: G derives
// from ClassGen<G> and befriends it).  G supplies:
//  * labels and power: fresh(), label(l), jump(l), skip_unless_power() (a label
//    to end_skip(l) at, "" if the stores are gated instead or the power is on for
//    certain, KnownStack), ungated(in) (an
//    object that turns gating off for in's code while it lives, if G needs that);
//  * values: load_int(o) (the INT32 accumulator), load_ints(a, b) and
//    load_reals(a, b) (the two INT32 / REAL working registers), store_int(d),
//    store_real(d) (from the accumulator, converted to d's type), set_error();
//  * per class, the target's instructions: compare_ints / compare_reals (push
//    a REL b); copy_word, move_const, move_real_to_int; int_arith (accumulator
//    = a op b), real_arith(op); div_labels, branch_zero_real, divide_real,
//    divisor_branch, divide_int, minus_one_result; word_not, shift, bitwise;
//    abs_int, real_fn; the timer and counter words: area_addr, gated_timer and
//    gated_counter (true if G made the whole instruction another way), put_word
//    (an ET / CV word) and put_flag (a Q or IN byte) of a constant, preset(pt),
//    advance(tw) (ET), unless_power(l) / if_power(l) (branch when the top is 0 /
//    1), if_flag(addr, set, l), restart_et(tw), et_below(l) (ET < PT), q_et(tq,
//    rel) (Q = ET rel PT), q_preset(tq) (Q = PT > 0), tof_on, remember_input(ti),
//    count(in, cw, cq) (CTU / CTD); gated_divmod(in) (true if G made a DIV or
//    MOD another way).
template <class G>
class ClassGen {
 public:
  void compare(const Instr& in) {
    const Operand &a = in.a[0], &b = in.a[1];
    Rel rel = op_info(in.op).rel;
    if (!a.is_real() && !b.is_real()) g().compare_ints(a, b, rel);
    else g().compare_reals(a, b, rel);
  }

  void move(const Instr& in) {
    const Operand &a = in.a[0], &d = in.a[1];
    std::string skip = g().skip_unless_power();
    if (a.kind == OpdKind::Real && d.kind == OpdKind::Real) g().copy_word(a, d);  // the IEEE word, exactly
    else if (a.kind == OpdKind::ConstInt || a.kind == OpdKind::ConstReal) g().move_const(a, d);
    else if (a.kind == OpdKind::Real) g().move_real_to_int(a, d);
    else {
      g().load_int(a);
      g().store_int(d);
    }
    g().end_skip(skip);
  }

  void arith(const Instr& in) {
    const Operand &a = in.a[0], &b = in.a[1], &d = in.a[2];
    std::string skip = g().skip_unless_power();
    if (a.is_real() || b.is_real()) {
      g().load_reals(a, b);
      g().real_arith(in.op);
      g().store_real(d);
    } else {
      g().int_arith(in.op, a, b);
      g().store_int(d);
    }
    g().end_skip(skip);
  }

  // DIV and MOD: a zero divisor sets S0 and leaves d alone; x / -1 = -x
  // (wrapping), x MOD -1 = 0.
  void divmod(const Instr& in) {
    const Operand &a = in.a[0], &b = in.a[1], &d = in.a[2];
    if (g().gated_divmod(in)) return;
    bool mod = in.op == Op::MOD, real = !mod && (a.is_real() || b.is_real());
    [[maybe_unused]] auto plain = g().ungated(in);
    std::string skip = g().skip_unless_power();
    if (skip.empty()) skip = g().fresh();  // power on for certain: no test, but the branches end here
    DivLabels l = g().div_labels(real);
    if (real) {
      g().load_reals(a, b);
      g().branch_zero_real(l);
      g().divide_real();
      g().store_real(d);
      g().jump(skip);
    } else {
      g().load_ints(a, b);
      g().divisor_branch(0, l.err);
      g().divisor_branch(-1, l.minus_one);
      g().divide_int(mod);
      if (!l.store.empty()) g().label(l.store);
      g().store_int(d);
      g().jump(skip);
      g().label(l.minus_one);
      g().minus_one_result(mod);
      if (!l.store.empty()) g().jump(l.store);
      else {
        g().store_int(d);
        g().jump(skip);
      }
    }
    g().label(l.err);
    g().set_error();
    g().end_skip(skip);
  }

  void logic(const Instr& in) {
    std::string skip = g().skip_unless_power();
    if (in.op == Op::WNOT) {
      g().word_not(in.a[0]);
      g().store_int(in.a[1]);
    } else {
      if (in.op == Op::SHL || in.op == Op::SHR) g().shift(in.op, in.a[0], in.a[1]);
      else g().bitwise(in.op, in.a[0], in.a[1]);
      g().store_int(in.a[2]);
    }
    g().end_skip(skip);
  }

  void special(const Instr& in) {
    const Operand &a = in.a[0], &d = in.a[1];
    [[maybe_unused]] auto plain = g().ungated(in);
    std::string skip = g().skip_unless_power();
    if (real_fn_info(op_info(in.op).fn).ints && !a.is_real()) g().abs_int(a, d);
    else g().real_fn(in.op, a, d);
    g().end_skip(skip);
  }

  void timer(const Instr& in) {
    uint32_t n = in.a[0].index;
    uint32_t tw = g().area_addr(Area::TW, n), tq = g().area_addr(Area::TQ, n), ti = g().area_addr(Area::TI, n);
    if (g().gated_timer(in, tw, tq, ti)) return;
    if (in.op == Op::RSTT) {
      std::string skip = g().skip_unless_power();
      g().put_word(tw, 0);
      g().put_flag(tq, 0);
      g().put_flag(ti, 0);
      return g().end_skip(skip);
    }
    g().preset(in.a[1]);
    if (in.op == Op::MTON || in.op == Op::MTOF || in.op == Op::MTP) return matiec_timer(in, tw, tq, ti);
    std::string off = g().fresh(), done = g().fresh();
    if (in.op == Op::TON) ton(tw, tq, ti, off, done);
    else if (in.op == Op::TOF) tof(tw, tq, ti, off, done);
    else tp(tw, tq, ti, off);
  }

  void counter(const Instr& in) {
    uint32_t n = in.a[0].index;
    uint32_t cw = g().area_addr(Area::CW, n), cq = g().area_addr(Area::CQ, n);
    if (g().gated_counter(in, cw, cq)) return;
    if (in.op == Op::RSTC) {
      std::string skip = g().skip_unless_power();
      g().put_word(cw, 0);
      g().put_flag(cq, 0);
      return g().end_skip(skip);
    }
    g().count(in, cw, cq);
  }

 private:
  G& g() { return static_cast<G&>(*this); }

  void ton(uint32_t tw, uint32_t tq, uint32_t ti, const std::string& off, const std::string& done) {
    std::string running = g().fresh(), q = g().fresh();
    g().unless_power(off);
    g().if_flag(ti, true, running);
    g().restart_et(tw);  // rising scan: timing starts
    g().jump(q);
    g().label(running);
    g().advance(tw);
    g().label(q);
    g().q_et(tq, Rel::Ge);
    g().put_flag(ti, 1);
    g().jump(done);
    g().label(off);
    g().put_word(tw, 0);
    g().put_flag(tq, 0);
    g().put_flag(ti, 0);
    g().label(done);
  }

  void tof(uint32_t tw, uint32_t tq, uint32_t ti, const std::string& off, const std::string& done) {
    std::string not_falling = g().fresh(), ti0 = g().fresh();
    g().unless_power(off);
    g().tof_on(tw, tq, ti);
    g().jump(done);
    g().label(off);
    g().if_flag(ti, false, not_falling);
    g().put_word(tw, 0);  // falling scan: timing starts
    g().q_preset(tq);
    g().jump(ti0);
    g().label(not_falling);
    g().if_flag(tq, false, ti0);
    g().advance(tw);
    g().q_et(tq, Rel::Lt);
    g().label(ti0);
    g().put_flag(ti, 0);
    g().label(done);
  }

  void tp(uint32_t tw, uint32_t tq, uint32_t ti, const std::string& off) {
    std::string idle = g().fresh(), remember = g().fresh();
    g().if_flag(tq, false, idle);
    g().advance(tw);
    g().et_below(remember);
    g().put_flag(tq, 0);
    g().jump(remember);
    g().label(idle);
    g().unless_power(off);
    g().if_flag(ti, true, remember);
    g().q_preset(tq);  // rising scan: the pulse starts
    g().put_word(tw, 0);
    g().jump(remember);
    g().label(off);
    g().put_word(tw, 0);
    g().label(remember);
    g().remember_input(ti);
  }

  // MTON MTOF MTP (docs/il.md, "MatIEC timers"), after preset()
  void matiec_timer(const Instr& in, uint32_t tw, uint32_t tq, uint32_t ti) {
    std::string remember = g().fresh();
    if (in.op == Op::MTON) {
      std::string reset = g().fresh();
      g().unless_power(reset);
      g().if_flag(ti, false, reset);  // rising scan: timing starts
      g().if_flag(tq, true, remember);  // done: holds while IN stays on
      g().advance(tw);
      g().q_et(tq, Rel::Ge);
      g().jump(remember);
      g().label(reset);
      g().put_word(tw, 0);
      g().put_flag(tq, 0);
    } else if (in.op == Op::MTOF) {
      std::string on = g().fresh();
      g().if_power(on);
      g().if_flag(ti, true, on);  // falling scan: Q stays on
      g().if_flag(tq, false, remember);
      g().advance(tw);
      g().q_et(tq, Rel::Lt);
      g().jump(remember);
      g().label(on);
      g().put_flag(tq, 1);
      g().put_word(tw, 0);
    } else {  // MTP
      std::string idle = g().fresh(), check = g().fresh();
      g().if_flag(tq, false, idle);
      g().advance(tw);
      g().et_below(remember);
      g().put_flag(tq, 0);  // the pulse ends
      g().jump(check);
      g().label(idle);
      g().unless_power(check);
      g().if_flag(ti, true, remember);
      g().put_flag(tq, 1);  // rising scan: the pulse starts
      g().put_word(tw, 0);
      g().jump(remember);
      g().label(check);  // Q is off: ET = 0 unless IN is on
      g().if_power(remember);
      g().put_word(tw, 0);
    }
    g().label(remember);
    g().remember_input(ti);
  }
};

}  // namespace ldc
