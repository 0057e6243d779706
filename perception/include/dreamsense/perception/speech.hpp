#pragma once
// Speech recognised against a grammar (modalities/speech): V28, F22 recognizeSpeech.
// Blackboard types of one modality (perception layer: below the modalities, which never include
// each other's headers). docs/blackboard.md maps the keys onto DREAM's global buffer (V1-V29).

#include "dreamsense/core/blackboard.hpp"
#include "dreamsense/core/sensor_frame.hpp"

#include <map>
#include <optional>
#include <string>
#include <vector>

namespace dreamsense {

// One utterance recognised against the session's grammar. Out-of-grammar speech, silence and
// noise produce no RecognizedSpeech at all (absence, not an error).
struct RecognizedSpeech {
  std::string text;       // recognised words, lower case, single spaces ("go forward ten meters")
  std::string tag;        // the grammar's output string (SRGS <tag>, as DREAM emitted); = text
                          // when the grammar has no tag for that alternative
  double confidence = 0;  // [0, 1]: grammar path against a free phone loop; 0.5 = a tie
  Timestamp start, end;   // first and last frame of the recognised words (session clock)
  SensorId sensor;        // the audio stream it came from
};

namespace keys {
// F22 recognizeSpeech: written once per recognised utterance (no entry while nothing is heard).
inline constexpr Key<RecognizedSpeech> kRecognizedSpeech{"audio.speech"};
}  // namespace keys

}  // namespace dreamsense
