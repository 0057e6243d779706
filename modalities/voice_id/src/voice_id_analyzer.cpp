#include "dreamsense/voice_id/voice_id_analyzer.hpp"

#include "dreamsense/audio/noise_suppressor.hpp"
#include "dreamsense/audio/stamped_audio.hpp"
#include "dreamsense/core/log.hpp"
#include "dreamsense/perception/head_pose.hpp"
#include "dreamsense/perception/sound_direction.hpp"
#include "dreamsense/perception/voice_id.hpp"

#include <algorithm>
#include <cmath>
#include <deque>
#include <map>
#include <optional>

namespace dreamsense::voice_id {

const char* to_string(VoiceIdMethod m) {
  return m == VoiceIdMethod::kGmmUbm ? "gmm_ubm" : "direction_rule";
}

Result<VoiceIdMethod> parse_voice_id_method(const std::string& s) {
  if (s == "gmm_ubm") return VoiceIdMethod::kGmmUbm;
  if (s == "direction_rule") return VoiceIdMethod::kDirectionRule;
  return make_error(ErrorCode::kInvalidArgument,
                    "voice id method '{}' is unknown (gmm_ubm or direction_rule)", s);
}

const char* to_string(VoiceDecision d) {
  return d == VoiceDecision::kUtterance ? "utterance" : "tracks";
}

Result<VoiceDecision> parse_voice_decision(const std::string& s) {
  if (s == "utterance") return VoiceDecision::kUtterance;
  if (s == "tracks") return VoiceDecision::kTracks;
  return make_error(ErrorCode::kInvalidArgument,
                    "voice decision '{}' is unknown (utterance or tracks)", s);
}

Status DirectionRuleOptions::check() const {
  if (!(angle_deg > 0 && angle_deg < 90 && min_confidence >= 0 && min_confidence < 1))
    return make_error(ErrorCode::kInvalidArgument,
                      "DirectionRuleOptions: angle_deg must be in (0, 90), min_confidence in "
                      "[0, 1)");
  return ok_status();
}

Status VoiceIdAnalyzerOptions::check() const {
  if (audio_sensor.empty())
    return make_error(ErrorCode::kInvalidArgument, "VoiceIdAnalyzerOptions: audio_sensor is empty");
  if (method == VoiceIdMethod::kGmmUbm && !model && model_file.empty())
    return make_error(ErrorCode::kInvalidArgument,
                      "VoiceIdAnalyzerOptions: method gmm_ubm needs a voice model (model or "
                      "model_file)");
  if (auto s = direction.check(); !s) return s;
  if (auto s = robot_gate.check(); !s) return s;
  if (auto s = tracks.check(); !s) return s;
  return segmenter.check();  // the stream's rate replaces vad.sample_rate when it starts
}

namespace {

struct Heard {
  Timestamp stamp;
  double azimuth_deg;
  double confidence;
};

class VoiceIdAnalyzer : public Analyzer {
 public:
  VoiceIdAnalyzer(VoiceIdAnalyzerOptions o, std::shared_ptr<const VoiceModel> model)
      : options_(std::move(o)), model_(std::move(model)) {}
  std::string_view name() const override { return "voice_id"; }
  AnalyzerContract contract() const override {
    AnalyzerContract c{{options_.audio_sensor}, {}, {}, {keys::kSpeakerIdentity.name}};
    if (!options_.reference_sensor.empty()) c.optional_inputs.push_back(options_.reference_sensor);
    if (options_.method == VoiceIdMethod::kDirectionRule)
      c.reads.push_back(keys::kSoundDirection.name);
    else if (options_.decision == VoiceDecision::kTracks)
      c.reads_previous.push_back(keys::kSoundDirection.name);
    if (child_cue_) c.reads_previous.push_back(keys::kHeadPose.name);
    return c;
  }

