#pragma once
// Is there speech in a short clip (e.g. a 1 s Speech Commands item), or only silence/noise?
//
// Speech = enough *voiced* frames that also stand out from the clip's own noise floor:
//  - level: frame RMS in dBFS (40 ms rectangular frames, 10 ms hop); the floor is the clip's
//    10th-percentile frame level; a frame counts when it is >= floor + active_db and
//    >= min_level_dbfs;
//  - voicing: YIN's cumulative-mean-normalised difference (de Cheveigne & Kawahara 2002) has a
//    dip below voicing_threshold at a lag in [1/f0_max, 1/f0_min]. White, pink and brown noise
//    stay near 1 (brown noise's difference grows ~linearly with lag, d' ~ 2), a steady hum is
//    periodic but never rises above its own floor.
// A clip is speech when the voiced active frames add up to >= min_voiced_s. Cheap (~5 ms per
// second of 16 kHz audio); used as the silence check in front of the recogniser.
//
// This is the whole-clip decision of the audio library's voice activity detection; streams use
// VoiceActivityDetector (voice_activity.hpp), whose noise floor needs a running stream. Kept as
// its own function because the 1 s Speech Commands clips give a stream no time to learn its
// floor (the speech-commands numbers in modalities/speech/README.md are measured with it).

#include "dreamsense/core/status.hpp"

#include <cstdint>
#include <span>

namespace dreamsense::audio {

struct SpeechPresenceOptions {
  double frame_s = 0.04;
  double hop_s = 0.01;
  double min_level_dbfs = -60.0;   // quieter frames never count
  double active_db = 9.0;          // above the clip's 10th-percentile frame level
  double voicing_threshold = 0.4;  // YIN d' dip (0 = perfectly periodic, ~1 = noise)
  double f0_min_hz = 50.0, f0_max_hz = 400.0;
  double min_voiced_s = 0.03;
  Status check() const;
};

struct SpeechPresence {
  bool speech = false;
  double peak_dbfs = -120, floor_dbfs = -120;  // loudest / 10th-percentile frame
  double voiced_s = 0;                         // voiced active audio
  // Span of the active frames (level above the gate), seconds from the clip start; both 0
  // when no frame is active.
  double start_s = 0, end_s = 0;
};

SpeechPresence detect_speech(std::span<const int16_t> samples, int sample_rate_hz,
                             const SpeechPresenceOptions& options = {});

}  // namespace dreamsense::audio
