#include "dreamsense/actions/online.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace dreamsense::actions {

int dream_trajectory_id(const std::string& label, const std::vector<std::string>& custom) {
  static const std::array<const char*, 7> kDream = {
      "none", "wave", "cover_eyes", "hands_on_head", "fly", "drive_car", "drink"};
  for (size_t i = 0; i < kDream.size(); ++i)
    if (label == kDream[i]) return static_cast<int>(i);
  for (size_t i = 0; i < custom.size() && i < 5; ++i)
    if (label == custom[i]) return 7 + static_cast<int>(i);
  return -1;
}

Status OnlineOptions::check() const {
  if (!(window_s >= 0 && window_s <= 60))
    return make_error(ErrorCode::kInvalidArgument, "online: window_s must be in [0, 60]");
  if (!(min_coverage > 0 && min_coverage <= 1))
    return make_error(ErrorCode::kInvalidArgument, "online: min_coverage must be in (0, 1]");
  if (!(max_gap_s > 0))
    return make_error(ErrorCode::kInvalidArgument, "online: max_gap_s must be > 0");
  if (!(smoothing_s >= 0))
    return make_error(ErrorCode::kInvalidArgument, "online: smoothing_s must be >= 0");
  return ok_status();
}

Result<OnlineActionClassifier> OnlineActionClassifier::create(
    std::shared_ptr<const ActionModel> model, std::shared_ptr<const GestureModel> gestures,
    const OnlineOptions& options) {
  if (auto s = options.check(); !s) return tl::unexpected(s.error());
  if (!model && !gestures)
    return make_error(ErrorCode::kInvalidArgument,
                      "online actions: neither an action model nor a gestures model given");
  OnlineActionClassifier c;
  c.model_ = std::move(model);
  c.gestures_ = std::move(gestures);
  c.options_ = options;
  c.window_s_ = options.window_s > 0 ? options.window_s : c.model_ ? c.model_->window_s() : 0;
  c.history_s_ = std::max(c.window_s_, c.gestures_ ? c.gestures_->history_s() : 0.0);
  return c;
}

void OnlineActionClassifier::reset() {
  history_.clear();
  smoothed_.clear();
  last_ = ActionResult{};
}

ActionResult OnlineActionClassifier::push(const SkeletonFrame& frame) {
  if (!history_.empty() && frame.stamp_ns <= history_.back().stamp_ns) return last_;
  if (!history_.empty() &&
      static_cast<double>(frame.stamp_ns - history_.back().stamp_ns) * 1e-9 > options_.max_gap_s)
    reset();
  history_.push_back(frame);
  const int64_t keep = static_cast<int64_t>(std::llround(history_s_ * 1e9));
  while (history_.size() > 1 && history_[1].stamp_ns <= frame.stamp_ns - keep) history_.pop_front();

  ActionResult r;
  r.stamp_ns = frame.stamp_ns;
  std::vector<std::string> custom_labels;
  if (gestures_) custom_labels = gestures_->labels();
  if (model_) {
    const int64_t len = static_cast<int64_t>(std::llround(window_s_ * 1e9));
    size_t first = history_.size() - 1;
    while (first > 0 && history_[first - 1].stamp_ns >= frame.stamp_ns - len) --first;
    const double span = static_cast<double>(frame.stamp_ns - history_[first].stamp_ns) * 1e-9;
    if (span >= options_.min_coverage * window_s_ && history_.size() - first >= 2) {
      scratch_.assign(history_.begin() + static_cast<std::ptrdiff_t>(first), history_.end());
      const ActionScores s = model_->classify(scratch_);
      if (!s.no_data) {
        r.ready = true;
        r.rejected = s.rejected;
        std::vector<double> scores = s.scores;
        if (options_.smoothing_s > 0) {
          if (smoothed_.size() != scores.size()) {
            smoothed_ = scores;
          } else {
            const double dt = static_cast<double>(frame.stamp_ns - smoothed_stamp_) * 1e-9;
            const double a = 1.0 - std::exp(-dt / options_.smoothing_s);
            for (size_t k = 0; k < scores.size(); ++k)
              smoothed_[k] += a * (scores[k] - smoothed_[k]);
          }
          smoothed_stamp_ = frame.stamp_ns;
          scores = smoothed_;
        }
        const auto& labels = model_->labels();
        for (size_t k = 0; k < labels.size(); ++k) r.scores.emplace_back(labels[k], scores[k]);
        if (!s.rejected) {
          const size_t best =
              static_cast<size_t>(std::max_element(scores.begin(), scores.end()) - scores.begin());
          r.label = labels[best];
        }
      }
    }
  }
  if (gestures_) {
    scratch_.assign(history_.begin(), history_.end());
    const GestureMatch m = gestures_->match(scratch_);
    for (size_t k = 0; k < m.class_distance.size(); ++k) {
      const double thr = gestures_->thresholds()[k];
      const double d = m.class_distance[k].second;
      r.scores.emplace_back(m.class_distance[k].first,
                            std::isfinite(d) ? std::clamp(1.0 - d / (2 * thr), 0.0, 1.0) : 0.0);
    }
    if (!m.no_data) r.ready = true;
    if (m.label != "none") {
      r.label = m.label;
      r.custom = true;
    }
  }
  r.dream_id = dream_trajectory_id(r.label, custom_labels);
  last_ = r;
  return r;
}

}  // namespace dreamsense::actions
