#include "dreamsense/audio/voice_activity.hpp"

#include "dreamsense/audio/energy_gate.hpp"
#include "dreamsense/audio/fft.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <string>

namespace dreamsense::audio {

Status VoiceActivityOptions::check() const {
  std::string bad;
  auto add = [&](const std::string& s) { bad += (bad.empty() ? "" : "; ") + s; };
  if (sample_rate < 4000 || sample_rate > 192000)
    add(fmt::format("sample_rate must be in [4000, 192000] (is {})", sample_rate));
  if (!(frame_s >= 0.005 && frame_s <= 0.1))
    add(fmt::format("frame_s must be in [0.005, 0.1] (is {})", frame_s));
  if (!(band_low_hz >= 0 && band_high_hz > band_low_hz))
    add(fmt::format("need 0 <= band_low_hz < band_high_hz (are {}, {})", band_low_hz,
                    band_high_hz));
  if (sample_rate > 0 && !(band_low_hz < sample_rate / 2.0))
    add(fmt::format("band_low_hz {} is above Nyquist", band_low_hz));
  if (!(energy_threshold_db > 0)) add("energy_threshold_db must be > 0");
  if (!(spectral_threshold_db > 0)) add("spectral_threshold_db must be > 0");
  if (!(noise_adapt_s > 0 && noise_fall_s > 0 && smoothing_s >= 0))
    add("noise_adapt_s and noise_fall_s must be > 0, smoothing_s >= 0");
  if (!(gate_threshold_db > 0 && gate_floor_rise_db_per_s >= 0))
    add("gate_threshold_db must be > 0, gate_floor_rise_db_per_s >= 0");
  if (!(noise_window_s >= 4 * frame_s))
    add(fmt::format("noise_window_s must be >= 4 frames (is {} s)", noise_window_s));
  if (!bad.empty()) return make_error(ErrorCode::kInvalidArgument, "VoiceActivityOptions: {}", bad);
  return ok_status();
}

struct VoiceActivityDetector::Impl {
  explicit Impl(int fft_size) : fft(fft_size) {}
  RealFft fft;
  std::vector<double> window;
  std::vector<float> pending;  // samples of the current partial frame
  int bin_lo = 0, bin_hi = 0;  // in-band bins [lo, hi)
  std::vector<double> smoothed, noise;
  // Minimum statistics: minima of `smoothed` per sub-window, the current sub-window's minimum.
  std::vector<std::vector<double>> block_min;
  std::vector<double> current_min;
  int block_frames = 0, frames_in_block = 0;
  size_t next_block = 0;
  int64_t frames_seen = 0;
  std::optional<EnergyGate> gate;  // kEnergyGate
  double a_smooth = 0, a_adapt = 0, a_fall = 0;
};

VoiceActivityDetector::VoiceActivityDetector(VoiceActivityOptions options,
                                             std::unique_ptr<Impl> impl)
    : options_(options), impl_(std::move(impl)) {}
VoiceActivityDetector::~VoiceActivityDetector() = default;

Result<std::unique_ptr<VoiceActivityDetector>> VoiceActivityDetector::create(
    const VoiceActivityOptions& options) {
  if (auto s = options.check(); !s) return tl::unexpected(s.error());
  const int len = static_cast<int>(std::lround(options.frame_s * options.sample_rate));
  int n = 1;
  while (n < len) n *= 2;
  auto impl = std::make_unique<Impl>(n);
  impl->window.resize(static_cast<size_t>(len));
  for (int i = 0; i < len; ++i)  // periodic Hann
    impl->window[static_cast<size_t>(i)] = 0.5 - 0.5 * std::cos(2 * std::numbers::pi * i / len);
  const double hz_per_bin = static_cast<double>(options.sample_rate) / n;
  impl->bin_lo = std::max(1, static_cast<int>(std::ceil(options.band_low_hz / hz_per_bin)));
  impl->bin_hi =
      std::min(n / 2, static_cast<int>(std::floor(options.band_high_hz / hz_per_bin)) + 1);
  if (impl->bin_hi <= impl->bin_lo) impl->bin_hi = impl->bin_lo + 1;
  const double frame_s = static_cast<double>(len) / options.sample_rate;
  impl->a_smooth = options.smoothing_s > 0 ? std::exp(-frame_s / options.smoothing_s) : 0.0;
  impl->a_adapt = std::exp(-frame_s / options.noise_adapt_s);
  impl->a_fall = std::exp(-frame_s / options.noise_fall_s);
  constexpr int kBlocks = 6;
  impl->block_frames =
      std::max(1, static_cast<int>(std::lround(options.noise_window_s / frame_s / kBlocks)));
  impl->block_min.assign(kBlocks, {});
  auto vad =
      std::unique_ptr<VoiceActivityDetector>(new VoiceActivityDetector(options, std::move(impl)));
  vad->frame_len_ = len;
  if (options.method == VoiceActivityMethod::kEnergyGate) {
    EnergyGateOptions g;
    g.threshold_db = options.gate_threshold_db;
    g.floor_rise_db_per_s = options.gate_floor_rise_db_per_s;
    vad->impl_->gate.emplace(g, static_cast<double>(len) / options.sample_rate);
  }
  vad->reset();
  return vad;
}

void VoiceActivityDetector::reset() {
  Impl& m = *impl_;
  m.pending.clear();
  const size_t nb = static_cast<size_t>(m.bin_hi - m.bin_lo);
  m.smoothed.assign(nb, 0.0);
  m.noise.assign(nb, 0.0);
  for (auto& b : m.block_min) b.clear();
  m.current_min.assign(nb, std::numeric_limits<double>::infinity());
  m.frames_in_block = 0;
  m.next_block = 0;
  m.frames_seen = 0;
  if (m.gate) m.gate->reset();
  pushed_ = 0;
}

void VoiceActivityDetector::push(std::span<const float> mono,
                                 std::vector<VoiceActivityFrame>& out) {
  Impl& m = *impl_;
  for (float v : mono) {
    m.pending.push_back(v);
    if (static_cast<int>(m.pending.size()) == frame_len_) {
      VoiceActivityFrame f = analyse_frame();
      f.first_sample = pushed_ + 1 - frame_len_;
      out.push_back(f);
      m.pending.clear();
    }
    ++pushed_;
  }
}

VoiceActivityFrame VoiceActivityDetector::analyse_frame() {
  Impl& m = *impl_;
  VoiceActivityFrame f;
  double* x = m.fft.real();
  double sum2 = 0;
  for (int i = 0; i < frame_len_; ++i) {
    const double v = m.pending[static_cast<size_t>(i)];
    sum2 += v * v;
    x[i] = v * m.window[static_cast<size_t>(i)];
  }
  for (int i = frame_len_; i < m.fft.size(); ++i) x[i] = 0;
  f.level_dbfs = 10 * std::log10(sum2 / frame_len_ + 1e-12);
  if (m.gate) {
    const EnergyGate::Decision d = m.gate->push(f.level_dbfs);
    f.speech = d.speech;
    f.energy_snr_db = d.margin_db + options_.gate_threshold_db;
    f.probability = static_cast<float>(1.0 / (1.0 + std::exp(-d.margin_db / 3.0)));
    ++m.frames_seen;
    return f;
  }
  m.fft.forward();
  const auto* spec = m.fft.spectrum();
  const size_t nb = m.noise.size();
  constexpr double kTiny = 1e-14;  // ~ -140 dB per bin: digital silence stays finite
  std::vector<double> power(nb);
  for (size_t k = 0; k < nb; ++k)
    power[k] = std::norm(spec[m.bin_lo + static_cast<int>(k)]) + kTiny;

  const bool first = m.frames_seen == 0;
  double e = 0, en = 0, spectral = 0;
  for (size_t k = 0; k < nb; ++k) {
    m.smoothed[k] = first ? power[k] : m.a_smooth * m.smoothed[k] + (1 - m.a_smooth) * power[k];
    if (first) m.noise[k] = m.smoothed[k];
    e += power[k];
    en += m.noise[k];
    // min(raw, smoothed): smoothing steadies the noise-only statistic without a decaying tail
    // after the speech stops.
    spectral += std::max(0.0, 10 * std::log10(std::min(power[k], m.smoothed[k]) / m.noise[k]));
  }
  f.energy_snr_db = 10 * std::log10(e / en);
  f.spectral_snr_db = spectral / static_cast<double>(nb);
  const double me = f.energy_snr_db - options_.energy_threshold_db;
  const double ms = f.spectral_snr_db - options_.spectral_threshold_db;
  f.speech = me > 0 || ms > 0;
  const double margin = std::max(me / 3.0, ms / 1.5);
  f.probability = static_cast<float>(1.0 / (1.0 + std::exp(-margin)));

  // Noise floor update: follow non-speech frames; fall fast wherever the power is below it.
  // Early frames (first 0.25 s) adapt as a running mean so the floor settles quickly.
  const double frame_s = static_cast<double>(frame_len_) / options_.sample_rate;
  const double warmup = std::max(1.0, 0.25 / frame_s);
  const double a_adapt =
      m.frames_seen < warmup ? 1.0 - 1.0 / (static_cast<double>(m.frames_seen) + 1) : m.a_adapt;
  for (size_t k = 0; k < nb; ++k) {
    const double p = m.smoothed[k];
    if (p < m.noise[k])
      m.noise[k] = m.a_fall * m.noise[k] + (1 - m.a_fall) * p;
    else if (!f.speech)
      m.noise[k] = a_adapt * m.noise[k] + (1 - a_adapt) * p;
    m.current_min[k] = std::min(m.current_min[k], p);
  }
  if (++m.frames_in_block == m.block_frames) {
    m.block_min[m.next_block] = m.current_min;
    m.next_block = (m.next_block + 1) % m.block_min.size();
    std::fill(m.current_min.begin(), m.current_min.end(), std::numeric_limits<double>::infinity());
    m.frames_in_block = 0;
    // Once the window is full: the floor may not stay below twice its minimum.
    bool full = true;
    for (const auto& b : m.block_min) full = full && !b.empty();
    if (full)
      for (size_t k = 0; k < nb; ++k) {
        double lo = std::numeric_limits<double>::infinity();
        for (const auto& b : m.block_min) lo = std::min(lo, b[k]);
        m.noise[k] = std::max(m.noise[k], 2.0 * lo);
      }
  }
  ++m.frames_seen;
  return f;
}

}  // namespace dreamsense::audio
