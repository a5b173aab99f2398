// ir/ladder.cpp -- IL back to rung trees, rung trees to the text grid.
#include "ir/ladder.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <map>
#include <optional>

namespace ldc {
namespace {

using K = TreeNode::Kind;

// ------------------------------------------------------------------ raising

bool is_push(Op op) {
  switch (op) {
    case Op::TRUE: case Op::LOAD: case Op::LOADN: case Op::LOADP: case Op::LOADF: return true;
    default: return op_info(op).klass == OpClass::Compare;
  }
}
bool is_modify(Op op) { return op == Op::AND || op == Op::ANDN || op == Op::OR || op == Op::ORN; }
bool is_block(Op op) { return op == Op::ANDBLK || op == Op::ORBLK; }
bool is_cond_op(Op op) { return is_push(op) || is_modify(op) || is_block(op); }
bool is_stack_op(Op op) { return is_cond_op(op) || op == Op::MPS || op == Op::MRD || op == Op::MPP; }

TreeNode leaf(const Instr& in) {
  TreeNode n;
  n.kind = K::Leaf;
  n.elem = in;
  if (in.op == Op::AND || in.op == Op::OR) n.elem.op = Op::LOAD;
  if (in.op == Op::ANDN || in.op == Op::ORN) n.elem.op = Op::LOADN;
  return n;
}

TreeNode combined(K k, TreeNode a, TreeNode b) {
  TreeNode n;
  n.kind = k;
  for (TreeNode* x : {&a, &b}) {
    if (x->kind == k) for (auto& kid : x->kids) n.kids.push_back(std::move(kid));
    else n.kids.push_back(std::move(*x));
  }
  return n;
}

TreeNode fork_of(std::vector<TreeNode> items) {
  if (items.size() == 1) return std::move(items[0]);
  TreeNode f;
  f.kind = K::Fork;
  for (auto& i : items) {
    if (i.kind == K::Fork) for (auto& k : i.kids) f.kids.push_back(std::move(k));
    else f.kids.push_back(std::move(i));
  }
  return f;
}

struct Raiser {
  const Rung& rung;
  size_t rung_no;
  const std::vector<Instr>& code;
  std::vector<int> depth;  // stack entries (relative to the rung's start) before each instruction

  Raiser(const Rung& r, size_t no) : rung(r), rung_no(no), code(r.code) {
    int d = 0;
    for (size_t i = 0; i < code.size(); i++)  // the grid has no loop (docs/format.md)
      if (code[i].op == Op::LOOP) refuse(i, "a LOOP (a jump back) cannot be drawn");
    for (const Instr& in : code) {
      depth.push_back(d);
      d += op_info(in.op).push - op_info(in.op).pop;
    }
    depth.push_back(d);
  }

  [[noreturn]] void refuse(size_t i, const std::string& why) const {
    std::string where = "rung " + std::to_string(rung_no + 1);
    int line = rung.line, col = 1;
    if (i < code.size()) {
      where += ", instruction " + std::to_string(i + 1) + " '" + instr_text(code[i]) + "'";
      if (code[i].loc.line) line = code[i].loc.line, col = std::max(1, code[i].loc.col);
    }
    throw CompileError(line, col, where + ": " + why + "; the rung has no ladder form");
  }

  // i is a push with `base` entries below it: the index of the AND/ORBLK that
  // brings the stack back to `base`, or -1 if something else comes first.
  long block_end(size_t i, int base) const {
    int d = base;
    for (size_t j = i; j < code.size(); j++) {
      Op op = code[j].op;
      if (!is_cond_op(op)) return -1;
      d += op_info(op).push - op_info(op).pop;
      if (d <= base) return long(j);
    }
    return -1;
  }

