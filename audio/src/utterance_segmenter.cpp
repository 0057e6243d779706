#include "dreamsense/audio/utterance_segmenter.hpp"

#include "dreamsense/audio/stamped_audio.hpp"

#include <algorithm>
#include <cmath>
#include <string>

namespace dreamsense::audio {

Status UtteranceSegmenterOptions::check() const {
  std::string bad;
  auto add = [&](const std::string& s) { bad += (bad.empty() ? "" : "; ") + s; };
  if (auto s = vad.check(); !s) add(s.error().message);
  if (channels < 1 || channels > 64)
    add(fmt::format("channels must be in [1, 64] (is {})", channels));
  if (vad_channel < -1 || vad_channel >= channels)
    add(fmt::format("vad_channel must be -1 or in [0, {}) (is {})", channels, vad_channel));
  if (!(min_speech_s >= 0 && hangover_s > 0 && pre_roll_s >= 0 && min_utterance_s >= 0))
    add("min_speech_s, pre_roll_s, min_utterance_s must be >= 0 and hangover_s > 0");
  if (!(max_utterance_s > hangover_s && max_utterance_s > min_speech_s))
    add(fmt::format("max_utterance_s ({}) must exceed hangover_s and min_speech_s",
                    max_utterance_s));
  if (max_jitter < Duration()) add("max_jitter must be >= 0");
  if (!bad.empty())
    return make_error(ErrorCode::kInvalidArgument, "UtteranceSegmenterOptions: {}", bad);
  return ok_status();
}

std::vector<float> Utterance::channel(int c) const {
  std::vector<float> out;
  if (c < 0 || c >= channels) return out;
  out.reserve(static_cast<size_t>(frames()));
  for (size_t i = static_cast<size_t>(c); i < samples.size(); i += static_cast<size_t>(channels))
    out.push_back(samples[i]);
  return out;
}

void fade_in_pre_roll(std::span<float> mono, const Utterance& u, double max_s) {
  if (u.sample_rate <= 0 || !(max_s > 0)) return;
  const int64_t pre_roll = duration_to_frames(u.speech_start - u.start, u.sample_rate);
  const int64_t n =
      std::min({pre_roll, duration_to_frames(Duration::from_seconds(max_s), u.sample_rate),
                static_cast<int64_t>(mono.size())});
  for (int64_t i = 0; i < n; ++i)
    mono[static_cast<size_t>(i)] *= static_cast<float>(i) / static_cast<float>(n);
}

UtteranceSegmenter::UtteranceSegmenter(UtteranceSegmenterOptions options,
                                       std::unique_ptr<VoiceActivityDetector> vad)
    : options_(options), vad_(std::move(vad)) {
  rate_ = options_.vad.sample_rate;
  frame_len_ = vad_->frame_length();
}
UtteranceSegmenter::~UtteranceSegmenter() = default;

Result<std::unique_ptr<UtteranceSegmenter>> UtteranceSegmenter::create(
    const UtteranceSegmenterOptions& options) {
  if (auto s = options.check(); !s) return tl::unexpected(s.error());
  auto vad = VoiceActivityDetector::create(options.vad);
  if (!vad) return tl::unexpected(vad.error());
  return std::unique_ptr<UtteranceSegmenter>(new UtteranceSegmenter(options, std::move(*vad)));
}

Timestamp UtteranceSegmenter::stamp_of(int64_t i) const {
  if (!origin_.is_set()) return Timestamp::unset();
  return origin_ + frames_to_duration(i, rate_);
}

void UtteranceSegmenter::reset() {
  vad_->reset();
  origin_ = Timestamp::unset();
  pushed_ = buffer_first_ = 0;
  buffer_.clear();
  in_speech_ = false;
  run_ = silence_ = run_start_ = 0;
  utt_begin_ = speech_begin_ = speech_end_ = 0;
  prob_sum_ = 0;
  prob_n_ = 0;
}

void UtteranceSegmenter::flush(std::vector<Utterance>& out) {
  if (in_speech_) finish(pushed_, false, out);
  reset();
}

Status UtteranceSegmenter::push(std::span<const float> interleaved, Timestamp stamp,
                                std::vector<Utterance>& out) {
  const size_t ch = static_cast<size_t>(options_.channels);
  if (interleaved.size() % ch != 0)
    return make_error(ErrorCode::kInvalidArgument,
                      "utterance segmenter: {} values is not a whole number of {}-channel frames",
                      interleaved.size(), ch);
  if (!stamp.is_set() || stamp.is_special())
    return make_error(ErrorCode::kInvalidArgument, "utterance segmenter: chunk has no stamp");
  if (origin_.is_set() && (stamp - stamp_of(pushed_)).abs() > options_.max_jitter) flush(out);
  if (!origin_.is_set()) origin_ = stamp;

  const size_t n = interleaved.size() / ch;
  buffer_.insert(buffer_.end(), interleaved.begin(), interleaved.end());
  mono_.resize(n);
  if (options_.vad_channel >= 0) {
    for (size_t i = 0; i < n; ++i)
      mono_[i] = interleaved[i * ch + static_cast<size_t>(options_.vad_channel)];
  } else {
    for (size_t i = 0; i < n; ++i) {
      float s = 0;
      for (size_t c = 0; c < ch; ++c) s += interleaved[i * ch + c];
      mono_[i] = s / static_cast<float>(ch);
    }
  }
  frames_.clear();
  vad_->push(mono_, frames_);
  pushed_ += static_cast<int64_t>(n);
  for (const auto& f : frames_) on_frame(f, out);
  if (!in_speech_) {
    // Keep only what can still become pre-roll (plus the current speech run).
    const int64_t pre = static_cast<int64_t>(std::llround(options_.pre_roll_s * rate_));
    const int64_t keep_from =
        (run_ > 0 ? run_start_ : vad_->samples_pushed() - (vad_->samples_pushed() % frame_len_)) -
        pre;
    if (keep_from - buffer_first_ > rate_) drop_before(keep_from);
  }
  return ok_status();
}

void UtteranceSegmenter::on_frame(const VoiceActivityFrame& f, std::vector<Utterance>& out) {
  const int64_t frame_end = f.first_sample + frame_len_;
  const double frame_s = static_cast<double>(frame_len_) / rate_;
  if (!in_speech_) {
    if (!f.speech) {
      run_ = 0;
      prob_sum_ = 0;
      prob_n_ = 0;
      return;
    }
    if (run_ == 0) run_start_ = f.first_sample;
    ++run_;
    prob_sum_ += f.probability;
    ++prob_n_;
    if (static_cast<double>(run_) * frame_s + 1e-9 >= options_.min_speech_s) {
      in_speech_ = true;
      silence_ = 0;
      speech_begin_ = run_start_;
      speech_end_ = frame_end;
      const int64_t pre = static_cast<int64_t>(std::llround(options_.pre_roll_s * rate_));
      utt_begin_ = std::max(buffer_first_, run_start_ - pre);
    }
    return;
  }
  if (f.speech) {
    silence_ = 0;
    speech_end_ = frame_end;
    prob_sum_ += f.probability;
    ++prob_n_;
  } else {
    ++silence_;
  }
  const double length_s = static_cast<double>(frame_end - utt_begin_) / rate_;
  if (static_cast<double>(silence_) * frame_s + 1e-9 >= options_.hangover_s) {
    finish(frame_end, false, out);
  } else if (length_s + 1e-9 >= options_.max_utterance_s) {
    const bool continuing = f.speech;
    finish(frame_end, true, out);
    if (continuing) {  // speech goes on: the next utterance opens at once, without pre-roll
      in_speech_ = true;
      utt_begin_ = speech_begin_ = frame_end;
      speech_end_ = frame_end;
      silence_ = 0;
    }
  }
}

void UtteranceSegmenter::finish(int64_t end_sample, bool truncated, std::vector<Utterance>& out) {
  in_speech_ = false;
  run_ = silence_ = 0;
  end_sample = std::min(end_sample, pushed_);
  const double speech_s = static_cast<double>(speech_end_ - speech_begin_) / rate_;
  if (speech_s + 1e-9 >= options_.min_utterance_s && end_sample > utt_begin_) {
    const size_t ch = static_cast<size_t>(options_.channels);
    Utterance u;
    u.start = stamp_of(utt_begin_);
    u.end = stamp_of(end_sample);
    u.speech_start = stamp_of(speech_begin_);
    u.speech_end = stamp_of(speech_end_);
    u.sample_rate = rate_;
    u.channels = options_.channels;
    u.truncated = truncated;
    u.mean_probability =
        prob_n_ > 0 ? static_cast<float>(prob_sum_ / static_cast<double>(prob_n_)) : 0.f;
    const auto b = buffer_.begin() + static_cast<std::ptrdiff_t>((utt_begin_ - buffer_first_) *
                                                                 static_cast<int64_t>(ch));
    const auto e = buffer_.begin() + static_cast<std::ptrdiff_t>((end_sample - buffer_first_) *
                                                                 static_cast<int64_t>(ch));
    u.samples.assign(b, e);
    out.push_back(std::move(u));
  }
  prob_sum_ = 0;
  prob_n_ = 0;
  drop_before(end_sample);
}

void UtteranceSegmenter::drop_before(int64_t sample) {
  sample = std::clamp(sample, buffer_first_, pushed_);
  const size_t ch = static_cast<size_t>(options_.channels);
  buffer_.erase(buffer_.begin(),
                buffer_.begin() +
                    static_cast<std::ptrdiff_t>(static_cast<size_t>(sample - buffer_first_) * ch));
  buffer_first_ = sample;
}

}  // namespace dreamsense::audio
