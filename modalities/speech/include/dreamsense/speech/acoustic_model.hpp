#pragma once
// Decoding with an acoustic model adapted to one talker (written by the speech_training
// library's adapt_acoustic_model, `dreamsense train speech`): the analyser only reads it.

#include "dreamsense/core/status.hpp"
#include "dreamsense/speech/recognizer.hpp"

#include <filesystem>

namespace dreamsense::speech {

// Name of the provenance file in an adapted model folder.
inline constexpr const char* kAdaptationFileName = "adaptation.yaml";

// Decode with the model in `dir`: sets options.model_dir and, when the folder was written by
// adapt_acoustic_model, the front end it was adapted with (frequency warp, noise and silence
// removal), so decoding sees the same features as training. Errors: no model there, an
// unreadable adaptation.yaml, or a front-end rate other than the recogniser's.
// A means-only folder (means + adaptation.yaml, no mdef: what we ship, see
// modalities/speech/models) decodes with adaptation.yaml's base_model and these means.
Status use_acoustic_model(RecognizerOptions& options, const std::filesystem::path& dir);

}  // namespace dreamsense::speech
