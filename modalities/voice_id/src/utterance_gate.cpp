#include "dreamsense/voice_id/utterance_gate.hpp"

#include <algorithm>
#include <cmath>

namespace dreamsense::voice_id {

Status UtteranceGateOptions::check() const {
  if (!(frame_s > 0 && threshold_db > 0 && min_speech_s >= 0 && hangover_s > 0 && padding_s >= 0 &&
        max_utterance_s > hangover_s))
    return make_error(ErrorCode::kInvalidArgument,
                      "UtteranceGateOptions: frame_s, threshold_db, hangover_s must be > 0, "
                      "min_speech_s and padding_s >= 0, and max_utterance_s > hangover_s");
  return ok_status();
}

UtteranceGate::UtteranceGate(UtteranceGateOptions options, int sample_rate)
    : options_(options), rate_(sample_rate) {
  DS_CHECK_GT(sample_rate, 0);
  frame_len_ = std::max(1, static_cast<int>(std::lround(options_.frame_s * rate_)));
}

void UtteranceGate::reset() {
  buffer_.clear();
  analysed_ = 0;
  noise_db_ = 0;
  in_speech_ = false;
  run_ = silence_ = utt_begin_ = speech_begin_ = last_loud_end_ = 0;
}

Timestamp UtteranceGate::stamp_of(size_t index) const {
  return buffer_start_ + Duration::from_ns(static_cast<int64_t>(index) * 1'000'000'000LL / rate_);
}

std::vector<Utterance> UtteranceGate::push(std::span<const float> samples, Timestamp stamp) {
  std::vector<Utterance> done;
  for (size_t i = 0; i < samples.size(); ++i) {
    if (buffer_.empty())
      buffer_start_ = stamp + Duration::from_ns(static_cast<int64_t>(i) * 1'000'000'000LL / rate_);
    buffer_.push_back(samples[i]);
    if (static_cast<int>(buffer_.size() - analysed_) >= frame_len_) gate_frame(done);
  }
  return done;
}

void UtteranceGate::gate_frame(std::vector<Utterance>& done) {
  double e = 0;
  for (int i = 0; i < frame_len_; ++i) {
    const double v = buffer_[analysed_ + static_cast<size_t>(i)];
    e += v * v;
  }
  const double db = 10 * std::log10(e / frame_len_ + 1e-12);
  analysed_ += static_cast<size_t>(frame_len_);
  // Noise floor: follows drops at once, rises slowly (3 dB per second).
  noise_db_ = std::min(db, noise_db_ + 3.0 * options_.frame_s);
  const bool loud = db > noise_db_ + options_.threshold_db;
  if (!in_speech_) {
    run_ = loud ? run_ + 1 : 0;
    if (static_cast<double>(run_) * options_.frame_s >= options_.min_speech_s && run_ > 0) {
      in_speech_ = true;
      silence_ = 0;
      const size_t first_loud = analysed_ - run_ * static_cast<size_t>(frame_len_);
      const size_t pad = static_cast<size_t>(options_.padding_s * rate_);
      utt_begin_ = first_loud > pad ? first_loud - pad : 0;
      speech_begin_ = first_loud;
      last_loud_end_ = analysed_;
    } else {
      // Drop audio that can no longer be padding.
      const size_t keep =
          static_cast<size_t>(options_.padding_s * rate_) + run_ * static_cast<size_t>(frame_len_);
      if (analysed_ > keep + static_cast<size_t>(rate_)) drop_front(analysed_ - keep);
    }
    return;
  }
  silence_ = loud ? 0 : silence_ + 1;
  if (loud) last_loud_end_ = analysed_;
  const double length_s = static_cast<double>(analysed_ - utt_begin_) / rate_;
  if (static_cast<double>(silence_) * options_.frame_s >= options_.hangover_s ||
      length_s >= options_.max_utterance_s)
    finish(done);
}

void UtteranceGate::finish(std::vector<Utterance>& done) {
  Utterance u;
  u.samples.assign(buffer_.begin() + static_cast<std::ptrdiff_t>(utt_begin_),
                   buffer_.begin() + static_cast<std::ptrdiff_t>(analysed_));
  u.start = stamp_of(speech_begin_);
  u.end = stamp_of(last_loud_end_);
  u.loud_begin = speech_begin_ - utt_begin_;
  u.loud_end = std::min(last_loud_end_, analysed_) - utt_begin_;
  in_speech_ = false;
  run_ = 0;
  drop_front(analysed_);
  done.push_back(std::move(u));
}

void UtteranceGate::drop_front(size_t n) {
  n = std::min(n, buffer_.size());
  buffer_.erase(buffer_.begin(), buffer_.begin() + static_cast<std::ptrdiff_t>(n));
  buffer_start_ = stamp_of(n);
  analysed_ -= std::min(analysed_, n);
  utt_begin_ -= std::min(utt_begin_, n);
  speech_begin_ -= std::min(speech_begin_, n);
  last_loud_end_ -= std::min(last_loud_end_, n);
}

}  // namespace dreamsense::voice_id
