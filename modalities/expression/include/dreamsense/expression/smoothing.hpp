#pragma once
// Per-track temporal smoothing of expression predictions, so that a label does not flicker
// between frames: an exponential moving average of the class probabilities (time constant in
// seconds of stream time, irregular frame intervals handled exactly), and hysteresis: the
// reported label changes only when another class's smoothed probability exceeds the current
// one's by switch_margin.

#include "dreamsense/core/status.hpp"
#include "dreamsense/expression/expression_model.hpp"

#include <cstdint>
#include <map>

namespace dreamsense::expression {

struct ExpressionSmoothingOptions {
  double time_constant_s = 0.4;
  double switch_margin = 0.1;
  double max_gap_s = 1.0;  // a track silent for longer starts over
  Status check() const;
};

class ExpressionSmoother {
 public:
  // `labels`: the model's labels (ExpressionModel::labels()).
  explicit ExpressionSmoother(std::vector<std::string> labels,
                              ExpressionSmoothingOptions options = {});
  // One prediction of track `track_id` at `stamp_ns` (stream time, increasing per track; an
  // older stamp restarts the track), with one probability per label.
  // Returns the smoothed prediction (probabilities = the moving average).
  ExpressionPrediction update(int64_t track_id, int64_t stamp_ns, const ExpressionPrediction& p);
  void forget(int64_t track_id) { tracks_.erase(track_id); }
  void reset() { tracks_.clear(); }
  size_t tracks() const { return tracks_.size(); }

 private:
  struct State {
    int64_t stamp_ns = 0;
    std::vector<float> probabilities;
    int label = -1;
  };
  std::vector<std::string> labels_;
  ExpressionSmoothingOptions options_;
  std::map<int64_t, State> tracks_;
};

}  // namespace dreamsense::expression
