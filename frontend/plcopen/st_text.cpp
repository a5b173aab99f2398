// frontend/plcopen/st_text.cpp -- see st_text.h.
#include "frontend/plcopen/st_text.h"

#include <algorithm>
#include <cstdlib>
#include <functional>
#include <map>
#include <set>

#include "frontend/st/st.h"

namespace ldc::plcopen {

using xml::Element;

namespace {

[[noreturn]] void fail_at(const Element* e, const std::string& msg) { throw CompileError(e->line, e->col, msg); }

// PLCopen's elementary type elements, spelled as ST spells them.
const std::set<std::string>& elementary() {
  static const std::set<std::string> k = {"BOOL", "SINT", "INT", "DINT", "LINT", "USINT", "UINT", "UDINT", "ULINT", "BYTE",
                                          "WORD", "DWORD", "LWORD", "REAL", "LREAL", "TIME", "LTIME", "DATE", "DT", "TOD"};
  return k;
}

const char* section_keyword(std::string_view s) {
  if (s == "inputVars") return "VAR_INPUT";
  if (s == "outputVars") return "VAR_OUTPUT";
  if (s == "inOutVars") return "VAR_IN_OUT";
  if (s == "localVars") return "VAR";
  if (s == "tempVars") return "VAR_TEMP";
  if (s == "externalVars") return "VAR_EXTERNAL";
  if (s == "globalVars") return "VAR_GLOBAL";
  return nullptr;
}

bool is_true(const std::string* a) { return a && (*a == "true" || *a == "1"); }

}  // namespace

const Element* body_text(const Element* lang) {
  for (const auto& c : lang->children)
    if (c->text.find_first_not_of(" \t\r\n") != std::string::npos) return c.get();
  return lang;
}

StText::StText(std::string_view file_text) : file_(file_text) {
  line_starts_.push_back(0);
  for (size_t i = 0; i < file_.size(); i++)
    if (file_[i] == '\n') line_starts_.push_back(uint32_t(i + 1));
}

void StText::add(Part& p, const std::string& text, const Element* at) const {
  std::string one = text;  // one line, whatever an attribute held
  std::replace(one.begin(), one.end(), '\n', ' ');
  std::replace(one.begin(), one.end(), '\r', ' ');
  p.text += one + "\n";
  p.origin.push_back({at->line, at->col, 0, false});
}

void StText::line(const std::string& text, const Element* at) { add(st_, text, at); }

// The body's lines, each placed at its first byte in the file.
void StText::add_body(Part& p, const Element* t) const {
  const std::string& s = t->text;
  for (size_t start = 0; start <= s.size();) {
    size_t end = s.find('\n', start);
    if (end == std::string::npos) end = s.size();
    Origin o{t->line, t->col, 0, false};
    auto seg = std::upper_bound(t->text_at.begin(), t->text_at.end(), std::make_pair(uint32_t(start), UINT32_MAX));
    if (seg != t->text_at.begin()) {
      --seg;
      o.off = seg->second + uint32_t(start - seg->first);
      o.exact = o.off < file_.size() || start == s.size();
    }
    p.text.append(s, start, end - start);
    p.text += "\n";
    p.origin.push_back(o);
    start = end + 1;
  }
}

std::string StText::type(const Element* t) const {
  std::string n(t->local_name());
  if (elementary().count(n)) return n;
  if (n == "string" || n == "wstring") {
    std::string s = n == "string" ? "STRING" : "WSTRING";
    if (const std::string* len = t->attr("length")) s += "[" + *len + "]";
    return s;
  }
  if (n == "derived") {
    if (!t->attr("name")) fail_at(t, "<derived> without a name (" + t->path() + ")");
    return *t->attr("name");
  }
  auto base = [&](const Element* e) {
    const Element* b = e->child("baseType");
    if (!b || b->children.empty()) fail_at(e, "<" + e->name + "> without its <baseType> (" + e->path() + ")");
    return type(b->children[0].get());
  };
  auto bound = [&](const Element* e, const char* which) {
    const std::string* v = e->attr(which);
    if (!v) fail_at(e, std::string("<") + e->name + "> without its " + which + " bound (" + e->path() + ")");
    return *v;
  };
  if (n == "array") {
    std::string dims;
    for (const Element* d : t->children_named("dimension")) dims += (dims.empty() ? "" : ", ") + bound(d, "lower") + ".." + bound(d, "upper");
    if (dims.empty()) fail_at(t, "an array without a <dimension> (" + t->path() + ")");
    return "ARRAY [" + dims + "] OF " + base(t);
  }
  if (n == "enum") {
    std::string vals;
    if (const Element* vs = t->child("values"))
      for (const Element* v : vs->children_named("value"))
        if (v->attr("name")) vals += (vals.empty() ? "" : ", ") + *v->attr("name");
    if (vals.empty()) fail_at(t, "an enumeration without values (" + t->path() + ")");
    return "(" + vals + ")";
  }
  if (n == "struct") {
    std::string s = "STRUCT";
    for (const Element* v : t->children_named("variable")) s += " " + declaration(v);
    return s + " END_STRUCT";
  }
  if (n == "subrangeSigned" || n == "subrangeUnsigned") {
    const Element* r = t->child("range");
    if (!r) fail_at(t, "a subrange without its <range> (" + t->path() + ")");
    return base(t) + " (" + bound(r, "lower") + ".." + bound(r, "upper") + ")";
  }
  fail_at(t, "type <" + t->name + "> is not one ldc reads in an ST or IL POU (" + t->path() + ")");
}

// An <initialValue>'s (or a <value>'s) content as an ST initial value.
std::string StText::value(const Element* v) const {
  if (const Element* s = v->child("simpleValue")) {
    if (!s->attr("value")) fail_at(s, "<simpleValue> without a value (" + s->path() + ")");
    return *s->attr("value");
  }
  if (const Element* a = v->child("arrayValue")) {
    std::string out;
    for (const Element* e : a->children_named("value")) {
      std::string x = value(e);
      if (const std::string* r = e->attr("repetitionValue")) x = *r + "(" + x + ")";
      out += (out.empty() ? "" : ", ") + x;
    }
    return "[" + out + "]";
  }
  if (const Element* s = v->child("structValue")) {
    std::string out;
    for (const Element* e : s->children_named("value")) {
      if (!e->attr("member")) fail_at(e, "a structure value without its member's name (" + e->path() + ")");
      out += (out.empty() ? "" : ", ") + *e->attr("member") + " := " + value(e);
    }
    return "(" + out + ")";
  }
  fail_at(v, "initial value <" + v->name + "> without a simple, array or structure value (" + v->path() + ")");
}

// NAME [AT address] : type [:= initial value];
std::string StText::declaration(const Element* var) const {
  const std::string* name = var->attr("name");
  if (!name || name->empty()) fail_at(var, "variable without a name (" + var->path() + ")");
  const Element* t = var->child("type");
  if (!t || t->children.empty()) fail_at(var, "variable '" + *name + "' has no type (" + var->path() + ")");
  std::string s = *name;
  if (const std::string* a = var->attr("address")) s += " AT " + *a;
  s += " : " + type(t->children[0].get());
  if (const Element* iv = var->child("initialValue")) s += " := " + value(iv);
  return s + ";";
}

void StText::interface(Part& p, const Element* itf) const {
  if (!itf) return;
  for (const auto& sec : itf->children) {
    const char* kw = section_keyword(sec->local_name());
    if (!kw) continue;  // returnType (in the header), documentation, addData
    std::string head = kw;
    if (is_true(sec->attr("constant"))) head += " CONSTANT";
    if (is_true(sec->attr("retain"))) head += " RETAIN";
    add(p, head, sec.get());
    for (const Element* v : sec->children_named("variable")) add(p, declaration(v), v);
    add(p, "END_VAR", sec.get());
  }
}

// ---------------------------------------------------------------- SFC as text

const Element* inline_st_text(const Element* e) {
  const Element* in = e ? e->child("inline") : nullptr;
  if (!in) return nullptr;
  const Element* b = in->child("body") ? in->child("body") : in;
  const Element* st = b->child("ST");
  return st ? body_text(st) : nullptr;
}

const Element* pou_action(const Element* pou, const std::string& name) {
  if (const Element* acts = pou->child("actions"))
    for (const Element* a : acts->children_named("action"))
      if (a->attr("name") && iecil::upper(*a->attr("name")) == iecil::upper(name)) return a;
  return nullptr;
}

namespace {

const Element* sfc_body(const Element* pou) {
  const Element* body = pou->child("body");
  return body ? body->child("SFC") : nullptr;
}

// The chart's elements by localId, and what each follows (its connections in).
struct ChartGraph {
  std::map<int, const Element*> el;
  std::map<int, std::vector<int>> in;
  std::vector<int> order;  // localIds in document order
  explicit ChartGraph(const Element* sfc) {
    for (const auto& c : sfc->children) {
      const std::string* id = c->attr("localId");
      if (!id) continue;
      int n = std::atoi(id->c_str());
      el[n] = c.get(), order.push_back(n);
      for (const Element* cpi : c->children_named("connectionPointIn"))
        for (const Element* cn : cpi->children_named("connection"))
          if (auto r = cn->attr("refLocalId")) in[n].push_back(std::atoi(r->c_str()));
    }
  }
  std::string kind(int id) const { auto it = el.find(id); return it == el.end() ? "" : std::string(it->second->local_name()); }
  std::vector<int> after(int id) const {
    std::vector<int> v;
    for (int n : order)
      if (auto i = in.find(n); i != in.end() && kind(n) != "actionBlock" && std::count(i->second.begin(), i->second.end(), id)) v.push_back(n);
    return v;
  }
};

}  // namespace

bool text_chart(const Element* pou) {
  const Element* sfc = sfc_body(pou);
  if (!sfc) return false;
  static const std::set<std::string> chart = {"step", "transition", "selectionDivergence", "selectionConvergence",
                                              "simultaneousDivergence", "simultaneousConvergence", "jumpStep", "actionBlock",
                                              "comment", "documentation", "addData"};
  for (const auto& c : sfc->children) {
    std::string k(c->local_name());
    if (!chart.count(k)) return false;  // an LD/FBD element: a condition drawn in the graph
    if (k == "transition" && !inline_st_text(c->child("condition"))) return false;
  }
  return true;
}

bool chart_action_bodies(const Element* pou) {
  const Element* sfc = sfc_body(pou);
  if (!sfc) return false;
  for (const Element* ab : sfc->children_named("actionBlock"))
    for (const Element* a : ab->children_named("action")) {
      const Element* ref = a->child("reference");
      if (a->child("inline") || (ref && ref->attr("name") && pou_action(pou, *ref->attr("name")))) return true;
    }
  return false;
}

// The chart as text (frontend/st/sfc_text.h), in Beremiz's order
// (PLCGenerator.ComputeSFCStep): from each initial step, the step with its
// associations, its actions' bodies, then its transitions (in document order),
// each followed by the steps it leads to.  A step no transition reaches is
// not written (nor run), as there.
void StText::chart(Part& p, const Element* pou, const Element* sfc) const {
  ChartGraph g(sfc);
  auto name_of = [&](int id) { return *g.el.at(id)->attr("name"); };
  std::map<std::string, int> step_named;
  for (int id : g.order)
    if (g.kind(id) == "step") {
      if (!g.el[id]->attr("name")) fail_at(g.el[id], "step without a name (" + g.el[id]->path() + ")");
      step_named[iecil::upper(name_of(id))] = id;
    }
  // a transition's source steps (back through divergences and simultaneous
  // convergences); `work` bounds the walks of a hostile graph of many branches
  long work = 0;
  std::function<void(int, std::vector<int>&, int)> sources = [&](int id, std::vector<int>& out, int depth) {
    if (depth > 64 || ++work > 100000) fail_at(g.el[id], "divergences nested past 64, or looping (" + g.el[id]->path() + ")");
    for (int r : g.in[id]) {
      std::string k = g.kind(r);
      if (k == "step") out.push_back(r);
      else if (k == "selectionDivergence" || k == "simultaneousConvergence") sources(r, out, depth + 1);
      else fail_at(g.el[id], "localId " + std::to_string(id) + " follows " + (k.empty() ? "nothing" : k) + "; a transition follows steps (" + g.el[id]->path() + ")");
    }
  };
  // the steps a transition leads to (forward through convergences, simultaneous divergences, jumps)
  std::function<void(int, std::vector<int>&, int)> targets = [&](int id, std::vector<int>& out, int depth) {
    if (depth > 64 || ++work > 100000) fail_at(g.el[id], "convergences nested past 64, or looping (" + g.el[id]->path() + ")");
    for (int n : g.after(id)) {
      std::string k = g.kind(n);
      if (k == "step") out.push_back(n);
      else if (k == "selectionConvergence" || k == "simultaneousDivergence") targets(n, out, depth + 1);
      else if (k == "jumpStep") {
        const std::string* t = g.el[n]->attr("targetName");
        if (!t || !step_named.count(iecil::upper(*t))) fail_at(g.el[n], "a jump to an unknown step (" + g.el[n]->path() + ")");
        out.push_back(step_named[iecil::upper(*t)]);
      } else if (k != "transition") {
        fail_at(g.el[n], k + " after a transition (" + g.el[n]->path() + ")");
      }
    }
  };
  std::map<int, std::vector<int>> from, to, of_step;  // transition -> steps; step -> its transitions
  for (int id : g.order)
    if (g.kind(id) == "transition") {
      sources(id, from[id], 0), targets(id, to[id], 0);
      if (from[id].empty() || to[id].empty()) fail_at(g.el[id], "transition localId " + std::to_string(id) + " without a step before and after it (" + g.el[id]->path() + ")");
      for (int s : from[id]) of_step[s].push_back(id);
    }
  auto step_list = [&](const std::vector<int>& v) {
    if (v.size() == 1) return name_of(v[0]);
    std::string s;
    for (int x : v) s += (s.empty() ? "(" : ", ") + name_of(x);
    return s + ")";
  };
  std::set<int> done_steps, done_trs;
  std::set<std::string> done_actions;
  int inline_no = 0;
  std::map<const Element*, std::string> inline_name;  // an inline <action>: STEP_INLINEn, numbered in document order
  for (int id : g.order)
    if (g.kind(id) == "actionBlock")
      for (const Element* a : g.el[id]->children_named("action"))
        if (inline_st_text(a) && !g.in[id].empty() && g.kind(g.in[id][0]) == "step")
          inline_name[a] = iecil::upper(name_of(g.in[id][0])) + "_INLINE" + std::to_string(++inline_no);
  std::function<void(int)> step = [&](int s) {
    if (!done_steps.insert(s).second) return;
    const Element* se = g.el[s];
    add(p, std::string(is_true(se->attr("initialStep")) ? "INITIAL_STEP " : "STEP ") + name_of(s) + ":", se);
    std::vector<std::pair<std::string, const Element*>> bodies;  // ACTIONs to write after the step
    for (int ab : g.order) {
      if (g.kind(ab) != "actionBlock" || g.in[ab].size() != 1 || g.in[ab][0] != s) continue;
      for (const Element* a : g.el[ab]->children_named("action")) {
        std::string q = a->attr("qualifier") ? *a->attr("qualifier") : "N";
        std::string n;
        if (inline_name.count(a)) {
          n = inline_name[a];
          bodies.push_back({n, inline_st_text(a)});
        } else if (const Element* ref = a->child("reference"); ref && ref->attr("name")) {
          n = *ref->attr("name");
          if (const Element* act = pou_action(pou, n)) {
            const Element* b = act->child("body");
            if (!b || !b->child("ST")) fail_at(a, "action '" + n + "' of step '" + name_of(s) + "' is not written in ST; ldc reads a chart's action bodies written in ST (" + a->path() + ")");
            bodies.push_back({n, body_text(b->child("ST"))});
          }
        } else {
          fail_at(a, "an action of step '" + name_of(s) + "' that is neither inline ST nor a reference (" + a->path() + ")");
        }
        std::string args = q;
        if (const std::string* d = a->attr("duration")) args += ", " + *d;
        if (const std::string* ind = a->attr("indicator")) args += ", " + *ind;
        add(p, "  " + n + "(" + args + ");", a);
      }
    }
    add(p, "END_STEP", se);
    for (const auto& [n, text] : bodies) {
      if (!done_actions.insert(iecil::upper(n)).second) continue;
      add(p, "ACTION " + n + ":", text);
      add_body(p, text);
      add(p, "END_ACTION", text);
    }
    for (int t : of_step[s]) {
      if (!done_trs.insert(t).second) continue;
      const Element* te = g.el[t];
      std::string head = "TRANSITION";
      if (const std::string* pr = te->attr("priority")) head += " (PRIORITY := " + *pr + ")";
      add(p, head + " FROM " + step_list(from[t]) + " TO " + step_list(to[t]), te);
      add(p, ":=", te);
      add_body(p, inline_st_text(te->child("condition")));
      add(p, ";", te);
      add(p, "END_TRANSITION", te);
      for (int n : to[t]) step(n);
    }
  };
  bool initial = false;
  for (int id : g.order)
    if (g.kind(id) == "step" && is_true(g.el[id]->attr("initialStep"))) step(id), initial = true;
  if (!initial) fail_at(sfc, "the SFC body of POU '" + *pou->attr("name") + "' has no initial step (" + sfc->path() + ")");
}

void StText::data_types(const Element* dts) {
  if (!dts || dts->children_named("dataType").empty()) return;
  add(st_, "TYPE", dts);
  for (const Element* dt : dts->children_named("dataType")) {
    const Element* b = dt->child("baseType");
    if (!b || b->children.empty()) fail_at(dt, "data type without its <baseType> (" + dt->path() + ")");
    std::string s = *dt->attr("name") + " : " + type(b->children[0].get());
    if (const Element* iv = dt->child("initialValue")) s += " := " + value(iv);
    add(st_, s + ";", dt);
  }
  add(st_, "END_TYPE", dts);
}

void StText::pou(const Element* pou) {
  const std::string& name = *pou->attr("name");
  std::string kind = pou->attr("pouType") ? *pou->attr("pouType") : "program";
  const Element* body = pou->child("body");
  const Element* sfc = text_chart(pou) ? sfc_body(pou) : nullptr;
  const Element* lang = body ? (body->child("ST") ? body->child("ST") : body->child("IL")) : nullptr;
  if (!lang && !sfc) fail_at(pou, "POU '" + name + "' has no ST or IL body (" + pou->path() + ")");
  Part& p = sfc || lang->local_name() == "ST" ? st_ : il_;
  const Element* itf = pou->child("interface");
  if (kind == "functionBlock") {
    add(p, "FUNCTION_BLOCK " + name, pou);
  } else if (kind == "function") {
    const Element* rt = itf ? itf->child("returnType") : nullptr;
    if (!rt || rt->children.empty()) fail_at(pou, "function '" + name + "' has no return type (" + pou->path() + ")");
    add(p, "FUNCTION " + name + " : " + type(rt->children[0].get()), pou);
  } else {
    add(p, "PROGRAM " + name, pou);
  }
  interface(p, itf);
  if (sfc) chart(p, pou, sfc);
  else add_body(p, body_text(lang));
  add(p, kind == "functionBlock" ? "END_FUNCTION_BLOCK" : kind == "function" ? "END_FUNCTION" : "END_PROGRAM", pou);
}

// Token k of part p, moved from its line of p to its place in the file.
void StText::place(const Part& p, iecil::Tok& k) const {
  if (k.line < 1 || size_t(k.line) > p.origin.size()) {  // the End token
    const Origin& o = p.origin.empty() ? Origin{} : p.origin.back();
    k.line = o.line, k.col = o.col;
    return;
  }
  const Origin& o = p.origin[size_t(k.line) - 1];
  if (!o.exact) {
    k.line = o.line, k.col = o.col;
    return;
  }
  uint32_t off = o.off + uint32_t(k.col - 1);
  auto ln = std::upper_bound(line_starts_.begin(), line_starts_.end(), off) - 1;
  k.line = int(ln - line_starts_.begin()) + 1;
  k.col = int(off - *ln) + 1;
}

std::vector<iecil::Tok> StText::lexed(const Part& p, bool st) const {
  std::vector<iecil::Tok> t;
  try {
    t = st ? st::lex(p.text) : iecil::lex(p.text);
  } catch (const CompileError& e) {
    iecil::Tok at;
    at.line = e.line, at.col = e.col;
    place(p, at);
    throw CompileError(at.line, at.col, e.what());
  }
  for (iecil::Tok& k : t) place(p, k);
  return t;
}

std::vector<iecil::Tok> StText::tokens() const {
  std::vector<iecil::Tok> out;
  if (!st_.text.empty()) out = st::to_il_tokens(lexed(st_, true));
  if (!il_.text.empty()) {
    if (!out.empty()) out.pop_back();  // its End
    std::vector<iecil::Tok> il = lexed(il_, false);
    out.insert(out.end(), il.begin(), il.end());
  }
  return out;
}

}  // namespace ldc::plcopen
