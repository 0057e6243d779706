#pragma once
// The XML of SRGS grammars, parsed by tinyxml2 (Debian libtinyxml2-dev) into a small tree that
// records every element's and text's source line: elements, attributes, character data (the
// five predefined entities and numeric character references decoded; CDATA kept verbatim);
// comments, processing instructions and the DOCTYPE are skipped. Errors are one line,
// "<source>:<line>: <problem>", also for an entity XML does not define (&nbsp;), which
// tinyxml2 itself would pass through as text.

#include "dreamsense/core/status.hpp"

#include <map>
#include <string>
#include <vector>

namespace dreamsense::speech::xml {

struct Node {
  bool is_text = false;
  std::string name;  // element name (namespace prefix kept); empty for text
  std::map<std::string, std::string> attributes;
  std::string text;  // character data for text nodes (entities decoded)
  std::vector<Node> children;
  int line = 0;
};

// Returns the document's root element. Errors: kCorruptData, "<source>:<line>: <problem>".
Result<Node> parse(const std::string& text, const std::string& source);

}  // namespace dreamsense::speech::xml
