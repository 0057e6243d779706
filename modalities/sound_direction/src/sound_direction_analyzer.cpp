#include "dreamsense/sound_direction/sound_direction_analyzer.hpp"

#include "dreamsense/core/log.hpp"
#include "dreamsense/perception/sound_direction.hpp"

#include <algorithm>
#include <cmath>

namespace dreamsense::sound_direction {
namespace {

class SoundDirectionAnalyzer : public Analyzer {
 public:
  SoundDirectionAnalyzer(SoundDirectionAnalyzerOptions o, std::unique_ptr<DirectionFinder> f)
      : options_(std::move(o)), finder_(std::move(f)) {}
  std::string_view name() const override { return "sound_direction"; }
  AnalyzerContract contract() const override {
    AnalyzerContract c{{options_.audio_sensor}, {}, {}, {keys::kSoundDirection.name}};
    if (!options_.reference_sensor.empty()) c.optional_inputs.push_back(options_.reference_sensor);
    return c;
  }

  Status process(const MultiFrame& in, const BlackboardView&, BlackboardWriter& out) override {
    if (gate_)  // the robot's reference first: the gate must know this tick
      for (const FramePtr& f : in.chunks_of(options_.reference_sensor)) {
        const AudioChunk* c = f->as<AudioChunk>();
        if (c == nullptr)
          return make_error(ErrorCode::kInvalidArgument,
                            "sound_direction: robot reference '{}' is not an audio stream",
                            options_.reference_sensor);
        if (auto s = gate_->push_reference(c->samples, c->channels, c->sample_rate, f->stamp); !s)
          return s;
      }
    const auto& chunks = in.chunks_of(options_.audio_sensor);
    if (chunks.empty()) return ok_status();
    const int fs = options_.geometry.sample_rate;
    const int channels = static_cast<int>(options_.geometry.mics_m.size());
    estimates_.clear();
    for (const FramePtr& f : chunks) {
      const AudioChunk* a = f->as<AudioChunk>();
      if (a == nullptr)
        return make_error(ErrorCode::kInvalidArgument,
                          "sound_direction: stream '{}' is not an audio stream",
                          options_.audio_sensor);
      if (a->sample_rate != fs || a->channels != channels)
        return make_error(ErrorCode::kInvalidArgument,
                          "sound_direction: stream '{}' has {} channel(s) at {} Hz but the "
                          "configured array has {} microphones at {} Hz",
                          options_.audio_sensor, a->channels, a->sample_rate, channels, fs);
      // A gap or overlap of more than one hop restarts the analysis at this chunk.
      if (origin_.is_set()) {
        const Timestamp expected = origin_ + samples_to_duration(pushed_);
        if (std::abs((f->stamp - expected).seconds()) >
            static_cast<double>(options_.finder.hop) / fs) {
          finder_->reset();
          origin_ = Timestamp::unset();
        }
      }
      if (!origin_.is_set()) {
        origin_ = f->stamp;
        pushed_ = 0;
      }
      if (gate_) gate_->push_microphone(a->samples, a->channels, a->sample_rate, f->stamp);
      if (auto s = finder_->push(a->samples, estimates_); !s)
        return make_error(s.error().code, "{} (stream '{}' at {})", s.error().message,
                          options_.audio_sensor, f->stamp.to_string());
      pushed_ += a->frames();
    }
    if (estimates_.empty()) return ok_status();
    for (const auto& e : estimates_) note_quality(e);

    const FrameEstimate& e = estimates_.back();
    const Timestamp stamp = std::min(origin_ + samples_to_duration(e.centre_sample), in.stamp);
    if (!e.voiced || !e.smoothed_peak || (gate_ && gate_->active(stamp))) {
      out.set_absent(keys::kSoundDirection, stamp);
      return ok_status();
    }
    const SrpPeak& p = *e.smoothed_peak;
    SoundDirection d;
    d.azimuth_deg = p.azimuth_deg;
    d.elevation_deg = p.elevation_deg;
    d.direction_array = p.unit;
    d.direction_world = options_.geometry.to_world_direction(p.unit);
    d.srp_power = p.power;
    d.sensor = options_.audio_sensor;
    out.set(keys::kSoundDirection, std::move(d), stamp, static_cast<float>(e.confidence));
    return ok_status();
  }

  void reset() override {
    finder_->reset();
    origin_ = Timestamp::unset();
    pushed_ = 0;
    silent_frames_ = 0;
    if (gate_) gate_->reset();
  }

  void enable_gate() {
    if (!options_.reference_sensor.empty())
      gate_ = std::make_unique<audio::ReferenceGate>(options_.robot_gate);
  }

 private:
  Duration samples_to_duration(int64_t n) const {
    return Duration::from_ns(n * 1000000000LL / options_.geometry.sample_rate);
  }
  void note_quality(const FrameEstimate& e) {
    if (e.clipped && !warned_clipped_) {
      warned_clipped_ = true;
      log::warn(
          "sound_direction: stream '{}' is clipped (>= 1% of samples at full scale); "
          "directions may be unreliable",
          options_.audio_sensor);
    }
    silent_frames_ = e.level_dbfs < options_.finder.vad.min_level_dbfs ? silent_frames_ + 1 : 0;
    const double silent_s =
        static_cast<double>(silent_frames_ * options_.finder.hop) / options_.geometry.sample_rate;
    if (silent_s >= 10.0 && !warned_silent_) {
      warned_silent_ = true;
      log::warn(
          "sound_direction: stream '{}' has been silent (below {} dBFS) for 10 s; no sound "
          "direction while it stays silent",
          options_.audio_sensor, options_.finder.vad.min_level_dbfs);
    }
  }

  SoundDirectionAnalyzerOptions options_;
  std::unique_ptr<DirectionFinder> finder_;
  std::vector<FrameEstimate> estimates_;
  std::unique_ptr<audio::ReferenceGate> gate_;
  Timestamp origin_ = Timestamp::unset();  // stamp of the finder's sample 0
  int64_t pushed_ = 0;
  int64_t silent_frames_ = 0;
  bool warned_clipped_ = false, warned_silent_ = false;
};

}  // namespace

Status SoundDirectionAnalyzerOptions::check() const {
  if (audio_sensor.empty())
    return make_error(ErrorCode::kInvalidArgument,
                      "SoundDirectionAnalyzerOptions: audio_sensor is empty");
  if (auto s = geometry.check(); !s) return s;
  if (auto s = robot_gate.check(); !s) return s;
  return finder.check(geometry.sample_rate);
}

Result<std::unique_ptr<Analyzer>> make_sound_direction_analyzer(
    const SoundDirectionAnalyzerOptions& options) {
  if (auto s = options.check(); !s) return tl::unexpected(s.error());
  auto f = DirectionFinder::create(options.geometry, options.finder);
  if (!f) return tl::unexpected(f.error());
  auto a = std::make_unique<SoundDirectionAnalyzer>(options, std::move(*f));
  a->enable_gate();
  return std::unique_ptr<Analyzer>(std::move(a));
}

}  // namespace dreamsense::sound_direction
