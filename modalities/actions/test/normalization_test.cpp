#include "dreamsense/actions/normalization.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "synthetic_body.hpp"

namespace dreamsense::actions {
namespace {

using test::BodyParams;
using test::Motion;

double max_difference(const NormalizedWindow& a, const NormalizedWindow& b) {
  double worst = 0;
  for (size_t i = 0; i < a.positions.size(); ++i)
    worst = std::max(worst, static_cast<double>(cv::norm(a.positions[i] - b.positions[i])));
  return worst;
}

TEST(Normalization, RemovesTranslationFacingAndBodySize) {
  BodyParams adult;
  BodyParams child;
  child.yaw_deg = 40;
  child.scale = 0.6;
  child.position = {-0.7, 0.3, 1.4};
  const auto a = test::sequence(Motion::kWaveRight, 0, 1.0, adult);
  const auto c = test::sequence(Motion::kWaveRight, 0, 1.0, child);
  const NormalizedWindow na = normalize_window(a, {});
  const NormalizedWindow nc = normalize_window(c, {});
  ASSERT_TRUE(na.usable && nc.usable);
  EXPECT_TRUE(na.facing_known);
  EXPECT_LT(max_difference(na, nc), 1e-4);
  EXPECT_NEAR(nc.body_size_m / na.body_size_m, 0.6, 1e-6);
  // Body frame: x = the body's left, y = up, z = forward.
  const cv::Vec3f sl = na.at(0, static_cast<int>(JointId::kShoulderLeft));
  const cv::Vec3f head = na.at(0, static_cast<int>(JointId::kHead));
  const cv::Vec3f foot = na.at(0, static_cast<int>(JointId::kFootLeft));
  EXPECT_GT(sl[0], 0.1f);
  EXPECT_GT(head[1], 0.5f);
  EXPECT_GT(foot[2], 0.0f);  // the feet point forward
}

TEST(Normalization, WithoutFacingOrScaleTheRotationRemains) {
  BodyParams turned;
  turned.yaw_deg = 60;
  const auto a = test::sequence(Motion::kStill, 0, 0.5, BodyParams{});
  const auto b = test::sequence(Motion::kStill, 0, 0.5, turned);
  BodyFrameOptions o;
  o.normalize_facing = false;
  o.normalize_scale = false;
  const NormalizedWindow na = normalize_window(a, o), nb = normalize_window(b, o);
  EXPECT_GT(max_difference(na, nb), 0.1);
  EXPECT_DOUBLE_EQ(na.body_size_m, 1.0);
}

TEST(Normalization, MissingAndNanJointsAreInterpolatedFromTheirNeighboursInTime) {
  auto seq = test::sequence(Motion::kWaveRight, 0, 1.0, BodyParams{});
  const NormalizedWindow clean = normalize_window(seq, {});
  const int hand = static_cast<int>(JointId::kHandRight);
  for (int f = 10; f < 13; ++f) seq[static_cast<size_t>(f)].joints[hand].confidence = 0.f;
  seq[20].joints[hand].position_m[1] = std::numeric_limits<double>::quiet_NaN();
  seq[21].joints[hand].position_m[0] = std::numeric_limits<double>::infinity();
  const NormalizedWindow w = normalize_window(seq, {});
  ASSERT_TRUE(w.usable);
  EXPECT_EQ(w.observed[10 * kJointCount + hand], 0);
  EXPECT_EQ(w.observed[20 * kJointCount + hand], 0);
  EXPECT_EQ(w.observed[9 * kJointCount + hand], 1);
  for (const auto& p : w.positions) EXPECT_TRUE(std::isfinite(p[0] + p[1] + p[2]));
  // Linear interpolation over 100 ms of a 1.5 Hz wave: within a few centimetres.
  EXPECT_LT(cv::norm(w.at(11, hand) - clean.at(11, hand)), 0.06);
  EXPECT_LT(cv::norm(w.at(20, hand) - clean.at(20, hand)), 0.06);
  EXPECT_NEAR(w.observed_fraction, 1.0 - 5.0 / (31.0 * kJointCount), 1e-9);
}

TEST(Normalization, JointNeverSeenTakesItsNeighbourAndInferredJointsAreKept) {
  auto seq = test::sequence(Motion::kStill, 0, 0.5, BodyParams{});
  const int hand = static_cast<int>(JointId::kHandLeft),
            wrist = static_cast<int>(JointId::kWristLeft);
  const int knee = static_cast<int>(JointId::kKneeLeft);
  for (auto& f : seq) {
    f.joints[hand].confidence = 0.f;
    f.joints[knee].confidence = 0.5f;  // inferred
  }
  const NormalizedWindow w = normalize_window(seq, {});
  ASSERT_TRUE(w.usable);
  EXPECT_LT(cv::norm(w.at(3, hand) - w.at(3, wrist)), 1e-6);
  EXPECT_EQ(w.observed[3 * kJointCount + knee], 1);
  BodyFrameOptions strict;
  strict.min_confidence = 0.6f;
  EXPECT_EQ(normalize_window(seq, strict).observed[3 * kJointCount + knee], 0);
}

TEST(Normalization, NoTorsoMeansNoData) {
  auto seq = test::sequence(Motion::kStill, 0, 0.5, BodyParams{});
  for (auto& f : seq)
    for (auto& j : f.joints) j.confidence = 0.f;
  seq[2].joints[static_cast<int>(JointId::kHandLeft)].confidence = 1.f;  // a hand alone
  EXPECT_FALSE(normalize_window(seq, {}).usable);
  EXPECT_FALSE(normalize_window({}, {}).usable);
}

TEST(Normalization, MissingShoulderLinesFallBackToTheSensorAxis) {
  auto seq = test::sequence(Motion::kStill, 0, 0.3, BodyParams{});
  for (auto& f : seq)
    for (JointId id :
         {JointId::kShoulderLeft, JointId::kShoulderRight, JointId::kHipLeft, JointId::kHipRight})
      f.joints[static_cast<int>(id)].confidence = 0.f;
  const NormalizedWindow w = normalize_window(seq, {});
  ASSERT_TRUE(w.usable);
  EXPECT_FALSE(w.facing_known);
  // Torso length alone gives the size (2 x torso).
  EXPECT_NEAR(w.body_size_m, 2 * 0.5, 1e-6);
}

TEST(Normalization, OptionsAreChecked) {
  BodyFrameOptions o;
  EXPECT_TRUE(o.check());
  o.up = {0, 0, 0};
  EXPECT_FALSE(o.check());
  o = {};
  o.min_confidence = 2.f;
  EXPECT_FALSE(o.check());
}

TEST(Normalization, ResamplingIsLinearInTime) {
  auto seq = test::sequence(Motion::kStill, 0, 1.0, BodyParams{});
  // Move the head linearly in x over the window.
  for (size_t i = 0; i < seq.size(); ++i)
    seq[i].joints[static_cast<int>(JointId::kHead)].position_m[0] +=
        0.3 * static_cast<double>(i) / (seq.size() - 1);
  BodyFrameOptions o;
  o.normalize_facing = false;
  o.normalize_scale = false;
  const NormalizedWindow w = normalize_window(seq, o);
  const auto r = resample_positions(w, 5);
  const int head = static_cast<int>(JointId::kHead);
  const float x0 = r[head][0];
  for (int i = 1; i < 5; ++i)
    EXPECT_NEAR(r[static_cast<size_t>(i) * kJointCount + head][0] - x0, 0.3 * i / 4, 1e-5);
}

}  // namespace
}  // namespace dreamsense::actions
