#include "dreamsense/head_pose/pose_filter.hpp"

#include "dreamsense/core/one_euro.hpp"
#include "dreamsense/head_pose/head_pose_estimator.hpp"
#include "dreamsense/perception/head_pose.hpp"

#include <opencv2/calib3d.hpp>

#include <cmath>

namespace dreamsense::head_pose {

Status PoseFilterOptions::check() const {
  std::string bad;
  if (!(min_cutoff_hz > 0)) bad += " min_cutoff_hz must be > 0;";
  if (!(beta_per_deg_s >= 0)) bad += " beta_per_deg_s must be >= 0;";
  if (!(beta_per_m_s >= 0)) bad += " beta_per_m_s must be >= 0;";
  if (!(derivative_cutoff_hz > 0)) bad += " derivative_cutoff_hz must be > 0;";
  if (!(max_gap_s > 0)) bad += " max_gap_s must be > 0;";
  if (!bad.empty()) return make_error(ErrorCode::kInvalidArgument, "PoseFilterOptions:{}", bad);
  return ok_status();
}

void PoseFilter::apply(HeadPose& pose) {
  pose.smoothed = false;
  if (!options_.enabled) return;
  const double dt = state_ ? (pose.frame_stamp - state_->stamp).seconds() : 0.0;
  if (!state_ || dt > options_.max_gap_s || dt < 0) {
    state_ = State{pose.frame_stamp, pose.world_from_head, pose.position_world_m, 0, 0};
    return;
  }
  if (dt == 0) {  // the same frame again: repeat the filtered pose
    pose.world_from_head = state_->R;
    pose.position_world_m = state_->p;
    pose.smoothed = true;
    update_derived(pose);
    return;
  }
  cv::Vec3d r;
  cv::Rodrigues(cv::Matx33d(state_->R.t() * pose.world_from_head), r);
  const cv::Vec3d dp = pose.position_world_m - state_->p;
  const double ad = one_euro_alpha(options_.derivative_cutoff_hz, dt);
  state_->ang_speed += ad * (cv::norm(r) * 180.0 / CV_PI / dt - state_->ang_speed);
  state_->lin_speed += ad * (cv::norm(dp) / dt - state_->lin_speed);
  const double fc = options_.min_cutoff_hz + options_.beta_per_deg_s * state_->ang_speed +
                    options_.beta_per_m_s * state_->lin_speed;
  const double a = one_euro_alpha(fc, dt);
  cv::Matx33d step;
  cv::Rodrigues(cv::Vec3d(a * r), step);
  state_->R = state_->R * step;
  state_->p += a * dp;
  state_->stamp = pose.frame_stamp;
  pose.world_from_head = state_->R;
  pose.position_world_m = state_->p;
  pose.smoothed = true;
  update_derived(pose);
}

}  // namespace dreamsense::head_pose
