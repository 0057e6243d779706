#pragma once
// Streaming sound-source direction finding: interleaved multichannel audio in, one estimate per
// analysis frame out. Frames of `frame_length` samples every `hop` samples; each frame goes
// through a voice-activity detector (in-band energy against a tracked noise floor) and, when
// voiced, SRP-PHAT (srp_phat.hpp). Maps of voiced frames are smoothed over time (exponential,
// time constant `smoothing_s`, restarted after `reset_after_silence_s` without voice); the
// estimate is the peak of the smoothed map. The finder also sums the maps of all voiced frames
// since the last reset_utterance(), for utterance-level estimates (eval doa).
//
// Confidence (0..1) is a calibrated function of the smoothed map's peak: the peak SRP value p
// (mean PHAT coherence over pairs; 1 for a perfectly coherent plane wave) and the ratio of the
// best competing local maximum q/p. See README.md for the calibration that makes 0.7 (the
// threshold DREAM's consumer used) correspond to a >= 90 % chance of being within 10 degrees.

#include "dreamsense/audio/mic_array.hpp"
#include "dreamsense/core/status.hpp"
#include "dreamsense/sound_direction/srp_phat.hpp"

#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <vector>

namespace dreamsense::sound_direction {

struct VadOptions {
  double threshold_db = 6.0;         // voiced if in-band power exceeds the noise floor by this
  double min_level_dbfs = -70.0;     // and is above this absolute level (digital silence: never)
  double floor_rise_db_per_s = 1.0;  // the floor follows minima at once, rises this slowly
  int hangover_frames = 2;           // frames kept voiced after the level drops
  Status check() const;
};

struct ConfidenceOptions {
  // confidence = clamp((p - power_at_0) / (power_at_1 - power_at_0), 0, 1) * (1 - q/p)^ambiguity
  // with p the smoothed peak SRP, q the best competing peak (README: calibration).
  double power_at_0 = 0.02;
  double power_at_1 = 0.12;
  double ambiguity_exponent = 0.5;
  Status check() const;
};

struct DirectionFinderOptions {
  PhatOptions phat;  // frame_length 1024 = 64 ms at 16 kHz
  int hop = 512;     // samples between frames (32 ms at 16 kHz), 1..frame_length
  SrpGridOptions grid;
  VadOptions vad;
  ConfidenceOptions confidence;
  double smoothing_s = 0.15;           // time constant of the map smoothing; 0 = none
  double reset_after_silence_s = 0.5;  // unvoiced gap after which smoothing starts afresh
  Status check(int sample_rate) const;
};

struct FrameEstimate {
  int64_t first_sample = 0;  // index of the frame's first sample since the stream started
  int64_t centre_sample = 0;
  bool clipped = false;      // >= 1 % of the frame's samples at full scale
  double level_dbfs = -200;  // in-band power
  bool voiced = false;
  // Only when voiced:
  std::optional<SrpPeak> frame_peak;     // of this frame's own map (no smoothing)
  std::optional<SrpPeak> smoothed_peak;  // the estimate (smoothed map)
  double confidence = 0;                 // of the smoothed estimate
};

class DirectionFinder {
 public:
  static Result<std::unique_ptr<DirectionFinder>> create(const MicArrayGeometry& geometry,
                                                         const DirectionFinderOptions& options);
  ~DirectionFinder();

  // Appends interleaved samples (channels() per frame, in [-1, 1]) and analyses every complete
  // frame, appending one FrameEstimate per frame to `out`. Non-finite samples are an error
  // (kCorruptData); `interleaved.size()` must be a multiple of channels().
  Status push(std::span<const float> interleaved, std::vector<FrameEstimate>& out);
  // Forgets buffered samples, smoothing, the noise floor and the sample counter.
  void reset();
  // Starts a new utterance accumulator (the smoothing is kept).
  void reset_utterance();
  // Peak of the SRP summed over the voiced frames since reset_utterance(); nullopt if none.
  std::optional<SrpPeak> utterance_peak() const;
  int utterance_frames() const;

  double confidence(const SrpPeak& peak) const;
  int channels() const;
  int sample_rate() const;
  const MicArrayGeometry& geometry() const;
  const DirectionFinderOptions& options() const;

 private:
  DirectionFinder() = default;
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace dreamsense::sound_direction
