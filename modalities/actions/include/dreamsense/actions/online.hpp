#pragma once
// Online use: skeleton frames go in one by one (int64 ns stamps); every call answers with a
// label, per-class scores and "none" when nothing matches. A sliding window over the recent
// history feeds the action model; an optional custom-gesture model is matched on the same
// history and wins when one of its gestures is within its threshold (README.md "Online").

#include "dreamsense/actions/action_model.hpp"
#include "dreamsense/actions/gesture_model.hpp"

#include <deque>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace dreamsense::actions {

// identifyTrajectory (primitives.md F20) index of a label: 0 none, 1 wave, 2 cover_eyes,
// 3 hands_on_head, 4 fly, 5 drive_car, 6 drink; custom gestures 7-11 in the order of
// `custom_labels`; -1 for anything else (e.g. a dataset's classes).
int dream_trajectory_id(const std::string& label,
                        const std::vector<std::string>& custom_labels = {});

struct OnlineOptions {
  double window_s = 0;        // 0 = the action model's window
  double min_coverage = 0.7;  // answer "none" (not ready) until the history spans this share
  double max_gap_s = 0.5;     // a longer gap between frames clears the history (tracking lost)
  // Exponential smoothing of the per-class scores (time constant, seconds; 0 = none). The label
  // is the best smoothed class; rejection uses the current window.
  double smoothing_s = 0;
  Status check() const;
};

struct ActionResult {
  int64_t stamp_ns = 0;
  std::string label = kNoneLabel;
  int dream_id = 0;  // F20 index (dream_trajectory_id), -1 outside DREAM's classes
  // Per class of the action model (its labels), then each custom gesture with a score in [0, 1]
  // (1 - distance / (2 threshold), clamped).
  std::vector<std::pair<std::string, double>> scores;
  bool ready = false;     // the window was long enough to classify
  bool rejected = false;  // open-set rejection of the action model
  bool custom = false;    // the label comes from the custom-gesture model
};

class OnlineActionClassifier {
 public:
  // Either model may be null (not both).
  static Result<OnlineActionClassifier> create(std::shared_ptr<const ActionModel> model,
                                               std::shared_ptr<const GestureModel> gestures,
                                               const OnlineOptions& options = {});
  // A frame older than or equal to the previous one is ignored (the previous answer is repeated).
  // A frame whose body is missing altogether (all confidences 0) still advances time.
  ActionResult push(const SkeletonFrame& frame);
  void reset();
  double window_s() const { return window_s_; }

 private:
  OnlineActionClassifier() = default;
  std::shared_ptr<const ActionModel> model_;
  std::shared_ptr<const GestureModel> gestures_;
  OnlineOptions options_;
  double window_s_ = 0, history_s_ = 0;
  std::deque<SkeletonFrame> history_;
  std::vector<SkeletonFrame> scratch_;
  std::vector<double> smoothed_;
  int64_t smoothed_stamp_ = 0;
  ActionResult last_;
};

}  // namespace dreamsense::actions
