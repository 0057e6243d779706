#include "dreamsense/audio/noise_suppressor.hpp"

#include "dreamsense/audio/fft.hpp"

#include <algorithm>
#include <cmath>
#include <string>

namespace dreamsense::audio {

Status NoiseSuppressorOptions::check() const {
  std::string bad;
  if (sample_rate < 4000 || sample_rate > 192000) bad += " sample_rate must be in [4000, 192000];";
  if (channels < 1 || channels > 64) bad += " channels must be in [1, 64];";
  if (!(frame_s >= 0.008 && frame_s <= 0.128)) bad += " frame_s must be in [0.008, 0.128];";
  if (!(gain_floor_db <= 0 && gain_floor_db >= -60)) bad += " gain_floor_db must be in [-60, 0];";
  if (!(dd_alpha >= 0 && dd_alpha < 1)) bad += " dd_alpha must be in [0, 1);";
  if (!(init_s > 0 && init_s <= 5)) bad += " init_s must be in (0, 5];";
  if (!(speech_ratio_db >= 0 && noise_tau_s > 0 && noise_rise_db_per_s >= 0))
    bad += " speech_ratio_db and noise_rise_db_per_s must be >= 0, noise_tau_s > 0;";
  if (!(low_hz >= 0 && high_hz > low_hz)) bad += " need 0 <= low_hz < high_hz;";
  if (!bad.empty())
    return make_error(ErrorCode::kInvalidArgument, "NoiseSuppressorOptions:{}", bad);
  return ok_status();
}

struct NoiseSuppressor::Impl {
  NoiseSuppressorOptions o;
  int n = 512, hop = 256, bins = 257, ch = 1;
  RealFft fft;
  std::vector<double> window;                              // sqrt-Hann
  std::vector<std::vector<double>> in_buf;                 // per channel, n samples (sliding)
  std::vector<std::vector<double>> out_buf;                // per channel, n samples (overlap-add)
  std::vector<std::vector<std::complex<double>>> spectra;  // per channel, this frame
  std::vector<double> noise, smoothed, gain_prev, gamma_prev, power;
  std::vector<float> pending;  // interleaved input not yet a full hop
  int band_lo = 0, band_hi = 0;
  int64_t frames_seen = 0;
  int init_frames = 1;
  double update = 0.1, rise = 1.0, floor_gain = 0.18, speech_ratio = 2.0;

  explicit Impl(const NoiseSuppressorOptions& opt)
      : o(opt), n(frame_size(opt)), hop(n / 2), bins(n / 2 + 1), ch(opt.channels), fft(n) {
    window.resize(static_cast<size_t>(n));
    for (int i = 0; i < n; ++i)
      window[static_cast<size_t>(i)] = std::sqrt(0.5 - 0.5 * std::cos(2 * M_PI * i / n));
    const double hop_s = static_cast<double>(hop) / o.sample_rate;
    update = 1 - std::exp(-hop_s / o.noise_tau_s);
    rise = std::pow(10.0, o.noise_rise_db_per_s * hop_s / 10);
    floor_gain = std::pow(10.0, o.gain_floor_db / 20);
    speech_ratio = std::pow(10.0, o.speech_ratio_db / 10);
    init_frames = std::max(1, static_cast<int>(std::lround(o.init_s / hop_s)));
    band_lo = std::clamp(static_cast<int>(std::ceil(o.low_hz * n / o.sample_rate)), 0, bins - 1);
    band_hi =
        std::clamp(static_cast<int>(std::floor(o.high_hz * n / o.sample_rate)), band_lo, bins - 1);
    reset();
  }

  static int frame_size(const NoiseSuppressorOptions& o) {
    const double want = o.frame_s * o.sample_rate;
    int p = 1;
    while (p * 2 <= want) p *= 2;
    return (want - p < 2 * p - want) ? p : 2 * p;
  }

