#include "dreamsense/speech/speech_analyzer.hpp"

#include "dreamsense/audio/noise_suppressor.hpp"
#include "dreamsense/audio/stamped_audio.hpp"
#include "dreamsense/core/log.hpp"
#include "dreamsense/perception/sound_direction.hpp"
#include "dreamsense/perception/speech.hpp"

#include <algorithm>
#include <cmath>
#include <condition_variable>
#include <deque>
#include <mutex>
#include <thread>

namespace dreamsense::speech {

Status SpeechAnalyzerOptions::check() const {
  if (audio_sensor.empty())
    return make_error(ErrorCode::kInvalidArgument, "SpeechAnalyzerOptions: audio_sensor is empty");
  if (grammar.empty())
    return make_error(ErrorCode::kInvalidArgument, "SpeechAnalyzerOptions: no grammar file");
  if (auto s = recognizer.check(); !s) return s;
  if (auto s = robot_gate.check(); !s) return s;
  if (!(fade_in_s >= 0) || fade_in_s > 1)
    return make_error(ErrorCode::kInvalidArgument,
                      "SpeechAnalyzerOptions: fade_in_s must be in [0, 1] s (got {})", fade_in_s);
  if (direction_margin < Duration())
    return make_error(ErrorCode::kInvalidArgument,
                      "SpeechAnalyzerOptions: direction_margin must be >= 0");
  // The stream's rate and channel count replace these when it starts; check the rest now.
  audio::UtteranceSegmenterOptions so = segmenter;
  so.channels = std::max(so.channels, so.vad_channel + 1);
  return so.check();
}

namespace {

class SpeechAnalyzer : public Analyzer {
 public:
  SpeechAnalyzer(SpeechAnalyzerOptions o, std::unique_ptr<Recognizer> r)
      : options_(std::move(o)), recognizer_(std::move(r)) {
    if (options_.background_decode) worker_ = std::thread([this] { decode_jobs(); });
  }
  SpeechAnalyzer(const SpeechAnalyzer&) = delete;
  SpeechAnalyzer& operator=(const SpeechAnalyzer&) = delete;
  ~SpeechAnalyzer() override {
    if (!worker_.joinable()) return;
    {
      std::lock_guard<std::mutex> lock(jobs_mutex_);
      stopping_ = true;
    }
    jobs_cv_.notify_all();
    worker_.join();
  }
  std::string_view name() const override { return "speech"; }
  AnalyzerContract contract() const override {
    AnalyzerContract c{{options_.audio_sensor}, {}, {}, {keys::kRecognizedSpeech.name}};
    if (options_.beamforming()) c.reads.push_back(keys::kSoundDirection.name);
    if (!options_.reference_sensor.empty()) c.optional_inputs.push_back(options_.reference_sensor);
    return c;
  }

  Status process(const MultiFrame& in, const BlackboardView& prior,
                 BlackboardWriter& out) override {
    if (options_.beamforming()) note_direction(prior);
    if (options_.background_decode) publish_decoded(out, in.stamp);
    utterances_.clear();
    if (gate_)  // the robot's reference first: the gate must know this tick before deciding
      for (const FramePtr& f : in.chunks_of(options_.reference_sensor)) {
        const AudioChunk* c = f->as<AudioChunk>();
        if (c == nullptr)
          return make_error(ErrorCode::kInvalidArgument,
                            "speech: robot reference '{}' is not an audio stream",
                            options_.reference_sensor);
        if (auto s = gate_->push_reference(c->samples, c->channels, c->sample_rate, f->stamp); !s)
          return s;
      }
    for (const FramePtr& f : in.chunks_of(options_.audio_sensor)) {
      const AudioChunk* c = f->as<AudioChunk>();
      if (c == nullptr || c->channels <= 0 || c->sample_rate <= 0)
        return make_error(ErrorCode::kInvalidArgument, "speech: '{}' is not an audio stream",
                          options_.audio_sensor);
      if (rate_ == 0) {
        if (auto s = start_stream(*c); !s) return s;
      } else if (c->sample_rate != rate_ || c->channels != channels_) {
        return make_error(ErrorCode::kInvalidArgument,
                          "speech: stream '{}' changed from {} ch at {} Hz to {} ch at {} Hz",
                          options_.audio_sensor, channels_, rate_, c->channels, c->sample_rate);
      }
      if (gate_) gate_->push_microphone(c->samples, c->channels, c->sample_rate, f->stamp);
      if (auto s = segmenter_->push(c->samples, f->stamp, utterances_); !s) {
        return make_error(s.error().code, "speech: {} (stream '{}' at {})", s.error().message,
                          options_.audio_sensor, f->stamp.to_string());
      }
    }
    for (auto& u : utterances_) {
      if (gate_ && !cut_robot_voice(u)) continue;
      std::optional<cv::Vec3d> dir;
      if (beamformer_) dir = direction_of(u);
      if (options_.background_decode) {
        std::lock_guard<std::mutex> lock(jobs_mutex_);
        jobs_.push_back({std::move(u), dir});
        jobs_cv_.notify_all();
        continue;
      }
      auto r = decode(u, dir);
      if (!r) return tl::unexpected(r.error());
      publish(std::move(*r), out, in.stamp);
    }
    return ok_status();
  }

