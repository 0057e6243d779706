#pragma once
// The robot's own voice (issue 16): a gate driven by the reference signal the robot's
// loudspeaker plays (session stream with role robot_audio). The array hears that voice ~15 dB
// above the child; without the gate it would be cut into utterances, decoded, given a speaker and
// a direction. The gate marks, in stamp time, when the robot is audible at the microphones:
// every 20 ms reference frame above `threshold_dbfs` is active, widened by `lead_s` before and
// `tail_s` after (propagation, device latency, the room's decay) and shifted by `offset_s` (the
// reference's stamps against the microphones'). Analysers drop or trim what falls inside it
// (half-duplex, as early speakerphones did): robot speech is never reported, and nothing the
// child says while the robot speaks is heard either (double talk; documented in README.md).
//
// The reference may have any sample rate (the gate works on its own frames and stamps). A time
// offset between the reference and the microphones is measured: the gate also takes the
// microphones' level (push_microphone) and, after `align_after_s` of robot speech, cross-
// correlates the reference's activity with the microphones' level over +-max_offset_s;
// measured_offset() reports the lag, and when it differs from offset_s by more than
// `align_tolerance_s` the gate uses it (log message from the analyser).

#include "dreamsense/core/status.hpp"
#include "dreamsense/core/timestamp.hpp"

#include <deque>
#include <optional>
#include <span>
#include <utility>
#include <vector>

namespace dreamsense::audio {

struct ReferenceGateOptions {
  double frame_s = 0.02;
  double threshold_dbfs = -50;  // reference frame level (RMS, dB full scale) that counts as sound
  double lead_s = 0.02;
  double tail_s = 0.4;  // RT60 of a living room + latency
  double offset_s = 0;  // microphone stamp = reference stamp + offset_s
  bool align = true;    // measure the offset (below) and use it when it disagrees
  double align_after_s = 2.0;
  double max_offset_s = 1.0;
  double align_tolerance_s = 0.06;
  Status check() const;
};

class ReferenceGate {
 public:
  explicit ReferenceGate(ReferenceGateOptions options = {});
  // Reference audio, interleaved (channel 0 is used), its rate and the stamp of its first sample.
  Status push_reference(std::span<const float> interleaved, int channels, int sample_rate,
                        Timestamp stamp);
  // Microphone audio (channel 0), for the offset measurement only.
  void push_microphone(std::span<const float> interleaved, int channels, int sample_rate,
                       Timestamp stamp);
  // Fraction of [a, b) during which the robot is audible at the microphones.
  double active_fraction(Timestamp a, Timestamp b) const;
  bool active(Timestamp t) const;
  // The longest sub-span of [a, b) in which the robot is not audible ({a, a} when none).
  std::pair<Timestamp, Timestamp> longest_quiet_span(Timestamp a, Timestamp b) const;
  // The measured offset (seconds; microphone = reference + offset), once measured.
  std::optional<double> measured_offset() const { return measured_offset_; }
  double offset_s() const { return offset_s_; }
  // Forget intervals that ended before t (memory bound).
  void forget_before(Timestamp t);
  void reset();
  const std::vector<std::pair<Timestamp, Timestamp>>& intervals() const { return intervals_; }

 private:
  struct Level {
    int64_t frame;  // global frame index (stamp / frame_s)
    double db;
  };
  void frame_level(std::vector<double>& acc, int64_t& acc_frame, int64_t frame, double power,
                   std::deque<Level>& out, bool reference);
  void add_active(int64_t frame);
  void try_align();

  ReferenceGateOptions options_;
  double offset_s_ = 0;
  int64_t frame_ns_;
  // Active reference frames as stamp intervals (without offset, lead and tail), merged.
  std::vector<std::pair<Timestamp, Timestamp>> raw_;
  mutable std::vector<std::pair<Timestamp, Timestamp>> intervals_;  // with offset, lead, tail
  std::deque<Level> ref_levels_, mic_levels_;
  std::vector<double> ref_acc_, mic_acc_;
  int64_t ref_acc_frame_ = INT64_MIN, mic_acc_frame_ = INT64_MIN;
  int64_t active_frames_ = 0;
  std::optional<double> measured_offset_;
  std::optional<int64_t> align_frame_;  // last reference frame the measurement uses
  bool aligned_ = false;
  void rebuild();
};

}  // namespace dreamsense::audio
