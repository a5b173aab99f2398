// ir/lower.cpp -- the rung tree becomes the mnemonic list (paper 003, Fig. 5):
//   X1 AND (X2 OR (X3 AND X4))  ->  LOAD X1, LOAD X2, LOAD X3, AND X4, ORBLK, ANDBLK
// Parallel outputs after a shared condition use MPS / MRD / MPP.
#include <algorithm>
#include <iterator>

#include "ir/ir.h"

namespace ldc {
namespace {

using K = TreeNode::Kind;

struct Lowering {
  std::vector<Instr>* out = nullptr;
  uint32_t edges = 0;
  int depth = 0, max_depth = 0;
  SrcLoc rung_loc;

  void emit(Instr in) {
    const OpInfo& oi = op_info(in.op);
    depth += oi.push - oi.pop;
    max_depth = std::max(max_depth, depth);
    if (max_depth > kMaxStackDepth)
      throw CompileError(in.loc.line, in.loc.col,
                         "rung too deeply nested: it needs more than " + std::to_string(kMaxStackDepth) +
                             " bit-stack entries");
    for (int i = 0; i < in.nopd(); i++)
      if (op_info(in.op).operands[i] == 'e') in.a[i] = Operand{OpdKind::Edge, Area::Sys, edges++};
    out->push_back(std::move(in));
  }
  void emit0(Op op, SrcLoc loc) {
    Instr in;
    in.op = op;
    in.loc = loc;
    emit(in);
  }

  static SrcLoc loc_of(const TreeNode& n) {
    const TreeNode* p = &n;
    while (!p->kids.empty()) p = &p->kids[0];
    return p->elem.loc;
  }

  // Push the value of a condition.
  void push(const TreeNode& n) {
    switch (n.kind) {
      case K::Leaf: emit(n.elem); break;
      case K::Series:
        push(n.kids[0]);
        for (size_t i = 1; i < n.kids.size(); i++) and_into(n.kids[i]);
        break;
      case K::Parallel:
        push(n.kids[0]);
        for (size_t i = 1; i < n.kids.size(); i++) or_into(n.kids[i]);
        break;
      default: throw CompileError(loc_of(n).line, loc_of(n).col, "internal: action where a condition was expected");
    }
  }
  // top = top AND n
  void and_into(const TreeNode& n) {
    if (n.kind == K::Leaf && (n.elem.op == Op::LOAD || n.elem.op == Op::LOADN)) {
      Instr in = n.elem;
      in.op = n.elem.op == Op::LOAD ? Op::AND : Op::ANDN;
      emit(in);
    } else if (n.kind == K::Series) {
      for (const auto& k : n.kids) and_into(k);
    } else {
      push(n);
      emit0(Op::ANDBLK, loc_of(n));
    }
  }
  // top = top OR n
  void or_into(const TreeNode& n) {
    if (n.kind == K::Leaf && (n.elem.op == Op::LOAD || n.elem.op == Op::LOADN)) {
      Instr in = n.elem;
      in.op = n.elem.op == Op::LOAD ? Op::OR : Op::ORN;
      emit(in);
    } else if (n.kind == K::Parallel) {
      for (const auto& k : n.kids) or_into(k);
    } else {
      push(n);
      emit0(Op::ORBLK, loc_of(n));
    }
  }

  // Does running this action change the top of the stack?
  static bool changes_top(const TreeNode& a) { return a.kind != K::Output; }

