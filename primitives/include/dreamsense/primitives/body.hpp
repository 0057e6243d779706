#pragma once
// Primitives answered from the child's skeleton (keys::kChildBody): F2 getArmAngle, F3 getBody,
// F4 getBodyPose, F9 getHands, F24 trackHand. The geometry functions are pure functions of one
// skeleton; the primitive functions answer from a PrimitiveContext. Units: metres and degrees.

#include "dreamsense/perception/body.hpp"
#include "dreamsense/primitives/context.hpp"

#include <opencv2/core.hpp>

#include <optional>
#include <vector>

namespace dreamsense::primitives {

// The body family's options block (EvaluatorOptions::families).
struct BodyPrimitiveOptions {
  // Default query of trackHand in batch analysis: the right hand's current position, predicted
  // this far ahead.
  double track_hand_dt_s = 0.2;
  Status check() const;
};

// Arm angles in the torso frame:
//   x_t: towards the child's left (from right to left shoulder),
//   y_t: up the spine (shoulder centre minus spine/hip centre, made orthogonal to x_t),
//   z_t = x_t x y_t: the direction the chest faces.
// For each upper arm (shoulder -> elbow) with unit direction u:
//   elevation = asin(u . y_t)   (-90 deg hanging down, 0 horizontal, +90 straight up)
//   azimuth   = atan2(u . z_t, u . lateral), lateral = +x_t for the left arm, -x_t for the right
//               (0 deg straight out sideways, +90 forward, +-180 behind).
// An arm whose shoulder or elbow is not tracked has no angle.
ArmAnglesValue arm_angles(const SkeletonBody& body);
// The body centre (spine; else mid shoulder-centre/hip-centre; else shoulder centre).
std::optional<cv::Vec3d> body_centre(const SkeletonBody& body);
// The ten DREAM joints in legacy order (untracked joints at the origin with confidence 0).
std::vector<JointPosition> body_pose(const SkeletonBody& body);
// Hand positions (the wrist when the hand is not tracked).
HandsValue hands(const SkeletonBody& body);

// Constant-velocity prediction of the hand nearest to `seed` after `dt_s`, from a least-squares
// fit over the history (newest first, within `window_s`).
struct HandPrediction {
  cv::Vec3d position_m;
  cv::Vec3d velocity_mps;
  bool left = false;  // which hand was tracked
  int samples = 0;
};
std::optional<HandPrediction> predict_hand(const std::vector<Entry<BodyState>>& history,
                                           const cv::Vec3d& seed, double dt_s,
                                           double window_s = 0.3);

Answer<ArmAnglesValue> get_arm_angle(const PrimitiveContext& ctx);
Answer<BodyValue> get_body(const PrimitiveContext& ctx);
Answer<BodyPoseValue> get_body_pose(const PrimitiveContext& ctx);
Answer<HandsValue> get_hands(const PrimitiveContext& ctx);
// trackHand(seed, dt); without a query the seed is the right hand's current position (else the
// left hand's) and dt BodyPrimitiveOptions::track_hand_dt_s.
Answer<TrackValue> track_hand(const PrimitiveContext& ctx,
                              const std::optional<TrackQuery>& query = std::nullopt);

}  // namespace dreamsense::primitives