  Status process(const MultiFrame& in, const BlackboardView& prior,
                 BlackboardWriter& out) override {
    if (options_.method == VoiceIdMethod::kDirectionRule || tracker_) remember_direction(prior);
    if (child_cue_) remember_child(prior);
    if (gate_)  // the robot's reference first: the gate must know this tick before deciding
      for (const FramePtr& f : in.chunks_of(options_.reference_sensor)) {
        const AudioChunk* c = f->as<AudioChunk>();
        if (c == nullptr)
          return make_error(ErrorCode::kInvalidArgument,
                            "voice_id: robot reference '{}' is not an audio stream",
                            options_.reference_sensor);
        if (auto s = gate_->push_reference(c->samples, c->channels, c->sample_rate, f->stamp); !s)
          return s;
        note_alignment();
      }
    for (const FramePtr& f : in.chunks_of(options_.audio_sensor)) {
      const AudioChunk* c = f->as<AudioChunk>();
      if (c == nullptr || c->channels <= 0)
        return make_error(ErrorCode::kInvalidArgument, "voice_id: '{}' is not an audio stream",
                          options_.audio_sensor);
      if (!segmenter_) {
        if (model_ && c->sample_rate / 2.0 < model_->features.high_hz)
          return make_error(ErrorCode::kUnsupported,
                            "voice_id: '{}' is sampled at {} Hz, the voice model needs >= {} Hz",
                            options_.audio_sensor, c->sample_rate,
                            static_cast<int>(std::ceil(2 * model_->features.high_hz)));
        audio::UtteranceSegmenterOptions so = options_.segmenter;
        so.vad.sample_rate = c->sample_rate;
        // Channel 0 is pushed (and scored); with vad_on_channel_mean also the channels' mean,
        // on which the segmenter then decides.
        seg_channels_ = options_.vad_on_channel_mean && c->channels > 1 ? 2 : 1;
        so.channels = seg_channels_;
        so.vad_channel = seg_channels_ - 1;
        auto seg = audio::UtteranceSegmenter::create(so);
        if (!seg)
          return make_error(seg.error().code, "voice_id: stream '{}': {}", options_.audio_sensor,
                            seg.error().message);
        segmenter_ = std::move(*seg);
        rate_ = c->sample_rate;
      } else if (c->sample_rate != rate_) {
        return make_error(ErrorCode::kInvalidArgument,
                          "voice_id: '{}' changed sample rate from {} to {} Hz",
                          options_.audio_sensor, rate_, c->sample_rate);
      }
      // Mono = channel 0 (averaging the array's microphones would comb-filter the speech).
      const size_t sc = static_cast<size_t>(seg_channels_), cc = static_cast<size_t>(c->channels);
      std::vector<float> mono(static_cast<size_t>(c->frames()) * sc);
      for (size_t i = 0; i < mono.size() / sc; ++i) {
        mono[i * sc] = c->samples[i * cc];
        if (sc == 2) {
          float m = 0;
          for (size_t k = 0; k < cc; ++k) m += c->samples[i * cc + k];
          mono[i * sc + 1] = m / static_cast<float>(cc);
        }
      }
      Timestamp stamp = f->stamp;
      if (model_ && model_->features.noise_suppression) {  // as the enrolment was
        if (!denoiser_) {
          audio::NoiseSuppressorOptions no;
          no.sample_rate = rate_;
          no.channels = seg_channels_;
          auto d = audio::NoiseSuppressor::create(no);
          if (!d) return make_error(d.error().code, "voice_id: {}", d.error().message);
          denoiser_ = std::move(*d);
        }
        // Output sample k is input sample k - latency: stamps follow the output count, and a
        // gap in the input restarts the suppressor.
        const Timestamp expected = ns_origin_ + audio::frames_to_duration(ns_pushed_, rate_);
        if (!ns_origin_.is_set() || std::abs((f->stamp - expected).seconds()) > 1e-3) {
          denoiser_->reset();
          ns_origin_ = f->stamp;
          ns_pushed_ = ns_emitted_ = 0;
        }
        denoised_.clear();
        denoiser_->process(mono, denoised_);
        ns_pushed_ += static_cast<int64_t>(mono.size() / sc);
        stamp = ns_origin_ + audio::frames_to_duration(ns_emitted_, rate_) -
                audio::frames_to_duration(denoiser_->latency(), rate_);
        ns_emitted_ += static_cast<int64_t>(denoised_.size() / sc);
        mono.swap(denoised_);
        if (mono.empty()) continue;
      }
      utterances_.clear();
      if (gate_) {
        gate_->push_microphone(mono, seg_channels_, rate_, stamp);
        note_alignment();
      }
      if (auto s = segmenter_->push(mono, stamp, utterances_); !s)
        return make_error(s.error().code, "voice_id: {}", s.error().message);
      for (const audio::Utterance& u : utterances_)
        if (auto s = decide(u, in.stamp, out); !s) return s;
    }
    return ok_status();
  }

  void reset() override {
    if (segmenter_) segmenter_->reset();
    if (gate_) gate_->reset();
    if (denoiser_) denoiser_->reset();
    ns_origin_ = Timestamp::unset();
    heard_.clear();
    seen_.clear();
    if (tracker_) tracker_->reset();
  }