  // A condition starting with the push at i over `base` entries; returns it
  // and the index after it.
  TreeNode cond(size_t& i, int base) {
    std::vector<TreeNode> st;
    while (i < code.size()) {
      const Instr& in = code[i];
      if (is_push(in.op)) {
        if (!st.empty() && block_end(i, base + int(st.size())) < 0) break;
        st.push_back(leaf(in));
      } else if (is_modify(in.op) && !st.empty()) {
        bool is_and = in.op == Op::AND || in.op == Op::ANDN;
        st.back() = combined(is_and ? K::Series : K::Parallel, std::move(st.back()), leaf(in));
      } else if (is_block(in.op) && st.size() >= 2) {
        TreeNode b = std::move(st.back());
        st.pop_back();
        st.back() = combined(in.op == Op::ANDBLK ? K::Series : K::Parallel, std::move(st.back()), std::move(b));
      } else {
        break;
      }
      i++;
    }
    if (st.size() != 1) refuse(i, "bit-stack entries pushed and never used");
    return std::move(st[0]);
  }

  // The action that the power flow on top of `p` entries drives, from i up to
  // the end of the rung, an MRD/MPP of an enclosing fork, or the start of the
  // next row.  Empty kids: no instruction belongs to it.
  std::optional<TreeNode> action(size_t& i, int p) {
    std::vector<TreeNode> items;
    while (i < code.size()) {
      const Instr& in = code[i];
      if (depth[i] != p) break;
      if (!is_stack_op(in.op)) {
        TreeNode o;
        o.kind = K::Output;
        o.elem = in;
        items.push_back(std::move(o));
        i++;
        continue;
      }
      if (in.op == Op::AND || in.op == Op::ANDN || is_push(in.op)) {
        TreeNode c;
        if (is_push(in.op)) {
          long e = block_end(i, p);
          if (e < 0) break;  // the next row
          if (code[size_t(e)].op != Op::ANDBLK) refuse(size_t(e), "an OR into the power flow");
          c = cond(i, p);
          if (i != size_t(e)) refuse(i, "a condition that does not end where its block does");
          i++;
        } else {
          c = leaf(in);
          i++;
        }
        size_t at = i;
        std::optional<TreeNode> rest = action(i, p);
        if (!rest) refuse(at, "a condition that reaches no output");
        TreeNode t;
        t.kind = K::Then;
        t.kids.push_back(std::move(c));
        t.kids.push_back(std::move(*rest));
        items.push_back(std::move(t));
        break;
      }
      if (in.op == Op::MPS) {
        size_t at = i++;
        std::vector<TreeNode> kids;
        while (true) {
          if (auto k = action(i, p + 1)) kids.push_back(std::move(*k));
          if (i < code.size() && code[i].op == Op::MRD && depth[i] == p + 1) { i++; continue; }
          if (i < code.size() && code[i].op == Op::MPP && depth[i] == p + 1) {
            i++;
            if (auto k = action(i, p)) kids.push_back(std::move(*k));
            break;
          }
          refuse(i < code.size() ? i : at, "MPS without its MPP");
        }
        if (!kids.empty()) items.push_back(fork_of(std::move(kids)));
        break;
      }
      break;  // OR, MRD, MPP, blocks, TRUE: the caller's
    }
    if (items.empty()) return std::nullopt;
    return fork_of(std::move(items));
  }

