#include "dreamsense/sound_direction/direction_finder.hpp"

#include "dreamsense/audio/energy_gate.hpp"

#include <algorithm>
#include <cmath>

namespace dreamsense::sound_direction {

Status VadOptions::check() const {
  std::string bad;
  if (!(threshold_db >= 0 && threshold_db <= 40)) bad += " threshold_db in [0, 40];";
  if (!(min_level_dbfs <= 0)) bad += " min_level_dbfs must be <= 0;";
  if (!(floor_rise_db_per_s >= 0)) bad += " floor_rise_db_per_s must be >= 0;";
  if (hangover_frames < 0) bad += " hangover_frames must be >= 0;";
  if (!bad.empty()) return make_error(ErrorCode::kInvalidArgument, "VadOptions:" + bad);
  return ok_status();
}

Status ConfidenceOptions::check() const {
  std::string bad;
  if (!(power_at_1 > power_at_0)) bad += " power_at_1 must exceed power_at_0;";
  if (!(ambiguity_exponent >= 0)) bad += " ambiguity_exponent must be >= 0;";
  if (!bad.empty()) return make_error(ErrorCode::kInvalidArgument, "ConfidenceOptions:" + bad);
  return ok_status();
}

Status DirectionFinderOptions::check(int sample_rate) const {
  if (auto s = phat.check(sample_rate); !s) return s;
  if (auto s = grid.check(); !s) return s;
  if (auto s = vad.check(); !s) return s;
  if (auto s = confidence.check(); !s) return s;
  std::string bad;
  if (hop < 1 || hop > phat.frame_length)
    bad += fmt::format(" hop {} outside [1, frame_length];", hop);
  if (!(smoothing_s >= 0)) bad += " smoothing_s must be >= 0;";
  if (!(reset_after_silence_s >= 0)) bad += " reset_after_silence_s must be >= 0;";
  if (!bad.empty()) return make_error(ErrorCode::kInvalidArgument, "DirectionFinderOptions:" + bad);
  return ok_status();
}

struct DirectionFinder::Impl {
  MicArrayGeometry geometry;
  DirectionFinderOptions options;
  std::unique_ptr<SrpPhat> srp;
  int channels = 0;
  double hop_s = 0;
  double alpha = 0;  // smoothing factor per hop

  std::vector<float> pending;  // interleaved, starts at stream sample `pending_start`
  int64_t pending_start = 0;
  int64_t next_frame = 0;

  std::optional<audio::EnergyGate> gate;  // voice activity on the in-band level
  std::vector<float> map, smoothed, utterance;
  bool has_smoothed = false;
  double unvoiced_s = 0;
  int utterance_frames = 0;
  double utterance_weight = 0;

