#include "dreamsense/speech/recognizer.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

namespace dreamsense::speech {
namespace {

namespace fs = std::filesystem;
const fs::path kTestData = "/usr/share/pocketsphinx/test/data";  // pocketsphinx-testdata
const fs::path kFixtures = fs::path(DREAMSENSE_SOURCE_DIR) / "modalities/speech/test/data";

bool have_model() { return fs::exists(RecognizerOptions{}.model_dir / "mdef"); }

std::vector<int16_t> read_raw(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  in.seekg(0, std::ios::end);
  std::vector<int16_t> s(static_cast<size_t>(in.tellg()) / 2);
  in.seekg(0);
  in.read(reinterpret_cast<char*>(s.data()), static_cast<std::streamsize>(s.size() * 2));
  return s;
}

TEST(Recognizer, GoForwardUnderItsGrammar) {
  if (!have_model() || !fs::exists(kTestData / "goforward.raw"))
    GTEST_SKIP() << "needs pocketsphinx-en-us and pocketsphinx-testdata";
  auto g = Grammar::from_file(kTestData / "goforward.gram");
  ASSERT_TRUE(g) << g.error().to_string();
  auto rec = Recognizer::create({}, *g);
  ASSERT_TRUE(rec) << rec.error().to_string();
  const auto audio = read_raw(kTestData / "goforward.raw");
  auto r = (*rec)->recognize(std::span<const int16_t>(audio), 16000, Timestamp::from_seconds(10));
  ASSERT_TRUE(r) << r.error().to_string();
  ASSERT_TRUE(r->has_value());
  EXPECT_EQ((*r)->text, "go forward ten meters");
  EXPECT_EQ((*r)->tag, "go forward ten meters");
  EXPECT_GE((*r)->confidence, 0.5);
  EXPECT_LE((*r)->confidence, 1.0);
  EXPECT_GT((*r)->start, Timestamp::from_seconds(10));
  EXPECT_LT((*r)->start, (*r)->end);
  EXPECT_LE((*r)->end, Timestamp::from_seconds(10 + audio.size() / 16000.0 + 0.01));

  // The same clip at 8 kHz (decimated), resampled back to 16 kHz inside.
  const auto low = resample(audio, 16000, 8000);
  auto r8 = (*rec)->recognize(std::span<const int16_t>(low), 8000);
  ASSERT_TRUE(r8) << r8.error().to_string();
  ASSERT_TRUE(r8->has_value());
  EXPECT_EQ((*r8)->text, "go forward ten meters");
}

TEST(Recognizer, SilenceAndOutOfGrammarGiveNothing) {
  if (!have_model() || !fs::exists(kTestData / "something.raw"))
    GTEST_SKIP() << "needs pocketsphinx-en-us and pocketsphinx-testdata";
  auto g = Grammar::from_file(kTestData / "goforward.gram");
  ASSERT_TRUE(g);
  auto rec = Recognizer::create({}, *g);
  ASSERT_TRUE(rec) << rec.error().to_string();
  const std::vector<float> silence(32000, 0.0f);
  auto r = (*rec)->recognize(std::span<const float>(silence), 16000);
  ASSERT_TRUE(r) << r.error().to_string();
  EXPECT_FALSE(r->has_value());
  const auto other = read_raw(kTestData / "something.raw");
  auto o = (*rec)->recognize(std::span<const int16_t>(other), 16000);
  ASSERT_TRUE(o) << o.error().to_string();
  EXPECT_FALSE(o->has_value()) << (*o)->text;
}

TEST(Recognizer, SrgsGrammarCompilesAndMapsTags) {
  if (!have_model()) GTEST_SKIP() << "needs pocketsphinx-en-us";
  auto g = Grammar::from_file(kFixtures / "speechconfig_like.grxml");
  ASSERT_TRUE(g) << g.error().to_string();
  auto rec = Recognizer::create({}, *g);
  ASSERT_TRUE(rec) << rec.error().to_string();
  const std::vector<int16_t> silence(16000, 0);
  auto r = (*rec)->recognize(std::span<const int16_t>(silence), 16000);
  ASSERT_TRUE(r);
  EXPECT_FALSE(r->has_value());
}

TEST(Recognizer, SrgsTagOnRealSpeech) {
  if (!have_model() || !fs::exists(kTestData / "goforward.raw"))
    GTEST_SKIP() << "needs pocketsphinx-en-us and pocketsphinx-testdata";
  auto g = Grammar::from_srgs(R"(<?xml version="1.0"?>
<grammar version="1.0" xml:lang="en-US" root="top" tag-format="semantics/1.0-literals"
         xmlns="http://www.w3.org/2001/06/grammar">
  <rule id="top" scope="public">
    <one-of>
      <item>go <ruleref uri="#dir"/> <ruleref uri="#num"/> <item repeat="0-1">meters</item>
            <tag>MOVE</tag></item>
      <item>stop <tag>STOP</tag></item>
    </one-of>
  </rule>
  <rule id="dir"><one-of><item>forward</item><item>backward</item></one-of></rule>
  <rule id="num"><one-of><item>one</item><item>five</item><item>ten</item></one-of></rule>
</grammar>)",
                              "turtle.grxml");
  ASSERT_TRUE(g) << g.error().to_string();
  auto rec = Recognizer::create({}, *g);
  ASSERT_TRUE(rec) << rec.error().to_string();
  const auto audio = read_raw(kTestData / "goforward.raw");
  auto r = (*rec)->recognize(std::span<const int16_t>(audio), 16000);
  ASSERT_TRUE(r) << r.error().to_string();
  ASSERT_TRUE(r->has_value());
  EXPECT_EQ((*r)->text, "go forward ten meters");
  EXPECT_EQ((*r)->tag, "MOVE");
}

TEST(Recognizer, Errors) {
  RecognizerOptions bad;
  bad.model_dir = "/nonexistent/en-us";
  auto g = Grammar::from_jsgf("#JSGF V1.0;\ngrammar t;\npublic <a> = hello;\n");
  ASSERT_TRUE(g);
  auto r = Recognizer::create(bad, *g);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("/nonexistent/en-us"), std::string::npos);
  EXPECT_NE(r.error().message.find("pocketsphinx-en-us"), std::string::npos);