  TreeNode rung_tree() {
    std::vector<TreeNode> rows;
    size_t i = 0;
    if (code.empty()) refuse(0, "an empty rung");
    while (i < code.size()) {
      const Instr& in = code[i];
      int d = depth[i];
      size_t at = i;
      std::optional<TreeNode> row;
      if (is_push(in.op)) {
        TreeNode c = cond(i, d);
        size_t act_at = i;
        std::optional<TreeNode> a = action(i, d + 1);
        if (!a) {
          if (act_at < code.size() && is_push(code[act_at].op))
            refuse(at, "its condition stays on the bit stack while another row runs (a store inside parentheses?)");
          refuse(act_at < code.size() ? act_at : at, "a condition that reaches no output");
        }
        if (c.kind == K::Leaf && c.elem.op == Op::TRUE && a->kind == K::Output) {  // an output at the rail
          rows.push_back(std::move(*a));
          continue;
        }
        TreeNode t;
        t.kind = K::Then;
        t.kids.push_back(std::move(c));
        t.kids.push_back(std::move(*a));
        row = std::move(t);
      } else {
        refuse(i, d == 0 && i == 0 ? "it reads the bit stack an earlier rung left"
                                   : "a stack operation outside any series/parallel block");
      }
      if (i < code.size() && !is_push(code[i].op))
        refuse(i, "a stack operation outside any series/parallel block");
      rows.push_back(std::move(*row));
    }
    return fork_of(std::move(rows));
  }
};

// ------------------------------------------------------------------ spelling

Dev dev_of(const Operand& o) {
  switch (o.kind) {
    case OpdKind::Timer: return Dev::T;
    case OpdKind::Counter: return Dev::C;
    default: break;
  }
  switch (o.area) {
    case Area::X: return Dev::X;
    case Area::Y: return Dev::Y;
    case Area::M: return Dev::M;
    case Area::K: return Dev::K;
    case Area::S: return Dev::S;
    case Area::TQ: case Area::TW: return Dev::T;
    case Area::CQ: case Area::CW: return Dev::C;
    case Area::WX: return Dev::WX;
    case Area::WY: return Dev::WY;
    case Area::D: return Dev::D;
    default: return Dev::F;
  }
}

bool alias_name_ok(const std::string& n) {
  if (n.empty() || std::isdigit(static_cast<unsigned char>(n[0]))) return false;
  for (char c : n)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_') return false;
  std::string why, u;
  for (char c : n) u += char(std::toupper(static_cast<unsigned char>(c)));
  return !parse_device(n) && !parse_iec_address(n, why) && u != "END";
}

struct Speller {
  std::map<std::pair<int, uint32_t>, std::string> names;  // (Dev, index) -> first alias

  std::map<std::string, int> names_upper;

  explicit Speller(const std::vector<Alias>& aliases) {
    for (const Alias& a : aliases) {
      names.emplace(std::make_pair(int(a.dev.dev), a.dev.index), a.name);
      std::string u;
      for (char c : a.name) u += char(std::toupper(static_cast<unsigned char>(c)));
      names_upper[u] = 1;
    }
  }
  std::string opd(const Operand& o, SrcLoc loc) const {
    switch (o.kind) {
      case OpdKind::Bit: case OpdKind::Int: case OpdKind::Real: case OpdKind::Timer: case OpdKind::Counter: {
        Dev d = dev_of(o);
        auto it = names.find({int(d), o.index});
        if (it != names.end()) return it->second;
        return std::string(dev_name(d)) + std::to_string(o.index);
      }
      case OpdKind::ConstInt: return std::to_string(o.ival);
      case OpdKind::ConstReal:
        if (!std::isfinite(o.fval)) throw CompileError(loc.line, std::max(1, loc.col), "the REAL constant " + real_text(o.fval) + " has no spelling in the grid");
        return real_text(o.fval);
      case OpdKind::Label: return o.label;
      default: return "";
    }
  }
  std::string input(const Instr& in) const {
    if (in.op == Op::TRUE) {
      if (names_upper.count("TRUE")) throw CompileError(in.loc.line, std::max(1, in.loc.col), "an always-closed contact [TRUE] cannot be drawn: the program has an alias named TRUE");
      return "[TRUE]";
    }
    std::string a = opd(in.a[0], in.loc);
    switch (in.op) {
      case Op::LOAD: return "[" + a + "]";
      case Op::LOADN: return "[/" + a + "]";
      case Op::LOADP: return "[P " + a + "]";
      case Op::LOADF: return "[N " + a + "]";
      default: break;
    }
    return "[" + a + " " + rel_info(op_info(in.op).rel).ld + " " + opd(in.a[1], in.loc) + "]";
  }
  std::string output(const Instr& in) const {
    std::string head;
    switch (in.op) {
      case Op::OUT: return "(" + opd(in.a[0], in.loc) + ")";
      case Op::OUTN: return "(/" + opd(in.a[0], in.loc) + ")";
      case Op::SET: head = "S"; break;
      case Op::RST: case Op::RSTT: case Op::RSTC: head = "RST"; break;
      case Op::WAND: head = "AND"; break;
      case Op::WOR: head = "OR"; break;
      case Op::WXOR: head = "XOR"; break;
      case Op::WNOT: head = "NOT"; break;
      default: head = op_info(in.op).name; break;
    }
    int n = in.nopd();
    // CTU/CTD carry their edge slot as a third operand: the grid allocates it
    if (in.op == Op::CTU || in.op == Op::CTD) n = 2;
    for (int k = 0; k < n; k++) head += " " + opd(in.a[k], in.loc);
    return "(" + head + ")";
  }
};

// ------------------------------------------------------------------ layout
// Blocks are drawn into their own canvas (relative coordinates) and copied
// into their parent's; nets are numbered globally, left to right.

struct Block {
  std::vector<std::string> rows;
  std::vector<LadderElem> elems;
  std::vector<LadderWire> wires;
  std::vector<LadderLink> links;
  int width = 0;