  double frame_confidence(const SrpPeak& p) const;
  void process_frame(std::span<const float> frame, FrameEstimate& e);
};

Result<std::unique_ptr<DirectionFinder>> DirectionFinder::create(
    const MicArrayGeometry& geometry, const DirectionFinderOptions& options) {
  if (auto s = geometry.check(); !s) return tl::unexpected(s.error());
  if (auto s = options.check(geometry.sample_rate); !s) return tl::unexpected(s.error());
  auto srp = SrpPhat::create(geometry, options.phat, options.grid);
  if (!srp) return tl::unexpected(srp.error());
  std::unique_ptr<DirectionFinder> f(new DirectionFinder());
  f->impl_ = std::make_unique<Impl>();
  Impl& m = *f->impl_;
  m.geometry = geometry;
  m.options = options;
  m.srp = std::move(*srp);
  m.channels = static_cast<int>(geometry.mics_m.size());
  m.hop_s = static_cast<double>(options.hop) / geometry.sample_rate;
  m.alpha = options.smoothing_s > 0 ? std::exp(-m.hop_s / options.smoothing_s) : 0.0;
  audio::EnergyGateOptions g;
  g.threshold_db = options.vad.threshold_db;
  g.floor_rise_db_per_s = options.vad.floor_rise_db_per_s;
  g.min_level_dbfs = options.vad.min_level_dbfs;
  g.hangover_frames = options.vad.hangover_frames;
  m.gate.emplace(g, m.hop_s);
  return f;
}

DirectionFinder::~DirectionFinder() = default;

void DirectionFinder::reset() {
  Impl& m = *impl_;
  m.pending.clear();
  m.pending_start = m.next_frame = 0;
  m.gate->reset();
  m.has_smoothed = false;
  m.unvoiced_s = 0;
  reset_utterance();
}

void DirectionFinder::reset_utterance() {
  impl_->utterance.assign(impl_->srp->grid().size(), 0.f);
  impl_->utterance_frames = 0;
  impl_->utterance_weight = 0;
}

std::optional<SrpPeak> DirectionFinder::utterance_peak() const {
  if (impl_->utterance_frames == 0) return std::nullopt;
  std::vector<float> mean = impl_->utterance;
  for (float& v : mean) v /= static_cast<float>(impl_->utterance_weight);
  return impl_->srp->peak(mean);
}
int DirectionFinder::utterance_frames() const { return impl_->utterance_frames; }
int DirectionFinder::channels() const { return impl_->channels; }
int DirectionFinder::sample_rate() const { return impl_->geometry.sample_rate; }
const MicArrayGeometry& DirectionFinder::geometry() const { return impl_->geometry; }
const DirectionFinderOptions& DirectionFinder::options() const { return impl_->options; }

double DirectionFinder::confidence(const SrpPeak& peak) const {
  return impl_->frame_confidence(peak);
}

double DirectionFinder::Impl::frame_confidence(const SrpPeak& peak) const {
  const ConfidenceOptions& c = options.confidence;
  const double level =
      std::clamp((peak.power - c.power_at_0) / (c.power_at_1 - c.power_at_0), 0.0, 1.0);
  const double unique =
      peak.power > 0 ? std::clamp(1.0 - std::max(peak.second_power, 0.0) / peak.power, 0.0, 1.0)
                     : 0.0;
  return level * std::pow(unique, c.ambiguity_exponent);
}

void DirectionFinder::Impl::process_frame(std::span<const float> frame, FrameEstimate& e) {
  size_t clipped = 0;
  for (float v : frame)
    if (std::abs(v) >= 0.999f) ++clipped;
  e.clipped = clipped * 100 >= frame.size();
  const double level = srp->analyse(frame);
  e.level_dbfs = 10 * std::log10(level + 1e-20);

  e.voiced = gate->push(e.level_dbfs).speech;
  if (!e.voiced) {
    unvoiced_s += hop_s;
    return;
  }
  srp->power_map(map);
  e.frame_peak = srp->peak(map);
  if (!has_smoothed || unvoiced_s > options.reset_after_silence_s) {
    smoothed = map;
    has_smoothed = true;
  } else {
    for (size_t i = 0; i < map.size(); ++i)
      smoothed[i] = static_cast<float>(alpha * smoothed[i] + (1 - alpha) * map[i]);
  }
  unvoiced_s = 0;
  e.smoothed_peak = srp->peak(smoothed);
  // Utterance accumulator: each frame weighted by its own confidence, so frames the VAD let
  // through but that carry no coherent source (noise bursts) hardly count.
  const float w = static_cast<float>(std::max(frame_confidence(*e.frame_peak), 1e-3));
  for (size_t i = 0; i < map.size(); ++i) utterance[i] += w * map[i];
  utterance_weight += w;
  ++utterance_frames;
}

Status DirectionFinder::push(std::span<const float> interleaved, std::vector<FrameEstimate>& out) {
  Impl& m = *impl_;
  if (interleaved.size() % static_cast<size_t>(m.channels) != 0)
    return make_error(ErrorCode::kInvalidArgument,
                      "sound direction: {} samples is not a whole number of {}-channel frames",
                      interleaved.size(), m.channels);
  for (float v : interleaved)
    if (!std::isfinite(v))
      return make_error(ErrorCode::kCorruptData, "sound direction: non-finite audio sample");
  if (m.utterance.empty()) reset_utterance();
  m.pending.insert(m.pending.end(), interleaved.begin(), interleaved.end());
  const int64_t n = m.srp->frame_length();
  const size_t c = static_cast<size_t>(m.channels);
  const int64_t available = m.pending_start + static_cast<int64_t>(m.pending.size() / c);
  while (m.next_frame + n <= available) {
    FrameEstimate e;
    e.first_sample = m.next_frame;
    e.centre_sample = m.next_frame + n / 2;
    const size_t off = static_cast<size_t>(m.next_frame - m.pending_start) * c;
    m.process_frame(std::span<const float>(m.pending.data() + off, static_cast<size_t>(n) * c), e);
    if (e.smoothed_peak) e.confidence = confidence(*e.smoothed_peak);
    out.push_back(std::move(e));
    m.next_frame += m.options.hop;
  }
  // Drop samples no future frame needs.
  const int64_t keep_from = std::min(m.next_frame, available);
  if (keep_from > m.pending_start) {
    m.pending.erase(m.pending.begin(),
                    m.pending.begin() +
                        static_cast<std::ptrdiff_t>((keep_from - m.pending_start) * m.channels));
    m.pending_start = keep_from;
  }
  return ok_status();
}

}  // namespace dreamsense::sound_direction
