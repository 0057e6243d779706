#pragma once
// Primitives answered from the microphone array: F16 getSoundDirection, F21 identifyVoice,
// F22 recognizeSpeech. Utterance primitives (F21, F22) are ok once, at the tick the utterance was
// decided, and no_data otherwise: the last utterance is never repeated.

#include "dreamsense/primitives/context.hpp"

namespace dreamsense::primitives {

// The audio family's options block (EvaluatorOptions::families).
struct AudioPrimitiveOptions {
  // Default query of getSoundDirection: directions with a lower confidence are no_data. The
  // confidence is calibrated (modalities/sound_direction/README.md): >= 0.5 is within 10 deg
  // about 90 % of the time in eval doa's rooms, >= 0.7 (DREAM's consumer) about 98 %.
  ThresholdQuery sound_direction{0.5};
  Status check() const;
};

// Directions with a confidence below the query's threshold are no_data (heard something, not
// confident enough).
Answer<SoundDirectionValue> get_sound_direction(const PrimitiveContext& ctx,
                                                const ThresholdQuery& query);
// Legacy (dream/): DREAM's [1] child / [0] therapist; [-1] for anyone else.
Answer<VoiceValue> identify_voice(const PrimitiveContext& ctx);
Answer<SpeechValue> recognize_speech(const PrimitiveContext& ctx);

}  // namespace dreamsense::primitives
