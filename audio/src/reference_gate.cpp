#include "dreamsense/audio/reference_gate.hpp"

#include <algorithm>
#include <cmath>
#include <string>

namespace dreamsense::audio {

Status ReferenceGateOptions::check() const {
  std::string bad;
  if (!(frame_s >= 0.005 && frame_s <= 0.1)) bad += " frame_s must be in [0.005, 0.1];";
  if (!(threshold_dbfs < 0)) bad += " threshold_dbfs must be < 0;";
  if (!(lead_s >= 0 && tail_s >= 0 && lead_s <= 2 && tail_s <= 5))
    bad += " lead_s must be in [0, 2] and tail_s in [0, 5];";
  if (!(std::abs(offset_s) <= 10)) bad += " offset_s must be within +-10 s;";
  if (!(align_after_s > 0 && max_offset_s > 0 && max_offset_s <= 5 && align_tolerance_s >= 0))
    bad += " align_after_s and max_offset_s (<= 5) must be > 0, align_tolerance_s >= 0;";
  if (!bad.empty()) return make_error(ErrorCode::kInvalidArgument, "ReferenceGateOptions:{}", bad);
  return ok_status();
}

ReferenceGate::ReferenceGate(ReferenceGateOptions options)
    : options_(options),
      offset_s_(options.offset_s),
      frame_ns_(static_cast<int64_t>(std::llround(options.frame_s * 1e9))) {}

void ReferenceGate::reset() {
  offset_s_ = options_.offset_s;
  raw_.clear();
  intervals_.clear();
  ref_levels_.clear();
  mic_levels_.clear();
  ref_acc_.clear();
  mic_acc_.clear();
  ref_acc_frame_ = mic_acc_frame_ = INT64_MIN;
  active_frames_ = 0;
  measured_offset_.reset();
  align_frame_.reset();
  aligned_ = false;
}

namespace {
int64_t floor_div(int64_t a, int64_t b) { return a / b - ((a % b != 0) && ((a < 0) != (b < 0))); }
}  // namespace

// Accumulates the power of the samples of one global frame; emits the frame's level when the
// next frame starts.
void ReferenceGate::frame_level(std::vector<double>& acc, int64_t& acc_frame, int64_t frame,
                                double power, std::deque<Level>& out, bool reference) {
  if (frame != acc_frame) {
    if (acc_frame != INT64_MIN && acc.size() == 2 && acc[1] > 0) {
      const double db = 10 * std::log10(std::max(acc[0] / acc[1], 1e-20));
      out.push_back({acc_frame, db});
      const size_t keep = static_cast<size_t>(30.0 / options_.frame_s);
      while (out.size() > keep) out.pop_front();
      if (reference && db > options_.threshold_dbfs) add_active(acc_frame);
    }
    acc.assign(2, 0.0);
    acc_frame = frame;
  }
  acc[0] += power;
  acc[1] += 1;
}

void ReferenceGate::add_active(int64_t frame) {
  ++active_frames_;
  const Timestamp a = Timestamp::from_ns(frame * frame_ns_);
  const Timestamp b = Timestamp::from_ns((frame + 1) * frame_ns_);
  if (!raw_.empty() && a <= raw_.back().second)
    raw_.back().second = std::max(raw_.back().second, b);
  else
    raw_.emplace_back(a, b);
  // The widened interval of this frame, merged into the last one.
  const Duration shift = Duration::from_seconds(offset_s_);
  const Timestamp wa = a + shift - Duration::from_seconds(options_.lead_s);
  const Timestamp wb = b + shift + Duration::from_seconds(options_.tail_s);
  if (!intervals_.empty() && wa <= intervals_.back().second)
    intervals_.back().second = std::max(intervals_.back().second, wb);
  else
    intervals_.emplace_back(wa, wb);
}

void ReferenceGate::rebuild() {
  intervals_.clear();
  const Duration shift = Duration::from_seconds(offset_s_);
  for (const auto& [a, b] : raw_) {
    const Timestamp wa = a + shift - Duration::from_seconds(options_.lead_s);
    const Timestamp wb = b + shift + Duration::from_seconds(options_.tail_s);
    if (!intervals_.empty() && wa <= intervals_.back().second)
      intervals_.back().second = std::max(intervals_.back().second, wb);
    else
      intervals_.emplace_back(wa, wb);
  }
}

Status ReferenceGate::push_reference(std::span<const float> x, int channels, int rate,
                                     Timestamp stamp) {
  if (channels <= 0 || rate <= 0)
    return make_error(ErrorCode::kInvalidArgument,
                      "robot reference: {} channel(s) at {} Hz is not audio", channels, rate);
  const size_t n = x.size() / static_cast<size_t>(channels);
  for (size_t i = 0; i < n; ++i) {
    const int64_t t = stamp.ns() + static_cast<int64_t>(i) * 1'000'000'000LL / rate;
    const double v = x[i * static_cast<size_t>(channels)];
    frame_level(ref_acc_, ref_acc_frame_, floor_div(t, frame_ns_), v * v, ref_levels_, true);
  }
  try_align();
  return ok_status();
}

void ReferenceGate::push_microphone(std::span<const float> x, int channels, int rate,
                                    Timestamp stamp) {
  if (!options_.align || aligned_ || channels <= 0 || rate <= 0) return;
  const size_t n = x.size() / static_cast<size_t>(channels);
  for (size_t i = 0; i < n; ++i) {
    const int64_t t = stamp.ns() + static_cast<int64_t>(i) * 1'000'000'000LL / rate;
    const double v = x[i * static_cast<size_t>(channels)];
    frame_level(mic_acc_, mic_acc_frame_, floor_div(t, frame_ns_), v * v, mic_levels_, false);
  }
  try_align();
}

// The lag (in frames) that maximises the microphones' mean level over the reference's active
// frames: the robot is by far the loudest thing the array hears while it speaks.
void ReferenceGate::try_align() {
  if (!options_.align || aligned_ || ref_levels_.empty() || mic_levels_.empty()) return;
  if (!align_frame_) {
    if (static_cast<double>(active_frames_) * options_.frame_s < options_.align_after_s) return;
    align_frame_ = ref_levels_.back().frame;  // enough robot speech up to here
  }
  const int64_t max_lag = static_cast<int64_t>(std::ceil(options_.max_offset_s / options_.frame_s));
  // Wait until the microphones have passed that frame by the largest lag.
  if (mic_levels_.back().frame < *align_frame_ + max_lag) return;
  const int64_t mic0 = mic_levels_.front().frame;
  auto mic_db = [&](int64_t f) -> std::optional<double> {
    const int64_t k = f - mic0;
    if (k < 0 || k >= static_cast<int64_t>(mic_levels_.size())) return std::nullopt;
    const Level& l = mic_levels_[static_cast<size_t>(k)];
    if (l.frame != f) return std::nullopt;  // a gap in the microphone stream
    return l.db;
  };
  double best = -1e300;
  int64_t best_lag = 0;
  for (int64_t lag = -max_lag; lag <= max_lag; ++lag) {
    double sum = 0;
    int count = 0;
    for (const Level& r : ref_levels_) {
      if (r.frame > *align_frame_) break;
      if (!(r.db > options_.threshold_dbfs)) continue;
      if (auto m = mic_db(r.frame + lag)) sum += *m, ++count;
    }
    if (count < static_cast<int>(options_.align_after_s / options_.frame_s / 2)) continue;
    const double mean = sum / count;
    if (mean > best + 1e-9) best = mean, best_lag = lag;
  }
  if (best <= -1e299) return;
  aligned_ = true;
  measured_offset_ = static_cast<double>(best_lag) * options_.frame_s;
  if (std::abs(*measured_offset_ - offset_s_) > options_.align_tolerance_s) {
    offset_s_ = *measured_offset_;
    rebuild();
  }
  mic_levels_.clear();
}

double ReferenceGate::active_fraction(Timestamp a, Timestamp b) const {
  if (!a.is_set() || !b.is_set())
    return 0.0;  // unset bounds: nothing to measure (and b - a overflows)
  if (!(b > a)) return active(a) ? 1.0 : 0.0;
  int64_t covered = 0;
  for (const auto& [s, e] : intervals_) {
    const Timestamp lo = std::max(a, s), hi = std::min(b, e);
    if (hi > lo) covered += (hi - lo).ns();
  }
  return static_cast<double>(covered) / static_cast<double>((b - a).ns());
}

bool ReferenceGate::active(Timestamp t) const {
  for (const auto& [s, e] : intervals_)
    if (t >= s && t < e) return true;
  return false;
}

std::pair<Timestamp, Timestamp> ReferenceGate::longest_quiet_span(Timestamp a, Timestamp b) const {
  std::pair<Timestamp, Timestamp> best{a, a};
  Timestamp cursor = a;
  auto consider = [&](Timestamp s, Timestamp e) {
    if (e - s > best.second - best.first) best = {s, e};
  };
  for (const auto& [s, e] : intervals_) {
    if (e <= cursor) continue;
    if (s >= b) break;
    if (s > cursor) consider(cursor, s);
    cursor = std::max(cursor, e);
    if (cursor >= b) break;
  }
  if (cursor < b) consider(cursor, b);
  return best;
}

void ReferenceGate::forget_before(Timestamp t) {
  auto drop = [&](std::vector<std::pair<Timestamp, Timestamp>>& v) {
    size_t k = 0;
    while (k < v.size() && v[k].second < t) ++k;
    v.erase(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k));
  };
  drop(intervals_);
  drop(raw_);
}

}  // namespace dreamsense::audio
