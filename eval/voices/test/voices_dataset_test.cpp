// Dataset check (label dataset): speaker identification on FSDD with 10 enrolment recordings per
// speaker, and the open set with one speaker held out. Skips cleanly without the data.

#include "dreamsense/eval/voice_eval.hpp"

#include <gtest/gtest.h>

#include <cstdlib>

namespace dreamsense::voice_id {
namespace {

std::filesystem::path fsdd_dir() {
  if (const char* d = std::getenv("DREAMSENSE_DATA")) return std::filesystem::path(d) / "fsdd";
  return std::filesystem::path(DREAMSENSE_SOURCE_DIR) / "../shared/data/fsdd";
}

TEST(VoiceIdDataset, FsddClosedSetWithTenEnrolmentRecordings) {
  VoiceEvalOptions o;
  o.dataset = "fsdd";
  o.dir = fsdd_dir();
  if (!std::filesystem::exists(o.dir / "recordings"))
    GTEST_SKIP() << "FSDD absent (" << o.dir << "); set DREAMSENSE_DATA";
  o.enroll = 10;
  auto r = run_voice_eval(o);
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_GE(r->metrics["accuracy"].get<double>(), 0.95) << r->per_class.dump();  // 0.978 measured
  EXPECT_GT(r->items, 1000u);
}

TEST(VoiceIdDataset, FsddHeldOutSpeakerIsMostlyRejected) {
  VoiceEvalOptions o;
  o.dataset = "fsdd";
  o.dir = fsdd_dir();
  if (!std::filesystem::exists(o.dir / "recordings"))
    GTEST_SKIP() << "FSDD absent (" << o.dir << "); set DREAMSENSE_DATA";
  o.enroll = 10;
  o.unknown = {"nicolas"};
  auto r = run_voice_eval(o);
  ASSERT_TRUE(r) << r.error().message;
  const auto& m = r->metrics;
  EXPECT_GE(m["accuracy"].get<double>(), 0.9);                                    // 0.957 measured
  EXPECT_GE(m["unknown_reject_rate"].get<double>(), 0.3) << r->per_class.dump();  // 0.52 measured
}

}  // namespace
}  // namespace dreamsense::voice_id
