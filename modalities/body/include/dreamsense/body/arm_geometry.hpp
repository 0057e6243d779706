#pragma once
// Arm angles of a skeleton (getArmAngle, F2), in the torso frame:
//   x_t: towards the child's left (from right to left shoulder),
//   y_t: up the spine (shoulder centre minus spine/hip centre, made orthogonal to x_t),
//   z_t = x_t × y_t: the direction the chest faces.
// For each upper arm (shoulder → elbow) with unit direction u:
//   elevation = asin(u · y_t)   (−90° hanging down, 0° horizontal, +90° straight up)
//   azimuth   = atan2(u · z_t, u · lateral), lateral = +x_t for the left arm, −x_t for the right
//               (0° straight out sideways, +90° forward, ±180° behind).

#include "dreamsense/core/sensor_frame.hpp"

#include <optional>

namespace dreamsense::body {

struct ArmAngle {
  double azimuth_deg = 0;
  double elevation_deg = 0;
};

struct ArmAngles {
  std::optional<ArmAngle> left, right;  // nullopt when the needed joints are not tracked
};

ArmAngles arm_angles(const SkeletonBody& body);

}  // namespace dreamsense::body
