// ir/codegen.cpp -- the parts of the macro compilers' shared code that are not
// templates: the known values of a rung's bit stack (KnownStack).
#include "ir/codegen.h"

namespace ldc {

signed char KnownStack::pop() {
  if (v_.empty()) return -1;
  signed char v = v_.back();
  v_.pop_back();
  return v;
}

signed char& KnownStack::top() {
  if (v_.empty()) v_.push_back(-1);
  return v_.back();
}

void KnownStack::step(const Instr& in) {
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

}  // namespace ldc