  RecognizerOptions o;
  o.garbage_phone_weight = 0;
  EXPECT_FALSE(o.check());
  if (!have_model()) GTEST_SKIP() << "needs pocketsphinx-en-us";
  auto oov = Grammar::from_jsgf("#JSGF V1.0;\ngrammar t;\npublic <a> = hello zzqxv;\n");
  auto r2 = Recognizer::create({}, *oov);
  ASSERT_FALSE(r2);
  EXPECT_NE(r2.error().message.find("zzqxv"), std::string::npos);
  auto broken = Grammar::from_jsgf("#JSGF V1.0;\ngrammar t;\npublic <a> = (hello;\n");
  auto r3 = Recognizer::create({}, *broken);
  ASSERT_FALSE(r3);
  EXPECT_EQ(r3.error().code, ErrorCode::kCorruptData);
  EXPECT_NE(r3.error().message.find("syntax error"), std::string::npos) << r3.error().message;
  auto undefined = Grammar::from_jsgf("#JSGF V1.0;\ngrammar t;\npublic <a> = hello <b>;\n");
  auto r4 = Recognizer::create({}, *undefined);
  ASSERT_FALSE(r4);
  EXPECT_EQ(r4.error().code, ErrorCode::kCorruptData) << r4.error().message;
  auto srgs = Grammar::from_srgs("<grammar>\n<rule id=\"a\">\n<one-of>\n</rule></grammar>");
  ASSERT_FALSE(srgs);
  EXPECT_NE(srgs.error().message.find("<string>:4:"), std::string::npos) << srgs.error().message;
}

TEST(Resample, PreservesATone) {
  std::vector<int16_t> tone(8000);
  for (size_t i = 0; i < tone.size(); ++i)
    tone[i] = static_cast<int16_t>(10000 * std::sin(2 * M_PI * 440 * i / 8000.0));
  const auto up = resample(tone, 8000, 16000);
  ASSERT_EQ(up.size(), 16000u);
  double err = 0;
  for (size_t i = 200; i < up.size() - 200; ++i)
    err = std::max(err, std::abs(up[i] - 10000 * std::sin(2 * M_PI * 440 * i / 16000.0)));
  EXPECT_LT(err, 60);
}

}  // namespace
}  // namespace dreamsense::speech