  int height() const { return int(rows.size()); }
  void put(int r, int c, const std::string& s) {
    while (int(rows.size()) <= r) rows.emplace_back();
    std::string& row = rows[size_t(r)];
    if (int(row.size()) < c + int(s.size())) row.resize(size_t(c) + s.size(), ' ');
    row.replace(size_t(c), s.size(), s);
    width = std::max(width, c + int(s.size()));
  }
  char at(int r, int c) const {
    if (r < 0 || r >= height() || c < 0 || c >= int(rows[size_t(r)].size())) return ' ';
    return rows[size_t(r)][size_t(c)];
  }
  void wire(int r, int c0, int c1, int net) {
    if (c1 < c0) return;
    put(r, c0, std::string(size_t(c1 - c0 + 1), '-'));
    wires.push_back({r, c0, c1, net});
  }
  void blit(const Block& b, int r0, int c0) {
    for (int r = 0; r < b.height(); r++) {
      const std::string& s = b.rows[size_t(r)];
      for (size_t c = 0; c < s.size(); c++)
        if (s[c] != ' ') put(r0 + r, c0 + int(c), std::string(1, s[c]));
      if (s.empty()) put(r0 + r, c0, "");
    }
    for (LadderElem e : b.elems) { e.row += r0, e.col += c0; elems.push_back(e); }
    for (LadderWire w : b.wires) { w.row += r0, w.col0 += c0, w.col1 += c0; wires.push_back(w); }
    for (LadderLink l : b.links) { l.row0 += r0, l.row1 += r0, l.col += c0; links.push_back(l); }
    width = std::max(width, c0 + b.width);
  }
};

bool vertical_char(char c) { return c == '+' || c == '|'; }

// Row at which `next` may go below `prev` (drawn at rows 0.. of this canvas,
// column offset `c0`) without a junction of one touching the other's.
int free_row(const Block& canvas, int r, const Block& next, int c0) {
  if (r == 0 || next.height() == 0) return r;
  const std::string& top = next.rows[0];
  for (size_t c = 0; c < top.size(); c++)
    if (vertical_char(top[c]) && vertical_char(canvas.at(r - 1, c0 + int(c)))) return r + 1;
  return r;
}

struct Drawer {
  const Speller& sp;
  int nets = 1;

