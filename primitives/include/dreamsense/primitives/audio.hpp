#pragma once
// Primitives answered from the microphone array: F16 getSoundDirection, F21 identifyVoice,
// F22 recognizeSpeech. Utterance primitives (F21, F22) are ok once, at the tick the utterance was
// decided, and no_data otherwise: the last utterance is never repeated.

#include "dreamsense/primitives/context.hpp"

namespace dreamsense::primitives {

// Directions with a confidence below the query's threshold are no_data (heard something, not
// confident enough).
Answer<SoundDirectionValue> get_sound_direction(const PrimitiveContext& ctx,
                                                const ThresholdQuery& query);
// Legacy (dream/): DREAM's [1] child / [0] therapist; [-1] for anyone else.
Answer<VoiceValue> identify_voice(const PrimitiveContext& ctx);
Answer<SpeechValue> recognize_speech(const PrimitiveContext& ctx);

}  // namespace dreamsense::primitives
