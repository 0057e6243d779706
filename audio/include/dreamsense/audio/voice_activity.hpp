#pragma once
// Frame-wise voice activity detection on a mono stream: the tree's one VAD, used by the speech
// and voice_id analysers (through UtteranceSegmenter) and, on its in-band level, by the sound
// direction finder (audio::EnergyGate directly).
//
// What it represents: the state of one stream. push() cuts the samples into consecutive
// non-overlapping frames of frame_length() samples (the last partial frame waits for more
// input) and returns one decision per completed frame, in order; frame k covers stream samples
// [k * frame_length(), (k + 1) * frame_length()).
//
// Decision (audio::EnergyGate, DREAM's kind of energy gate): speech when the frame's RMS level
// is threshold_db above a floor that starts at the first frame, follows drops at once and rises
// at most floor_rise_db_per_s, so a long utterance cannot talk the floor up (an adaptive
// spectral floor learns a reader's steady speech as noise within seconds: measured in
// README.md). A lasting rise of the noise becomes the floor at floor_rise_db_per_s. Absence of
// speech is a decision, not an error.

#include "dreamsense/core/status.hpp"

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

namespace dreamsense::audio {

struct VoiceActivityOptions {
  int sample_rate = 16000;
  double frame_s = 0.02;             // frame (and hop) length
  double threshold_db = 10.0;        // level above the floor
  double floor_rise_db_per_s = 3.0;  // the floor's fastest rise
  Status check() const;              // lists every bad field
};

struct VoiceActivityFrame {
  int64_t first_sample = 0;  // stream sample index of the frame's first sample
  bool speech = false;
  float probability = 0.f;   // monotone in the margin over the threshold; 0.5 at threshold
  double snr_db = 0;         // level over the floor learnt from the frames before
  double level_dbfs = -120;  // frame RMS, dB re full scale
};

class VoiceActivityDetector {
 public:
  static Result<std::unique_ptr<VoiceActivityDetector>> create(const VoiceActivityOptions& options);
  ~VoiceActivityDetector();
  VoiceActivityDetector(const VoiceActivityDetector&) = delete;
  VoiceActivityDetector& operator=(const VoiceActivityDetector&) = delete;

  // Appends one decision per frame completed by `mono` (values in [-1, 1]) to `out`.
  void push(std::span<const float> mono, std::vector<VoiceActivityFrame>& out);
  // Forgets the stream (floor included).
  void reset();

  int frame_length() const { return frame_len_; }
  const VoiceActivityOptions& options() const { return options_; }
  // Stream samples consumed so far (including a pending partial frame).
  int64_t samples_pushed() const { return pushed_; }

 private:
  struct Impl;
  VoiceActivityDetector(VoiceActivityOptions options, std::unique_ptr<Impl> impl);

  VoiceActivityOptions options_;
  std::unique_ptr<Impl> impl_;
  int frame_len_ = 0;
  int64_t pushed_ = 0;
};

}  // namespace dreamsense::audio
