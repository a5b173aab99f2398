// The XML reader under the PLCopen importer: what it keeps, and where it
// reports what it refuses.
#include <gtest/gtest.h>

#include "frontend/plcopen/xml.h"
#include "ir/ir.h"

using namespace ldc;

namespace {

// The error as "line:col: message".
std::string error_of(const std::string& text) {
  try {
    xml::parse(text);
  } catch (const CompileError& e) {
    return std::to_string(e.line) + ":" + std::to_string(e.col) + ": " + e.what();
  }
  return "no error";
}

}  // namespace

TEST(Xml, ElementsAttributesText) {
  auto d = xml::parse("<?xml version='1.0' encoding='utf-8'?>\n<a x=\"1\" y='two'>hi<b/><c k=\"v\">t</c>!</a>");
  const xml::Element& a = *d.root;
  EXPECT_EQ(a.name, "a");
  EXPECT_EQ(a.line, 2);
  EXPECT_EQ(a.col, 1);
  ASSERT_NE(a.attr("x"), nullptr);
  EXPECT_EQ(*a.attr("x"), "1");
  EXPECT_EQ(*a.attr("y"), "two");
  EXPECT_EQ(a.attr("z"), nullptr);
  EXPECT_EQ(a.text, "hi!");
  ASSERT_EQ(a.children.size(), 2u);
  EXPECT_EQ(a.children[1]->text, "t");
  EXPECT_EQ(a.child("c")->parent, &a);
  EXPECT_EQ(a.children[1]->col, 24);
}

TEST(Xml, EntitiesCdataComments) {
  auto d = xml::parse("<a t=\"&lt;&amp;&gt;&quot;&apos;&#65;&#x42;\">x &lt; y<!-- no --><![CDATA[<raw & text>]]>&#xE9;</a>");
  EXPECT_EQ(*d.root->attr("t"), "<&>\"'AB");
  EXPECT_EQ(d.root->text, "x < y<raw & text>\xC3\xA9");
}

TEST(Xml, AttributeWhitespaceAndLineEnds) {
  auto d = xml::parse("<a v=\"1\t2\n3\">l1\r\nl2\rl3</a>");
  EXPECT_EQ(*d.root->attr("v"), "1 2 3");
  EXPECT_EQ(d.root->text, "l1\nl2\nl3");
}

TEST(Xml, NamespacesKeptAsPrefixes) {
  auto d = xml::parse("<project xmlns=\"http://www.plcopen.org/xml/tc6_0201\" xmlns:xhtml=\"x\"><xhtml:p>t</xhtml:p></project>");
  const xml::Element* p = d.root->children[0].get();
  EXPECT_EQ(p->name, "xhtml:p");
  EXPECT_EQ(p->local_name(), "p");
  EXPECT_EQ(d.root->child("p"), p);
  EXPECT_EQ(*d.root->attr("xmlns:xhtml"), "x");
}

TEST(Xml, Paths) {
  auto d = xml::parse("<r><a/><b><c/></b><a><c/><c/></a></r>");
  const xml::Element* a2 = d.root->children[2].get();
  EXPECT_EQ(a2->path(), "/r/a[2]");
  EXPECT_EQ(a2->children[1]->path(), "/r/a[2]/c[2]");
  EXPECT_EQ(d.root->children[1]->children[0]->path(), "/r/b/c");
}

TEST(Xml, BomPrologDoctypeAndProcessingInstructions) {
  auto d = xml::parse("\xEF\xBB\xBF<?xml version=\"1.0\"?><!-- c --><!DOCTYPE r><?pi data?><r><?pi x?></r><!-- end -->\n");
  EXPECT_EQ(d.root->name, "r");
}

TEST(Xml, Errors) {
  EXPECT_EQ(error_of("<a>\n  <b>\n</a>"), "3:1: </a> does not match <b> opened at line 2, column 3");
  EXPECT_EQ(error_of("<a>\n<b></b>"), "2:8: end of file inside element <a> opened at line 1");
  EXPECT_EQ(error_of("<a x='1' x='2'/>"), "1:10: attribute 'x' appears twice in <a>");
  EXPECT_EQ(error_of("<a>&nbsp;</a>"), "1:4: unknown entity '&nbsp;' (XML knows &lt; &gt; &amp; &quot; &apos; and &#N;)");
  EXPECT_EQ(error_of("<a>&#0;</a>"), "1:4: character reference '&#0;' is not an XML character");
  EXPECT_EQ(error_of("<a>a & b</a>"), "1:6: '&' must start a reference like &amp; or &#60; (write & as &amp;)");
  EXPECT_EQ(error_of("<a v='<'/>"), "1:7: '<' is not allowed in an attribute value (write &lt;)");
  EXPECT_EQ(error_of("<a><!-- x -- y --></a>"), "1:11: '--' is not allowed inside a comment");
  EXPECT_EQ(error_of("<a><![CDATA[x</a>"), "1:4: CDATA section is not closed with ']]>'");
  EXPECT_EQ(error_of("<a/><b/>"), "1:5: a second root element; an XML document has exactly one");
  EXPECT_EQ(error_of("<a/>text"), "1:5: text after the root element");
  EXPECT_EQ(error_of(""), "1:1: no root element: the file is not XML");
  EXPECT_EQ(error_of("  <?xml version='1.0'?><a/>"), "1:3: '<?xml ...?>' is only allowed at the very start of the file");
  EXPECT_EQ(error_of("<?xml version='1.0' encoding='UTF-16'?><a/>"), "1:21: encoding 'UTF-16' is not supported; save the file as UTF-8");
  EXPECT_EQ(error_of("<a b=1/>"), "1:6: expected a quoted value for attribute 'b'");
  EXPECT_EQ(error_of("<a\n  x='1'y='2'/>"), "2:8: expected a blank before the attribute");
  EXPECT_EQ(error_of("<!DOCTYPE r [<!ENTITY e 'x'>]><r/>"), "1:1: a DOCTYPE with an internal subset ('[...]') is not supported");
  EXPECT_EQ(error_of("</a>"), "1:1: end tag without a matching start tag");
  EXPECT_EQ(error_of("<a>]]></a>"), "1:4: ']]>' is not allowed in text");
  EXPECT_EQ(error_of("<1a/>"), "1:2: expected a name, found '1'");
}

TEST(Xml, DepthLimit) {
  std::string deep;
  for (int i = 0; i < xml::kMaxDepth + 1; i++) deep += "<a>";
  EXPECT_EQ(error_of(deep).substr(0, 9), "1:1537: e");
  std::string ok;
  for (int i = 0; i < xml::kMaxDepth; i++) ok += "<a>";
  for (int i = 0; i < xml::kMaxDepth; i++) ok += "</a>";
  EXPECT_NO_THROW(xml::parse(ok));
}
