#include "dreamsense/body/arm_geometry.hpp"

#include <cmath>

namespace dreamsense::body {
namespace {
constexpr double kRadToDeg = 180.0 / M_PI;

cv::Vec3d unit(const cv::Vec3d& v) {
  const double n = cv::norm(v);
  return n > 1e-9 ? v / n : cv::Vec3d(0, 0, 0);
}

std::optional<ArmAngle> upper_arm_angle(const SkeletonBody& b, JointId shoulder, JointId elbow,
                                        const cv::Vec3d& lateral, const cv::Vec3d& up,
                                        const cv::Vec3d& forward) {
  if (!b.joint(shoulder).valid() || !b.joint(elbow).valid()) return std::nullopt;
  const cv::Vec3d u = unit(b.joint(elbow).position_m - b.joint(shoulder).position_m);
  if (cv::norm(u) == 0) return std::nullopt;
  ArmAngle a;
  a.elevation_deg = std::asin(std::clamp(u.dot(up), -1.0, 1.0)) * kRadToDeg;
  a.azimuth_deg = std::atan2(u.dot(forward), u.dot(lateral)) * kRadToDeg;
  return a;
}
}  // namespace

ArmAngles arm_angles(const SkeletonBody& b) {
  ArmAngles out;
  const auto& ls = b.joint(JointId::kShoulderLeft);
  const auto& rs = b.joint(JointId::kShoulderRight);
  const auto& sc = b.joint(JointId::kShoulderCenter);
  if (!ls.valid() || !rs.valid() || !sc.valid()) return out;
  const cv::Vec3d x = unit(ls.position_m - rs.position_m);
  // "Up" from the spine when it is tracked; otherwise the hip centre.
  const JointObservation& low =
      b.joint(JointId::kSpine).valid() ? b.joint(JointId::kSpine) : b.joint(JointId::kHipCenter);
  if (!low.valid()) return out;
  cv::Vec3d y = sc.position_m - low.position_m;
  y = unit(y - x * y.dot(x));
  if (cv::norm(y) == 0) return out;
  const cv::Vec3d z = x.cross(y);
  out.left = upper_arm_angle(b, JointId::kShoulderLeft, JointId::kElbowLeft, x, y, z);
  out.right = upper_arm_angle(b, JointId::kShoulderRight, JointId::kElbowRight, -x, y, z);
  return out;
}

}  // namespace dreamsense::body