  // A condition: entered at (0, 0), left at (0, width).
  Block cond(const TreeNode& n, int in, int out) {
    Block b;
    switch (n.kind) {
      case K::Leaf: {
        std::string t = sp.input(n.elem);
        b.put(0, 0, t);
        b.elems.push_back({0, 0, int(t.size()), false, n.elem, t, in, out});
        return b;
      }
      case K::Series: {
        int cur = in, x = 0;
        for (size_t k = 0; k < n.kids.size(); k++) {
          if (k) { b.wire(0, x, x + 1, cur); x += 2; }
          int nxt = k + 1 == n.kids.size() ? out : nets++;
          Block kb = cond(n.kids[k], cur, nxt);
          b.blit(kb, 0, x);
          x += kb.width;
          cur = nxt;
        }
        return b;
      }
      case K::Parallel: {
        std::vector<Block> kids;
        int m = 0;
        for (const TreeNode& k : n.kids) {
          kids.push_back(cond(k, in, out));
          m = std::max(m, kids.back().width);
        }
        int right = 3 + m + 2;
        int r = 0, first = 0, last = 0;
        for (size_t k = 0; k < kids.size(); k++) {
          r = free_row(b, r, kids[k], 3);
          if (k == 0) first = r;
          last = r;
          b.put(r, 0, "+");
          b.wire(r, 0, 2, in);
          b.blit(kids[k], r, 3);
          b.wire(r, 3 + kids[k].width, right, out);
          r += std::max(1, kids[k].height());
        }
        for (int rr = first; rr <= last; rr++) {
          bool tops = b.at(rr, 0) == '-' || b.at(rr, 0) == '+';
          b.put(rr, 0, tops ? "+" : "|");
          b.put(rr, right, tops ? "+" : "|");
        }
        b.links.push_back({0, first, last, in});
        b.links.push_back({right, first, last, out});
        return b;
      }
      default: throw CompileError(0, 1, "internal: an action where a condition was expected");
    }
  }

  static int cond_width(const TreeNode& n, const Speller& sp) {
    switch (n.kind) {
      case K::Leaf: return int(sp.input(n.elem).size());
      case K::Series: {
        int w = 0;
        for (size_t k = 0; k < n.kids.size(); k++) w += (k ? 2 : 0) + cond_width(n.kids[k], sp);
        return w;
      }
      default: {
        int m = 0;
        for (const auto& k : n.kids) m = std::max(m, cond_width(k, sp));
        return m + 6;
      }
    }
  }
  // The narrowest an action can be drawn (its outputs at the right end).
  static int action_width(const TreeNode& a, const Speller& sp) {
    switch (a.kind) {
      case K::Output: return int(sp.output(a.elem).size());
      case K::Then: return cond_width(a.kids[0], sp) + 2 + action_width(a.kids[1], sp);
      default: {
        int m = 0;
        for (const auto& k : a.kids) m = std::max(m, action_width(k, sp));
        return 3 + m;
      }
    }
  }

  // An action `width` wide, entered at (0, 0) with the power of net `in`.
  Block action(const TreeNode& a, int in, int width) {
    Block b;
    switch (a.kind) {
      case K::Output: {
        std::string t = sp.output(a.elem);
        int x = width - int(t.size());
        b.wire(0, 0, x - 1, in);
        b.put(0, x, t);
        b.elems.push_back({0, x, int(t.size()), true, a.elem, t, in, -1});
        return b;
      }
      case K::Then: {
        int mid = nets++;
        Block c = cond(a.kids[0], in, mid);
        b.blit(c, 0, 0);
        b.wire(0, c.width, c.width + 1, mid);
        b.blit(action(a.kids[1], mid, width - c.width - 2), 0, c.width + 2);
        return b;
      }
      case K::Fork: {
        int r = 0, first = 0, last = 0;
        for (size_t k = 0; k < a.kids.size(); k++) {
          Block kb = action(a.kids[k], in, width - 3);
          r = free_row(b, r, kb, 3);
          if (k == 0) first = r;
          last = r;
          b.put(r, 0, "+");
          b.wire(r, 0, 2, in);
          b.blit(kb, r, 3);
          r += std::max(1, kb.height());
        }
        for (int rr = first; rr <= last; rr++) b.put(rr, 0, b.at(rr, 1) == '-' ? "+" : "|");
        b.links.push_back({0, first, last, in});
        return b;
      }
      default: throw CompileError(0, 1, "internal: a condition where an action was expected");
    }
  }

