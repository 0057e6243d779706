#include "dreamsense/actions/online.hpp"

#include <gtest/gtest.h>

#include "synthetic_body.hpp"

namespace dreamsense::actions {
namespace {

using test::BodyParams;
using test::Motion;

std::shared_ptr<const ActionModel> small_model() {
  std::vector<LabelledSequence> ex;
  for (int s = 0; s < 6; ++s)
    for (auto [motion, label] :
         {std::pair{Motion::kStill, "none"}, std::pair{Motion::kWaveRight, "wave"},
          std::pair{Motion::kArmsUp, "hands_on_head"}}) {
      BodyParams p;
      p.seed = 10 + static_cast<uint64_t>(s);
      p.scale = 0.6 + 0.08 * s;
      p.speed = 0.8 + 0.1 * s;
      p.noise_m = 0.01;
      ex.push_back({label, "s" + std::to_string(s), "", test::sequence(motion, 0.3 * s, 1.0, p)});
    }
  ActionModelOptions o;
  o.window_s = 1.0;
  auto m = ActionModel::train(ex, o);
  EXPECT_TRUE(m) << m.error().message;
  return std::make_shared<const ActionModel>(std::move(*m));
}

TEST(Online, AnswersNoneUntilTheWindowFillsThenTheAction) {
  auto c = OnlineActionClassifier::create(small_model(), nullptr);
  ASSERT_TRUE(c) << c.error().message;
  BodyParams p;
  p.seed = 99;
  const auto seq = test::sequence(Motion::kWaveRight, 0, 3.0, p);
  int waves = 0, after = 0;
  for (const auto& f : seq) {
    const ActionResult r = c->push(f);
    if (f.stamp_ns < 500'000'000) {
      EXPECT_FALSE(r.ready);
      EXPECT_EQ(r.label, "none");
      EXPECT_EQ(r.dream_id, 0);
    }
    if (f.stamp_ns >= 1'000'000'000) {
      ++after;
      waves += r.label == "wave";

      EXPECT_TRUE(r.ready);
      EXPECT_EQ(r.scores.size(), 3u);
      if (r.label == "wave") {
        EXPECT_EQ(r.dream_id, 1);
      }
    }
  }
  EXPECT_GE(waves, after * 9 / 10);
}

TEST(Online, GapsClearTheHistoryAndOldFramesAreIgnored) {
  auto c = OnlineActionClassifier::create(small_model(), nullptr);
  ASSERT_TRUE(c);
  BodyParams p;
  const auto seq = test::sequence(Motion::kArmsUp, 0, 1.5, p);
  ActionResult last;
  for (const auto& f : seq) last = c->push(f);
  EXPECT_TRUE(last.ready);
  // The same stamp again: ignored, same answer.
  const ActionResult again = c->push(seq.back());
  EXPECT_EQ(again.stamp_ns, last.stamp_ns);
  // One second later (gap > max_gap_s): history restarts, not ready.
  auto later = test::body_at(Motion::kArmsUp, 2.6, p);
  EXPECT_FALSE(c->push(later).ready);
}

TEST(Online, MissingBodyGivesNoneNotAnError) {
  auto c = OnlineActionClassifier::create(small_model(), nullptr);
  ASSERT_TRUE(c);
  for (int i = 0; i < 60; ++i) {
    SkeletonFrame f;  // all joints missing
    f.stamp_ns = i * 33'333'333LL;
    const ActionResult r = c->push(f);
    EXPECT_EQ(r.label, "none");
    EXPECT_FALSE(r.ready);
  }
}

TEST(Online, DreamIdsFollowPrimitiveF20) {
  EXPECT_EQ(dream_trajectory_id("none"), 0);
  EXPECT_EQ(dream_trajectory_id("wave"), 1);
  EXPECT_EQ(dream_trajectory_id("cover_eyes"), 2);
  EXPECT_EQ(dream_trajectory_id("hands_on_head"), 3);
  EXPECT_EQ(dream_trajectory_id("fly"), 4);
  EXPECT_EQ(dream_trajectory_id("drive_car"), 5);
  EXPECT_EQ(dream_trajectory_id("drink"), 6);
  EXPECT_EQ(dream_trajectory_id("spin", {"clap", "spin"}), 8);
  EXPECT_EQ(dream_trajectory_id("walk"), -1);
  EXPECT_FALSE(OnlineActionClassifier::create(nullptr, nullptr));
}

}  // namespace
}  // namespace dreamsense::actions
