#pragma once
// A simple standing body for unit tests, in the optical frame (x right, y down, z forward),
// facing the sensor (body's left = +x) before `yaw_deg` turns it about the vertical axis.
// Arm motions are functions of time.

#include "dreamsense/actions/skeleton_sequence.hpp"

#include <cmath>
#include <functional>
#include <random>

namespace dreamsense::actions::test {

enum class Motion { kStill, kWaveRight, kWaveLeft, kArmsUp, kPunchRight, kCircleRight };

struct BodyParams {
  double yaw_deg = 0;
  double scale = 1.0;  // 1 = adult (~1.75 m), 0.6 = child
  cv::Vec3d position{0, 0, 2.5};
  double rate_hz = 30;
  double speed = 1.0;  // motion speed multiplier
  double noise_m = 0.0;
  uint64_t seed = 1;
};

inline SkeletonFrame body_at(Motion motion, double t, const BodyParams& p) {
  const double s = p.scale;
  // Body coordinates: x = body's left, y = up, z = forward (towards the sensor when yaw = 0).
  std::array<cv::Vec3d, kJointCount> b{};
  auto at = [&](JointId id) -> cv::Vec3d& { return b[static_cast<size_t>(id)]; };
  at(JointId::kHipCenter) = {0, 0, 0};
  at(JointId::kSpine) = {0, 0.25, 0};
  at(JointId::kShoulderCenter) = {0, 0.5, 0};
  at(JointId::kHead) = {0, 0.7, 0};
  at(JointId::kShoulderLeft) = {0.18, 0.47, 0};
  at(JointId::kShoulderRight) = {-0.18, 0.47, 0};
  at(JointId::kHipLeft) = {0.1, -0.05, 0};
  at(JointId::kHipRight) = {-0.1, -0.05, 0};
  at(JointId::kKneeLeft) = {0.1, -0.5, 0.02};
  at(JointId::kKneeRight) = {-0.1, -0.5, 0.02};
  at(JointId::kAnkleLeft) = {0.1, -0.9, 0};
  at(JointId::kAnkleRight) = {-0.1, -0.9, 0};
  at(JointId::kFootLeft) = {0.1, -0.95, 0.08};
  at(JointId::kFootRight) = {-0.1, -0.95, 0.08};
  // Arms hanging by default.
  for (double side : {1.0, -1.0}) {
    const bool left = side > 0;
    const cv::Vec3d sh = at(left ? JointId::kShoulderLeft : JointId::kShoulderRight);
    at(left ? JointId::kElbowLeft : JointId::kElbowRight) = sh + cv::Vec3d(side * 0.02, -0.28, 0);
    at(left ? JointId::kWristLeft : JointId::kWristRight) =
        sh + cv::Vec3d(side * 0.03, -0.53, 0.02);
    at(left ? JointId::kHandLeft : JointId::kHandRight) = sh + cv::Vec3d(side * 0.03, -0.62, 0.03);
  }
  const double w = 2 * CV_PI * 1.5 * p.speed * t;
  auto raise = [&](bool left, double sway, double fwd) {
    const double side = left ? 1 : -1;
    const cv::Vec3d sh = at(left ? JointId::kShoulderLeft : JointId::kShoulderRight);
    at(left ? JointId::kElbowLeft : JointId::kElbowRight) =
        sh + cv::Vec3d(side * 0.25, 0.05, fwd * 0.5);
    at(left ? JointId::kWristLeft : JointId::kWristRight) =
        sh + cv::Vec3d(side * 0.25 + sway, 0.3, fwd);
    at(left ? JointId::kHandLeft : JointId::kHandRight) =
        sh + cv::Vec3d(side * 0.25 + sway * 1.2, 0.38, fwd);
  };
  switch (motion) {
    case Motion::kStill:
      break;
    case Motion::kWaveRight:
      raise(false, 0.12 * std::sin(w), 0.05);
      break;
    case Motion::kWaveLeft:
      raise(true, 0.12 * std::sin(w), 0.05);
      break;
    case Motion::kArmsUp:
      raise(true, 0.0, 0.0);
      raise(false, 0.0, 0.0);
      break;
    case Motion::kPunchRight: {
      const double e = 0.5 * (1 - std::cos(w));  // 0..1
      const cv::Vec3d sh = at(JointId::kShoulderRight);
      at(JointId::kElbowRight) = sh + cv::Vec3d(-0.05, -0.1, 0.1 + 0.2 * e);
      at(JointId::kWristRight) = sh + cv::Vec3d(-0.02, 0.0, 0.2 + 0.35 * e);
      at(JointId::kHandRight) = sh + cv::Vec3d(-0.02, 0.0, 0.28 + 0.37 * e);
      break;
    }
    case Motion::kCircleRight: {
      const cv::Vec3d sh = at(JointId::kShoulderRight);
      const cv::Vec3d c = sh + cv::Vec3d(-0.1, 0.0, 0.45);
      at(JointId::kElbowRight) = sh + cv::Vec3d(-0.08, -0.05, 0.25);
      at(JointId::kWristRight) = c + cv::Vec3d(0.15 * std::cos(w), 0.15 * std::sin(w), 0);
      at(JointId::kHandRight) = c + cv::Vec3d(0.17 * std::cos(w), 0.17 * std::sin(w), 0.02);
      break;
    }
  }
  // Body -> optical frame: facing the sensor means body z = -optical z and body left = +x.
  const double a = p.yaw_deg * CV_PI / 180;
  std::mt19937_64 rng(p.seed * 1000003ULL + static_cast<uint64_t>(std::llround(t * 1e4)));
  std::normal_distribution<double> noise(0, p.noise_m);
  SkeletonFrame f;
  f.stamp_ns = static_cast<int64_t>(std::llround(t * 1e9));
  for (int j = 0; j < kJointCount; ++j) {
    const cv::Vec3d q = b[static_cast<size_t>(j)] * s;
    // Rotate about the vertical (body y) axis, then map (x, y, z)_body -> (x, -y, -z)_optical.
    const cv::Vec3d r(std::cos(a) * q[0] + std::sin(a) * q[2], q[1],
                      -std::sin(a) * q[0] + std::cos(a) * q[2]);
    cv::Vec3d o(r[0], -r[1], -r[2]);
    o += p.position;
    if (p.noise_m > 0) o += cv::Vec3d(noise(rng), noise(rng), noise(rng));
    f.joints[static_cast<size_t>(j)].position_m = o;
    f.joints[static_cast<size_t>(j)].confidence = 1.f;
  }
  return f;
}

inline SkeletonSequence sequence(Motion motion, double t0, double duration_s, const BodyParams& p) {
  SkeletonSequence out;
  const int n = static_cast<int>(std::floor(duration_s * p.rate_hz)) + 1;
  for (int i = 0; i < n; ++i) out.push_back(body_at(motion, t0 + i / p.rate_hz, p));
  return out;
}

}  // namespace dreamsense::actions::test
