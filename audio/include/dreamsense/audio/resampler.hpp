#pragma once
// Streaming sample-rate conversion of interleaved multichannel audio (libsoxr, Debian
// libsoxr-dev), stateful across chunks.
//
// What it represents: one continuous audio stream at `input_rate` turned into the same stream at
// `output_rate`. Output sample k of a segment is the signal at time origin + k / output_rate,
// where origin is the stamp of the segment's first input sample (soxr is time-aligned: no
// leading filter delay in its output). Stamps are therefore computed from sample counts, never
// from a clock, and after flush() a segment of n input samples has produced exactly
// round(n * output_rate / input_rate) output samples.
//
// Segments: when an input chunk's stamp differs from the one its predecessor implies (origin +
// samples so far / input_rate) by more than `max_jitter`, the resampler flushes the current
// segment (its tail comes out first) and starts a new one at the chunk's stamp. A gap in the
// input is therefore a gap in the output, never a silent time shift.
//
// Not thread-safe; one instance per stream.

#include "dreamsense/audio/stamped_audio.hpp"
#include "dreamsense/core/status.hpp"
#include "dreamsense/core/timestamp.hpp"

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

namespace dreamsense::audio {

enum class ResamplerQuality {
  kQuick,     // cubic interpolation (SoX "quick")
  kLow,       // 16-bit, large roll-off
  kMedium,    // 16-bit, medium roll-off
  kHigh,      // 20-bit (SoX default "high"): 0.913 x Nyquist pass band
  kVeryHigh,  // 28-bit
};

struct ResamplerOptions {
  int input_rate = 0;       // Hz, > 0
  int output_rate = 16000;  // Hz, > 0
  int channels = 1;         // interleaved channels, 1..64
  ResamplerQuality quality = ResamplerQuality::kHigh;
  // Stamp mismatch tolerated between consecutive chunks before a new segment starts. Live
  // sources stamp by sample count (mismatch 0); recordings round stamps to the ns.
  Duration max_jitter = Duration::from_ms(1);
  Status check() const;  // lists every bad field
};

class Resampler {
 public:
  static Result<std::unique_ptr<Resampler>> create(const ResamplerOptions& options);
  ~Resampler();
  Resampler(const Resampler&) = delete;
  Resampler& operator=(const Resampler&) = delete;

  // Feeds `interleaved` (frames * channels values; a partial frame is kInvalidArgument) whose
  // first sample is at `stamp`, and appends the output that is ready to `out` (zero, one or
  // two blocks: two when a stamp discontinuity flushed the previous segment). Blocks carry the
  // output rate and channel count. Float input is in [-1, 1]; int16 is scaled by 1/32768.
  Status process(std::span<const float> interleaved, Timestamp stamp,
                 std::vector<StampedAudio>& out);
  Status process(std::span<const int16_t> interleaved, Timestamp stamp,
                 std::vector<StampedAudio>& out);
  // End of input: appends the rest of the current segment (if any) and starts afresh.
  Status flush(std::vector<StampedAudio>& out);
  // Drops everything buffered (no output) and starts afresh.
  void reset();

  const ResamplerOptions& options() const { return options_; }
  // Samples (per channel) consumed / produced in the current segment.
  int64_t input_frames() const { return in_frames_; }
  int64_t output_frames() const { return out_frames_; }
  // Whole-signal conversion of a buffer (a one-segment stream, flushed).
  static Result<std::vector<float>> convert(std::span<const float> interleaved, int channels,
                                            int input_rate, int output_rate,
                                            ResamplerQuality quality = ResamplerQuality::kHigh);

 private:
  struct Impl;
  Resampler(ResamplerOptions options, std::unique_ptr<Impl> impl);
  Status feed(const float* data, int64_t frames, Timestamp stamp, std::vector<StampedAudio>& out);
  Status drain(std::vector<StampedAudio>& out);

  ResamplerOptions options_;
  std::unique_ptr<Impl> impl_;
  Timestamp origin_ = Timestamp::unset();  // stamp of the segment's first input sample
  int64_t in_frames_ = 0, out_frames_ = 0;
  std::vector<float> scratch_;  // int16 -> float
};

}  // namespace dreamsense::audio