  // The rung: the rail in column 0, each row joined only at the rail.
  Block rung(const TreeNode& root) {
    std::vector<const TreeNode*> rows;
    if (root.kind == K::Fork) for (const auto& k : root.kids) rows.push_back(&k);
    else rows.push_back(&root);
    int w = 0;
    for (const TreeNode* r : rows) w = std::max(w, action_width(*r, sp));
    Block b;
    int r = 0;
    for (const TreeNode* row : rows) {
      Block kb = action(*row, 0, w);
      r = free_row(b, r, kb, 3);
      b.wire(r, 1, 2, 0);
      b.blit(kb, r, 3);
      r += std::max(1, kb.height());
    }
    for (int rr = 0; rr < b.height(); rr++) b.put(rr, 0, "|");
    return b;
  }
};

}  // namespace

TreeProgram raise_to_tree(const Program& p) {
  TreeProgram t;
  t.source = p.source;
  t.aliases = p.aliases;
  t.vars = p.vars;
  t.retain = p.retain;
  t.end_labels = p.end_labels;
  for (size_t i = 0; i < p.rungs.size(); i++) {
    const Rung& r = p.rungs[i];
    TreeRung tr;
    tr.labels = r.labels;
    tr.title = r.title;
    tr.line = r.line;
    tr.root = Raiser(r, i).rung_tree();
    t.rungs.push_back(std::move(tr));
  }
  return t;
}

Ladder draw_ladder(const TreeProgram& p) {
  Ladder l;
  l.aliases = p.aliases;
  l.retain = p.retain;
  l.end_labels = p.end_labels;
  for (const Alias& a : p.aliases)
    if (!alias_name_ok(a.name)) throw CompileError(1, 1, "the alias name '" + a.name + "' cannot be written in the grid");
  Speller sp(p.aliases);
  for (const TreeRung& tr : p.rungs) {
    if (tr.title.find_first_of("\r\n") != std::string::npos)
      throw CompileError(std::max(1, tr.line), 1, "the rung title has a line break; a grid title is one line");
    Drawer d{sp};
    Block b = d.rung(tr.root);
    LadderRung lr;
    lr.labels = tr.labels;
    lr.title = tr.title;
    lr.line = tr.line;
    for (std::string& row : b.rows) {
      while (!row.empty() && row.back() == ' ') row.pop_back();
      lr.rows.push_back(std::move(row));
    }
    lr.elems = std::move(b.elems);
    lr.wires = std::move(b.wires);
    lr.links = std::move(b.links);
    lr.nets = d.nets;
    l.rungs.push_back(std::move(lr));
  }
  return l;
}

std::string print_ladder(const Ladder& l, const std::string& source_name) {
  std::string out = "# " + source_name + " as a ladder grid (ldc --emit=ld)\n";
  for (const Alias& a : l.aliases)
    out += "alias " + a.name + " = " + dev_name(a.dev.dev) + std::to_string(a.dev.index) +
           (a.ty == Ty::None ? "" : std::string(" : ") + ty_info(a.ty).name) + "\n";
  for (const DeviceRef& d : l.retain) out += "retain " + std::string(dev_name(d.dev)) + std::to_string(d.index) + "\n";
  for (const LadderRung& r : l.rungs) {
    out += "\n";
    for (const auto& lb : r.labels) out += "label " + lb + "\n";
    if (!r.title.empty()) out += "rung \"" + r.title + "\"\n";
    for (const auto& row : r.rows) out += row + "\n";
  }
  if (!l.end_labels.empty()) out += "\n";
  for (const auto& lb : l.end_labels) out += "label " + lb + "\n";
  return out;
}

}  // namespace ldc
