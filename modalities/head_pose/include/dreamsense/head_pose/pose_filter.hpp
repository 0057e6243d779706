#pragma once
// Temporal smoothing of the head pose: a One Euro filter (Casiez, Roussel & Vogel, CHI 2012)
// applied on the rotation group and to the position. Each update moves the filtered pose a
// fraction alpha of the way to the new measurement (rotation: geodesic interpolation via the
// rotation vector of R_prev^T R_new):
//   alpha = 1 / (1 + tau / dt),  tau = 1 / (2 pi f_c),
//   f_c = min_cutoff_hz + beta_per_deg_s * |angular speed| + beta_per_m_s * |linear speed|,
// the speeds themselves low-passed with derivative_cutoff_hz. At rest (f_c = 1 Hz) the time
// constant is 0.16 s and jitter is removed; during a 100 deg/s turn f_c = 6 Hz, tau = 27 ms, so
// the lag stays ~1 frame at 25 Hz. A gap longer than max_gap_s restarts the filter.

#include "dreamsense/perception/head_pose.hpp"

#include <optional>

namespace dreamsense::head_pose {

struct PoseFilterOptions {
  bool enabled = true;
  double min_cutoff_hz = 1.0;
  double beta_per_deg_s = 0.05;  // Hz of cut-off per deg/s of angular speed
  double beta_per_m_s = 20.0;    // Hz of cut-off per m/s of linear speed
  double derivative_cutoff_hz = 1.0;
  double max_gap_s = 0.5;
  Status check() const;
};

class PoseFilter {
 public:
  explicit PoseFilter(PoseFilterOptions options = {}) : options_(options) {}
  // Filters pose.world_from_head and pose.position_world_m in place (stamp = pose.frame_stamp),
  // recomputes the derived fields and sets pose.smoothed. Passes through when disabled.
  void apply(HeadPose& pose);
  void reset() { state_.reset(); }

 private:
  struct State {
    Timestamp stamp;
    cv::Matx33d R;
    cv::Vec3d p;
    double ang_speed = 0, lin_speed = 0;  // filtered, deg/s and m/s
  };
  PoseFilterOptions options_;
  std::optional<State> state_;
};

}  // namespace dreamsense::head_pose
