// frontend/plcopen/st_text.cpp -- see st_text.h.
#include "frontend/plcopen/st_text.h"

#include <algorithm>
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
  const Element* lang = body ? (body->child("ST") ? body->child("ST") : body->child("IL")) : nullptr;
  if (!lang) fail_at(pou, "POU '" + name + "' has no ST or IL body (" + pou->path() + ")");
  Part& p = lang->local_name() == "ST" ? st_ : il_;
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
  add_body(p, body_text(lang));
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
