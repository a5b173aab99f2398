// frontend/plcopen/st_text.h -- a PLCopen project's declarations and its ST
// and IL bodies written as the text the ST and IEC IL readers take, every
// token placed back at its position in the XML file (docs/plcopen.md, "ST and
// IL POUs").  The PLCopen reader compiles an ST or IL POU through the typed
// reader (frontend/iecil/typed.cpp) this way, as Beremiz hands MatIEC the ST
// it generates from the XML.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "frontend/iecil/iecil.h"
#include "frontend/plcopen/xml.h"

namespace ldc::plcopen {

class StText {
 public:
  explicit StText(std::string_view file_text);
  // TYPE ... END_TYPE: every <dataType> of <dataTypes>.
  void data_types(const xml::Element* data_types);
  // A POU: its interface as declarations and its ST or IL body.
  void pou(const xml::Element* pou);
  // A line of ST of our own, its tokens placed at `at`.
  void line(const std::string& text, const xml::Element* at);
  // The text of an element (an inline ST condition), at its place in the file.
  void text(const xml::Element* text_el) { add_body(st_, text_el); }
  // Everything, read: the ST as IL tokens (st::to_il_tokens), then the IL
  // POUs.  Throws CompileError at the XML file's position.
  std::vector<iecil::Tok> tokens() const;
  // An XML <type>'s child (<INT/>, <array>, <derived name=.../> ...) as ST.
  std::string type(const xml::Element* t) const;

 private:
  struct Origin {
    int line = 1, col = 1;  // a line of our own: all its tokens here
    uint32_t off = 0;       // a line of a body: its first byte in the file
    bool exact = false;
  };
  struct Part {
    std::string text;
    std::vector<Origin> origin;  // per line of text
  };
  std::string_view file_;
  std::vector<uint32_t> line_starts_;
  Part st_, il_;

  void add(Part& p, const std::string& text, const xml::Element* at) const;
  void add_body(Part& p, const xml::Element* text_el) const;
  void interface(Part& p, const xml::Element* itf) const;
  void chart(Part& p, const xml::Element* pou, const xml::Element* sfc) const;
  std::string value(const xml::Element* v) const;
  std::string declaration(const xml::Element* var) const;
  void place(const Part& p, iecil::Tok& k) const;
  std::vector<iecil::Tok> lexed(const Part& p, bool st) const;
};

// The element holding an <ST> or <IL> body's text (its <xhtml:p>, or itself).
const xml::Element* body_text(const xml::Element* lang);

// The text of the inline ST of an SFC condition or action (<inline><ST>, or
// <inline><body><ST>), or null.
const xml::Element* inline_st_text(const xml::Element* e);
// The POU's action `name` (<actions><action name=...>), or null.
const xml::Element* pou_action(const xml::Element* pou, const std::string& name);

// Is `pou`'s body an SFC chart written in text alone -- steps, transitions
// whose conditions are inline ST, actions that are variables, inline ST or
// the POU's ST actions, and no LD/FBD element -- which StText writes as the
// chart as text that the ST reader takes (docs/plcopen.md, "SFC function blocks")?
bool text_chart(const xml::Element* pou);
// Has the chart of `pou` an action that is a body (inline, or one of the
// POU's <actions>) rather than a variable?
bool chart_action_bodies(const xml::Element* pou);

}  // namespace ldc::plcopen
