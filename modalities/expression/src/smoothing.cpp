#include "dreamsense/expression/smoothing.hpp"

#include <algorithm>
#include <cmath>

namespace dreamsense::expression {

Status ExpressionSmoothingOptions::check() const {
  if (!(time_constant_s >= 0) || !(switch_margin >= 0 && switch_margin < 1) || !(max_gap_s > 0))
    return make_error(ErrorCode::kInvalidArgument,
                      "ExpressionSmoothingOptions: time_constant_s >= 0, switch_margin in [0, 1), "
                      "max_gap_s > 0");
  return ok_status();
}

ExpressionSmoother::ExpressionSmoother(std::vector<std::string> labels,
                                       ExpressionSmoothingOptions options)
    : labels_(std::move(labels)), options_(options) {
  DS_CHECK(options_.check().has_value());
}

ExpressionPrediction ExpressionSmoother::update(int64_t track_id, int64_t stamp_ns,
                                                const ExpressionPrediction& p) {
  DS_CHECK_EQ(p.probabilities.size(), labels_.size());
  auto it = tracks_.find(track_id);
  const double gap_s = it == tracks_.end() ? 0.0 : (stamp_ns - it->second.stamp_ns) * 1e-9;
  if (it == tracks_.end() || gap_s < 0 || gap_s > options_.max_gap_s) {
    State s{stamp_ns, p.probabilities, p.index};
    tracks_[track_id] = s;
    return p;
  }
  State& s = it->second;
  const double alpha =
      options_.time_constant_s > 0 ? 1.0 - std::exp(-gap_s / options_.time_constant_s) : 1.0;
  for (size_t k = 0; k < s.probabilities.size(); ++k)
    s.probabilities[k] += static_cast<float>(alpha * (p.probabilities[k] - s.probabilities[k]));
  s.stamp_ns = stamp_ns;
  const int best = static_cast<int>(
      std::max_element(s.probabilities.begin(), s.probabilities.end()) - s.probabilities.begin());
  if (s.label < 0 || s.label >= static_cast<int>(s.probabilities.size()) ||
      s.probabilities[best] > s.probabilities[s.label] + options_.switch_margin)
    s.label = best;
  ExpressionPrediction out = p;
  out.probabilities = s.probabilities;
  out.index = s.label;
  out.confidence = s.probabilities[static_cast<size_t>(s.label)];
  out.label = labels_[static_cast<size_t>(s.label)];
  return out;
}

}  // namespace dreamsense::expression
