#pragma once
// Frame-wise voice activity detection on a mono stream: band energy and spectral SNR against an
// adaptive per-frequency noise floor (see README.md, "Voice activity").
//
// What it represents: the state of one stream. push() cuts the samples into consecutive
// non-overlapping frames of frame_length() samples (the last partial frame waits for more
// input) and returns one decision per completed frame, in order; frame k covers stream samples
// [k * frame_length(), (k + 1) * frame_length()).
//
// Decision: speech when the frame's in-band energy is energy_threshold_db above the noise
// floor's, or the mean per-bin SNR (log, clamped at 0 dB) is spectral_threshold_db. The noise
// floor (per FFT bin) starts at the first frame, follows non-speech frames (time constant
// noise_adapt_s), falls fast (noise_fall_s) wherever a bin is below it, and never stays below
// twice the minimum of the smoothed power over the last noise_window_s (so a lasting rise of the
// noise is accepted as noise after that window). Absence of speech is a decision, not an error.
//
// Method kEnergyGate (DREAM's energy gate, the voice_id analyser's measured choice): speech when
// the frame's RMS level is gate_threshold_db above a floor that follows drops at once and rises
// gate_floor_rise_db_per_s (the floor cannot be talked up during a long utterance, which the
// adaptive floor above can when a reader speaks for seconds without a pause).

#include "dreamsense/core/status.hpp"

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

namespace dreamsense::audio {

enum class VoiceActivityMethod { kSpectral, kEnergyGate };

struct VoiceActivityOptions {
  VoiceActivityMethod method = VoiceActivityMethod::kSpectral;
  int sample_rate = 16000;
  double frame_s = 0.02;                          // frame (and hop) length
  double band_low_hz = 150, band_high_hz = 4000;  // band of the features (clipped to Nyquist)
  double energy_threshold_db = 9.0;               // in-band energy above the noise floor's
  double spectral_threshold_db = 5.0;             // mean clamped per-bin SNR
  double noise_adapt_s = 1.0;                     // noise floor time constant (non-speech)
  double noise_fall_s = 0.1;                      // ... where the power is below the floor
  double noise_window_s = 3.0;                    // minimum-statistics window
  double smoothing_s = 0.04;                      // power smoothing for the spectral feature
  double gate_threshold_db = 10.0;                // kEnergyGate: level above the floor
  double gate_floor_rise_db_per_s = 3.0;          // kEnergyGate: the floor's fastest rise
  Status check() const;                           // lists every bad field
};

struct VoiceActivityFrame {
  int64_t first_sample = 0;  // stream sample index of the frame's first sample
  bool speech = false;
  float probability = 0.f;     // monotone in the margin over the thresholds; 0.5 at threshold
  double energy_snr_db = 0;    // in-band energy over the noise floor's (gate: level - floor)
  double spectral_snr_db = 0;  // mean over in-band bins of max(0, 10 log10(P / N))
  double level_dbfs = -120;    // frame RMS, dB re full scale
};

class VoiceActivityDetector {
 public:
  static Result<std::unique_ptr<VoiceActivityDetector>> create(const VoiceActivityOptions& options);
  ~VoiceActivityDetector();
  VoiceActivityDetector(const VoiceActivityDetector&) = delete;
  VoiceActivityDetector& operator=(const VoiceActivityDetector&) = delete;

  // Appends one decision per frame completed by `mono` (values in [-1, 1]) to `out`.
  void push(std::span<const float> mono, std::vector<VoiceActivityFrame>& out);
  // Forgets the stream (noise floor included).
  void reset();

  int frame_length() const { return frame_len_; }
  const VoiceActivityOptions& options() const { return options_; }
  // Stream samples consumed so far (including a pending partial frame).
  int64_t samples_pushed() const { return pushed_; }

 private:
  struct Impl;
  VoiceActivityDetector(VoiceActivityOptions options, std::unique_ptr<Impl> impl);
  VoiceActivityFrame analyse_frame();

  VoiceActivityOptions options_;
  std::unique_ptr<Impl> impl_;
  int frame_len_ = 0;
  int64_t pushed_ = 0;
};

}  // namespace dreamsense::audio
