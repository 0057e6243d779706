#pragma once
// A conjugate eye-in-head yaw bias of uncalibrated (anatomical) eyeballs, learnt online from the
// child's fixations on the robot's head (issue 15; README.md "Yaw from fixations on the robot").
//
// The anatomical eyeballs sit behind the eye openings' centroids; when a child's pupils do not
// rest in the middle of the openings (or the landmarks of the openings are biased, e.g. by
// glasses), every gaze is turned sideways by the same few degrees: the demo's glasses child
// measured 8 deg. A child in robot therapy looks at the robot's head for a large share of the
// session (the demo: ~40 %), so the gaze rays that pass near it give the bias: per tick, the
// sideways angle between the target's direction and the gaze (both in the head frame). Over the
// ticks whose corrected gaze is within max_yaw_deg sideways and max_pitch_deg up/down of the
// target, the median of those angles is the bias. It is shrunk towards zero by dead_zone_deg
// (the estimate's own error on a child without a bias, ~2 deg) and applied only after
// min_fixations such ticks, so a child without a bias keeps the uncorrected gaze. A correction
// learnt in an earlier session with the same eyeballs (the subject folder's gaze.yaml) can stand
// in until then (start_deg).

#include "dreamsense/core/status.hpp"

#include <opencv2/core.hpp>

#include <deque>

namespace dreamsense::gaze {

// Largest sideways correction accepted from a file or an option (deg): the demo's glasses child,
// the largest bias measured, needed 6.
inline constexpr double kMaxFixationYawDeg = 20;

struct FixationYawOptions {
  bool enabled = false;  // on for the self-calibration's anatomical eyeballs (gaze model file)
  // A fixation: this session's corrected gaze this close to the target sideways and up/down
  // (head frame). Sideways wider than the self-calibration's 10 deg: with a bias about as large
  // as the window, a window centred on the target holds only the nearer half of the looks at
  // it, their median stays within the dead zone and the window never moves (demo seed 770:
  // bias ~10 deg, nothing learnt, gaze 13.5 deg; modalities/gaze/README.md).
  double max_yaw_deg = 15;
  double max_pitch_deg = 12;
  int min_fixations = 10;    // no correction before this many fixations
  int window = 500;          // the median of the newest this many fixations (~50 s of looks)
  double dead_zone_deg = 2;  // |median| below this: no correction; above: median -+ this
  // The correction until min_fixations are seen (deg; within +-kMaxFixationYawDeg): 0, or what an
  // earlier session of this child learnt for the same eyeballs (GazeModelFile). It does not move
  // the fixation window: this session's estimate is its own.
  double start_deg = 0;
  Status check() const;
};

// Yaw and pitch (deg) of a head-frame direction (forward −z, x to the subject's left, y down):
// positive yaw towards +x, positive pitch towards +y.
cv::Vec2d head_yaw_pitch_deg(const cv::Vec3d& direction_head);

// `direction_head` turned by `yaw_deg` about the head's y axis (towards +x for positive angles,
// the sense of head_yaw_pitch_deg).
cv::Vec3d turned_yaw(const cv::Vec3d& direction_head, double yaw_deg);

class FixationYawEstimator {
 public:
  explicit FixationYawEstimator(FixationYawOptions options = {}) : options_(options) {}
  // The yaw (deg) to add to the gaze's eye-in-head direction now (0 while disabled; start_deg
  // while learning).
  double correction_deg() const;
  int fixations() const { return static_cast<int>(offsets_.size()); }
  // One tick's uncorrected gaze and the target's direction from the eyes, both in the head frame.
  // Updates the correction for the following ticks.
  void observe(const cv::Vec3d& gaze_head, const cv::Vec3d& target_head);
  void reset();

 private:
  FixationYawOptions options_;
  std::deque<double> offsets_;
  double learnt_deg_ = 0;  // this session's own estimate (0 before min_fixations)
};

}  // namespace dreamsense::gaze
