// ir/codegen.cpp -- the parts of the macro compilers' shared code that are not
// templates: the contacts that can wait for their block's combine
// (deferred_contacts).
#include "ir/codegen.h"

namespace ldc {

namespace {

// may an instruction stand in a block whose contact is deferred past it?
bool pure_bit(Op op) {
  switch (op) {
    case Op::LOAD: case Op::LOADN: case Op::AND: case Op::ANDN: case Op::OR: case Op::ORN: case Op::LOADP:
    case Op::LOADF: case Op::TRUE: case Op::ANDBLK: case Op::ORBLK:
      return true;
    default: return op_info(op).klass == OpClass::Compare;
  }
}

// the block instruction that combines the contact at i, or -1
int combine_of(const std::vector<Instr>& code, size_t i) {
  int d = 0;  // the block's entries above the contact
  for (size_t k = i + 1; k < code.size() && k <= i + kDeferReach; k++) {
    Op op = code[k].op;
    if (!pure_bit(op)) return -1;
    const OpInfo& info = op_info(op);
    if ((op == Op::ANDBLK || op == Op::ORBLK) && d == 1) return int(k);
    if (info.push == 0 && d < 1 + info.pop) return -1;  // it reads the contact's entry or below
    d += info.push - info.pop;
  }
  return -1;
}

}  // namespace

std::vector<int> deferred_contacts(const std::vector<Instr>& code) {
  std::vector<int> partner(code.size(), -1);
  for (size_t i = 0; i < code.size(); i++) {
    if (code[i].op != Op::LOAD && code[i].op != Op::LOADN) continue;
    int j = combine_of(code, i);
    if (j >= 0) partner[i] = j, partner[size_t(j)] = int(i);
  }
  return partner;
}

Instr combined_contact(const Instr& contact, const Instr& blk) {
  Instr c = contact;
  bool n = contact.op == Op::LOADN;
  c.op = blk.op == Op::ANDBLK ? (n ? Op::ANDN : Op::AND) : (n ? Op::ORN : Op::OR);
  return c;
}

}  // namespace ldc