  void reset() override {
    if (worker_.joinable()) {  // utterances of the old stream are dropped, not reported
      std::unique_lock<std::mutex> lock(jobs_mutex_);
      jobs_.clear();
      jobs_cv_.wait(lock, [this] { return !busy_; });
      decoded_.clear();
    }
    rate_ = channels_ = 0;
    segmenter_.reset();
    beamformer_.reset();
    directions_.clear();
    if (gate_) gate_->reset();
  }

  void enable_gate() {
    if (!options_.reference_sensor.empty())
      gate_ = std::make_unique<audio::ReferenceGate>(options_.robot_gate);
  }

 private:
  struct HeardDirection {
    Timestamp stamp;
    cv::Vec3d direction;
    double weight;
  };

  Status start_stream(const AudioChunk& c) {
    rate_ = c.sample_rate;
    channels_ = c.channels;
    audio::UtteranceSegmenterOptions so = options_.segmenter;
    so.vad.sample_rate = rate_;
    so.channels = channels_;
    so.vad_channel = std::min(so.vad_channel, channels_ - 1);
    auto s = audio::UtteranceSegmenter::create(so);
    if (!s)
      return make_error(s.error().code, "speech: stream '{}': {}", options_.audio_sensor,
                        s.error().message);
    segmenter_ = std::move(*s);
    if (options_.beamforming()) {
      if (static_cast<size_t>(channels_) != options_.mic_positions_m.size())
        return make_error(ErrorCode::kInvalidArgument,
                          "speech: stream '{}' has {} channel(s) but the microphone array has {} "
                          "microphones",
                          options_.audio_sensor, channels_, options_.mic_positions_m.size());
      audio::BeamformerOptions bo;
      bo.sample_rate = rate_;
      bo.mic_positions_m = options_.mic_positions_m;
      bo.method = options_.beamformer;
      auto b = audio::Beamformer::create(bo);
      if (!b) return make_error(b.error().code, "speech: {}", b.error().message);
      beamformer_ = std::move(*b);
    }
    return ok_status();
  }

  // Cuts the utterance to its longest part without the robot's voice; false when too little of
  // its speech is left (the robot spoke it).
  bool cut_robot_voice(audio::Utterance& u) const {
    const auto [qa, qb] = gate_->longest_quiet_span(u.start, u.end);
    const Timestamp sa = std::max(u.speech_start, qa), sb = std::min(u.speech_end, qb);
    if (!(sb > sa) || (sb - sa).seconds() < options_.min_free_speech_s) {
      log::debug("speech: utterance {:.2f}-{:.2f} s not decoded: the robot is speaking",
                 u.speech_start.seconds(), u.speech_end.seconds());
      return false;
    }
    if (qa <= u.start && qb >= u.end) return true;
    const int64_t n = u.frames();
    const int64_t b = std::clamp(audio::duration_to_frames(qa - u.start, rate_), int64_t{0}, n);
    const int64_t e = std::clamp(audio::duration_to_frames(qb - u.start, rate_), b, n);
    const size_t ch = static_cast<size_t>(u.channels);
    u.samples = std::vector<float>(u.samples.begin() + static_cast<std::ptrdiff_t>(b * ch),
                                   u.samples.begin() + static_cast<std::ptrdiff_t>(e * ch));
    u.end = u.start + audio::frames_to_duration(e, rate_);
    u.start = u.start + audio::frames_to_duration(b, rate_);
    u.speech_start = sa;
    u.speech_end = sb;
    return true;
  }

  // Keeps the sound directions of the last seconds (one per new blackboard entry).
  void note_direction(const BlackboardView& prior) {
    auto e = prior.get(keys::kSoundDirection);
    if (e && e->present() && e->value->sensor == options_.audio_sensor &&
        (directions_.empty() || e->stamp > directions_.back().stamp))
      directions_.push_back({e->stamp, e->value->direction_array,
                             std::max(1e-3, static_cast<double>(e->confidence))});
    const double keep_s = options_.segmenter.max_utterance_s + 5.0;
    while (!directions_.empty() && e && (e->stamp - directions_.front().stamp).seconds() > keep_s)
      directions_.pop_front();
  }

  // Confidence-weighted mean direction heard during the utterance's speech, if any.
  std::optional<cv::Vec3d> direction_of(const audio::Utterance& u) const {
    cv::Vec3d sum(0, 0, 0);
    for (const auto& d : directions_)
      if (d.stamp >= u.speech_start - options_.direction_margin &&
          d.stamp <= u.speech_end + options_.direction_margin)
        sum += d.weight * d.direction;
    if (cv::norm(sum) < 1e-9) return std::nullopt;
    return sum / cv::norm(sum);
  }

