// frontend/treebuild.h -- internal: building rung trees by hand, for the
// readers that translate other formats (LDmicro, PLCopen XML) and the grid
// reader.  Not a public header.
#pragma once

#include <vector>

#include "ir/ir.h"

namespace ldc::treebuild {

using K = TreeNode::Kind;

inline Operand bit_opd(Area a, uint32_t i) { return Operand{OpdKind::Bit, a, i}; }
inline Operand int_opd(Area a, uint32_t i) { return Operand{OpdKind::Int, a, i}; }
inline Operand const_opd(int32_t v) {
  Operand o{OpdKind::ConstInt};
  o.ival = v;
  return o;
}
inline Operand timer_opd(uint32_t i) {
  Operand o{OpdKind::Timer};
  o.index = i;
  return o;
}
inline Operand counter_opd(uint32_t i) {
  Operand o{OpdKind::Counter};
  o.index = i;
  return o;
}

// a and b under a node of kind k, flattening nodes of that kind already there
inline TreeNode make_combined(K k, TreeNode a, TreeNode b) {
  TreeNode n;
  n.kind = k;
  for (TreeNode* x : {&a, &b}) {
    if (x->kind == k) for (auto& kid : x->kids) n.kids.push_back(std::move(kid));
    else n.kids.push_back(std::move(*x));
  }
  return n;
}

// Actions side by side; a single action stays as it is.
inline TreeNode fork_of(std::vector<TreeNode> items) {
  if (items.size() == 1) return std::move(items[0]);
  TreeNode f;
  f.kind = K::Fork;
  for (auto& i : items) {
    if (i.kind == K::Fork) for (auto& k : i.kids) f.kids.push_back(std::move(k));
    else f.kids.push_back(std::move(i));
  }
  return f;
}

// A Boolean condition with the constants kept apart, so that always-true and
// always-false parts cost nothing.
struct Cond {
  enum Kind { True, False, Expr } k = True;
  TreeNode n;
  static Cond yes() { return {}; }
  static Cond no() { return {False, {}}; }
  static Cond of(TreeNode t) { return {Expr, std::move(t)}; }
};

inline Cond c_and(Cond a, Cond b) {
  if (a.k == Cond::False || b.k == Cond::False) return Cond::no();
  if (a.k == Cond::True) return b;
  if (b.k == Cond::True) return a;
  return Cond::of(make_combined(K::Series, std::move(a.n), std::move(b.n)));
}
inline Cond c_or(Cond a, Cond b) {
  if (a.k == Cond::True || b.k == Cond::True) return Cond::yes();
  if (a.k == Cond::False) return b;
  if (b.k == Cond::False) return a;
  return Cond::of(make_combined(K::Parallel, std::move(a.n), std::move(b.n)));
}

// FALSE as a leaf: a compare that never holds (`0 <> 0`), shown as `text`.
inline TreeNode false_leaf(SrcLoc loc, const char* text) {
  TreeNode n;
  n.kind = K::Leaf;
  n.elem.op = Op::LDNE;
  n.elem.a[0] = const_opd(0);
  n.elem.a[1] = const_opd(0);
  n.elem.loc = loc;
  n.text = text;
  return n;
}

}  // namespace ldc::treebuild
