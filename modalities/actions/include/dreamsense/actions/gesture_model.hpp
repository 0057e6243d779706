#pragma once
// Custom gestures taught by demonstration (few-shot, e.g. three examples each): every example
// becomes a template, a trajectory of the arms in the body frame; a window of the recent
// skeleton history matches a template when its dynamic-time-warping distance is below the
// class threshold learnt from the examples themselves (open set: anything else is "none").
// README.md "Custom gestures".

#include "dreamsense/actions/normalization.hpp"
#include "dreamsense/actions/skeleton_sequence.hpp"
#include "dreamsense/core/status.hpp"

#include <filesystem>
#include <span>
#include <string>
#include <vector>

namespace dreamsense::actions {

struct GestureOptions {
  BodyFrameOptions body;
  int samples = 24;  // instants per template / window (time-normalised)
  // Sakoe-Chiba band half-width as a fraction of `samples`, for template-to-template distances.
  double band = 0.25;
  // Live matching is subsequence DTW (open begin): each template is looked for inside the last
  // history_factor x its duration, resampled at the template's rate; the match must end within
  // the last end_slack of the template's samples (the gesture is going on now) and span between
  // min_speed and max_speed times the template's samples... i.e. the gesture may be performed
  // that much faster or slower, at any phase of a repeated movement.
  double history_factor = 1.6;
  double end_slack = 0.15;
  double min_speed = 0.6, max_speed = 1.6;
  // Class threshold = max(min_threshold, threshold_factor x the largest leave-one-out distance
  // between the class's own examples); one example: 2 x min_threshold. Distances are in body
  // units (torso length + shoulder width) per joint.
  double threshold_factor = 2.0;
  double min_threshold = 0.08;
  // Shortest and longest demonstration accepted (seconds).
  double min_duration_s = 0.3, max_duration_s = 10.0;
  Status check() const;
};

struct GestureTemplate {
  std::string label;
  double duration_s = 0;
  std::vector<float> trajectory;  // samples x kGestureDims, row-major
};

// Per frame: elbows, wrists and hands (left, right) relative to the shoulder centre.
inline constexpr int kGestureJoints = 6;
inline constexpr int kGestureDims = kGestureJoints * 3;

struct GestureMatch {
  std::string label = "none";  // "none" when no class is within its threshold (or no data)
  double distance = 0;         // of the best class (infinity when nothing could be compared)
  double threshold = 0;        // of the best class
  std::vector<std::pair<std::string, double>> class_distance;  // per label, best template
  bool no_data = false;
};

class GestureModel {
 public:
  static constexpr const char* kFormatName = "dreamsense.actions.gestures";
  static constexpr int kFormatVersion = 1;

  // One demonstration per LabelledSequence (its frames = the gesture from start to end).
  // "none" is not a gesture label. Errors name the demonstration (its `source`).
  static Result<GestureModel> train(const std::vector<LabelledSequence>& demonstrations,
                                    const GestureOptions& options);

  // `history`: the recent frames, oldest first, stamps increasing; the newest frame is "now".
  GestureMatch match(std::span<const SkeletonFrame> history) const;
  // DTW distance between a window (already cut) and one template (for tests and tools).
  double distance(std::span<const SkeletonFrame> window, const GestureTemplate& t) const;

  const std::vector<std::string>& labels() const { return labels_; }  // order of first example
  const std::vector<double>& thresholds() const { return thresholds_; }
  const std::vector<GestureTemplate>& templates() const { return templates_; }
  const GestureOptions& options() const { return options_; }
  // The history match() looks at: the longest template times history_factor.
  double history_s() const;

  Status save(const std::filesystem::path& path) const;
  static Result<GestureModel> load(const std::filesystem::path& path);

 private:
  GestureOptions options_;
  std::vector<std::string> labels_;
  std::vector<double> thresholds_;
  std::vector<GestureTemplate> templates_;
  std::vector<float> trajectory(std::span<const SkeletonFrame> frames) const;
  double dtw(const std::vector<float>& a, const std::vector<float>& b) const;
  double subsequence_dtw(const std::vector<float>& history, const std::vector<float>& t) const;
  std::vector<float> resampled_trajectory(std::span<const SkeletonFrame> frames, int n) const;
};

}  // namespace dreamsense::actions
