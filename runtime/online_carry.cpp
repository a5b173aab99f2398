// runtime/online_carry.cpp -- state carried by identity across an online
// download (runtime/online_carry.h, docs/runtime.md "What a download carries").
#include "runtime/online_carry.h"

#include <algorithm>
#include <cstring>
#include <deque>
#include <map>
#include <optional>
#include <set>
#include <tuple>

namespace ldc::plc {
namespace {

// ---------------------------------------------------------------- names

// The first cell of each alias, so an operand reads as the variable it is.
using NameOf = std::map<std::pair<Area, uint32_t>, std::string>;

NameOf names_of(const Image& img) {
  NameOf m;
  for (const Alias& a : img.aliases) {
    Area bit = bit_area(a.dev.dev), word = word_area(a.dev.dev);
    if (bit != Area::Count) m.emplace(std::make_pair(bit, a.dev.index), a.name);
    if (word != Area::Count) m.emplace(std::make_pair(word, a.dev.index), a.name);
  }
  return m;
}

std::string operand_name(const Operand& o, const NameOf& names) {
  if (o.kind == OpdKind::Bit || o.kind == OpdKind::Int || o.kind == OpdKind::Real) {
    auto it = names.find({o.area, o.index});
    return it != names.end() ? it->second : point_name(o.area, o.index);
  }
  if (o.kind == OpdKind::Edge) return "E";  // the slot number is what moves
  return operand_text(o);
}

// ---------------------------------------------------------------- edge slots

// One edge slot and the element it belongs to.
struct EdgeSite {
  uint32_t slot;
  std::string kind;  // "P" "N" "CTU" "CTD"
  std::string dev;   // the bit it reads (by its variable's name if it has one), or the counter
  uint32_t rung;
  uint32_t nth;      // among the rung's slots of this kind and device
  int line;
  std::string text() const {
    std::string s = kind == "P" || kind == "N" ? "edge [" + kind + " " + dev + "]" : "counter edge " + kind + " " + dev;
    return line > 0 ? s + " (line " + std::to_string(line) + ")" : s;
  }
};

struct EdgeSites {
  std::vector<EdgeSite> sites;              // in program order
  std::vector<std::string> rung_text;       // each rung's instructions, slot numbers left out
  std::vector<std::string> rung_title;
};

EdgeSites edge_sites(const Image& img) {
  EdgeSites es;
  std::map<uint32_t, const LineEntry*> at;
  for (const LineEntry& e : img.lines) at.emplace(e.il_offset, &e);
  NameOf names = names_of(img);
  es.rung_title = img.rung_titles;
  auto text_of = [&](uint32_t r) -> std::string& {
    if (es.rung_text.size() <= r) es.rung_text.resize(r + 1);
    return es.rung_text[r];
  };
  std::map<std::tuple<uint32_t, std::string, std::string>, uint32_t> nth;
  uint32_t rung = 0;
  int line = 0;
  for (uint32_t off = 0; off < img.il.size();) {
    Instr in;
    uint32_t next = decode_instr(img.il, off, in);
    if (auto it = at.find(off); it != at.end()) rung = it->second->rung, line = it->second->line;
    std::string& t = text_of(rung);
    t += kOps[int(in.op)].name;
    if (in.ty != Ty::None) t += std::string(".") + ty_info(in.ty).name;
    for (int i = 0; i < in.nopd(); i++) t += " " + operand_name(in.a[i], names);
    t += "\n";
    std::string kind, dev;
    uint32_t slot = 0;
    if (in.op == Op::LOADP || in.op == Op::LOADF) {
      kind = in.op == Op::LOADP ? "P" : "N", dev = operand_name(in.a[0], names), slot = in.a[1].index;
    } else if (in.op == Op::CTU || in.op == Op::CTD) {
      kind = in.op == Op::CTU ? "CTU" : "CTD", dev = "C" + std::to_string(in.a[0].index), slot = in.a[2].index;
    }
    if (!kind.empty()) es.sites.push_back({slot, kind, dev, rung, nth[{rung, kind, dev}]++, line});
    off = next;
  }
  return es;
}

// {new site, old site} pairs: the same element of an unchanged rung, then of
// a rung with the same title, then by device in program order.
std::vector<std::pair<size_t, size_t>> match_edges(const EdgeSites& nw, const EdgeSites& old) {
  std::vector<bool> new_done(nw.sites.size()), old_done(old.sites.size());
  std::vector<std::pair<size_t, size_t>> out;
  auto pass = [&](auto key_of_new, auto key_of_old) {
    std::map<std::string, std::deque<size_t>> free;
    for (size_t j = 0; j < old.sites.size(); j++)
      if (!old_done[j]) {
        std::string k = key_of_old(j);
        if (!k.empty()) free[k].push_back(j);
      }
    for (size_t i = 0; i < nw.sites.size(); i++) {
      if (new_done[i]) continue;
      std::string k = key_of_new(i);
      auto it = k.empty() ? free.end() : free.find(k);
      if (it == free.end() || it->second.empty()) continue;
      size_t j = it->second.front();
      it->second.pop_front();
      new_done[i] = old_done[j] = true;
      out.push_back({i, j});
    }
  };
  auto site_key = [](const EdgeSite& s) { return s.kind + "\x1f" + s.dev + "\x1f" + std::to_string(s.nth) + "\x1f"; };
  auto text = [](const EdgeSites& e, uint32_t r) { return r < e.rung_text.size() ? e.rung_text[r] : std::string(); };
  auto title = [](const EdgeSites& e, uint32_t r) { return r < e.rung_title.size() ? e.rung_title[r] : std::string(); };
  pass([&](size_t i) { return site_key(nw.sites[i]) + text(nw, nw.sites[i].rung); },
       [&](size_t j) { return site_key(old.sites[j]) + text(old, old.sites[j].rung); });
  pass([&](size_t i) { std::string t = title(nw, nw.sites[i].rung); return t.empty() ? t : site_key(nw.sites[i]) + t; },
       [&](size_t j) { std::string t = title(old, old.sites[j].rung); return t.empty() ? t : site_key(old.sites[j]) + t; });
  pass([&](size_t i) { return nw.sites[i].kind + "\x1f" + nw.sites[i].dev; },
       [&](size_t j) { return old.sites[j].kind + "\x1f" + old.sites[j].dev; });
  return out;
}

// ---------------------------------------------------------------- variables

// A named variable's cells: one byte range (an alias), or a whole variable of
// the image's `vars` section (its bits in M or K, its cells in D or F).  I/O
// points (X Y WX WY), S, and timers and counters (carried by their device)
// are not variables here.
struct Range {
  bool shared;  // M, K: in the global image
  uint32_t off, size;
};
struct VarSite {
  std::string name;
  std::string type;
  std::vector<Range> ranges;
  std::string where;  // "D3"
  bool whole = false;  // from the `vars` section
};

bool overlaps(const VarSite& a, const VarSite& b) {
  for (const Range& x : a.ranges)
    for (const Range& y : b.ranges)
      if (x.off < y.off + y.size && y.off < x.off + x.size) return true;
  return false;
}

// Is alias `leaf` a part of variable `var` (var.x, var[1], var itself)?
bool part_of(const std::string& leaf, const std::string& var) {
  return leaf.size() >= var.size() && leaf.compare(0, var.size(), var) == 0 &&
         (leaf.size() == var.size() || leaf[var.size()] == '.' || leaf[var.size()] == '[');
}

std::optional<VarSite> alias_site(const Alias& a, const Layout& L) {
  Dev d = a.dev.dev;
  if (d != Dev::M && d != Dev::K && d != Dev::D && d != Dev::F) return std::nullopt;
  Area area = d == Dev::M ? Area::M : d == Dev::K ? Area::K : d == Dev::D ? Area::D : Area::F;
  uint32_t cells = area_is_bit(area) ? 1 : a.ty == Ty::None ? 1 : uint32_t(std::max(1, ty_info(a.ty).cells));
  if (uint64_t(a.dev.index) + cells > L.count[int(area)]) return std::nullopt;  // not a place of this layout
  VarSite v;
  v.name = a.name;
  v.ranges.push_back({area_is_bit(area), L.addr(area, a.dev.index), cells * L.elem_size(area)});
  // An untyped word is a DINT (REAL in F), an untyped bit a BOOL.
  v.type = a.ty != Ty::None ? ty_info(a.ty).name : area_is_bit(area) ? "BOOL" : area == Area::F ? "REAL" : "DINT";
  v.type += area_is_bit(area) ? "" : area == Area::F ? " in F" : " in D";
  v.where = point_name(area, a.dev.index);
  return v;
}

VarSite whole_site(const VarPlace& p, const Layout& L) {
  VarSite v;
  v.name = p.name, v.type = p.type, v.whole = true;
  if (p.cells != Area::Count) {
    v.ranges.push_back({false, L.addr(p.cells, p.cell_first), p.cell_count * L.elem_size(p.cells)});
    v.where = point_name(p.cells, p.cell_first);
  }
  if (p.bits != Area::Count) {
    v.ranges.push_back({true, L.addr(p.bits, p.bit_first), p.bit_count});
    if (v.where.empty()) v.where = point_name(p.bits, p.bit_first);
  }
  return v;
}

// The variables: the `vars` section's wholes when `wholes` (both images have
// one), and the aliases that are not part of one; `parts` gets the aliases
// that are (a whole whose type changed carries its parts one by one).
std::vector<VarSite> var_sites(const Image& img, bool wholes, std::vector<VarSite>* parts) {
  std::vector<VarSite> out;
  std::set<std::string> seen;
  if (wholes)
    for (const VarPlace& p : img.vars)
      if (seen.insert(p.name).second) out.push_back(whole_site(p, img.layout));
  for (const Alias& a : img.aliases) {
    std::optional<VarSite> v = alias_site(a, img.layout);
    if (!v) continue;
    bool in_whole = wholes && std::any_of(img.vars.begin(), img.vars.end(), [&](const VarPlace& p) { return part_of(a.name, p.name); });
    if (in_whole) {
      if (parts) parts->push_back(std::move(*v));
    } else if (seen.insert(a.name).second) {
      out.push_back(std::move(*v));
    }
  }
  return out;
}

// ---------------------------------------------------------------- initial memory

// The first-scan initialisation: of each rung that begins `[TRUE] LOAD S1`,
// the moves of constants that follow.
Program init_program(const Image& img) {
  std::map<uint32_t, uint32_t> rung_at;
  for (const LineEntry& e : img.lines) rung_at.emplace(e.il_offset, e.rung);
  Program p;
  std::vector<Instr> cur;
  enum { Start, Gated, Done } st = Start;
  uint32_t rung = UINT32_MAX;
  auto flush = [&] {
    if (st != Start && cur.size() > 1) {
      Rung r;
      r.code = std::move(cur);
      p.rungs.push_back(std::move(r));
    }
    cur.clear();
    st = Start;
  };
  for (uint32_t off = 0; off < img.il.size();) {
    Instr in;
    uint32_t next = decode_instr(img.il, off, in);
    auto it = rung_at.find(off);
    uint32_t r = it != rung_at.end() ? it->second : rung;
    if (r != rung) flush(), rung = r;
    bool konst = in.a[0].kind == OpdKind::ConstInt || in.a[0].kind == OpdKind::ConstReal || in.a[0].kind == OpdKind::ConstT;
    if (st == Start && cur.empty() && in.op == Op::TRUE) {
      cur.push_back(in);
    } else if (st == Start && in.op == Op::LOAD && in.a[0].area == Area::S && in.a[0].index == kBitFirstScan) {
      if (!cur.empty()) cur.clear();  // [TRUE] LOAD S1: the TRUE is its own condition, not needed
      cur.push_back(in), st = Gated;
    } else if (st == Gated && (in.op == Op::MOV || in.op == Op::TMOVE) && konst) {
      cur.push_back(in);
    } else if (st == Gated) {
      st = Done;
    } else if (st == Start) {
      cur.clear(), st = Done;
    }
    off = next;
  }
  flush();
  return p;
}

std::vector<uint8_t> run_init(const Image& img, const Program& init, uint8_t fill) {
  const Layout& L = img.layout;
  std::vector<uint8_t> mem(L.size, 0);
  for (Area a : {Area::M, Area::K, Area::D, Area::F})
    std::memset(mem.data() + L.offset[int(a)], fill, L.count[int(a)] * L.elem_size(a));
  if (init.rungs.empty()) return mem;
  mem[L.addr(Area::S, kBitFirstScan)] = 1;
  BinaryIl b = encode_il(init);
  if (!validate_il(b.code, L).empty()) return mem;  // cannot happen for a checked image's instructions
  Interpreter(b.code, L).scan(mem.data());
  return mem;
}

// Which bytes the first-scan initialisation writes: it is run on the
// variable areas filled with 0x00 and with 0xa5, and a byte it writes ends
// equal in both (only M K D F bytes are asked about).
std::vector<bool> initialised_bytes(const Image& img) {
  Program init = init_program(img);
  std::vector<uint8_t> a = run_init(img, init, 0x00), b = run_init(img, init, 0xa5);
  std::vector<bool> w(a.size());
  for (size_t i = 0; i < a.size(); i++) w[i] = a[i] == b[i];
  return w;
}

}  // namespace

std::vector<uint8_t> initial_memory(const Image& img) { return run_init(img, init_program(img), 0); }

// ---------------------------------------------------------------- the plan

CarryPlan plan_carry(const Image& old_img, const Image& new_img) {
  CarryPlan plan;
  CarryReport& rep = plan.report;
  // Edge slots.
  EdgeSites ne = edge_sites(new_img), oe = edge_sites(old_img);
  std::vector<bool> new_matched(ne.sites.size()), old_matched(oe.sites.size());
  for (auto [i, j] : match_edges(ne, oe)) {
    plan.edges.push_back({ne.sites[i].slot, oe.sites[j].slot});
    new_matched[i] = old_matched[j] = true;
    rep.edges_kept++;
  }
  for (size_t i = 0; i < ne.sites.size(); i++)
    if (!new_matched[i]) rep.added.push_back(ne.sites[i].text());
  for (size_t j = 0; j < oe.sites.size(); j++)
    if (!old_matched[j]) rep.dropped.push_back(oe.sites[j].text());
  // Named variables.
  const bool wholes = !old_img.vars.empty() && !new_img.vars.empty();
  std::vector<VarSite> new_parts, old_parts;
  std::vector<VarSite> nv = var_sites(new_img, wholes, &new_parts), ov = var_sites(old_img, wholes, &old_parts);
  std::map<std::string, const VarSite*> old_by_name, old_part_by_name;
  for (const VarSite& v : ov) old_by_name.emplace(v.name, &v);
  for (const VarSite& v : old_parts) old_part_by_name.emplace(v.name, &v);
  std::vector<uint8_t> init = initial_memory(new_img);
  std::vector<bool> written = initialised_bytes(new_img);
  auto fill = [&](const VarSite& v) {
    for (const Range& r : v.ranges)
      plan.fills.push_back({r.shared, r.off, std::vector<uint8_t>(init.begin() + r.off, init.begin() + r.off + r.size)});
  };
  auto copy = [&](const VarSite& from, const VarSite& to) {
    for (size_t i = 0; i < to.ranges.size(); i++)
      if (from.ranges[i].off != to.ranges[i].off)
        plan.copies.push_back({to.ranges[i].shared, from.ranges[i].off, to.ranges[i].off, to.ranges[i].size});
  };
  auto same_shape = [](const VarSite& a, const VarSite& b) {
    if (a.type != b.type || a.ranges.size() != b.ranges.size()) return false;
    for (size_t i = 0; i < a.ranges.size(); i++)
      if (a.ranges[i].size != b.ranges[i].size || a.ranges[i].shared != b.ranges[i].shared) return false;
    return true;
  };
  std::vector<const VarSite*> carried;
  std::set<std::string> in_new;
  for (const VarSite& v : nv) {
    in_new.insert(v.name);
    auto it = old_by_name.find(v.name);
    if (it == old_by_name.end()) continue;
    const VarSite& o = *it->second;
    if (!same_shape(o, v)) {
      fill(v);
      // A whole whose type changed: its parts of the same name and type are carried.
      size_t kept = 0;
      for (const VarSite& np : new_parts) {
        if (!v.whole || !part_of(np.name, v.name)) continue;
        auto op = old_part_by_name.find(np.name);
        if (op == old_part_by_name.end() || !part_of(op->first, o.name) || !same_shape(*op->second, np)) continue;
        plan.copies.push_back({np.ranges[0].shared, op->second->ranges[0].off, np.ranges[0].off, np.ranges[0].size});
        kept++;
      }
      rep.reset.push_back(v.name + " (" + o.type + " -> " + v.type + ": initial value" +
                          (kept ? ", " + std::to_string(kept) + " parts of the same name and type carried" : std::string()) + ")");
      continue;
    }
    rep.vars_kept++;
    carried.push_back(&v);
    if (o.ranges.empty() || o.ranges[0].off != v.ranges[0].off || (o.ranges.size() > 1 && o.ranges[1].off != v.ranges[1].off)) {
      copy(o, v);
      rep.moved.push_back(v.name + " " + o.where + " -> " + v.where);
    }
  }
  for (const VarSite& v : nv) {
    if (old_by_name.count(v.name)) continue;
    // A new variable: its initial value where its cells were another
    // variable's or the program initialises them; else the device as it is.
    bool other = std::any_of(ov.begin(), ov.end(), [&](const VarSite& o) { return overlaps(o, v); });
    bool inits = std::any_of(v.ranges.begin(), v.ranges.end(), [&](const Range& r) {
      return std::any_of(written.begin() + r.off, written.begin() + r.off + r.size, [](bool b) { return b; });
    });
    bool shares = std::any_of(carried.begin(), carried.end(), [&](const VarSite* c) { return overlaps(*c, v); });
    if ((other || inits) && !shares) fill(v);
    rep.added.push_back(v.name);
  }
  for (const VarSite& o : ov)
    if (!in_new.count(o.name)) rep.dropped.push_back(o.name);
  return plan;
}

void apply_carry(const CarryPlan& plan, const Layout& ol, const uint8_t* old_mem, const Layout& nl, uint8_t* new_mem,
                 uint8_t* global) {
  // Every area but the edge memory sits at the same offset in both.
  uint32_t e_old = ol.offset[int(Area::E)], e_new = nl.offset[int(Area::E)];
  std::memcpy(new_mem, old_mem, std::min(e_old, e_new));
  std::memset(new_mem + e_new, 0, nl.count[int(Area::E)]);
  for (auto [ns, os] : plan.edges)
    if (ns < nl.count[int(Area::E)] && os < ol.count[int(Area::E)]) new_mem[e_new + ns] = old_mem[e_old + os];
  // Old values are read before anything is written: moves may chain.
  std::vector<std::vector<uint8_t>> vals;
  for (const CarryPlan::Copy& c : plan.copies) {
    const uint8_t* src = (c.shared && global ? global : old_mem) + c.from;
    vals.emplace_back(src, src + c.size);
  }
  auto put = [&](bool shared, uint32_t off, const uint8_t* bytes, size_t n) {
    std::memcpy(new_mem + off, bytes, n);
    if (shared && global) std::memcpy(global + off, bytes, n);
  };
  for (const CarryPlan::Fill& f : plan.fills) put(f.shared, f.off, f.bytes.data(), f.bytes.size());
  for (size_t i = 0; i < plan.copies.size(); i++) put(plan.copies[i].shared, plan.copies[i].to, vals[i].data(), vals[i].size());
}

// ---------------------------------------------------------------- the report

std::string CarryReport::text() const {
  auto list = [](const std::vector<std::string>& v) {
    std::string s;
    size_t shown = std::min<size_t>(v.size(), 12);
    for (size_t i = 0; i < shown; i++) s += (i ? ", " : "") + v[i];
    if (v.size() > shown) s += ", and " + std::to_string(v.size() - shown) + " more";
    return s;
  };
  std::string s = "carried " + std::to_string(edges_kept) + " edge slot" + (edges_kept == 1 ? "" : "s") + " and " +
                  std::to_string(vars_kept) + " variable" + (vars_kept == 1 ? "" : "s") + ", devices by address";
  if (!moved.empty()) s += " (moved: " + list(moved) + ")";
  if (!added.empty()) s += "; new: " + list(added);
  if (!reset.empty()) s += "; reset: " + list(reset);
  if (!dropped.empty()) s += "; dropped: " + list(dropped);
  return s;
}

}  // namespace ldc::plc
