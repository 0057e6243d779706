#include "dreamsense/speech/srgs.hpp"

#include <gtest/gtest.h>

#include <filesystem>

namespace dreamsense::speech {
namespace {

const std::filesystem::path kData =
    std::filesystem::path(DREAMSENSE_SOURCE_DIR) / "modalities/speech/test/data";

std::string wrap(const std::string& rules, const std::string& root = "r") {
  return "<?xml version=\"1.0\"?>\n<grammar version=\"1.0\" root=\"" + root +
         "\" xmlns=\"http://www.w3.org/2001/06/grammar\">\n" + rules + "\n</grammar>\n";
}

TEST(Srgs, DreamLikeGrammarToJsgf) {
  auto g = SrgsGrammar::parse_file(kData / "speechconfig_like.grxml");
  ASSERT_TRUE(g) << g.error().to_string();
  EXPECT_EQ(g->root(), "rootRule");
  EXPECT_EQ(g->to_jsgf("dream"),
            "#JSGF V1.0;\n\ngrammar dream;\n\n"
            "public <rootRule> = ((broom | (vroom vroom)) | ((bye bye) | goodbye) | <move> | "
            "(ho [ho [ho]]));\n"
            "<move> = (go <direction> [please]);\n"
            "<direction> = (forward | backward);\n");
}

TEST(Srgs, TagsAreTheOutputs) {
  auto g = SrgsGrammar::parse_file(kData / "speechconfig_like.grxml");
  ASSERT_TRUE(g) << g.error().to_string();
  EXPECT_EQ(g->tag_for(split_words("vroom vroom")), "Broom,broom");
  EXPECT_EQ(g->tag_for(split_words("broom")), "Broom,broom");
  EXPECT_EQ(g->tag_for(split_words("Goodbye")), "Bye bye");
  EXPECT_EQ(g->tag_for(split_words("go backward please")), "go");
  EXPECT_EQ(g->tag_for(split_words("ho ho ho")), "ho");
  EXPECT_EQ(g->tag_for(split_words("ho ho ho ho")), std::nullopt);  // repeat max 3
  EXPECT_EQ(g->tag_for(split_words("vroom")), std::nullopt);
  EXPECT_EQ(g->tag_for({}), std::nullopt);
}

TEST(Srgs, RepeatForms) {
  auto g =
      SrgsGrammar::parse(wrap("<rule id=\"r\" scope=\"public\"><item repeat=\"1-\">a</item> "
                              "<item repeat=\"0-\">b</item> <item repeat=\"2\">c</item> "
                              "<item repeat=\"2-\">d</item></rule>"));
  ASSERT_TRUE(g) << g.error().to_string();
  EXPECT_EQ(g->to_jsgf("t"), "#JSGF V1.0;\n\ngrammar t;\n\npublic <r> = (a+ b* c c d d+);\n");
  EXPECT_TRUE(g->tag_for(split_words("a a c c d d d")).has_value());
  EXPECT_FALSE(g->tag_for(split_words("a c c d")).has_value());
  EXPECT_FALSE(g->tag_for(split_words("c c d d")).has_value());
}

// fuzz_grammar found repeat counts beyond int throwing out of std::stoi: now a clear error.
TEST(Srgs, HugeRepeatCountIsAnErrorNotACrash) {
  auto g =
      SrgsGrammar::parse(wrap("<rule id=\"r\" scope=\"public\"><item repeat=\"1-"
                              "99999999999999999999\">a</item></rule>"));
  ASSERT_FALSE(g);
  EXPECT_NE(g.error().to_string().find("bad repeat"), std::string::npos) << g.error().to_string();
}

TEST(Srgs, EntitiesTokensAndUntaggedPaths) {
  auto g =
      SrgsGrammar::parse(wrap("<rule id=\"r\"><token>Rock&amp;Roll</token> <!-- c --> it"
                              "<ruleref special=\"NULL\"/></rule>"));
  ASSERT_TRUE(g) << g.error().to_string();
  EXPECT_EQ(g->to_jsgf("t"), "#JSGF V1.0;\n\ngrammar t;\n\npublic <r> = (\"rock&roll\" it);\n");
  EXPECT_EQ(g->tag_for({"rock&roll", "it"}), "");  // in the grammar, no tag on the path
}

struct BadCase {
  const char* xml;
  const char* expect;  // substring of the message, includes the line number
};

TEST(Srgs, MalformedGrammarsGiveLineNumbers) {
  const BadCase cases[] = {
      {"<grammar root=\"r\">\n<rule id=\"r\">\n<one-of><item>a</item>\n</rule>\n</grammar>",
       "<string>:4: end tag </rule> does not match <one-of> opened on line 3"},
      {"<grammar root=\"r\">\n<rule id=\"r\">\n<ruleref uri=\"#nope\"/>\n</rule>\n</grammar>",
       "<string>:3: reference to undefined rule \"nope\""},
      {"<grammar root=\"x\">\n<rule id=\"r\">a</rule>\n</grammar>", "<string>:1: root rule \"x\""},
      {"<grammar>\n<rule id=\"r\">\n<item repeat=\"3-1\">a</item></rule></grammar>",
       "<string>:3: repeat=\"3-1\" has max < min"},
      {"<grammar>\n\n<rule id=\"r\"><one-of>text</one-of></rule></grammar>",
       "<string>:3: text directly inside <one-of>"},
      {"<grammar>\n<rule id=\"r\">a &nbsp; b</rule></grammar>",
       "<string>:2: unknown entity &nbsp;"},
      {"<grammar>\n<rule id=\"r\">\n<item>a</item>\n", "<string>:2: malformed XML"},
      {"<grammar>\n<rule id=\"r\" scope=public>a</rule></grammar>",
       "<string>:2: malformed attribute in <rule> (values must be quoted)"},
      {"<grammar>\n<!-- </rule> in a comment -->\n<rule id=\"r\"><item>a</rule>\n</grammar>",
       "<string>:3: end tag </rule> does not match <item> opened on line 3"},
      {"<grammar>\n<rule id=\"r\">a</rule>\n<![CDATA[", "<string>:3: unterminated CDATA"},
      {"<grammar>\n<rule id=\"r\">a</rule>\n<rule id=\"r\">b</rule></grammar>",
       "<string>:3: duplicate rule id \"r\""},
      {"<grammar>\n<rule>a</rule></grammar>", "<string>:2: <rule> without id"},
      {"<speak/>", "<string>:1: root element is <speak>"},
  };
  for (const auto& c : cases) {
    auto g = SrgsGrammar::parse(c.xml);
    ASSERT_FALSE(g) << c.xml;
    EXPECT_EQ(g.error().code, ErrorCode::kCorruptData);
    EXPECT_NE(g.error().message.find(c.expect), std::string::npos)
        << "got: " << g.error().message << "\nwant: " << c.expect;
  }
}

}  // namespace
}  // namespace dreamsense::speech