  // An utterance waiting for the background decoder, with the direction heard during it.
  struct Job {
    audio::Utterance utterance;
    std::optional<cv::Vec3d> direction;
  };

  // The background decoder (SpeechAnalyzerOptions::background_decode): one utterance at a time,
  // in the order they ended, so the recogniser and the beamformer are only used by this thread.
  void decode_jobs() {
    std::unique_lock<std::mutex> lock(jobs_mutex_);
    while (true) {
      jobs_cv_.wait(lock, [this] { return stopping_ || !jobs_.empty(); });
      if (stopping_) return;
      Job job = std::move(jobs_.front());
      jobs_.pop_front();
      busy_ = true;
      lock.unlock();
      Result<std::optional<RecognizedSpeech>> r = decode(job.utterance, job.direction);
      lock.lock();
      busy_ = false;
      decoded_.push_back(std::move(r));
      jobs_cv_.notify_all();
    }
  }

  // Writes the oldest result the background decoder has finished at this tick (one per tick: a
  // second one would overwrite it on the blackboard; the next waits for the next tick). A
  // decoding error is logged: it costs that utterance, not the analysis.
  void publish_decoded(BlackboardWriter& out, Timestamp tick) {
    while (true) {
      std::optional<Result<std::optional<RecognizedSpeech>>> r;
      {
        std::lock_guard<std::mutex> lock(jobs_mutex_);
        if (decoded_.empty()) return;
        r = std::move(decoded_.front());
        decoded_.pop_front();
      }
      if (!*r) {
        log::warn("speech: an utterance was not decoded: {}", r->error().message);
        continue;
      }
      if (!**r) continue;  // out of grammar or noise: nothing to report
      publish(std::move(**r), out, tick);
      return;
    }
  }

  void publish(std::optional<RecognizedSpeech> heard, BlackboardWriter& out, Timestamp tick) {
    if (!heard) return;  // out of grammar or noise: nothing to report
    const float confidence = static_cast<float>(heard->confidence);
    out.set(keys::kRecognizedSpeech, std::move(*heard), tick, confidence);
  }

  // Beamforms (towards `dir`, when given), cleans and recognises one utterance; nullopt when
  // nothing in the grammar was said.
  Result<std::optional<RecognizedSpeech>> decode(const audio::Utterance& u,
                                                 const std::optional<cv::Vec3d>& dir) {
    std::vector<float> mono;
    if (dir) {
      beamformer_->steer(*dir);
      auto y = beamformer_->apply(u.samples);
      if (!y) return tl::unexpected(y.error());
      mono = std::move(*y);
    } else {
      mono = u.channel(0);  // no array or no direction: channel 0 (see the header)
    }
    audio::fade_in_pre_roll(mono, u, options_.fade_in_s);
    if (options_.noise_suppression) {
      auto clean = audio::suppress_noise(mono, rate_);
      if (!clean) return tl::unexpected(clean.error());
      mono = std::move(*clean);
    }
    auto r = recognizer_->recognize(std::span<const float>(mono), rate_, u.start);
    if (!r) return tl::unexpected(r.error());
    if (*r) (*r)->sensor = options_.audio_sensor;
    return r;
  }

  SpeechAnalyzerOptions options_;
  std::unique_ptr<Recognizer> recognizer_;
  int rate_ = 0, channels_ = 0;
  std::unique_ptr<audio::UtteranceSegmenter> segmenter_;
  std::unique_ptr<audio::Beamformer> beamformer_;
  std::unique_ptr<audio::ReferenceGate> gate_;
  std::deque<HeardDirection> directions_;
  std::vector<audio::Utterance> utterances_;  // scratch
  // Background decoding: jobs_ and decoded_ are shared with worker_ under jobs_mutex_.
  std::mutex jobs_mutex_;
  std::condition_variable jobs_cv_;
  std::deque<Job> jobs_;
  std::deque<Result<std::optional<RecognizedSpeech>>> decoded_;
  bool busy_ = false, stopping_ = false;
  std::thread worker_;  // last: started when everything it uses exists
};

}  // namespace

Result<std::unique_ptr<Analyzer>> make_speech_analyzer(const SpeechAnalyzerOptions& options) {
  if (auto s = options.check(); !s) return tl::unexpected(s.error());
  auto grammar = Grammar::from_file(options.grammar);
  if (!grammar) return tl::unexpected(grammar.error());
  auto recognizer = Recognizer::create(options.recognizer, *grammar);
  if (!recognizer) return tl::unexpected(recognizer.error());
  auto a = std::make_unique<SpeechAnalyzer>(options, std::move(*recognizer));
  a->enable_gate();
  return std::unique_ptr<Analyzer>(std::move(a));
}

}  // namespace dreamsense::speech
