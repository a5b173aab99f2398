// ir/codegen.h -- what the macro compilers (backend-x86, backend-c40sim) share,
// whatever their instruction type: the table of bit-instruction templates,
// parsed once, and the dispatch of an IL instruction to the routine of its
// class (ops.def's class column).
#pragma once

#include <map>
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
  }
}

}  // namespace ldc
