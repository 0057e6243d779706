#include "dreamsense/actions/features.hpp"

#include <gtest/gtest.h>

#include <algorithm>

#include "synthetic_body.hpp"

namespace dreamsense::actions {
namespace {

using test::BodyParams;
using test::Motion;

double distance(const std::vector<float>& a, const std::vector<float>& b) {
  double s = 0;
  for (size_t i = 0; i < a.size(); ++i) s += (a[i] - b[i]) * (a[i] - b[i]);
  return std::sqrt(s);
}

TEST(Features, DimensionsMatchForEveryMethodAndJointSet) {
  const auto seq = test::sequence(Motion::kWaveRight, 0, 1.0, BodyParams{});
  const NormalizedWindow w = normalize_window(seq, {});
  for (auto method : {FeatureMethod::kRelativePositions, FeatureMethod::kPyramid})
    for (auto joints : {JointSet::kAll, JointSet::kUpperBody}) {
      FeatureOptions o;
      o.method = method;
      o.joints = joints;
      EXPECT_EQ(static_cast<int>(extract_features(w, o).size()), feature_dimension(o));
    }
  FeatureOptions rjp;
  rjp.method = FeatureMethod::kRelativePositions;
  rjp.joints = JointSet::kAll;
  EXPECT_EQ(feature_dimension(rjp), 4 * 190 * 3);  // 20 joints: 190 pairs
  EXPECT_EQ(joint_indices(JointSet::kUpperBody).size(), 12u);
}

TEST(Features, RelativePositionsArePairwiseDifferences) {
  const auto seq = test::sequence(Motion::kStill, 0, 0.5, BodyParams{});
  const NormalizedWindow w = normalize_window(seq, {});
  FeatureOptions o;
  o.method = FeatureMethod::kRelativePositions;
  o.rjp_frames = 1;
  const auto f = extract_features(w, o);
  // First pair: joint 0 (shoulder centre) - joint 1 (head).
  const cv::Vec3f d = w.at(0, 0) - w.at(0, 1);
  EXPECT_NEAR(f[0], d[0], 1e-6);
  EXPECT_NEAR(f[1], d[1], 1e-6);
  EXPECT_NEAR(f[2], d[2], 1e-6);
}

TEST(Features, PyramidSeesTemporalOrderButNotTheFrameRate) {
  BodyParams p30, p15;
  p15.rate_hz = 15;
  const auto a = test::sequence(Motion::kPunchRight, 0, 0.4, p30);
  const auto b = test::sequence(Motion::kPunchRight, 0, 0.4, p15);
  auto reversed = a;
  std::reverse(reversed.begin(), reversed.end());
  for (size_t i = 0; i < reversed.size(); ++i) reversed[i].stamp_ns = a[i].stamp_ns;
  const FeatureOptions o;
  const auto fa = extract_features(normalize_window(a, {}), o);
  const auto fb = extract_features(normalize_window(b, {}), o);
  const auto fr = extract_features(normalize_window(reversed, {}), o);
  EXPECT_LT(distance(fa, fb), 0.1 * distance(fa, fr));
  EXPECT_GT(distance(fa, fr), 0.5);
}

TEST(Features, DistancesAreInvariantToTheFacingAndFollowTheHands) {
  FeatureOptions o;
  o.distances = true;
  const int without = feature_dimension(FeatureOptions{});
  EXPECT_EQ(feature_dimension(o), without + 3 * 2 * 66);  // 3 cells x (mean, sd) x 66 pairs
  // The pairwise distances (the tail of the descriptor) do not depend on where the body faces
  // when facing normalisation is off; the positions do.
  BodyParams front, side;
  side.yaw_deg = 70;
  BodyFrameOptions no_facing;
  no_facing.normalize_facing = false;
  const auto a = extract_features(
      normalize_window(test::sequence(Motion::kWaveRight, 0, 1.0, front), no_facing), o);
  const auto b = extract_features(
      normalize_window(test::sequence(Motion::kWaveRight, 0, 1.0, side), no_facing), o);
  ASSERT_EQ(static_cast<int>(a.size()), feature_dimension(o));
  const std::vector<float> da(a.begin() + without, a.end()), db(b.begin() + without, b.end());
  const std::vector<float> pa(a.begin(), a.begin() + without), pb(b.begin(), b.begin() + without);
  EXPECT_LT(distance(da, db), 1e-3);
  EXPECT_GT(distance(pa, pb), 0.5);
  // A still body: every distance's spread is 0; a wave moves the hand: some spread is not.
  const auto still = extract_features(
      normalize_window(test::sequence(Motion::kStill, 0, 1.0, front), no_facing), o);
  double spread_still = 0, spread_wave = 0;
  for (int k = without + 1; k < static_cast<int>(still.size()); k += 2) {
    spread_still = std::max(spread_still, static_cast<double>(still[static_cast<size_t>(k)]));
    spread_wave = std::max(spread_wave, static_cast<double>(a[static_cast<size_t>(k)]));
  }
  EXPECT_LT(spread_still, 1e-4);
  EXPECT_GT(spread_wave, 0.05);
}

TEST(Features, UnusableWindowGivesNoFeatures) {
  EXPECT_TRUE(extract_features(NormalizedWindow{}, FeatureOptions{}).empty());
}

TEST(Features, OptionsAreChecked) {
  FeatureOptions o;
  EXPECT_TRUE(o.check());
  o.samples = 2;
  EXPECT_FALSE(o.check());
  o = {};
  o.fourier = 16;  // >= samples / 2
  EXPECT_FALSE(o.check());
  EXPECT_FALSE(feature_method_from_string("bogus"));
  EXPECT_EQ(*feature_method_from_string("relative_positions"), FeatureMethod::kRelativePositions);
}

}  // namespace
}  // namespace dreamsense::actions
