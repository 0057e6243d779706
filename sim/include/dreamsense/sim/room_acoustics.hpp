#pragma once
// Shoebox room acoustics by the image-source method (Allen & Berkley, "Image method for
// efficiently simulating small-room acoustics", JASA 65(4), 1979).
//
// Coordinates are metres in the *room frame*: origin at one corner, the room spans
// [0, size.x] x [0, size.y] x [0, size.z]. Any microphone array geometry is accepted.
// Every image source contributes a fractional-delay tap (Hann-windowed sinc) scaled by
// beta^(number of reflections) / r, so the direct path of a source 1 m away has gain 1.
// All walls share one pressure reflection coefficient beta = sqrt(1 - alpha), alpha from
// Sabine's formula RT60 = 0.161 V / (S alpha). In a non-cubic shoebox the image method with
// uniform walls decays more slowly than Sabine predicts once the sparse axial/tangential images
// dominate (5x4x3 m: T30 is 20-35 % longer than requested), so by default (match_rt60) alpha is
// refined, starting from Sabine's value, until the simulated Schroeder T30 of a canonical
// placement matches rt60_s (a few image-method runs, cached per room).
//
// Thread safety: all functions are reentrant; FFTW plan creation is serialised internally.

#include "dreamsense/core/status.hpp"

#include <opencv2/core.hpp>

#include <cstdint>
#include <optional>
#include <span>
#include <vector>

namespace dreamsense::sim {

// Planar multichannel signal: channels[c][n].
using Channels = std::vector<std::vector<double>>;

struct RoomOptions {
  cv::Vec3d size_m{5.0, 4.0, 3.0};  // shoebox extents (room frame), all > 0
  double rt60_s = 0.35;             // reverberation time (Sabine); 0 = anechoic (direct path only)
  int max_order = -1;               // max number of reflections per image; -1 = unlimited
  // Images farther than this are dropped (bounds the RIR length). 0 = speed_of_sound * rt60_s,
  // i.e. the time the field needs to decay by 60 dB (at least 1.5 x the room diagonal).
  double max_image_distance_m = 0;
  double sample_rate_hz = 16000;    // > 0
  double speed_of_sound_m_s = 343;  // > 0
  int sinc_half_width = 16;         // taps on each side of a fractional delay, 2..128
  bool match_rt60 = true;           // refine Sabine's alpha so the simulated T30 = rt60_s
  Status check() const;
};

// Source and microphones, room frame (metres); all must lie strictly inside the room.
struct AcousticPlacement {
  cv::Vec3d source_m{0, 0, 0};
  std::vector<cv::Vec3d> mics_m;
};

// Pressure reflection coefficient of every wall for the requested RT60 (Sabine).
// Returns 0 for rt60 <= 0 (anechoic). Precondition: size > 0.
double sabine_reflection_coefficient(const cv::Vec3d& size_m, double rt60_s);

// Reflection coefficient whose image-method T30 (canonical placement) equals options.rt60_s,
// found by fixed-point iteration from Sabine's value (cached; thread-safe).
double matched_reflection_coefficient(const RoomOptions& options);

// One room impulse response per microphone (same length for every mic).
Result<Channels> room_impulse_responses(const RoomOptions& options,
                                        const AcousticPlacement& placement);

// Linear convolution (length a.size() + b.size() - 1) by FFT (FFTW3, FFTW_ESTIMATE plans so
// results are deterministic). Empty input -> empty output.
std::vector<double> fft_convolve(std::span<const double> a, std::span<const double> b);

// The mono signal as heard at every microphone: mono convolved with each RIR.
// Output length = mono.size() + rir length - 1.
Result<Channels> simulate(std::span<const double> mono, const RoomOptions& options,
                          const AcousticPlacement& placement);

enum class NoiseColor { kWhite, kPink };

// Independent Gaussian noise per channel with unit mean power (pink: 1/f power spectrum).
// Deterministic for a seed (std::mt19937_64 + Box-Muller, no library distributions).
Channels make_noise(int channels, size_t frames, NoiseColor color, uint64_t seed);

// Mean power (mean of squares over all channels) of samples [begin, end) of every channel.
double mean_power(const Channels& signal, size_t begin = 0, size_t end = SIZE_MAX);

// Adds noise so that 10 log10(reference_power / noise_power) = snr_db, where reference_power
// defaults to mean_power(signal). Returns the noise power added.
double add_noise(Channels& signal, double snr_db, NoiseColor color, uint64_t seed,
                 std::optional<double> reference_power = std::nullopt);

// RT60 estimated from an impulse response by Schroeder backward integration: a line is fitted
// to the energy decay curve between from_db and to_db (defaults: T20, -5..-25 dB) and
// extrapolated to -60 dB. Returns nullopt if the curve never reaches to_db.
std::optional<double> schroeder_rt60(std::span<const double> rir, double sample_rate_hz,
                                     double from_db = -5.0, double to_db = -25.0);

}  // namespace dreamsense::sim
