#pragma once
// Fixed beamforming of a microphone array toward a direction, in the STFT domain (FFTW):
// weighted overlap-add with sqrt-Hann analysis and synthesis windows at 50 % overlap, so the
// delays are exact fractional delays (phase shifts) per frequency bin.
//
// Methods:
// - kDelayAndSum: every channel is advanced by its far-field arrival-time difference toward the
//   steered direction and the channels are averaged. Gain 1 toward the steered direction; against
//   noise uncorrelated between the mics, +10 log10(M) dB SNR.
// - kSuperdirective: MVDR weights for a spherically isotropic (diffuse) noise field with
//   diagonal loading, w = (Γ + μI)⁻¹ d / (dᴴ (Γ + μI)⁻¹ d), Γ_ij = sinc(2π f |p_i - p_j| / c).
//   Also distortionless toward the steered direction; better against reverberation and diffuse
//   noise at low frequencies, worse against uncorrelated sensor noise when μ is small (μ → ∞ is
//   delay-and-sum).
//
// Geometry is plain data: mic positions (metres, channel order) in the array frame; a direction
// is a vector in the same frame (normalised here). The output is referenced to the centroid of
// the mics: output sample i is the beam's estimate of the wave passing the centroid at the time
// of input sample i (one output per input sample once flush() has run; the latency before flush
// is at most one frame). Not thread-safe; one instance per stream.

#include "dreamsense/core/status.hpp"

#include <opencv2/core.hpp>

#include <memory>
#include <span>
#include <vector>

namespace dreamsense::audio {

enum class BeamformerMethod { kDelayAndSum, kSuperdirective };

struct BeamformerOptions {
  int sample_rate = 16000;
  std::vector<cv::Vec3d> mic_positions_m;  // one per channel, >= 1, array frame
  BeamformerMethod method = BeamformerMethod::kDelayAndSum;
  // STFT frame length in samples (even, >= 4 x the largest inter-mic delay); 0 = the power of
  // two nearest to 32 ms. Hop = half a frame.
  int frame_length = 0;
  double speed_of_sound_m_s = 343.0;
  double diagonal_loading = 0.1;  // μ of kSuperdirective (relative to Γ_ii = 1)
  Status check() const;           // lists every bad field
};

class Beamformer {
 public:
  static Result<std::unique_ptr<Beamformer>> create(const BeamformerOptions& options);
  ~Beamformer();
  Beamformer(const Beamformer&) = delete;
  Beamformer& operator=(const Beamformer&) = delete;

  // Far-field steering toward `direction` (array frame, any non-zero length). Takes effect from
  // the next STFT frame (the overlap-add cross-fades between the old and new weights).
  // Precondition: direction is finite and non-zero (checked).
  void steer(const cv::Vec3d& direction);
  cv::Vec3d direction() const { return direction_; }
  // Arrival time of a far-field wave from the steered direction at each mic, relative to the
  // centroid (s; negative = earlier than at the centroid).
  std::vector<double> arrival_delays_s() const;

  // Interleaved input (a whole number of frames of channels() values); appends the mono output
  // that became final.
  Status process(std::span<const float> interleaved, std::vector<float>& out);
  // End of input: appends the remaining output (total output = total input frames) and resets
  // the stream (the steering is kept).
  void flush(std::vector<float>& out);
  // Forgets buffered audio; keeps the steering.
  void reset();

  // A whole buffer through a fresh stream (reset, process, flush); same length as the input.
  Result<std::vector<float>> apply(std::span<const float> interleaved);

  int channels() const { return static_cast<int>(options_.mic_positions_m.size()); }
  int frame_length() const { return n_; }
  const BeamformerOptions& options() const { return options_; }

 private:
  struct Impl;
  Beamformer(BeamformerOptions options, std::unique_ptr<Impl> impl, int n);
  void update_weights();
  void run_frame();

  BeamformerOptions options_;
  std::unique_ptr<Impl> impl_;
  int n_ = 0;
  cv::Vec3d direction_{0, 0, 1};
};

}  // namespace dreamsense::audio
