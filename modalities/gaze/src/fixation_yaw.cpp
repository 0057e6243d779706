#include "dreamsense/gaze/fixation_yaw.hpp"

#include "dreamsense/core/camera_model.hpp"
#include "dreamsense/core/statistics.hpp"

#include <cmath>
#include <vector>

namespace dreamsense::gaze {
namespace {
constexpr double kDegreesPerRadian = 180.0 / CV_PI;
}  // namespace

Status FixationYawOptions::check() const {
  if (!(max_yaw_deg > 0 && max_yaw_deg <= 45 && max_pitch_deg > 0 && max_pitch_deg <= 45))
    return make_error(ErrorCode::kInvalidArgument,
                      "FixationYawOptions: max_yaw_deg and max_pitch_deg must be in (0, 45] (got "
                      "{}, {})",
                      max_yaw_deg, max_pitch_deg);
  if (min_fixations < 1 || window < min_fixations)
    return make_error(ErrorCode::kInvalidArgument,
                      "FixationYawOptions: need 1 <= min_fixations <= window (got {}, {})",
                      min_fixations, window);
  if (!(dead_zone_deg >= 0 && dead_zone_deg < 20))
    return make_error(ErrorCode::kInvalidArgument,
                      "FixationYawOptions: dead_zone_deg must be in [0, 20) (got {})",
                      dead_zone_deg);
  if (!(std::abs(start_deg) <= kMaxFixationYawDeg))
    return make_error(ErrorCode::kInvalidArgument,
                      "FixationYawOptions: start_deg must be within +-{} (got {})",
                      kMaxFixationYawDeg, start_deg);
  return ok_status();
}

cv::Vec2d head_yaw_pitch_deg(const cv::Vec3d& d) {
  return {std::atan2(d[0], -d[2]) * kDegreesPerRadian, std::atan2(d[1], -d[2]) * kDegreesPerRadian};
}

cv::Vec3d turned_yaw(const cv::Vec3d& d, double yaw_deg) {
  // The head pose's yaw turns the gaze towards −x (HeadPose conventions), hence the sign.
  return rotation_from_ypr_deg(-yaw_deg, 0, 0) * d;
}

double FixationYawEstimator::correction_deg() const {
  if (!options_.enabled) return 0;
  return fixations() >= options_.min_fixations ? learnt_deg_ : options_.start_deg;
}

void FixationYawEstimator::observe(const cv::Vec3d& gaze_head, const cv::Vec3d& target_head) {
  if (!options_.enabled) return;
  const cv::Vec2d offset = head_yaw_pitch_deg(target_head) - head_yaw_pitch_deg(gaze_head);
  if (!std::isfinite(offset[0]) || !std::isfinite(offset[1])) return;
  // The selection follows this session's own estimate (a biased gaze on the target is still a
  // fixation), not start_deg: an earlier session's value does not steer what this one learns.
  if (std::abs(offset[0] - learnt_deg_) > options_.max_yaw_deg ||
      std::abs(offset[1]) > options_.max_pitch_deg)
    return;
  offsets_.push_back(offset[0]);
  if (static_cast<int>(offsets_.size()) > options_.window) offsets_.pop_front();
  if (static_cast<int>(offsets_.size()) < options_.min_fixations) return;
  const double bias = upper_median(std::vector<double>(offsets_.begin(), offsets_.end()));
  learnt_deg_ = std::copysign(std::max(0.0, std::abs(bias) - options_.dead_zone_deg), bias);
}

void FixationYawEstimator::reset() {
  offsets_.clear();
  learnt_deg_ = 0;
}

}  // namespace dreamsense::gaze