  void reset() {
    in_buf.assign(static_cast<size_t>(ch), std::vector<double>(static_cast<size_t>(n), 0.0));
    out_buf.assign(static_cast<size_t>(ch), std::vector<double>(static_cast<size_t>(n), 0.0));
    spectra.assign(static_cast<size_t>(ch),
                   std::vector<std::complex<double>>(static_cast<size_t>(bins)));
    noise.assign(static_cast<size_t>(bins), 0.0);
    smoothed.assign(static_cast<size_t>(bins), 0.0);
    gain_prev.assign(static_cast<size_t>(bins), 1.0);
    gamma_prev.assign(static_cast<size_t>(bins), 1.0);
    power.assign(static_cast<size_t>(bins), 0.0);
    pending.clear();
    frames_seen = 0;
  }

  // Back to the start of the signal, keeping the learnt noise (the one-shot second pass).
  void rewind() {
    const auto n_keep = noise;
    const auto s_keep = smoothed;
    reset();
    noise = n_keep;
    smoothed = s_keep;
    frames_seen = init_frames + 1;
  }

  // One hop of new samples per channel is at the end of in_buf: analyse, filter, overlap-add.
  void frame(std::vector<float>& out) {
    std::fill(power.begin(), power.end(), 0.0);
    for (int c = 0; c < ch; ++c) {
      const auto& x = in_buf[static_cast<size_t>(c)];
      double* r = fft.real();
      for (int i = 0; i < n; ++i) r[i] = x[static_cast<size_t>(i)] * window[static_cast<size_t>(i)];
      fft.forward();
      const std::complex<double>* s = fft.spectrum();
      auto& sp = spectra[static_cast<size_t>(c)];
      for (int k = 0; k < bins; ++k) {
        sp[static_cast<size_t>(k)] = s[k];
        power[static_cast<size_t>(k)] += std::norm(s[k]) / ch;
      }
    }
    // Noise estimate.
    ++frames_seen;
    double p_band = 0, n_band = 0;
    for (int k = band_lo; k <= band_hi; ++k) {
      p_band += power[static_cast<size_t>(k)];
      n_band += noise[static_cast<size_t>(k)];
    }
    const bool initialising = frames_seen <= init_frames;
    const bool speech = !initialising && p_band > speech_ratio * n_band;
    for (int k = 0; k < bins; ++k) {
      const size_t kk = static_cast<size_t>(k);
      smoothed[kk] = frames_seen == 1 ? power[kk] : 0.7 * smoothed[kk] + 0.3 * power[kk];
      if (initialising) {
        noise[kk] += (power[kk] - noise[kk]) / static_cast<double>(frames_seen);
      } else {
        if (!speech)
          noise[kk] += update * (power[kk] - noise[kk]);
        else  // creeps towards a lasting rise, never faster than noise_rise_db_per_s
          noise[kk] = std::min(noise[kk] * rise, std::max(noise[kk], smoothed[kk]));
        if (smoothed[kk] < noise[kk]) noise[kk] = smoothed[kk];
      }
    }
    // Gains (decision-directed Wiener), the same for every channel.
    for (int c = 0; c < ch; ++c) {
      auto& sp = spectra[static_cast<size_t>(c)];
      std::complex<double>* s = fft.spectrum();
      for (int k = 0; k < bins; ++k) {
        const size_t kk = static_cast<size_t>(k);
        double g = 1.0;
        if (c == 0) {
          if (k < band_lo) {
            g = floor_gain;
          } else if (k <= band_hi) {
            const double nk = std::max(noise[kk], 1e-20);
            const double gamma = power[kk] / nk;
            const double xi = o.dd_alpha * gain_prev[kk] * gain_prev[kk] * gamma_prev[kk] +
                              (1 - o.dd_alpha) * std::max(gamma - 1, 0.0);
            g = std::max(xi / (1 + xi), floor_gain);
            gamma_prev[kk] = std::min(gamma, 1e6);
          }
          gain_prev[kk] = g;
        } else {
          g = gain_prev[kk];
        }
        s[k] = sp[kk] * g;
      }
      fft.inverse();
      const double* r = fft.real();
      auto& ob = out_buf[static_cast<size_t>(c)];
      for (int i = 0; i < n; ++i)
        ob[static_cast<size_t>(i)] += r[i] * window[static_cast<size_t>(i)] / n;
    }
    // Emit the first hop, shift.
    const size_t start = out.size();
    out.resize(start + static_cast<size_t>(hop * ch));
    for (int c = 0; c < ch; ++c) {
      auto& ob = out_buf[static_cast<size_t>(c)];
      for (int i = 0; i < hop; ++i)
        out[start + static_cast<size_t>(i * ch + c)] =
            static_cast<float>(ob[static_cast<size_t>(i)]);
      std::copy(ob.begin() + hop, ob.end(), ob.begin());
      std::fill(ob.end() - hop, ob.end(), 0.0);
    }
  }

