// frontend/plcopen/xml.cpp -- the XML reader of xml.h: a single pass over the text with
// an explicit element stack (so nesting depth costs no native stack), exact
// well-formedness checks where a mistake would change the meaning (unclosed
// or mismatched tags, bad references, duplicate attributes, '<' in values),
// and every error at the line and column where it was found.
#include "frontend/plcopen/xml.h"

#include <algorithm>
#include <cctype>
#include <cstdint>

#include "ir/ir.h"

namespace ldc::xml {

std::string_view Element::local_name() const {
  size_t c = name.find(':');
  return c == std::string::npos ? std::string_view(name) : std::string_view(name).substr(c + 1);
}

const std::string* Element::attr(std::string_view n) const {
  for (const auto& a : attrs)
    if (a.first == n) return &a.second;
  return nullptr;
}

const Element* Element::child(std::string_view n) const {
  for (const auto& c : children)
    if (c->local_name() == n) return c.get();
  return nullptr;
}

std::vector<const Element*> Element::children_named(std::string_view n) const {
  std::vector<const Element*> v;
  for (const auto& c : children)
    if (c->local_name() == n) v.push_back(c.get());
  return v;
}

std::string Element::path() const {
  std::vector<const Element*> chain;
  for (const Element* e = this; e; e = e->parent) chain.push_back(e);
  std::string out;
  for (auto it = chain.rbegin(); it != chain.rend(); ++it) {
    const Element* e = *it;
    out += "/" + e->name;
    if (!e->parent) continue;
    int same = 0, index = 0;
    for (const auto& s : e->parent->children)
      if (s->name == e->name) {
        same++;
        if (s.get() == e) index = same;
      }
    if (same > 1) out += "[" + std::to_string(index) + "]";
  }
  return out;
}

namespace {

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r'; }
bool name_start(unsigned char c) { return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || c == '_' || c == ':' || c >= 0x80; }
bool name_char(unsigned char c) { return name_start(c) || (c >= '0' && c <= '9') || c == '-' || c == '.'; }

void put_utf8(std::string& s, uint32_t cp) {
  if (cp < 0x80) s += char(cp);
  else if (cp < 0x800) { s += char(0xC0 | (cp >> 6)); s += char(0x80 | (cp & 0x3F)); }
  else if (cp < 0x10000) { s += char(0xE0 | (cp >> 12)); s += char(0x80 | ((cp >> 6) & 0x3F)); s += char(0x80 | (cp & 0x3F)); }
  else { s += char(0xF0 | (cp >> 18)); s += char(0x80 | ((cp >> 12) & 0x3F)); s += char(0x80 | ((cp >> 6) & 0x3F)); s += char(0x80 | (cp & 0x3F)); }
}

class Reader {
 public:
  explicit Reader(std::string_view t) : t_(t) {
    line_start_.push_back(0);
    for (size_t i = 0; i < t.size(); i++)
      if (t[i] == '\n') line_start_.push_back(i + 1);
  }
  Document document();

 private:
  std::string_view t_;
  size_t p_ = 0;
  std::vector<size_t> line_start_;

