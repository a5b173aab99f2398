// ir/regions.cpp -- cutting a program into regions for the change-driven scan
// (ir/regions.h, docs/change-driven.md).
#include "ir/regions.h"

#include <algorithm>
#include <map>
#include <stdexcept>

namespace ldc {

namespace {

bool is_device(const Operand& o) { return o.kind == OpdKind::Bit || o.kind == OpdKind::Int || o.kind == OpdKind::Real; }

Span cell(const Layout& L, Area a, uint32_t index) { return {L.addr(a, index), L.elem_size(a)}; }

// A typed operand's bytes: a bit device for BOOL, else the type's cells.
Span typed_cell(const Layout& L, const Operand& o, Ty t) {
  uint32_t len = area_is_bit(o.area) ? 1 : 4 * uint32_t(std::max(1, ty_info(t).cells));
  return {L.addr(o.area, o.index), len};
}

void timer_or_counter(const Instr& in, const Layout& L, Footprint& f) {
  const uint32_t n = in.a[0].index;
  const bool counter = in.a[0].kind == OpdKind::Counter;
  std::vector<Span> own = {cell(L, counter ? Area::CW : Area::TW, n), cell(L, counter ? Area::CQ : Area::TQ, n)};
  if (!counter) own.push_back(cell(L, Area::TI, n));
  for (const Span& s : own) f.reads.push_back(s), f.writes.push_back(s);
  for (int k = 1; k < in.nopd(); k++)
    if (is_device(in.a[k])) f.reads.push_back(cell(L, in.a[k].area, in.a[k].index));
    else if (in.a[k].kind == OpdKind::Edge) f.reads.push_back(cell(L, Area::E, in.a[k].index)), f.writes.push_back(cell(L, Area::E, in.a[k].index));
  const Op op = in.op;
  f.uses_time = op == Op::TON || op == Op::TOF || op == Op::TP || op == Op::MTON || op == Op::MTOF || op == Op::MTP;
}

// The elements an LDX / STX may reach: its base, then (hi - lo) strides on,
// by the bounds of the IDX right before it.
bool array_span(const Instr& in, const Instr* prev, const Operand& base, const Layout& L, Span& out) {
  if (!prev || prev->op != Op::TIDX || !is_device(base) || in.a[in.op == Op::TLDX ? 1 : 2].kind != OpdKind::ConstInt) return false;
  const int64_t lo = prev->a[1].ival, hi = prev->a[2].ival;
  const int64_t stride = in.a[in.op == Op::TLDX ? 1 : 2].ival;
  if (hi < lo || stride < 0) return false;
  const Span first = typed_cell(L, base, in.ty);
  const int64_t last = int64_t(L.addr(base.area, base.index)) + (hi - lo) * stride * L.elem_size(base.area);
  if (last + first.len > int64_t(L.size)) return false;
  out = {first.off, uint32_t(last - first.off) + first.len};
  return true;
}

void typed(const Instr& in, const Instr* prev, const Layout& L, Footprint& f) {
  const char* sig = op_info(in.op).operands;
  for (int k = 0; k < in.nopd(); k++) {
    const Operand& o = in.a[k];
    if (!is_device(o)) continue;
    Span s;
    if (sig[k] == 'a') {
      if (!array_span(in, prev, o, L, s)) { f.bounded = false; return; }
    } else {
      s = typed_cell(L, o, operand_type(in, k));
    }
    (sig[k] == 'r' || (sig[k] == 'a' && in.op == Op::TSTX) ? f.writes : f.reads).push_back(s);
  }
  // an arithmetic or string error sets S0 (compares and IDX never do)
  if (op_info(in.op).push == 0 && in.op != Op::TIDX) f.writes.push_back(cell(L, Area::S, kBitError));
}

}  // namespace

Footprint footprint(const Instr& in, const Instr* prev, const Layout& L) {
  Footprint f;
  const OpInfo& info = op_info(in.op);
  if (info.klass == OpClass::Typed) {
    typed(in, prev, L, f);
    return f;
  }
  if (info.klass == OpClass::Timer || info.klass == OpClass::Counter) {
    timer_or_counter(in, L, f);
    return f;
  }
  const char* sig = info.operands;
  for (int k = 0; k < in.nopd(); k++) {
    const Operand& o = in.a[k];
    switch (sig[k]) {
      case 'b': case 'v': case 'i':
        if (is_device(o)) f.reads.push_back(cell(L, o.area, o.index));
        break;
      case 'w': case 'd':
        if (is_device(o)) f.writes.push_back(cell(L, o.area, o.index));
        break;
      case 'e':
        f.reads.push_back(cell(L, Area::E, o.index)), f.writes.push_back(cell(L, Area::E, o.index));
        break;
      default: break;  // a label
    }
  }
  // a zero divisor sets S0 (DIV, MOD, and a REAL division)
  if (in.op == Op::DIV || in.op == Op::MOD) f.writes.push_back(cell(L, Area::S, kBitError));
  return f;
}

std::vector<Span> merge_spans(std::vector<Span> v) {
  std::sort(v.begin(), v.end(), [](const Span& a, const Span& b) { return a.off < b.off; });
  std::vector<Span> out;
  for (const Span& s : v) {
    if (s.len == 0) continue;
    if (!out.empty() && s.off <= out.back().off + out.back().len)
      out.back().len = std::max(out.back().off + out.back().len, s.off + s.len) - out.back().off;
    else
      out.push_back(s);
  }
  return out;
}

namespace {

// join[i]: rung i must be in the region of rung i - 1.  "" or why the
// program is one region.
std::string joins(const Program& p, std::vector<char>& join) {
  const size_t n = p.rungs.size();
  std::map<std::string, size_t> label_rung;
  for (size_t i = 0; i < n; i++)
    for (const std::string& l : p.rungs[i].labels) label_rung.emplace(l, i);
  for (const std::string& l : p.end_labels) label_rung.emplace(l, n);
  auto join_range = [&](size_t from, size_t to) {  // rungs [from, to] one region
    for (size_t k = from + 1; k <= to && k < n; k++) join[k] = 1;
  };
  size_t loop_lo = n, loop_hi = 0;
  for (size_t i = 0; i < n; i++) {
    if (i > 0 && foreign_stack_use(p.rungs[i].code) >= 0) join[i] = 1;
    for (const Instr& in : p.rungs[i].code) {
      if (in.op == Op::END) join_range(i, n - 1);
      if (in.op != Op::JMP && in.op != Op::LOOP) continue;
      auto it = label_rung.find(in.a[0].label.str());
      if (it == label_rung.end()) return "a jump to the label '" + in.a[0].label.str() + "', which no rung has";
      const size_t j = it->second;
      if (in.op == Op::JMP) {
        if (j <= i) return "a JMP to a label at or above its rung";
        join_range(i, j - 1);
      } else {
        if (j > i) return "a LOOP to a label below its rung";
        loop_lo = std::min(loop_lo, j), loop_hi = std::max(loop_hi, i);
      }
    }
  }
  if (loop_lo < n) join_range(loop_lo, loop_hi);
  return "";
}

bool overlaps(const std::vector<Span>& v, Span c) {
  return std::any_of(v.begin(), v.end(), [&](const Span& s) { return s.off < c.off + c.len && c.off < s.off + s.len; });
}

// Does an instruction of rungs [first, end) other than the timer instruction
// at `self` write timer n's words?
bool timer_shared(const std::vector<std::vector<Span>>& writes, size_t self, uint32_t n, const Layout& L) {
  const Span mine[] = {cell(L, Area::TW, n), cell(L, Area::TQ, n), cell(L, Area::TI, n)};
  for (size_t k = 0; k < writes.size(); k++)
    if (k != self)
      for (const Span& c : mine)
        if (overlaps(writes[k], c)) return true;
  return false;
}

void add_footprints(const Program& p, const Layout& L, Region& r, std::string& whole) {
  std::vector<std::vector<Span>> writes;  // per instruction of the region
  std::vector<std::pair<size_t, uint32_t>> timers;  // (instruction, timer) of each that reads dt
  for (uint32_t i = r.first; i < r.end; i++) {
    const std::vector<Instr>& code = p.rungs[i].code;
    for (size_t k = 0; k < code.size(); k++) {
      Footprint f = footprint(code[k], k ? &code[k - 1] : nullptr, L);
      if (!f.bounded && whole.empty())
        whole = "'" + op_spelling(code[k]) + "' at line " + std::to_string(code[k].loc.line) + " reaches memory the analysis cannot bound";
      if (f.uses_time) timers.emplace_back(writes.size(), code[k].a[0].index);
      r.reads.insert(r.reads.end(), f.reads.begin(), f.reads.end());
      r.writes.insert(r.writes.end(), f.writes.begin(), f.writes.end());
      writes.push_back(std::move(f.writes));
    }
  }
  r.uses_time = !timers.empty();
  for (const auto& [k, n] : timers) r.time_always = r.time_always || timer_shared(writes, k, n, L);
  r.reads = merge_spans(std::move(r.reads));
  r.writes = merge_spans(std::move(r.writes));
}

}  // namespace

RegionPlan plan_regions(const Program& p, const Layout& L, uint32_t max_rungs) {
  RegionPlan plan;
  const size_t n = p.rungs.size();
  std::vector<char> join(n, 0);
  plan.whole = joins(p, join);
  if (!plan.whole.empty()) std::fill(join.begin(), join.end(), 1);
  max_rungs = std::max<uint32_t>(1, max_rungs);
  for (size_t i = 0; i < n; i++) {
    if (plan.regions.empty() || (!join[i] && plan.regions.back().end - plan.regions.back().first >= max_rungs))
      plan.regions.push_back(Region{uint32_t(i), uint32_t(i), {}, {}, false, false, 0});
    plan.regions.back().end = uint32_t(i + 1);
  }
  for (Region& r : plan.regions) add_footprints(p, L, r, plan.whole);
  const BinaryIl il = encode_il(p);
  for (Region& r : plan.regions) r.il_offset = r.first < il.rung_offset.size() ? il.rung_offset[r.first] : 0;
  if (!plan.whole.empty() && plan.regions.size() > 1) {
    Region all{0, uint32_t(n), {}, {}, false, false, 0};
    add_footprints(p, L, all, plan.whole);
    plan.regions.assign(1, std::move(all));
  }
  return plan;
}

Program program_of_il(std::span<const uint8_t> il, std::span<const uint32_t> rung_of, uint32_t edge_slots) {
  Program p;
  p.edge_slots = edge_slots;
  std::map<uint32_t, size_t> rung_at;  // IL offset of each rung's first instruction -> rung
  size_t k = 0;
  for (uint32_t off = 0; off < il.size(); k++) {
    if (k >= rung_of.size()) throw std::runtime_error("the line map has fewer entries than the IL has instructions");
    const uint32_t r = rung_of[k];
    if (r != p.rungs.size() - 1) {
      if (r != p.rungs.size()) throw std::runtime_error("the line map's rungs are not in order");
      p.rungs.emplace_back();
      rung_at[off] = r;
    }
    Instr in;
    const uint32_t next = decode_instr(il, off, in);
    p.rungs.back().code.push_back(in);
    off = next;
  }
  for (Rung& r : p.rungs)
    for (Instr& in : r.code) {
      if (in.op != Op::JMP && in.op != Op::LOOP) continue;
      const uint32_t t = in.a[0].index;
      const std::string name = "@" + std::to_string(t);
      in.a[0].label = name;
      std::vector<std::string>& at = t == il.size() ? p.end_labels
                                   : rung_at.count(t) ? p.rungs[rung_at[t]].labels
                                   : throw std::runtime_error("a jump lands at IL offset " + std::to_string(t) + ", inside a rung");
      if (std::find(at.begin(), at.end(), name) == at.end()) at.push_back(name);
    }
  return p;
}

Program region_program(const Program& p, const Region& r) {
  Program q;
  q.source = p.source;
  q.edge_slots = p.edge_slots;
  q.rungs.assign(p.rungs.begin() + r.first, p.rungs.begin() + r.end);
  // a jump past the region's last rung lands on the next rung's label: its end
  q.end_labels = r.end < p.rungs.size() ? p.rungs[r.end].labels : p.end_labels;
  return q;
}

}  // namespace ldc
