#pragma once
// A streaming noise suppressor (issue 16): short-time Wiener filter with a decision-directed
// a-priori SNR (Ephraim & Malah 1984; Scalart & Vieira Filho 1996) and a noise power spectrum
// learnt from the frames that hold no speech.
//
// STFT: frame N = the power of two nearest 32 ms (512 at 16 kHz), hop N/2, sqrt-Hann analysis and
// synthesis windows (weighted overlap-add, perfect reconstruction at gain 1), the tree's FFT
// wrapper (fft.hpp). Every channel gets the same gain per bin, computed from the channels' mean
// power, so the inter-channel phases (direction, beamforming) are kept.
// Noise estimate N(k): the mean of the first `init_s`; then a frame whose in-band power is less
// than `speech_ratio_db` above the noise's is non-speech and updates N with time constant
// `noise_tau_s`; a bin whose smoothed power falls below N pulls it down at once (minimum
// tracking); N otherwise rises by at most `noise_rise_db_per_s` (a lasting rise of the noise
// becomes noise).
// Gain per bin: xi = a G_prev^2 gamma_prev + (1 - a) max(gamma - 1, 0), gamma = P / N,
// G = max(xi / (1 + xi), gain_floor).
// Output: one sample per input sample, `latency()` samples late (N/2); flush() returns the rest.

#include "dreamsense/core/status.hpp"

#include <memory>
#include <span>
#include <vector>

namespace dreamsense::audio {

struct NoiseSuppressorOptions {
  int sample_rate = 16000;
  int channels = 1;
  double frame_s = 0.032;      // rounded to a power of two of samples
  double gain_floor_db = -15;  // strongest attenuation (deeper makes "musical noise")
  double dd_alpha = 0.98;      // decision-directed smoothing
  double init_s = 0.1;         // the first frames are noise
  double speech_ratio_db = 3;  // frames this far above the noise are speech (no update)
  double noise_tau_s = 0.5;    // noise update time constant in non-speech frames
  double noise_rise_db_per_s = 1.0;
  double low_hz = 80;  // below: attenuated by gain_floor (hum, rumble); above high_hz untouched
  double high_hz = 7800;
  Status check() const;
};

class NoiseSuppressor {
 public:
  static Result<std::unique_ptr<NoiseSuppressor>> create(const NoiseSuppressorOptions& options);
  ~NoiseSuppressor();
  // Interleaved samples in; appends the same number of (interleaved) samples to `out`,
  // latency() samples late.
  void process(std::span<const float> in, std::vector<float>& out);
  // Appends the remaining latency() samples per channel (the input padded with zeros).
  void flush(std::vector<float>& out);
  void reset();
  int latency() const;
  int frame() const;

 private:
  struct Impl;
  explicit NoiseSuppressor(std::unique_ptr<Impl> impl);
  friend Result<std::vector<float>> suppress_noise(std::span<const float>, int,
                                                   NoiseSuppressorOptions, int);
  std::unique_ptr<Impl> impl_;
};

// One-shot: the whole signal (mono) through a fresh suppressor, latency removed (same length).
// passes = 2: the first pass learns the noise over the whole recording, the second filters with
// it (a recording that starts with speech); 1 = exactly what the streaming filter does.
Result<std::vector<float>> suppress_noise(std::span<const float> mono, int sample_rate,
                                          NoiseSuppressorOptions options = {}, int passes = 2);

}  // namespace dreamsense::audio
