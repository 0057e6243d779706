#pragma once
// Energy gate that cuts a mono audio stream into utterances: 20 ms frames, a noise floor that
// follows drops at once and rises 3 dB/s, speech when a frame is threshold_db above the floor for
// min_speech_s; the utterance ends after hangover_s of quiet (or at max_utterance_s) and keeps
// padding_s of audio before its first loud frame. Same rule and defaults as the speech
// analyser's gate (modalities/speech), so both see the same utterances.

#include "dreamsense/core/status.hpp"
#include "dreamsense/core/timestamp.hpp"

#include <deque>
#include <span>
#include <vector>

namespace dreamsense::voice_id {

struct UtteranceGateOptions {
  double frame_s = 0.02;          // energy frames
  double threshold_db = 10.0;     // speech when a frame is this far above the noise floor
  double min_speech_s = 0.15;     // shorter bursts are ignored
  double hangover_s = 0.5;        // quiet that ends an utterance
  double padding_s = 0.25;        // audio kept before the first loud frame
  double max_utterance_s = 10.0;  // longer utterances are cut
  Status check() const;
};

struct Utterance {
  std::vector<float> samples;  // from padding_s before the first loud frame to the cut
  Timestamp start, end;        // first loud frame and end of the last loud frame (session clock)
  size_t loud_begin = 0, loud_end = 0;  // the same as indices into samples
};

class UtteranceGate {
 public:
  // Precondition: options.check() passed, sample_rate > 0.
  UtteranceGate(UtteranceGateOptions options, int sample_rate);
  // Feeds samples whose first one is at `stamp`; returns the utterances that ended in them.
  std::vector<Utterance> push(std::span<const float> samples, Timestamp stamp);
  int sample_rate() const { return rate_; }
  void reset();

 private:
  void gate_frame(std::vector<Utterance>& done);
  void finish(std::vector<Utterance>& done);
  void drop_front(size_t n);
  Timestamp stamp_of(size_t index) const;

  UtteranceGateOptions options_;
  int rate_;
  int frame_len_;
  std::deque<float> buffer_;
  Timestamp buffer_start_;
  size_t analysed_ = 0;
  double noise_db_ = 0;
  bool in_speech_ = false;
  size_t run_ = 0, silence_ = 0, utt_begin_ = 0;
  size_t speech_begin_ = 0, last_loud_end_ = 0;  // buffer indices of the loud part
};

}  // namespace dreamsense::voice_id