  // Run an action; `have_top` says whether its power flow is on top already
  // (false at the left rail).
  void action(const TreeNode& a, bool have_top) {
    switch (a.kind) {
      case K::Output:
        if (!have_top) emit0(Op::TRUE, a.elem.loc);
        emit(a.elem);
        break;
      case K::Then:
        if (have_top) and_into(a.kids[0]);
        else push(a.kids[0]);
        action(a.kids[1], true);
        break;
      case K::Fork: {
        size_t n = a.kids.size();
        if (!have_top) {  // rows joined only at the rail: independent
          for (const auto& k : a.kids) {
            int d0 = depth;  // what a row leaves below the top is never read again
            action(k, false);
            depth = d0;
          }
          break;
        }
        bool save = false;
        for (size_t i = 0; i + 1 < n; i++) save |= changes_top(a.kids[i]);
        if (!save) {
          for (const auto& k : a.kids) action(k, true);
          break;
        }
        emit0(Op::MPS, loc_of(a.kids[0]));
        bool dirty = false;
        for (size_t i = 0; i < n; i++) {
          if (i + 1 == n) emit0(Op::MPP, loc_of(a.kids[i]));
          else if (dirty) emit0(Op::MRD, loc_of(a.kids[i]));
          action(a.kids[i], true);
          dirty = changes_top(a.kids[i]);
        }
        break;
      }
      default: throw CompileError(loc_of(a).line, loc_of(a).col, "internal: condition where an action was expected");
    }
  }
};

void print_node(const TreeNode& n, int indent, std::string& out) {
  out += std::string(indent * 2, ' ');
  switch (n.kind) {
    case K::Leaf: out += "[" + n.text + "]\n"; return;
    case K::Output: out += "(" + n.text + ")\n"; return;
    case K::Series: out += "SERIES\n"; break;
    case K::Parallel: out += "PARALLEL\n"; break;
    case K::Then: out += "THEN\n"; break;
    case K::Fork: out += "FORK\n"; break;
  }
  for (const auto& k : n.kids) print_node(k, indent + 1, out);
}

}  // namespace

std::string print_tree(const TreeProgram& p) {
  std::string out;
  int i = 0;
  for (const auto& r : p.rungs) {
    for (const auto& l : r.labels) out += "label " + l + "\n";
    out += "rung " + std::to_string(++i) + " (line " + std::to_string(r.line) + ")";
    if (!r.title.empty()) out += " \"" + r.title + "\"";
    out += "\n";
    if (r.raw.empty()) print_node(r.root, 1, out);
    for (const Instr& in : r.raw) out += "  IL " + instr_text(in) + "\n";
  }
  for (const auto& l : p.end_labels) out += "label " + l + "\n";
  return out;
}

// A rung given as IL: its edge slots, numbered in a row from whatever its own
// program numbered them, become the program's next ones.
static void lower_raw(const TreeRung& tr, Program& p) {
  Rung& r = p.rungs.emplace_back();
  r.labels = tr.labels;
  r.title = tr.title;
  r.line = tr.line;
  r.code = tr.raw;
  uint32_t lo = UINT32_MAX, hi = 0;
  for (const Instr& in : r.code)
    for (const Operand& o : in.a)
      if (o.kind == OpdKind::Edge) lo = std::min(lo, o.index), hi = std::max(hi, o.index);
  if (lo == UINT32_MAX) return;
  for (Instr& in : r.code)
    for (Operand& o : in.a)
      if (o.kind == OpdKind::Edge) o.index = o.index - lo + p.edge_slots;
  p.edge_slots += hi - lo + 1;
}

void lower_rung(const TreeRung& tr, Program& p) {
  if (!tr.raw.empty()) return lower_raw(tr, p);
  Lowering low;
  low.edges = p.edge_slots;
  std::vector<Instr> code;
  low.out = &code;
  low.action(tr.root, false);
  Rung& r = p.rungs.emplace_back();
  r.labels = tr.labels;
  r.title = tr.title;
  r.line = tr.line;
  r.code.assign(std::make_move_iterator(code.begin()), std::make_move_iterator(code.end()));  // exact capacity
  p.edge_slots = low.edges;
}

Program lower_to_il(const TreeProgram& tp) {
  Program p;
  p.source = tp.source;
  p.end_labels = tp.end_labels;
  p.aliases = tp.aliases;
  p.vars = tp.vars;
  p.retain = tp.retain;
  p.rungs.reserve(tp.rungs.size());
  for (const auto& tr : tp.rungs) lower_rung(tr, p);
  return p;
}

}  // namespace ldc
