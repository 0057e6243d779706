#include "dreamsense/audio/speech_presence.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

namespace dreamsense::audio {

Status SpeechPresenceOptions::check() const {
  if (!(frame_s > 0 && hop_s > 0 && active_db >= 0 && voicing_threshold > 0 && f0_min_hz > 0 &&
        f0_max_hz > f0_min_hz && min_voiced_s >= 0 && frame_s * f0_min_hz >= 1.0))
    return make_error(ErrorCode::kInvalidArgument,
                      "SpeechPresenceOptions: frame_s, hop_s, voicing_threshold, f0_min_hz > 0, "
                      "f0_max_hz > f0_min_hz, active_db, min_voiced_s >= 0 and a frame must hold "
                      "one period of f0_min_hz");
  return ok_status();
}

namespace {

// Minimum of YIN's cumulative-mean-normalised difference over lags [lo, hi].
double yin_min(const float* x, int n, int lo, int hi) {
  const int w = n - hi;  // integration window
  if (w <= 0) return 1.0;
  double cum = 0, best = 1e9;
  for (int tau = 1; tau <= hi; ++tau) {
    double d = 0;
    for (int j = 0; j < w; ++j) {
      const double diff = x[j] - x[j + tau];
      d += diff * diff;
    }
    cum += d;
    const double dn = cum > 0 ? d * tau / cum : 1.0;
    if (tau >= lo) best = std::min(best, dn);
  }
  return best;
}

}  // namespace

SpeechPresence detect_speech(std::span<const int16_t> s, int rate, const SpeechPresenceOptions& o) {
  SpeechPresence r;
  if (rate <= 0 || s.empty()) return r;
  const int frame = std::max(1, static_cast<int>(std::lround(o.frame_s * rate)));
  const int hop = std::max(1, static_cast<int>(std::lround(o.hop_s * rate)));
  const int lo = std::max(2, static_cast<int>(std::floor(rate / o.f0_max_hz)));
  const int hi = std::min(frame / 2, static_cast<int>(std::ceil(rate / o.f0_min_hz)));
  std::vector<double> level;
  std::vector<size_t> starts;
  for (size_t i = 0; i + static_cast<size_t>(frame) <= s.size() || (i == 0 && !s.empty());
       i += static_cast<size_t>(hop)) {
    const size_t n = std::min(s.size() - i, static_cast<size_t>(frame));
    double mean = 0, e = 0;
    for (size_t j = 0; j < n; ++j) mean += s[i + j];
    mean /= static_cast<double>(n);
    for (size_t j = 0; j < n; ++j) e += (s[i + j] - mean) * (s[i + j] - mean);
    level.push_back(10 * std::log10(e / static_cast<double>(n) / (32768.0 * 32768.0) + 1e-12));
    starts.push_back(i);
  }
  std::vector<double> sorted = level;
  std::sort(sorted.begin(), sorted.end());
  r.peak_dbfs = sorted.back();
  r.floor_dbfs = sorted[sorted.size() / 10];
  const double gate = std::max(r.floor_dbfs + o.active_db, o.min_level_dbfs);
  std::vector<float> buf(static_cast<size_t>(frame));
  int voiced = 0;
  bool any_active = false;
  for (size_t k = 0; k < level.size(); ++k) {
    if (level[k] < gate) continue;
    const double t0 = static_cast<double>(starts[k]) / rate;
    const double t1 = static_cast<double>(starts[k] + static_cast<size_t>(frame)) / rate;
    if (!any_active) r.start_s = t0;
    r.end_s = std::min(t1, static_cast<double>(s.size()) / rate);
    any_active = true;
    const size_t n = std::min(s.size() - starts[k], static_cast<size_t>(frame));
    if (static_cast<int>(n) <= hi) continue;
    for (size_t j = 0; j < n; ++j) buf[j] = static_cast<float>(s[starts[k] + j]);
    if (yin_min(buf.data(), static_cast<int>(n), lo, hi) < o.voicing_threshold) ++voiced;
  }
  r.voiced_s = voiced * o.hop_s;
  r.speech = r.voiced_s >= o.min_voiced_s;
  return r;
}

}  // namespace dreamsense::audio