  [[noreturn]] void fail_at(size_t off, const std::string& msg) const {
    size_t l = size_t(std::upper_bound(line_start_.begin(), line_start_.end(), off) - line_start_.begin());
    throw CompileError(int(l), int(off - line_start_[l - 1]) + 1, msg);
  }
  [[noreturn]] void fail(const std::string& msg) const { fail_at(p_, msg); }
  void where(Element& e, size_t off) const {
    size_t l = size_t(std::upper_bound(line_start_.begin(), line_start_.end(), off) - line_start_.begin());
    e.line = int(l);
    e.col = int(off - line_start_[l - 1]) + 1;
  }
  bool at(std::string_view s) const { return t_.compare(p_, s.size(), s) == 0; }
  bool eof() const { return p_ >= t_.size(); }
  void skip_space() {
    while (!eof() && is_space(t_[p_])) p_++;
  }
  std::string name() {
    if (eof() || !name_start((unsigned char)t_[p_])) fail(eof() ? "unexpected end of file, expected a name" : std::string("expected a name, found '") + t_[p_] + "'");
    size_t s = p_;
    while (!eof() && name_char((unsigned char)t_[p_])) p_++;
    return std::string(t_.substr(s, p_ - s));
  }
  // After '&': a reference, appended to out.
  void reference(std::string& out) {
    size_t amp = p_ - 1;
    size_t semi = t_.find(';', p_);
    if (semi == std::string_view::npos || semi - p_ > 12) fail_at(amp, "'&' must start a reference like &amp; or &#60; (write & as &amp;)");
    std::string_view r = t_.substr(p_, semi - p_);
    if (r == "lt") out += '<';
    else if (r == "gt") out += '>';
    else if (r == "amp") out += '&';
    else if (r == "quot") out += '"';
    else if (r == "apos") out += '\'';
    else if (!r.empty() && r[0] == '#') {
      bool hex = r.size() > 1 && r[1] == 'x';
      std::string_view digits = r.substr(hex ? 2 : 1);
      if (digits.empty()) fail_at(amp, "empty character reference '&" + std::string(r) + ";'");
      uint32_t cp = 0;
      for (char c : digits) {
        int d = (c >= '0' && c <= '9') ? c - '0' : hex && (c >= 'a' && c <= 'f') ? c - 'a' + 10
                : hex && (c >= 'A' && c <= 'F') ? c - 'A' + 10 : -1;
        if (d < 0) fail_at(amp, "bad character reference '&" + std::string(r) + ";'");
        cp = cp * (hex ? 16 : 10) + uint32_t(d);
        if (cp > 0x10FFFF) fail_at(amp, "character reference '&" + std::string(r) + ";' is outside Unicode");
      }
      bool ok = cp == 0x9 || cp == 0xA || cp == 0xD || (cp >= 0x20 && cp <= 0xD7FF) || (cp >= 0xE000 && cp <= 0xFFFD) || cp >= 0x10000;
      if (!ok) fail_at(amp, "character reference '&" + std::string(r) + ";' is not an XML character");
      put_utf8(out, cp);
    } else {
      fail_at(amp, "unknown entity '&" + std::string(r) + ";' (XML knows &lt; &gt; &amp; &quot; &apos; and &#N;)");
    }
    p_ = semi + 1;
  }
  void comment() {  // at "<!--"
    size_t start = p_;
    p_ += 4;
    size_t end = t_.find("--", p_);
    if (end == std::string_view::npos) fail_at(start, "comment '<!--' is not closed with '-->'");
    if (end + 2 >= t_.size() || t_[end + 2] != '>') fail_at(end, "'--' is not allowed inside a comment");
    p_ = end + 3;
  }
  void pi() {  // at "<?"
    size_t start = p_;
    p_ += 2;
    std::string target = name();
    std::string lower = target;
    for (char& c : lower) c = char(std::tolower((unsigned char)c));
    if (lower == "xml") fail_at(start, "'<?xml ...?>' is only allowed at the very start of the file");
    size_t end = t_.find("?>", p_);
    if (end == std::string_view::npos) fail_at(start, "processing instruction '<?" + target + "' is not closed with '?>'");
    p_ = end + 2;
  }
  void prolog_decl() {  // at "<?xml"
    size_t start = p_;
    size_t end = t_.find("?>", p_);
    if (end == std::string_view::npos) fail_at(start, "'<?xml' declaration is not closed with '?>'");
    p_ += 5;
    if (p_ < end && !is_space(t_[p_])) fail_at(start, "expected '<?xml version=\"1.0\" ...?>'");
    // version, encoding, standalone: pseudo-attributes
    bool version = false;
    while (true) {
      skip_space();
      if (p_ >= end) break;
      size_t ns = p_;
      std::string n = name();
      skip_space();
      if (eof() || t_[p_] != '=') fail("expected '=' after '" + n + "' in the XML declaration");
      p_++;
      skip_space();
      if (eof() || (t_[p_] != '"' && t_[p_] != '\'')) fail("expected a quoted value in the XML declaration");
      char q = t_[p_++];
      size_t ve = t_.find(q, p_);
      if (ve == std::string_view::npos || ve > end) fail("unterminated value in the XML declaration");
      std::string v(t_.substr(p_, ve - p_));
      p_ = ve + 1;
      if (n == "version") {
        if (v.rfind("1.", 0) != 0) fail_at(ns, "XML version '" + v + "' is not supported (1.x only)");
        version = true;
      } else if (n == "encoding") {
        std::string e = v;
        for (char& c : e) c = char(std::tolower((unsigned char)c));
        if (e != "utf-8" && e != "utf8" && e != "us-ascii" && e != "ascii")
          fail_at(ns, "encoding '" + v + "' is not supported; save the file as UTF-8");
      } else if (n != "standalone") {
        fail_at(ns, "unknown '" + n + "' in the XML declaration");
      }
    }
    if (!version) fail_at(start, "the XML declaration needs a version");
    p_ = end + 2;
  }
  void doctype() {  // at "<!DOCTYPE"
    size_t start = p_;
    size_t end = t_.find('>', p_);
    size_t bracket = t_.find('[', p_);
    if (bracket != std::string_view::npos && (end == std::string_view::npos || bracket < end))
      fail_at(start, "a DOCTYPE with an internal subset ('[...]') is not supported");
    if (end == std::string_view::npos) fail_at(start, "'<!DOCTYPE' is not closed with '>'");
    p_ = end + 1;
  }
  // Attribute value after the opening quote; normalizes white space to blanks.
  std::string attr_value(char q, size_t open) {
    std::string v;
    while (true) {
      if (eof()) fail_at(open, "attribute value is not closed");
      char c = t_[p_++];
      if (c == q) break;
      if (c == '<') fail_at(p_ - 1, "'<' is not allowed in an attribute value (write &lt;)");
      if (c == '&') { reference(v); continue; }
      if (c == '\r') {
        if (!eof() && t_[p_] == '\n') p_++;
        v += ' ';
      } else if (c == '\n' || c == '\t') v += ' ';
      else v += c;
    }
    return v;
  }
};

Document Reader::document() {
  Document doc;
  if (at("\xEF\xBB\xBF")) p_ = 3;
  if (at("<?xml") && p_ + 5 < t_.size() && (is_space(t_[p_ + 5]) || t_[p_ + 5] == '?')) prolog_decl();
  std::vector<Element*> stack;
  bool root_done = false;
  while (true) {
    if (stack.empty()) {
      // misc: blanks, comments, processing instructions (and one DOCTYPE before the root)
      skip_space();
      if (eof()) break;
      if (at("<!--")) { comment(); continue; }
      if (at("<?")) { pi(); continue; }
      if (at("<!DOCTYPE")) {
        if (root_done || doc.root) fail("DOCTYPE must come before the root element");
        doctype();
        continue;
      }
      if (t_[p_] != '<') fail(root_done ? "text after the root element" : "expected the root element '<...>'");
      if (root_done) fail("a second root element; an XML document has exactly one");
      if (at("</")) fail("end tag without a matching start tag");
      if (at("<!")) fail("unexpected '<!' outside the root element");
    }
    if (eof()) {
      const Element* open = stack.back();
      fail_at(t_.size(), "end of file inside element <" + open->name + "> opened at line " + std::to_string(open->line));
    }
    char c = t_[p_];
    if (c == '<') {
      if (at("<!--")) { comment(); continue; }
      if (at("<![CDATA[")) {
        size_t start = p_;
        size_t end = t_.find("]]>", p_ + 9);
        if (end == std::string_view::npos) fail_at(start, "CDATA section is not closed with ']]>'");
        std::string_view data = t_.substr(p_ + 9, end - p_ - 9);
        stack.back()->text_at.emplace_back(uint32_t(stack.back()->text.size()), uint32_t(p_ + 9));
        for (size_t i = 0; i < data.size(); i++) {
          if (data[i] == '\r') {
            stack.back()->text += '\n';
            if (i + 1 < data.size() && data[i + 1] == '\n') i++;
          } else stack.back()->text += data[i];
        }
        p_ = end + 3;
        continue;
      }
      if (at("<?")) { pi(); continue; }
      if (at("<!")) fail("unexpected '<!' (only comments and CDATA sections may appear here)");
      if (at("</")) {
        size_t start = p_;
        p_ += 2;
        std::string n = name();
        skip_space();
        if (eof() || t_[p_] != '>') fail("expected '>' to close </" + n);
        p_++;
        Element* open = stack.back();
        if (n != open->name)
          fail_at(start, "</" + n + "> does not match <" + open->name + "> opened at line " + std::to_string(open->line) +
                             ", column " + std::to_string(open->col));
        stack.pop_back();
        if (stack.empty()) root_done = true;
        continue;
      }
      // start tag
      size_t start = p_;
      p_++;
      auto e = std::make_unique<Element>();
      where(*e, start);
      e->name = name();
      while (true) {
        bool had_space = !eof() && is_space(t_[p_]);
        skip_space();
        if (eof()) fail_at(start, "start tag <" + e->name + " is not closed");
        if (t_[p_] == '>' || at("/>")) break;
        if (!had_space) fail("expected a blank before the attribute");
        size_t an = p_;
        std::string a = name();
        skip_space();
        if (eof() || t_[p_] != '=') fail("expected '=' after attribute '" + a + "'");
        p_++;
        skip_space();
        if (eof() || (t_[p_] != '"' && t_[p_] != '\'')) fail("expected a quoted value for attribute '" + a + "'");
        size_t open = p_;
        char q = t_[p_++];
        std::string v = attr_value(q, open);
        if (e->attr(a)) fail_at(an, "attribute '" + a + "' appears twice in <" + e->name + ">");
        e->attrs.emplace_back(std::move(a), std::move(v));
      }
      bool empty = at("/>");
      p_ += empty ? 2 : 1;
      Element* raw = e.get();
      if (stack.empty()) doc.root = std::move(e);
      else stack.back()->children.push_back(std::move(e));
      if (empty) {
        if (stack.empty()) root_done = true;
        continue;
      }
      if (int(stack.size()) + 1 > kMaxDepth) fail_at(start, "elements nested too deeply (more than " + std::to_string(kMaxDepth) + " levels)");
      stack.push_back(raw);
      continue;
    }
    // character data
    Element* cur = stack.back();
    cur->text_at.emplace_back(uint32_t(cur->text.size()), uint32_t(p_));
    while (!eof() && t_[p_] != '<') {
      char ch = t_[p_++];
      if (ch == '&') reference(cur->text);
      else if (ch == '\r') {
        if (!eof() && t_[p_] == '\n') p_++;
        cur->text += '\n';
      } else if (ch == ']' && at("]>")) {
        fail_at(p_ - 1, "']]>' is not allowed in text");
      } else cur->text += ch;
    }
  }
  if (!doc.root) fail_at(t_.size(), "no root element: the file is not XML");
  // parent links, now that nothing moves
  std::vector<Element*> todo{doc.root.get()};
  while (!todo.empty()) {
    Element* e = todo.back();
    todo.pop_back();
    for (auto& k : e->children) {
      k->parent = e;
      todo.push_back(k.get());
    }
  }
  return doc;
}

}  // namespace

Document parse(std::string_view text) { return Reader(text).document(); }

}  // namespace ldc::xml
