#include "dreamsense/gaze/gaze_filter.hpp"

#include "dreamsense/core/one_euro.hpp"

#include <algorithm>
#include <cmath>

namespace dreamsense::gaze {

Status GazeFilterOptions::check() const {
  std::string bad;
  if (!(min_cutoff_hz > 0)) bad += " min_cutoff_hz must be > 0;";
  if (!(beta_per_deg_s >= 0)) bad += " beta_per_deg_s must be >= 0;";
  if (!(derivative_cutoff_hz > 0)) bad += " derivative_cutoff_hz must be > 0;";
  if (!(max_gap_s > 0)) bad += " max_gap_s must be > 0;";
  if (!bad.empty()) return make_error(ErrorCode::kInvalidArgument, "GazeFilterOptions:{}", bad);
  return ok_status();
}

cv::Vec3d DirectionFilter::apply(Timestamp stamp, const cv::Vec3d& direction) {
  const cv::Vec3d d = direction / cv::norm(direction);
  if (!options_.enabled) return d;
  const double dt = state_ ? (stamp - state_->stamp).seconds() : 0.0;
  if (!state_ || dt < 0 || dt > options_.max_gap_s) {
    state_ = State{stamp, d, 0};
    return d;
  }
  if (dt == 0) return state_->direction;  // the same frame again
  const double angle = std::acos(std::clamp(state_->direction.dot(d), -1.0, 1.0));
  state_->speed_deg_s += one_euro_alpha(options_.derivative_cutoff_hz, dt) *
                         (angle * 180 / CV_PI / dt - state_->speed_deg_s);
  const double a =
      one_euro_alpha(options_.min_cutoff_hz + options_.beta_per_deg_s * state_->speed_deg_s, dt);
  // Rotate a fraction a of the way (spherical interpolation).
  if (angle > 1e-12) {
    const double s = std::sin(angle);
    state_->direction =
        (std::sin((1 - a) * angle) / s) * state_->direction + (std::sin(a * angle) / s) * d;
    state_->direction /= cv::norm(state_->direction);
  }
  state_->stamp = stamp;
  return state_->direction;
}

}  // namespace dreamsense::gaze
