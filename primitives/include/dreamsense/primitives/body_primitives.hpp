#pragma once
// Primitives answered from the child's skeleton (keys::kChildBody): getArmAngle (F2),
// getBody (F3), getBodyPose (F4), getHands (F9), trackHand (F24).
// Pure functions of a blackboard view; units: metres and degrees; legacy vectors in mm.

#include "dreamsense/body/arm_geometry.hpp"
#include "dreamsense/core/blackboard.hpp"
#include "dreamsense/core/perception.hpp"

#include <opencv2/core.hpp>

#include <optional>
#include <vector>

namespace dreamsense::primitives {

struct JointPosition {
  JointId joint;
  cv::Vec3d position_m;
  float confidence;
};

// getBody: the body centre (spine; else mid shoulder-centre/hip-centre; else shoulder centre).
std::optional<cv::Vec3d> body_centre(const SkeletonBody& body);
// getBodyPose: the ten DREAM joints in legacy order (untracked joints have confidence 0).
std::vector<JointPosition> body_pose(const SkeletonBody& body);
// getHands: hand positions (wrist when the hand is not tracked).
struct Hands {
  std::optional<cv::Vec3d> left, right;
};
Hands hands(const SkeletonBody& body);

// trackHand: constant-velocity prediction of the hand nearest to `seed` after `dt_s`, from a
// least-squares fit over the history (newest first, within `window_s`).
struct HandPrediction {
  cv::Vec3d position_m;
  cv::Vec3d velocity_mps;
  bool left = false;  // which hand was tracked
  int samples = 0;
};
std::optional<HandPrediction> predict_hand(const std::vector<Entry<BodyState>>& history,
                                           const cv::Vec3d& seed, double dt_s,
                                           double window_s = 0.3);

}  // namespace dreamsense::primitives
