#pragma once
// GCC-PHAT per microphone pair (Knapp & Carter, IEEE TASSP 24(4), 1976) and SRP-PHAT over a grid
// of directions (DiBiase, PhD thesis, Brown University, 2000): the steered response power of a
// direction is the mean over all mic pairs of the pair's PHAT-weighted cross-correlation at the
// time difference that direction implies (far field, plane wave).
//
// Frames are Hann-windowed; the cross-correlations are computed by FFTW3 with frequency-domain
// zero padding (`upsample`), so lags are resolved to 1/upsample sample and read with linear
// interpolation. The correlation is normalised so that a perfectly coherent pair gives 1 at its
// delay: SRP values lie in [-1, 1] and are comparable across arrays and frame lengths.
//
// Thread safety: an SrpPhat / GccPhat object is not thread-safe (it owns scratch buffers); use
// one per thread. Creating one is thread-safe (FFTW plan creation is serialised internally).

#include "dreamsense/audio/mic_array.hpp"
#include "dreamsense/core/status.hpp"

#include <opencv2/core.hpp>

#include <memory>
#include <optional>
#include <span>
#include <vector>

namespace dreamsense::sound_direction {

// The array geometry lives in the audio base library (speech beamforming uses it too).
using audio::MicArrayGeometry;
using audio::named_geometry;
using audio::read_mic_array;

struct PhatOptions {
  int frame_length = 1024;    // samples per analysis frame (64 ms at 16 kHz); a power of 2
  int upsample = 4;           // lag resolution 1/upsample sample; 1..16
  double min_freq_hz = 150;   // PHAT band: bins outside it get weight 0
  double max_freq_hz = 6000;  // (clamped to Nyquist)
  Status check(int sample_rate) const;
};

// Cross-correlation of two equally long signals by GCC-PHAT.
class GccPhat {
 public:
  static Result<std::unique_ptr<GccPhat>> create(const PhatOptions& options, int sample_rate);
  ~GccPhat();
  // Delay of `b` relative to `a` in samples (positive: b lags a), searched within
  // [-max_lag, max_lag] samples, with sub-sample (parabolic) refinement; `peak` is the normalised
  // correlation at the delay (1 = perfectly coherent). Both spans must hold frame_length samples.
  struct Delay {
    double samples = 0;
    double peak = 0;
  };
  Delay delay(std::span<const float> a, std::span<const float> b, double max_lag) const;

 private:
  GccPhat() = default;
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// One direction of the search grid (array frame).
struct GridDirection {
  double azimuth_deg = 0;
  double elevation_deg = 0;
  cv::Vec3d unit{0, 0, 1};
};

struct SrpGridOptions {
  double azimuth_step_deg = 1.0;
  double elevation_step_deg = 5.0;  // used for planar and volumetric arrays
  double speed_of_sound_m_s = 343.0;
  Status check() const;
};

// The grid for a geometry: linear arrays (rank 1) get azimuth -90..90 in the horizontal (x-z)
// plane only, since a linear array cannot tell front from back nor measure elevation; planar
// arrays get the half-sphere on the side of +z (front) or, for a horizontal array, above it;
// volumetric arrays the whole sphere.
std::vector<GridDirection> make_grid(const MicArrayGeometry& geometry,
                                     const SrpGridOptions& options);

struct SrpPeak {
  size_t index = 0;  // grid index of the maximum
  double azimuth_deg = 0;
  std::optional<double> elevation_deg;  // nullopt for linear arrays
  cv::Vec3d unit{0, 0, 1};              // array frame
  double power = 0;                     // SRP at the peak, in [-1, 1]
  double second_power = 0;  // best local maximum at least `min_separation_deg` away (or -1)
};

class SrpPhat {
 public:
  static Result<std::unique_ptr<SrpPhat>> create(const MicArrayGeometry& geometry,
                                                 const PhatOptions& phat,
                                                 const SrpGridOptions& grid = {});
  ~SrpPhat();

  const std::vector<GridDirection>& grid() const;
  int channels() const;
  int frame_length() const;
  bool linear() const;

  // Spectra of one frame: `interleaved` holds frame_length * channels samples. Also returns the
  // mean in-band power per channel (for voice-activity detection), relative to full scale.
  double analyse(std::span<const float> interleaved);
  // SRP-PHAT of the last analysed frame over the grid (size grid().size()).
  void power_map(std::vector<float>& map);
  // The maximum of a map, refined by a parabola along azimuth (linear arrays).
  SrpPeak peak(std::span<const float> map, double min_separation_deg = 20.0) const;

 private:
  SrpPhat() = default;
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace dreamsense::sound_direction
