#include "dreamsense/speech/speech_analyzer.hpp"

#include "dreamsense/core/log.hpp"
#include "dreamsense/core/perception.hpp"

#include <algorithm>
#include <cmath>
#include <deque>

namespace dreamsense::speech {

Status UtteranceGateOptions::check() const {
  if (!(frame_s > 0 && threshold_db > 0 && min_speech_s >= 0 && hangover_s > 0 && padding_s >= 0 &&
        max_utterance_s > hangover_s))
    return make_error(ErrorCode::kInvalidArgument,
                      "UtteranceGateOptions: frame_s, threshold_db, hangover_s must be > 0 and "
                      "max_utterance_s > hangover_s");
  return ok_status();
}

Status SpeechAnalyzerOptions::check() const {
  if (audio_sensor.empty())
    return make_error(ErrorCode::kInvalidArgument, "SpeechAnalyzerOptions: audio_sensor is empty");
  if (grammar.empty())
    return make_error(ErrorCode::kInvalidArgument, "SpeechAnalyzerOptions: no grammar file");
  if (auto s = recognizer.check(); !s) return s;
  return gate.check();
}

namespace {

class SpeechAnalyzer : public Analyzer {
 public:
  SpeechAnalyzer(SpeechAnalyzerOptions o, std::unique_ptr<Recognizer> r)
      : options_(std::move(o)), recognizer_(std::move(r)) {}
  std::string_view name() const override { return "speech"; }
  AnalyzerContract contract() const override {
    return {{options_.audio_sensor}, {}, {}, {keys::kRecognizedSpeech.name}};
  }

  Status process(const MultiFrame& in, const BlackboardView&, BlackboardWriter& out) override {
    for (const FramePtr& f : in.chunks_of(options_.audio_sensor)) {
      const AudioChunk* c = f->as<AudioChunk>();
      if (c == nullptr || c->channels <= 0)
        return make_error(ErrorCode::kInvalidArgument, "speech: '{}' is not an audio stream",
                          options_.audio_sensor);
      if (rate_ == 0) {
        rate_ = c->sample_rate;
        frame_len_ = std::max(1, static_cast<int>(std::lround(options_.gate.frame_s * rate_)));
      }
      // Mono = channel 0 (the array's microphones are 15-23 cm apart: averaging them would
      // comb-filter the speech).
      const int64_t n = c->frames();
      for (int64_t i = 0; i < n; ++i) {
        if (buffer_.empty())
          buffer_start_ = f->stamp + Duration::from_ns(i * 1'000'000'000LL / rate_);
        buffer_.push_back(c->samples[static_cast<size_t>(i * c->channels)]);
        if (static_cast<int>(buffer_.size() - analysed_) >= frame_len_) {
          if (auto s = gate_frame(out, in.stamp); !s) return s;
        }
      }
    }
    return ok_status();
  }

  void reset() override {
    buffer_.clear();
    analysed_ = 0;
    in_speech_ = false;
  }

 private:
  // Energy of the next frame; tracks the noise floor; opens/closes utterances.
  Status gate_frame(BlackboardWriter& out, Timestamp tick) {
    double e = 0;
    for (int i = 0; i < frame_len_; ++i) {
      const double v = buffer_[analysed_ + static_cast<size_t>(i)];
      e += v * v;
    }
    const double db = 10 * std::log10(e / frame_len_ + 1e-12);
    analysed_ += static_cast<size_t>(frame_len_);
    // Noise floor: follows drops at once, rises slowly (3 dB per second).
    noise_db_ = std::min(db, noise_db_ + 3.0 * options_.gate.frame_s);
    const bool loud = db > noise_db_ + options_.gate.threshold_db;
    const size_t frames_per_s = static_cast<size_t>(rate_);
    if (!in_speech_) {
      run_ = loud ? run_ + 1 : 0;
      if (run_ * options_.gate.frame_s >= options_.gate.min_speech_s) {
        in_speech_ = true;
        silence_ = 0;
        // Keep padding before the first loud frame.
        const size_t first_loud = analysed_ - run_ * static_cast<size_t>(frame_len_);
        const size_t pad = static_cast<size_t>(options_.gate.padding_s * rate_);
        utt_begin_ = first_loud > pad ? first_loud - pad : 0;
      } else {
        // Drop audio that can no longer be padding.
        const size_t keep = static_cast<size_t>(options_.gate.padding_s * rate_) +
                            run_ * static_cast<size_t>(frame_len_);
        if (analysed_ > keep + frames_per_s) drop_front(analysed_ - keep);
      }
      return ok_status();
    }
    silence_ = loud ? 0 : silence_ + 1;
    const double length_s = static_cast<double>(analysed_ - utt_begin_) / rate_;
    if (silence_ * options_.gate.frame_s >= options_.gate.hangover_s ||
        length_s >= options_.gate.max_utterance_s)
      return finish_utterance(out, tick);
    return ok_status();
  }

  Status finish_utterance(BlackboardWriter& out, Timestamp tick) {
    std::vector<float> samples(buffer_.begin() + static_cast<std::ptrdiff_t>(utt_begin_),
                               buffer_.begin() + static_cast<std::ptrdiff_t>(analysed_));
    const Timestamp start = buffer_start_ + Duration::from_ns(static_cast<int64_t>(utt_begin_) *
                                                              1'000'000'000LL / rate_);
    in_speech_ = false;
    run_ = 0;
    drop_front(analysed_);
    auto r = recognizer_->recognize(std::span<const float>(samples), rate_, start);
    if (!r) return tl::unexpected(r.error());
    if (!*r) return ok_status();  // out of grammar or noise: nothing to report
    RecognizedSpeech s = **r;
    s.sensor = options_.audio_sensor;
    const float confidence = static_cast<float>(s.confidence);
    out.set(keys::kRecognizedSpeech, std::move(s), tick, confidence);
    return ok_status();
  }

  void drop_front(size_t n) {
    n = std::min(n, buffer_.size());
    buffer_.erase(buffer_.begin(), buffer_.begin() + static_cast<std::ptrdiff_t>(n));
    buffer_start_ =
        buffer_start_ + Duration::from_ns(static_cast<int64_t>(n) * 1'000'000'000LL / rate_);
    analysed_ -= std::min(analysed_, n);
    utt_begin_ -= std::min(utt_begin_, n);
  }

  SpeechAnalyzerOptions options_;
  std::unique_ptr<Recognizer> recognizer_;
  std::deque<float> buffer_;  // mono samples not yet discarded
  Timestamp buffer_start_;    // stamp of buffer_.front()
  size_t analysed_ = 0;       // samples of buffer_ already gated
  int rate_ = 0, frame_len_ = 0;
  double noise_db_ = 0;  // starts high: the first frames pull it down
  bool in_speech_ = false;
  size_t run_ = 0, silence_ = 0, utt_begin_ = 0;
};

}  // namespace

Result<std::unique_ptr<Analyzer>> make_speech_analyzer(const SpeechAnalyzerOptions& options) {
  if (auto s = options.check(); !s) return tl::unexpected(s.error());
  auto grammar = Grammar::from_file(options.grammar);
  if (!grammar) return tl::unexpected(grammar.error());
  auto recognizer = Recognizer::create(options.recognizer, *grammar);
  if (!recognizer) return tl::unexpected(recognizer.error());
  return std::unique_ptr<Analyzer>(new SpeechAnalyzer(options, std::move(*recognizer)));
}

}  // namespace dreamsense::speech