  void enable_tracks() {
    if (model_ && options_.method == VoiceIdMethod::kGmmUbm &&
        options_.decision == VoiceDecision::kTracks) {
      SpeakerTrackOptions t = options_.tracks;
      const bool child_enrolled =
          std::any_of(model_->speakers.begin(), model_->speakers.end(),
                      [](const EnrolledSpeaker& sp) { return sp.id == "child"; });
      if (t.child_speaker_id.empty() && options_.use_seen_child && child_enrolled)
        t.child_speaker_id = "child";
      tracker_ = std::make_unique<SpeakerTracker>(t, model_->threshold);
      child_cue_ = !t.child_speaker_id.empty() && options_.array_from_world_R.has_value();
    }
  }

  void enable_gate() {
    if (!options_.reference_sensor.empty())
      gate_ = std::make_unique<audio::ReferenceGate>(options_.robot_gate);
  }

 private:
  void remember_direction(const BlackboardView& prior) {
    const auto e = prior.get(keys::kSoundDirection);
    if (!e || !e->present()) return;
    if (!heard_.empty() && heard_.back().stamp >= e->stamp) return;  // already seen
    heard_.push_back({e->stamp, e->value->azimuth_deg, e->confidence});
    const Duration keep = Duration::from_seconds(options_.segmenter.max_utterance_s + 5.0);
    while (!heard_.empty() && e->stamp - heard_.front().stamp > keep) heard_.pop_front();
  }

  // The child's head seen by the cameras, as an azimuth in the array frame in the sound
  // direction's convention (atan2(x, z); asin(x / r) for a linear array).
  void remember_child(const BlackboardView& prior) {
    const auto e = prior.get(keys::kHeadPose);
    if (!e || !e->present()) return;
    const Timestamp stamp = e->value->frame_stamp.is_set() ? e->value->frame_stamp : e->stamp;
    if (!seen_.empty() && seen_.back().stamp >= stamp) return;  // already seen
    const cv::Vec3d a =
        *options_.array_from_world_R * e->value->position_world_m + options_.array_from_world_t;
    const double r = cv::norm(a);
    if (!(r > 0) || (!options_.array_is_linear && a[0] == 0 && a[2] == 0)) return;
    // A linear array (mics on x) measures the angle from its axis, the same for front and back
    // and for any elevation, and reports it as an azimuth in the front half-plane: asin(x / r).
    const double azimuth = options_.array_is_linear ? std::asin(std::clamp(a[0] / r, -1.0, 1.0))
                                                    : std::atan2(a[0], a[2]);
    seen_.push_back({stamp, azimuth * 180 / M_PI, 1.0});
    const Duration keep = Duration::from_seconds(options_.segmenter.max_utterance_s + 5.0 +
                                                 options_.seen_child_lookback_s);
    while (!seen_.empty() && stamp - seen_.front().stamp > keep) seen_.pop_front();
  }

  void note_alignment() {
    if (alignment_noted_ || !gate_->measured_offset()) return;
    alignment_noted_ = true;
    const double m = *gate_->measured_offset();
    if (std::abs(m - options_.robot_gate.offset_s) > options_.robot_gate.align_tolerance_s)
      log::warn(
          "voice_id: robot reference '{}' is offset by {:+.2f} s against '{}' (measured from "
          "the robot's speech; configured {:+.2f} s): using the measured offset",
          options_.reference_sensor, m, options_.audio_sensor, options_.robot_gate.offset_s);
  }

