#pragma once
// SRGS 1.0 XML grammars (W3C Speech Recognition Grammar Specification, XML form) as used by
// DREAM (SA/config/Speechconfig.grxml, Microsoft Speech Platform), translated to JSGF for
// PocketSphinx, plus the mapping from recognised words back to the grammar's <tag> strings.
//
// Supported subset: <grammar root=...>, <rule id=... [scope=public|private]>, <one-of>, <item>
// (repeat="n", "m-n", "m-"; weight is ignored), <ruleref uri="#id"> (local rules only; the
// special rules NULL/VOID/GARBAGE are rejected), <tag> (its text is a literal output string, as
// with tag-format semantics/1.0-literals), plain-text tokens, <token>. Comments, <?xml ...?>,
// <!DOCTYPE ...>, <lexicon>, <meta>, <metadata> and <example> are skipped.
// Unbounded repeats become JSGF * / +; bounded ones are expanded (a a [a] for 2-3) because
// sphinxbase 0.8's JSGF compiler links a Kleene loop back to the start of the enclosing public
// rule, which over-generates.

#include "dreamsense/core/status.hpp"

#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace dreamsense::speech {

// One node of a grammar rule's body.
struct SrgsNode {
  enum class Kind { kToken, kSequence, kOneOf, kRuleRef, kTag };
  Kind kind = Kind::kSequence;
  std::string text;                // kToken: one lower-case word; kRuleRef: rule id; kTag: literal
  std::vector<SrgsNode> children;  // kSequence / kOneOf
  int min_repeat = 1;              // kSequence only (an <item repeat=...>)
  int max_repeat = 1;              // -1 = unbounded
  int line = 0;                    // source line (1-based) for messages
};

struct SrgsRule {
  std::string id;
  bool is_public = false;
  SrgsNode body;  // kSequence
};

class SrgsGrammar {
 public:
  // Parses SRGS XML. Errors (kCorruptData) are one line: "<source>:<line>: <problem>".
  static Result<SrgsGrammar> parse(const std::string& xml, const std::string& source = "<string>");
  static Result<SrgsGrammar> parse_file(const std::filesystem::path& path);

  const std::string& root() const { return root_; }
  const std::vector<SrgsRule>& rules() const { return rules_; }

  // The grammar as JSGF V1.0 text: one public rule <root>; every other rule private, rule names
  // sanitised to [A-Za-z0-9_]. Words are lower case.
  std::string to_jsgf(const std::string& grammar_name = "dreamsense") const;

  // The tag of the path that generates `words` (as the decoder returns them, lower case), i.e.
  // the last <tag> met along that path (semantics/1.0-literals); nullopt when the words are not
  // in the grammar, "" when they are but no tag lies on their path.
  std::optional<std::string> tag_for(const std::vector<std::string>& words) const;

 private:
  std::string root_;
  std::vector<SrgsRule> rules_;
  std::map<std::string, size_t> index_;
};

// Splits on white space and lower-cases (ASCII).
std::vector<std::string> split_words(const std::string& text);

}  // namespace dreamsense::speech
