// gaze_filter: fixation noise is reduced, a saccade is followed within a few frames, gaps
// restart, bad options are reported.

#include "dreamsense/gaze/gaze_filter.hpp"

#include "dreamsense/core/camera_model.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace dreamsense::gaze {
namespace {

double angle_deg(const cv::Vec3d& a, const cv::Vec3d& b) {
  return std::acos(std::clamp(a.dot(b) / cv::norm(a) / cv::norm(b), -1.0, 1.0)) * 180 / CV_PI;
}
cv::Vec3d dir(double yaw, double pitch) {
  return rotation_from_ypr_deg(yaw, pitch, 0) * cv::Vec3d(0, 0, -1);
}

TEST(DirectionFilter, ReducesFixationNoiseAndFollowsSaccades) {
  DirectionFilter f;
  std::mt19937 rng(5);
  std::normal_distribution<double> noise(0, 2.0);  // deg per frame
  double raw_err = 0, filtered_err = 0;
  int n = 0;
  auto t = [](int i) { return Timestamp::from_ns(int64_t{40000000} * i); };
  for (int i = 0; i < 50; ++i) {  // 2 s fixation at (10, 5)
    const cv::Vec3d m = dir(10 + noise(rng), 5 + noise(rng));
    const cv::Vec3d out = f.apply(t(i), m);
    if (i >= 25) {
      raw_err += angle_deg(m, dir(10, 5));
      filtered_err += angle_deg(out, dir(10, 5));
      ++n;
    }
  }
  EXPECT_LT(filtered_err / n, 0.5 * raw_err / n);
  // A 25-degree saccade: within 5 frames (200 ms) the filter is within 3 deg of the target.
  cv::Vec3d out;
  for (int i = 50; i < 55; ++i) out = f.apply(t(i), dir(-15, 5));
  EXPECT_LT(angle_deg(out, dir(-15, 5)), 3.0);
  // A gap restarts: the first measurement after it passes unchanged.
  const cv::Vec3d after = f.apply(t(100), dir(20, -10));
  EXPECT_LT(angle_deg(after, dir(20, -10)), 1e-9);
  // Disabled: identity.
  GazeFilterOptions off;
  off.enabled = false;
  DirectionFilter g(off);
  g.apply(t(0), dir(0, 0));
  EXPECT_LT(angle_deg(g.apply(t(1), dir(30, 0)), dir(30, 0)), 1e-9);
}

TEST(DirectionFilter, BadOptions) {
  GazeFilterOptions o;
  o.min_cutoff_hz = 0;
  o.max_gap_s = -1;
  const auto s = o.check();
  ASSERT_FALSE(s);
  EXPECT_NE(s.error().message.find("min_cutoff_hz"), std::string::npos);
  EXPECT_NE(s.error().message.find("max_gap_s"), std::string::npos);
}

}  // namespace
}  // namespace dreamsense::gaze
