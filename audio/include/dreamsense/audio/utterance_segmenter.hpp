#pragma once
// Cuts a (multichannel) audio stream into utterances with the voice activity detector: an
// utterance opens after min_speech_s of consecutive speech frames, keeps pre_roll_s of audio
// before its first speech frame, and closes after hangover_s of non-speech (the hangover is part
// of the utterance) or when it reaches max_utterance_s (then it is cut and marked truncated; the
// next one opens as soon as speech continues). Utterances whose speech part (first speech frame
// to end of the last) is shorter than min_utterance_s are dropped.
//
// Stamps come from sample counts anchored at the first chunk's stamp: sample i of the stream is
// at origin + i / sample_rate. A chunk whose stamp is more than max_jitter away from where the
// stream should be (a gap or overlap) closes any open utterance and re-anchors the stream.
// Voice activity is decided on one channel (`vad_channel`) or the mean of all (-1); utterances
// keep every channel, so a beamformer can run on them afterwards.

#include "dreamsense/audio/voice_activity.hpp"
#include "dreamsense/core/status.hpp"
#include "dreamsense/core/timestamp.hpp"

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

namespace dreamsense::audio {

struct UtteranceSegmenterOptions {
  VoiceActivityOptions vad;       // its sample_rate is the stream's
  int channels = 1;               // interleaved channels of the pushed audio
  int vad_channel = 0;            // channel the decision is made on; -1 = mean of all channels
  double min_speech_s = 0.15;     // consecutive speech that opens an utterance
  double hangover_s = 0.5;        // non-speech that closes it
  double pre_roll_s = 0.25;       // audio kept before the first speech frame
  double min_utterance_s = 0.0;   // shorter speech parts are dropped
  double max_utterance_s = 10.0;  // longer utterances are cut
  Duration max_jitter = Duration::from_ms(1);
  Status check() const;  // lists every bad field
};

struct Utterance {
  Timestamp start, end;  // stamps of the first sample and one past the last ([start, end))
  Timestamp speech_start, speech_end;  // first speech frame's start, last speech frame's end
  int sample_rate = 0, channels = 0;
  std::vector<float> samples;  // interleaved, (end - start) * sample_rate frames
  bool truncated = false;      // cut at max_utterance_s
  float mean_probability = 0;  // VAD probability averaged over the speech part
  int64_t frames() const {
    return channels > 0 ? static_cast<int64_t>(samples.size()) / channels : 0;
  }
  // One channel (0-based) as a mono signal.
  std::vector<float> channel(int c) const;
};

// Fades in the start of a mono signal cut from `u` (same rate, same first sample) with a linear
// ramp over at most `max_s` seconds, never reaching into the speech: only the pre-roll before
// u.speech_start is touched. Why: a segment cut out of a continuous stream starts abruptly, and
// PocketSphinx decoded that step in the noise as a word ("eight seven of clubs" on 5 of 36
// development demo seeds; modalities/speech/README.md).
void fade_in_pre_roll(std::span<float> mono, const Utterance& u, double max_s);

class UtteranceSegmenter {
 public:
  static Result<std::unique_ptr<UtteranceSegmenter>> create(
      const UtteranceSegmenterOptions& options);
  ~UtteranceSegmenter();
  UtteranceSegmenter(const UtteranceSegmenter&) = delete;
  UtteranceSegmenter& operator=(const UtteranceSegmenter&) = delete;

  // Feeds interleaved samples (a whole number of frames) whose first sample is at `stamp`;
  // appends every utterance this completes to `out`.
  Status push(std::span<const float> interleaved, Timestamp stamp, std::vector<Utterance>& out);
  // End of stream: closes an open utterance (if it has enough speech) and forgets the stream.
  void flush(std::vector<Utterance>& out);
  void reset();

  bool in_utterance() const { return in_speech_; }
  const UtteranceSegmenterOptions& options() const { return options_; }
  // Stamp of stream sample `i` of the current anchor (unset before the first push).
  Timestamp stamp_of(int64_t i) const;

 private:
  UtteranceSegmenter(UtteranceSegmenterOptions options, std::unique_ptr<VoiceActivityDetector> vad);
  void on_frame(const VoiceActivityFrame& f, std::vector<Utterance>& out);
  void finish(int64_t end_sample, bool truncated, std::vector<Utterance>& out);
  void drop_before(int64_t sample);

  UtteranceSegmenterOptions options_;
  std::unique_ptr<VoiceActivityDetector> vad_;
  int rate_ = 0, frame_len_ = 0;
  Timestamp origin_ = Timestamp::unset();
  int64_t pushed_ = 0;         // stream samples pushed since origin_
  std::vector<float> buffer_;  // interleaved, stream samples [buffer_first_, pushed_)
  int64_t buffer_first_ = 0;
  std::vector<VoiceActivityFrame> frames_;  // scratch
  std::vector<float> mono_;                 // scratch
  bool in_speech_ = false;
  int64_t run_ = 0, silence_ = 0;  // consecutive speech / non-speech frames
  int64_t run_start_ = 0;          // first sample of the current speech run
  int64_t utt_begin_ = 0, speech_begin_ = 0, speech_end_ = 0;
  double prob_sum_ = 0;
  int64_t prob_n_ = 0;
};

}  // namespace dreamsense::audio
