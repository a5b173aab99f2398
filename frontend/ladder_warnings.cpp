// frontend/ladder_warnings.cpp -- the checks a PLC engineer's tool makes of a
// ladder program (GX Works' double-coil check and its kin), on the IL of any
// ladder reader, each a named warning (docs/diagnostics.md).  They work on
// the IL so that the grid reader, LDmicro and PLCopen LD share them; every
// instruction keeps the place of the element it came from.
#include <map>

#include "frontend/diag.h"
#include "frontend/frontend.h"

namespace ldc {
namespace {

struct Place {
  int line = 0, col = 0;
};

Place place_of(const Rung& r, const Instr& in) {
  if (in.loc.line > 0) return {in.loc.line, in.loc.col > 0 ? in.loc.col : 1};
  return {r.line, 1};
}

// "'motor' (Y0)" where an alias names the device, else "Y0".
class Names {
 public:
  explicit Names(const Program& p) {
    for (const Alias& a : p.aliases) {
      std::string dev = std::string(dev_name(a.dev.dev)) + std::to_string(a.dev.index);
      alias_.emplace(dev, a.name);  // the first alias of a device
    }
  }
  bool named(const std::string& dev) const { return alias_.count(dev) != 0; }
  std::string operator()(const std::string& dev) const {
    auto it = alias_.find(dev);
    return it == alias_.end() ? dev : "'" + it->second + "' (" + dev + ")";
  }

 private:
  std::map<std::string, std::string> alias_;
};

bool is_action(Op op) {
  OpClass k = op_info(op).klass;
  if (k == OpClass::Basic) return op == Op::OUT || op == Op::OUTN || op == Op::SET || op == Op::RST;
  return k != OpClass::Compare;
}

bool is_timer_op(Op op) {
  return op == Op::TON || op == Op::TOF || op == Op::TP || op == Op::MTON || op == Op::MTOF || op == Op::MTP;
}

// -Wdouble-coil: OUT/OUTN of one bit in two places (SET and RST are meant to
// come in pairs and are not counted).  -Wshared-timer: one timer under two
// timer elements, one counter under two elements counting the same way (a
// CTU and a CTD of one counter are an up/down counter).
void warn_drivers(const Program& p, Diagnostics& d, const Names& names, bool named_only) {
  struct First {
    Place at;
    Op op;
  };
  std::map<std::string, First> coils, timers;
  for (const Rung& r : p.rungs)
    for (const Instr& in : r.code) {
      Place at = place_of(r, in);
      if ((in.op == Op::OUT || in.op == Op::OUTN) && in.a[0].kind == OpdKind::Bit && d.wants("double-coil")) {
        std::string dev = operand_text(in.a[0]);
        if (named_only && !names.named(dev)) continue;
        auto [it, fresh] = coils.emplace(dev, First{at, in.op});
        if (!fresh && d.warning("double-coil", p.source, at.line, at.col,
                                names(dev) + " is driven by a second coil (a double coil): the last one run wins"))
          d.note(p.source, it->second.at.line, it->second.at.col, "first driven here");
      }
      bool timer = is_timer_op(in.op), counter = in.op == Op::CTU || in.op == Op::CTD;
      if ((timer || counter) && d.wants("shared-timer")) {
        std::string dev = (timer ? "T" : "C") + std::to_string(in.a[0].index);
        std::string key = counter ? dev + op_info(in.op).name : dev;  // a counter: per direction
        auto [it, fresh] = timers.emplace(key, First{at, in.op});
        if (!fresh && d.warning("shared-timer", p.source, at.line, at.col,
                                std::string(timer ? "timer " : "counter ") + names(dev) + " is driven by a second " +
                                    (timer ? "timer element" : std::string(op_info(in.op).name)) +
                                    ": both update the same " + (timer ? "timer" : "count") + " every scan"))
          d.note(p.source, it->second.at.line, it->second.at.col, "first driven here");
      }
    }
}

// -Wundriven: a done bit read that no timer or counter element can set.
void warn_undriven(const Program& p, Diagnostics& d, const Names& names) {
  if (!d.wants("undriven")) return;
  std::map<std::string, bool> driven;  // "T3", "C0"
  for (const Rung& r : p.rungs)
    for (const Instr& in : r.code) {
      if (is_timer_op(in.op)) driven["T" + std::to_string(in.a[0].index)] = true;
      if (in.op == Op::CTU || in.op == Op::CTD) driven["C" + std::to_string(in.a[0].index)] = true;
    }
  std::map<std::string, bool> told;
  for (const Rung& r : p.rungs)
    for (const Instr& in : r.code)
      for (int i = 0; i < in.nopd(); i++) {
        const Operand& o = in.a[i];
        if (o.kind != OpdKind::Bit || (o.area != Area::TQ && o.area != Area::CQ)) continue;
        bool t = o.area == Area::TQ;
        std::string dev = (t ? "T" : "C") + std::to_string(o.index);
        if (driven.count(dev) || told[dev]) continue;
        told[dev] = true;
        Place at = place_of(r, in);
        d.warning("undriven", p.source, at.line, at.col,
                  names(dev) + " is read, but no " + (t ? "timer" : "counter") + " element drives it: its done bit stays 0");
      }
}

// -Wunreachable: code after an unconditional (JMP L) or (END), up to the next
// label (where a jump may land).
void warn_unreachable(const Program& p, Diagnostics& d) {
  if (!d.wants("unreachable")) return;
  for (size_t k = 0; k < p.rungs.size(); k++) {
    const Rung& r = p.rungs[k];
    for (size_t i = 1; i < r.code.size(); i++) {
      const Instr& in = r.code[i];
      if (in.op != Op::JMP && in.op != Op::END) continue;
      bool alone = r.code[i - 1].op == Op::TRUE && (i == 1 || is_action(r.code[i - 2].op));
      if (!alone) continue;
      // the first instruction that never runs: the rest of this rung, else the next rungs up to a label
      const Rung* where = nullptr;
      const Instr* first = nullptr;
      if (i + 1 < r.code.size()) where = &r, first = &r.code[i + 1];
      else if (k + 1 < p.rungs.size() && p.rungs[k + 1].labels.empty() && !p.rungs[k + 1].code.empty())
        where = &p.rungs[k + 1], first = &where->code[0];
      if (!first) continue;
      Place at = place_of(*where, *first), from = place_of(r, in);
      std::string what = in.op == Op::JMP ? "(JMP " + in.a[0].label.str() + ") always jumps over it" : "(END) always ends the scan before it";
      if (d.warning("unreachable", p.source, at.line, at.col, "never run: the unconditional " + what))
        d.note(p.source, from.line, from.col, in.op == Op::JMP ? "the jump" : "the end");
    }
  }
}

}  // namespace

void warn_ladder(const Program& p, Diagnostics& d, bool named_only) {
  Names names(p);
  warn_drivers(p, d, names, named_only);
  warn_undriven(p, d, names);
  warn_unreachable(p, d);
}

}  // namespace ldc
