#pragma once
// Who spoke (modalities/voice_id): V27, F21 identifyVoice.
// Blackboard types of one modality (perception layer: below the modalities, which never include
// each other's headers). docs/blackboard.md maps the keys onto DREAM's global buffer (V1-V29).

#include "dreamsense/core/blackboard.hpp"
#include "dreamsense/core/sensor_frame.hpp"

#include <map>
#include <optional>
#include <string>
#include <vector>

namespace dreamsense {

// The speaker of one utterance. speaker_id is "child", "therapist" or "unknown" in a therapy
// session (any enrolled name in general); method says how it was decided: "gmm_ubm" (speaker
// models) or "direction_rule" (DREAM's fallback from the sound direction, chosen explicitly).
struct SpeakerIdentity {
  std::string speaker_id;
  std::string name;      // display name from the enrolment (= speaker_id when none)
  double score = 0;      // [0, 1]: confidence in speaker_id
  Timestamp start, end;  // the utterance (session clock)
  SensorId sensor;       // the audio stream it came from
  std::string method;
};

namespace keys {
// Written once per utterance heard (no entry while nobody speaks).
inline constexpr Key<SpeakerIdentity> kSpeakerIdentity{"audio.speaker"};
}  // namespace keys

}  // namespace dreamsense
