#pragma once
// A tiny XML reader for the SRGS subset: elements, attributes, character data, comments,
// CDATA, processing instructions and a DOCTYPE without an internal subset; the five predefined
// entities and numeric character references. Every element and text records its source line.
// Not a validating parser: enough for hand-written grammars, with line-numbered errors.

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