  void push(std::span<const float> in, std::vector<float>& out) {
    size_t i = 0;
    const size_t need = static_cast<size_t>(hop * ch);
    while (i < in.size()) {
      const size_t take = std::min(need - pending.size(), in.size() - i);
      pending.insert(pending.end(), in.begin() + static_cast<std::ptrdiff_t>(i),
                     in.begin() + static_cast<std::ptrdiff_t>(i + take));
      i += take;
      if (pending.size() < need) break;
      for (int c = 0; c < ch; ++c) {
        auto& b = in_buf[static_cast<size_t>(c)];
        std::copy(b.begin() + hop, b.end(), b.begin());
        for (int j = 0; j < hop; ++j)
          b[static_cast<size_t>(n - hop + j)] = pending[static_cast<size_t>(j * ch + c)];
      }
      pending.clear();
      frame(out);
    }
  }
};

Result<std::unique_ptr<NoiseSuppressor>> NoiseSuppressor::create(const NoiseSuppressorOptions& o) {
  if (auto s = o.check(); !s) return tl::unexpected(s.error());
  return std::unique_ptr<NoiseSuppressor>(new NoiseSuppressor(std::make_unique<Impl>(o)));
}
NoiseSuppressor::NoiseSuppressor(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
NoiseSuppressor::~NoiseSuppressor() = default;
void NoiseSuppressor::process(std::span<const float> in, std::vector<float>& out) {
  impl_->push(in, out);
}
void NoiseSuppressor::reset() { impl_->reset(); }
int NoiseSuppressor::latency() const { return impl_->hop; }
int NoiseSuppressor::frame() const { return impl_->n; }
void NoiseSuppressor::flush(std::vector<float>& out) {
  // Zeros through the filter until every pending input sample has come out.
  const size_t pending_frames = impl_->pending.size() / static_cast<size_t>(impl_->ch);
  const size_t want = out.size() + (pending_frames + static_cast<size_t>(impl_->hop)) *
                                       static_cast<size_t>(impl_->ch);
  std::vector<float> zeros(static_cast<size_t>(impl_->hop * impl_->ch), 0.0f);
  while (out.size() < want) impl_->push(zeros, out);
  out.resize(want);
}

Result<std::vector<float>> suppress_noise(std::span<const float> mono, int sample_rate,
                                          NoiseSuppressorOptions options, int passes) {
  options.sample_rate = sample_rate;
  options.channels = 1;
  DS_ASSIGN_OR_RETURN(auto ns, NoiseSuppressor::create(options));
  std::vector<float> out;
  out.reserve(mono.size() + static_cast<size_t>(2 * ns->frame()));
  // Two passes: the first learns the noise over the whole recording (its pauses pull the
  // estimate down even when it starts with speech), the second filters with it.
  ns->process(mono, out);
  ns->flush(out);
  for (int p = 1; p < passes; ++p) {
    ns->impl_->rewind();
    out.clear();
    ns->process(mono, out);
    ns->flush(out);
  }
  const size_t lat = static_cast<size_t>(ns->latency());
  std::vector<float> y(mono.size(), 0.0f);
  for (size_t i = 0; i < y.size() && i + lat < out.size(); ++i) y[i] = out[i + lat];
  return y;
}

}  // namespace dreamsense::audio
