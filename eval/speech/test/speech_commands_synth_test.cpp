// `eval speech --dataset speech-commands` end to end on a small synthetic set (espeak-ng voices
// of the held-out "test" half, written by the speech_synth fixture into the build tree).
// Synthetic speech is not the real test: the thresholds here only guard the plumbing, the
// silence check and the rejection of other words. Skips without espeak-ng.
#include "dreamsense/eval/speech_eval.hpp"

#include <gtest/gtest.h>

#include <filesystem>

namespace dreamsense::speech {
namespace {

TEST(SpeechCommandsSynthetic, TwelveClassJsonAndSaneNumbers) {
  const std::filesystem::path dir =
      std::filesystem::path(DREAMSENSE_BINARY_DIR) / "test_data/speech_commands_synth";
  if (!std::filesystem::exists(dir / "_silence_"))
    GTEST_SKIP() << "no synthetic set at " << dir << " (needs espeak-ng; made by speech_synth)";
  if (!std::filesystem::exists(RecognizerOptions{}.model_dir / "mdef"))
    GTEST_SKIP() << "needs pocketsphinx-en-us";
  SpeechEvalOptions o;
  o.dataset = "speech-commands";
  o.dir = dir;
  auto r = run_speech_eval(o);
  ASSERT_TRUE(r) << r.error().to_string();
  EXPECT_EQ(r->to_json()["task"], "speech");
  EXPECT_EQ(r->to_json()["dataset"]["name"], "speech-commands");
  const auto m = r->to_json()["metrics"];
  ASSERT_TRUE(m.contains("accuracy") && m.contains("false_accept_rate"));
  EXPECT_EQ(r->to_json()["per_class"].size(), 12u);
  for (const char* l : {"yes", "go", "_unknown_", "_silence_"})
    EXPECT_TRUE(r->to_json()["per_class"][l].contains("recall")) << l;
  EXPECT_GE(r->to_json()["per_class"]["_silence_"]["recall"].get<double>(), 0.99)
      << r->to_json()["items"].dump(1);
  EXPECT_LE(m["false_accept_rate"].get<double>(), 0.2) << r->to_json()["items"].dump(1);
  EXPECT_GE(m["accuracy"].get<double>(), 0.35) << r->to_json()["items"].dump(1);
  EXPECT_GT(r->to_json()["timing"]["rtf"].get<double>(), 0.0);
  EXPECT_LT(r->to_json()["timing"]["rtf"].get<double>(), 1.0);
}

}  // namespace
}  // namespace dreamsense::speech