  Status decide(const audio::Utterance& u_in, Timestamp tick, BlackboardWriter& out) {
    const audio::Utterance* up = &u_in;
    audio::Utterance trimmed;
    if (gate_) {  // the robot's voice: keep the longest robot-free part, if enough speech is left
      const auto [qa, qb] = gate_->longest_quiet_span(u_in.start, u_in.end);
      const Timestamp sa = std::max(u_in.speech_start, qa), sb = std::min(u_in.speech_end, qb);
      if (!(sb > sa) || (sb - sa).seconds() < options_.min_free_speech_s) {
        log::debug("voice_id: utterance {:.2f}-{:.2f} s dropped: the robot is speaking",
                   u_in.speech_start.seconds(), u_in.speech_end.seconds());
        return ok_status();
      }
      if (qa > u_in.start || qb < u_in.end) {
        const int64_t n = u_in.frames();
        const auto ch = static_cast<std::ptrdiff_t>(u_in.channels);
        const int64_t b =
            std::clamp(audio::duration_to_frames(qa - u_in.start, rate_), int64_t{0}, n);
        const int64_t e = std::clamp(audio::duration_to_frames(qb - u_in.start, rate_), b, n);
        trimmed.start = u_in.start + audio::frames_to_duration(b, rate_);
        trimmed.end = u_in.start + audio::frames_to_duration(e, rate_);
        trimmed.speech_start = sa;
        trimmed.speech_end = sb;
        trimmed.channels = u_in.channels;
        trimmed.sample_rate = u_in.sample_rate;
        trimmed.samples.assign(u_in.samples.begin() + b * ch, u_in.samples.begin() + e * ch);
        up = &trimmed;
      }
    }
    const audio::Utterance& u = *up;
    SpeakerIdentity id;
    id.start = u.speech_start;
    id.end = u.speech_end;
    id.sensor = options_.audio_sensor;
    id.method = to_string(options_.method);
    if (options_.method == VoiceIdMethod::kGmmUbm) {
      // The speech part only (+-50 ms): the pre-roll and the hangover are the room's noise.
      const int64_t margin = static_cast<int64_t>(0.05 * rate_);
      const std::vector<float> scored = u.channels > 1 ? u.channel(0) : std::vector<float>{};
      const std::vector<float>& ch0 = u.channels > 1 ? scored : u.samples;
      const int64_t n = static_cast<int64_t>(ch0.size());
      const int64_t b = std::clamp(
          audio::duration_to_frames(u.speech_start - u.start, rate_) - margin, int64_t{0}, n);
      const int64_t e =
          std::clamp(audio::duration_to_frames(u.speech_end - u.start, rate_) + margin, b, n);
      auto r = identify(
          *model_,
          std::span<const float>(ch0).subspan(static_cast<size_t>(b), static_cast<size_t>(e - b)),
          rate_, /*denoised=*/true);
      if (!r) return tl::unexpected(r.error());
      if (r->frames == 0) return ok_status();  // nothing speech-like in it
      {
        std::string scores;
        for (const auto& sc : r->scores)
          scores += fmt::format(" {}={:.3f}",
                                options_.include_names ? sc.id : public_speaker_id(*model_, sc.id),
                                sc.llr);
        log::debug("voice_id: utterance {:.2f}-{:.2f} s, {} frames, llr{}",
                   u.speech_start.seconds(), u.speech_end.seconds(), r->frames, scores);
      }
      if (tracker_) decide_on_track(u, *r);
      // Enrolment folder names may be people's names: the public id unless names are asked for.
      id.speaker_id = public_speaker_id(*model_, r->speaker_id);
      id.name = options_.include_names ? r->name : id.speaker_id;
      id.score = r->score;
    } else {
      direction_rule(u, id);
    }
    const float confidence = static_cast<float>(id.score);
    out.set(keys::kSpeakerIdentity, std::move(id), tick, confidence);
    return ok_status();
  }

  // Confidence-weighted circular mean of the azimuths stamped in [from, to] (nullopt: fewer
  // than min_count of them).
  static std::optional<double> mean_azimuth(const std::deque<Heard>& directions, Timestamp from,
                                            Timestamp to, int min_count) {
    double sx = 0, sy = 0;
    int n = 0;
    for (const auto& h : directions) {
      if (h.stamp < from || h.stamp > to) continue;
      const double a = h.azimuth_deg * M_PI / 180, w = std::max(1e-3, h.confidence);
      sx += w * std::cos(a), sy += w * std::sin(a), ++n;
    }
    if (n < min_count) return std::nullopt;
    return std::atan2(sy, sx) * 180 / M_PI;
  }
  // Where the utterance came from: the directions heard during its speech (at least three).
  std::optional<double> azimuth_of(const audio::Utterance& u) const {
    return mean_azimuth(heard_, u.speech_start, u.speech_end, 3);
  }
  // The utterance's angle from the child's head seen during its speech (or shortly before).
  std::optional<double> seen_child_offset(const audio::Utterance& u,
                                          std::optional<double> azimuth) const {
    if (!azimuth || !child_cue_) return std::nullopt;
    const auto seen =
        mean_azimuth(seen_, u.speech_start - Duration::from_seconds(options_.seen_child_lookback_s),
                     u.speech_end, 1);
    if (!seen) return std::nullopt;
    return azimuth_difference_deg(*azimuth, *seen);
  }

