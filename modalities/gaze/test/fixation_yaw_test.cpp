#include "dreamsense/gaze/fixation_yaw.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace dreamsense::gaze {
namespace {

cv::Vec3d direction(double yaw_deg, double pitch_deg) {
  return turned_yaw(cv::Vec3d(0, std::tan(pitch_deg * CV_PI / 180), -1), yaw_deg);
}

TEST(FixationYaw, TurnedYawMatchesTheAnglesItReads) {
  const cv::Vec2d a = head_yaw_pitch_deg(turned_yaw(cv::Vec3d(0, 0, -1), 10));
  EXPECT_NEAR(a[0], 10, 1e-9);
  EXPECT_NEAR(a[1], 0, 1e-9);
  EXPECT_GT(turned_yaw(cv::Vec3d(0, 0, -1), 10)[0], 0);  // towards +x
  const cv::Vec2d b = head_yaw_pitch_deg(turned_yaw(direction(-5, 8), 3));
  EXPECT_NEAR(b[0], -2, 1e-9);
  EXPECT_NEAR(b[1], 8, 0.2);  // pitch about the same (measured against z)
}

// Gaze rays that look at the target 6 deg to its -x side (with +-1 deg of scatter): after
// min_fixations the correction is the bias less the dead zone, and it turns towards +x.
TEST(FixationYaw, LearnsAConjugateBiasFromFixations) {
  FixationYawOptions o;
  o.enabled = true;
  FixationYawEstimator e(o);
  const cv::Vec3d target = direction(0, 0) * 0.9;
  for (int i = 0; i < 40; ++i) {
    e.observe(direction(-6 + std::sin(i * 1.3), 2 * std::cos(i * 0.7)), target);
    if (i + 1 < o.min_fixations) {
      EXPECT_EQ(e.correction_deg(), 0) << i;
    }
  }
  EXPECT_EQ(e.fixations(), 40);
  EXPECT_NEAR(e.correction_deg(), 6 - o.dead_zone_deg, 0.5);
  e.reset();
  EXPECT_EQ(e.correction_deg(), 0);
  EXPECT_EQ(e.fixations(), 0);
}

// A bias as large as the self-calibration's 10-deg window, looks at the target scattered by
// +-8 deg, a quarter of the looks elsewhere (+-30 deg): a window that narrow, centred on the
// target, keeps only the nearer half of the looks at it and stays near the dead zone (demo seed
// 770); the default window learns the bias.
TEST(FixationYaw, LearnsABiasAsLargeAsTheSelfCalibrationsWindow) {
  FixationYawOptions o;
  o.enabled = true;
  FixationYawEstimator wide(o);
  o.max_yaw_deg = 10;
  FixationYawEstimator narrow(o);
  const cv::Vec3d target = direction(0, 0);
  for (int i = 0; i < 400; ++i) {
    const bool elsewhere = std::fmod(i * 0.618034, 1.0) < 0.25;
    const double yaw = elsewhere ? 30 * std::sin(i * 0.37) : -10 + 8 * std::sin(i * 1.7);
    wide.observe(direction(yaw, 0), target);
    narrow.observe(direction(yaw, 0), target);
  }
  EXPECT_GT(wide.correction_deg(), 6);
  EXPECT_LT(narrow.correction_deg(), 4);
}

TEST(FixationYaw, NoCorrectionForASmallBiasLooksElsewhereOrWhenDisabled) {
  FixationYawOptions o;
  o.enabled = true;
  const cv::Vec3d target = direction(0, 0);
  FixationYawEstimator small(o), elsewhere(o);
  for (int i = 0; i < 40; ++i) {
    small.observe(direction(-1.5 + 0.3 * std::sin(i), 0), target);  // within the dead zone
    elsewhere.observe(direction(25 + std::sin(i), 20), target);     // a toy, not the robot
  }
  EXPECT_EQ(small.fixations(), 40);
  EXPECT_EQ(small.correction_deg(), 0);
  EXPECT_EQ(elsewhere.fixations(), 0);
  EXPECT_EQ(elsewhere.correction_deg(), 0);
  FixationYawEstimator off(FixationYawOptions{});  // disabled by default
  for (int i = 0; i < 40; ++i) off.observe(direction(-6, 0), target);
  EXPECT_EQ(off.fixations(), 0);
  EXPECT_EQ(off.correction_deg(), 0);
}

// An earlier session's correction (the subject folder's) is applied from the first tick; this
// session's own fixations replace it once there are min_fixations of them, selected without it.
TEST(FixationYaw, AStartValueStandsInUntilTheSessionsOwnFixations) {
  FixationYawOptions o;
  o.enabled = true;
  o.start_deg = 8;
  FixationYawEstimator e(o);
  EXPECT_EQ(e.correction_deg(), 8);
  const cv::Vec3d target = direction(0, 0);
  // 20 deg to the side: inside a window around the start value, outside the session's own.
  e.observe(direction(-20, 0), target);
  EXPECT_EQ(e.fixations(), 0);
  EXPECT_EQ(e.correction_deg(), 8);
  for (int i = 0; i < 40; ++i) {
    e.observe(direction(-4 + 0.5 * std::sin(i * 1.3), 0), target);
    if (i + 1 < o.min_fixations) {
      EXPECT_EQ(e.correction_deg(), 8) << i;
    }
  }
  EXPECT_NEAR(e.correction_deg(), 4 - o.dead_zone_deg, 0.5);  // this session's, not the start
  e.reset();
  EXPECT_EQ(e.correction_deg(), 8);
  o.enabled = false;  // off: no start value either
  EXPECT_EQ(FixationYawEstimator(o).correction_deg(), 0);
}

TEST(FixationYaw, OptionsAreChecked) {
  FixationYawOptions o;
  EXPECT_TRUE(o.check());
  o.max_yaw_deg = 0;
  EXPECT_FALSE(o.check());
  o = {};
  o.window = o.min_fixations - 1;
  EXPECT_FALSE(o.check());
  o = {};
  o.dead_zone_deg = -1;
  EXPECT_FALSE(o.check());
  o = {};
  o.start_deg = -kMaxFixationYawDeg;
  EXPECT_TRUE(o.check());
  o.start_deg = kMaxFixationYawDeg + 1;
  EXPECT_FALSE(o.check());
  o.start_deg = std::nan("");
  EXPECT_FALSE(o.check());
}

}  // namespace
}  // namespace dreamsense::gaze
