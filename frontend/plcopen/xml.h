// frontend/plcopen/xml.h -- a small XML reader for the PLCopen importer: elements,
// attributes, character data, comments, CDATA sections, entity and character
// references, the <?xml ...?> prolog and other processing instructions.
// Namespaces are not resolved: a name keeps its prefix ("xhtml:p").
// Errors are CompileError(line, col, message), 1-based, columns in bytes.
#pragma once

#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace ldc::xml {

struct Element {
  std::string name;  // as written, prefix included
  std::vector<std::pair<std::string, std::string>> attrs;  // in document order, values decoded
  std::vector<std::unique_ptr<Element>> children;          // child elements in order
  std::string text;  // all character data directly inside (CDATA included), decoded
  // Where the runs of `text` begin: {offset in text, byte offset in the file},
  // one per run of character data or CDATA section (a body's ST or IL text is
  // read with its own positions: docs/plcopen.md "ST and IL POUs").
  std::vector<std::pair<uint32_t, uint32_t>> text_at;
  int line = 0, col = 0;  // of the '<' that opens the element
  const Element* parent = nullptr;

  // The name without its namespace prefix ("p" for "xhtml:p").
  std::string_view local_name() const;
  // The attribute's value, or nullptr.  Matches the name as written.
  const std::string* attr(std::string_view name) const;
  // The first child / all children whose local name is `name`.
  const Element* child(std::string_view name) const;
  std::vector<const Element*> children_named(std::string_view name) const;
  // "/project/types/pous/pou[2]/body/LD/contact[5]": each step is the name as
  // written, with a 1-based index among same-named siblings when there are several.
  std::string path() const;
};

struct Document {
  std::unique_ptr<Element> root;
};

// Parses a whole document.  Limits: nesting depth 512, input size as the caller
// checks.  Throws CompileError.
Document parse(std::string_view text);

constexpr int kMaxDepth = 512;

}  // namespace ldc::xml