  // The decision on the utterance's voice track (speaker_tracks.hpp) replaces its own.
  void decide_on_track(const audio::Utterance& u, Identification& r) {
    UtteranceEvidence e;
    e.start = u.speech_start;
    e.end = u.speech_end;
    e.azimuth_deg = azimuth_of(u);
    e.seen_child_offset_deg = seen_child_offset(u, e.azimuth_deg);
    e.frames = r.frames;
    e.scores = r.scores;
    const TrackDecision d = tracker_->add(e);
    if (d.track_utterances > 1 || d.inherited)
      log::debug(
          "voice_id: utterance {:.2f}-{:.2f} s on track {} at {:.0f} deg ({} utterances, {:.0f} "
          "frames): {} (track llr {:.3f}{}{})",
          u.speech_start.seconds(), u.speech_end.seconds(), d.track, d.azimuth_deg,
          d.track_utterances, d.track_frames,
          d.speaker_id == kUnknownSpeaker ? d.speaker_id
          : options_.include_names        ? d.speaker_id
                                          : public_speaker_id(*model_, d.speaker_id),
          d.llr, d.inherited ? ", not its own voice's answer" : "",
          d.by_place ? fmt::format(", decided by the child seen {:.0f} deg away",
                                   e.seen_child_offset_deg.value_or(0))
                     : std::string());
    r.best_id = d.best_id;
    r.scores = d.scores;
    r.llr = d.llr;
    // Confidence: the logistic of the named speaker's mean LLR on the track against the
    // threshold (low when the name comes from the places rather than the voice).
    const double p = 1.0 / (1.0 + std::exp(-(d.llr - model_->threshold) / model_->score_scale));
    if (d.speaker_id != kUnknownSpeaker) {
      r.speaker_id = r.name = d.speaker_id;
      for (const auto& s : model_->speakers)
        if (s.id == d.speaker_id) r.name = s.name;
      r.score = p;
    } else {
      r.speaker_id = r.name = kUnknownSpeaker;
      r.score = 1.0 - p;
    }
  }

  // DREAM's rule on every direction heard during the utterance (none heard: unknown).
  void direction_rule(const audio::Utterance& u, SpeakerIdentity& id) const {
    int votes[2] = {0, 0}, heard = 0;  // 0 therapist, 1 child
    const auto& d = options_.direction;
    for (const auto& h : heard_) {
      if (h.stamp < u.speech_start || h.stamp > u.speech_end) continue;
      ++heard;
      if (!(h.confidence > d.min_confidence)) continue;
      const double a = std::abs(h.azimuth_deg);
      if (a > d.angle_deg)
        ++votes[0];
      else if (h.azimuth_deg != 0)
        ++votes[1];
    }
    if (votes[0] == votes[1]) {  // no decisive direction, or a tie
      id.speaker_id = id.name = kUnknownSpeaker;
      id.score = 0;
      return;
    }
    const int win = votes[1] > votes[0] ? 1 : 0;
    id.speaker_id = id.name = win == 1 ? "child" : "therapist";
    id.score = static_cast<double>(votes[win]) / heard;
  }

  VoiceIdAnalyzerOptions options_;
  std::shared_ptr<const VoiceModel> model_;
  std::unique_ptr<audio::UtteranceSegmenter> segmenter_;
  std::unique_ptr<audio::ReferenceGate> gate_;
  std::unique_ptr<audio::NoiseSuppressor> denoiser_;
  std::vector<float> denoised_;  // scratch
  Timestamp ns_origin_ = Timestamp::unset();
  int64_t ns_pushed_ = 0, ns_emitted_ = 0;
  bool alignment_noted_ = false;
  int rate_ = 0;
  int seg_channels_ = 1;  // pushed to the segmenter: channel 0 (+ the channels' mean)
  std::vector<audio::Utterance> utterances_;  // scratch
  std::deque<Heard> heard_;  // directions of the last seconds (direction rule, tracks)
  std::deque<Heard> seen_;   // the child's head seen by the cameras: azimuth in the array frame
  // The seen child is used: tracks, the array's extrinsics and a speaker to name (enable_tracks).
  bool child_cue_ = false;
  std::unique_ptr<SpeakerTracker> tracker_;  // decision kTracks
};

}  // namespace

Result<std::unique_ptr<Analyzer>> make_voice_id_analyzer(const VoiceIdAnalyzerOptions& options) {
  if (auto s = options.check(); !s) return tl::unexpected(s.error());
  std::shared_ptr<const VoiceModel> model = options.model;
  if (options.method == VoiceIdMethod::kGmmUbm && !model) {
    auto m = VoiceModel::load(options.model_file);
    if (!m) return tl::unexpected(m.error());
    model = std::make_shared<const VoiceModel>(std::move(*m));
  }
  if (model)
    if (auto s = model->check(); !s) return tl::unexpected(s.error());
  if (options.method == VoiceIdMethod::kDirectionRule) model.reset();
  auto a = std::make_unique<VoiceIdAnalyzer>(options, std::move(model));
  a->enable_gate();
  a->enable_tracks();
  return std::unique_ptr<Analyzer>(std::move(a));
}

}  // namespace dreamsense::voice_id
