#include "xml_dom.hpp"

#include <algorithm>
#include <cctype>
#include <tinyxml2.h>
#include <utility>
#include <vector>

namespace dreamsense::speech::xml {
namespace {

// What went wrong, in words (tinyxml2's own names are enum identifiers).
std::string describe(tinyxml2::XMLError e) {
  switch (e) {
    case tinyxml2::XML_ERROR_MISMATCHED_ELEMENT:
      return "end tag does not match the element it closes";
    case tinyxml2::XML_ERROR_PARSING_ELEMENT:
      return "malformed or unclosed element";
    case tinyxml2::XML_ERROR_PARSING_ATTRIBUTE:
      return "malformed attribute (values must be quoted)";
    case tinyxml2::XML_ERROR_PARSING_TEXT:
      return "malformed character data";
    case tinyxml2::XML_ERROR_PARSING_CDATA:
      return "unterminated CDATA section";
    case tinyxml2::XML_ERROR_PARSING_COMMENT:
      return "unterminated comment";
    case tinyxml2::XML_ERROR_PARSING_DECLARATION:
      return "malformed XML declaration";
    case tinyxml2::XML_ERROR_PARSING_UNKNOWN:
      return "malformed DOCTYPE or processing instruction";
    case tinyxml2::XML_ERROR_EMPTY_DOCUMENT:
      return "no root element";
    case tinyxml2::XML_ELEMENT_DEPTH_EXCEEDED:
      return "elements nested too deeply";
    default:
      return "malformed XML (an element left open, or the document ends early?)";
  }
}

// tinyxml2's detail after "Line number=N: " (e.g. "XMLElement name=one-of"), if any.
std::string detail(const tinyxml2::XMLDocument& doc) {
  const std::string s = doc.ErrorStr() ? doc.ErrorStr() : "";
  const auto at = s.find("Line number=");
  if (at == std::string::npos) return {};
  const auto colon = s.find(": ", at);
  return colon == std::string::npos ? std::string() : s.substr(colon + 2);
}

// tinyxml2 reports a mismatched end tag at the line of the element it should have closed
// (`name`, opened on `open_line`); this finds the offending end tag itself by a light scan of
// the text from there (comments, CDATA and processing instructions skipped). Returns its line
// and name, or line 0 when the scan does not find it.
std::pair<int, std::string> mismatched_end_tag(const std::string& text, int open_line,
                                               const std::string& name) {
  size_t pos = 0;
  for (int line = 1; line < open_line && pos != std::string::npos; ++line)
    pos = text.find('\n', pos) == std::string::npos ? std::string::npos : text.find('\n', pos) + 1;
  if (pos == std::string::npos) return {0, {}};
  auto name_at = [&](size_t i) {
    size_t j = i;
    while (j < text.size() && !std::isspace(static_cast<unsigned char>(text[j])) &&
           text[j] != '>' && text[j] != '/')
      ++j;
    return text.substr(i, j - i);
  };
  auto line_of = [&](size_t i) {
    return 1 +
           static_cast<int>(std::count(text.begin(), text.begin() + static_cast<long>(i), '\n'));
  };
  for (pos = text.find('<', pos); pos != std::string::npos; pos = text.find('<', pos + 1))
    if (name_at(pos + 1) == name) break;
  std::vector<std::string> open;
  for (; pos != std::string::npos; pos = text.find('<', pos + 1)) {
    if (text.compare(pos, 4, "<!--") == 0) {
      pos = text.find("-->", pos);
    } else if (text.compare(pos, 9, "<![CDATA[") == 0) {
      pos = text.find("]]>", pos);
    } else if (text.compare(pos, 2, "<?") == 0 || text.compare(pos, 2, "<!") == 0) {
      pos = text.find('>', pos);
    } else if (text.compare(pos, 2, "</") == 0) {
      const std::string n = name_at(pos + 2);
      if (open.empty()) return {0, {}};
      if (open.back() != n) return {line_of(pos), n};
      open.pop_back();
      if (open.empty()) return {0, {}};
    } else {
      const std::string n = name_at(pos + 1);
      const size_t end = text.find('>', pos);
      if (end == std::string::npos) return {0, {}};
      if (text[end - 1] != '/') open.push_back(n);
      pos = end;
    }
    if (pos == std::string::npos) break;
  }
  return {0, {}};
}

// An entity reference tinyxml2 left undecoded ("&name;" with a name XML does not define).
std::string unknown_entity(const std::string& text) {
  for (size_t i = text.find('&'); i != std::string::npos; i = text.find('&', i + 1)) {
    size_t j = i + 1;
    if (j >= text.size() || !std::isalpha(static_cast<unsigned char>(text[j]))) continue;
    while (j < text.size() && (std::isalnum(static_cast<unsigned char>(text[j])) ||
                               text[j] == '-' || text[j] == '_' || text[j] == '.'))
      ++j;
    if (j < text.size() && text[j] == ';') return text.substr(i, j + 1 - i);
  }
  return {};
}

Status convert(const tinyxml2::XMLElement& e, const std::string& source, Node& out) {
  out.name = e.Name();
  out.line = e.GetLineNum();
  for (const tinyxml2::XMLAttribute* a = e.FirstAttribute(); a != nullptr; a = a->Next())
    out.attributes[a->Name()] = a->Value();
  for (const tinyxml2::XMLNode* c = e.FirstChild(); c != nullptr; c = c->NextSibling()) {
    if (const auto* t = c->ToText()) {
      Node text;
      text.is_text = true;
      text.text = t->Value() ? t->Value() : "";
      text.line = t->GetLineNum();
      if (!t->CData())
        if (auto bad = unknown_entity(text.text); !bad.empty())
          return make_error(ErrorCode::kCorruptData, "{}:{}: unknown entity {}", source, text.line,
                            bad);
      out.children.push_back(std::move(text));
    } else if (const auto* child = c->ToElement()) {
      Node n;
      DS_RETURN_IF_ERROR(convert(*child, source, n));
      out.children.push_back(std::move(n));
    }  // comments, declarations, DOCTYPE: skipped
  }
  return ok_status();
}

}  // namespace

Result<Node> parse(const std::string& text, const std::string& source) {
  tinyxml2::XMLDocument doc(/*processEntities=*/true, tinyxml2::PRESERVE_WHITESPACE);
  const tinyxml2::XMLError e = doc.Parse(text.data(), text.size());
  if (e != tinyxml2::XML_SUCCESS) {
    const std::string more = detail(doc);
    const std::string prefix = "XMLElement name=";
    const std::string element =
        more.rfind(prefix, 0) == 0 ? more.substr(prefix.size()) : std::string();
    if (e == tinyxml2::XML_ERROR_MISMATCHED_ELEMENT && !element.empty()) {
      const auto [line, end_tag] = mismatched_end_tag(text, doc.ErrorLineNum(), element);
      if (line > 0)
        return make_error(ErrorCode::kCorruptData,
                          "{}:{}: end tag </{}> does not match <{}> opened on line {}", source,
                          line, end_tag, element, doc.ErrorLineNum());
      return make_error(ErrorCode::kCorruptData, "{}:{}: element <{}> is closed by another end tag",
                        source, doc.ErrorLineNum(), element);
    }
    if (e == tinyxml2::XML_ERROR_PARSING_ATTRIBUTE && !element.empty())
      return make_error(ErrorCode::kCorruptData,
                        "{}:{}: malformed attribute in <{}> (values must be quoted)", source,
                        doc.ErrorLineNum(), element);
    return make_error(ErrorCode::kCorruptData, "{}:{}: {}{}", source, doc.ErrorLineNum(),
                      describe(e), more.empty() ? "" : " (" + more + ")");
  }
  const tinyxml2::XMLElement* root = doc.RootElement();
  if (root == nullptr) return make_error(ErrorCode::kCorruptData, "{}:1: no root element", source);
  Node out;
  DS_RETURN_IF_ERROR(convert(*root, source, out));
  return out;
}

}  // namespace dreamsense::speech::xml
