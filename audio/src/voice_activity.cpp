#include "dreamsense/audio/voice_activity.hpp"

#include "dreamsense/audio/energy_gate.hpp"

#include <cmath>
#include <string>

namespace dreamsense::audio {

Status VoiceActivityOptions::check() const {
  std::string bad;
  auto add = [&](const std::string& s) { bad += (bad.empty() ? "" : "; ") + s; };
  if (sample_rate < 4000 || sample_rate > 192000)
    add(fmt::format("sample_rate must be in [4000, 192000] (is {})", sample_rate));
  if (!(frame_s >= 0.005 && frame_s <= 0.1))
    add(fmt::format("frame_s must be in [0.005, 0.1] (is {})", frame_s));
  if (!(threshold_db > 0 && floor_rise_db_per_s >= 0))
    add("threshold_db must be > 0, floor_rise_db_per_s >= 0");
  if (!bad.empty()) return make_error(ErrorCode::kInvalidArgument, "VoiceActivityOptions: {}", bad);
  return ok_status();
}

struct VoiceActivityDetector::Impl {
  Impl(const EnergyGateOptions& g, double frame_s) : gate(g, frame_s) {}
  EnergyGate gate;
  double sum2 = 0;  // of the current partial frame
  int in_frame = 0;
};

VoiceActivityDetector::VoiceActivityDetector(VoiceActivityOptions options,
                                             std::unique_ptr<Impl> impl)
    : options_(options), impl_(std::move(impl)) {}
VoiceActivityDetector::~VoiceActivityDetector() = default;

Result<std::unique_ptr<VoiceActivityDetector>> VoiceActivityDetector::create(
    const VoiceActivityOptions& options) {
  DS_RETURN_IF_ERROR(options.check());
  const int len = static_cast<int>(std::lround(options.frame_s * options.sample_rate));
  EnergyGateOptions g;
  g.threshold_db = options.threshold_db;
  g.floor_rise_db_per_s = options.floor_rise_db_per_s;
  auto impl = std::make_unique<Impl>(g, static_cast<double>(len) / options.sample_rate);
  auto vad =
      std::unique_ptr<VoiceActivityDetector>(new VoiceActivityDetector(options, std::move(impl)));
  vad->frame_len_ = len;
  vad->reset();
  return vad;
}

void VoiceActivityDetector::reset() {
  impl_->gate.reset();
  impl_->sum2 = 0;
  impl_->in_frame = 0;
  pushed_ = 0;
}

void VoiceActivityDetector::push(std::span<const float> mono,
                                 std::vector<VoiceActivityFrame>& out) {
  Impl& m = *impl_;
  for (float v : mono) {
    m.sum2 += static_cast<double>(v) * v;
    ++pushed_;
    if (++m.in_frame < frame_len_) continue;
    VoiceActivityFrame f;
    f.first_sample = pushed_ - frame_len_;
    f.level_dbfs = 10 * std::log10(m.sum2 / frame_len_ + 1e-12);
    const EnergyGate::Decision d = m.gate.push(f.level_dbfs);
    f.speech = d.speech;
    f.snr_db = d.margin_db + options_.threshold_db;
    f.probability = static_cast<float>(1.0 / (1.0 + std::exp(-d.margin_db / 3.0)));
    out.push_back(f);
    m.sum2 = 0;
    m.in_frame = 0;
  }
}

}  // namespace dreamsense::audio
