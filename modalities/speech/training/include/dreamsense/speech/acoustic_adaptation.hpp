#pragma once
// Speaker enrolment for speech recognition: MAP adaptation of a PocketSphinx acoustic model's
// Gaussian means to one talker (e.g. the child of a therapy session) from a few dozen of their
// utterances with known words. Children's and accented speech are where the packaged adult
// models fail most; adapting to the person who will be heard is the classical remedy. Measured
// on FSDD (take cross-validation per speaker) in README.md.
//
// Method (CMU Sphinx's adaptation recipe, with Debian's sphinxtrain binaries run as programs):
// 1. features: each utterance is run through the very front end the decoder will use (same
//    Recognizer options: rate, resampling, noise removal, silence removal, frequency warp);
//    PocketSphinx logs the cepstra it computed (-mfclogdir), so training and decoding agree;
// 2. the model is put in SphinxTrain form: text mdef (pocketsphinx_mdef_convert) and float
//    mixture weights decoded from PocketSphinx's quantised `sendump`;
// 3. `bw` collects Baum-Welch statistics along the transcripts (one pass);
// 4. `map_adapt` gives MAP estimates; only the means are kept (adapting variances, mixture
//    weights and transitions as well was worse on held-out takes, README);
// 5. the output folder is a copy of the model with the new `means` and `adaptation.yaml`
//    (what it was adapted from, on how much speech, with which front end). Decode with it by
//    setting RecognizerOptions::model_dir (same front-end options as here), or use_acoustic_model.
//
// Library dreamsense::speech_training (training spawns sphinxtrain; the analyser library
// dreamsense::speech only decodes).

#include "dreamsense/core/status.hpp"
#include "dreamsense/speech/acoustic_model.hpp"  // kAdaptationFileName, use_acoustic_model
#include "dreamsense/speech/recognizer.hpp"

#include <cstdint>
#include <filesystem>
#include <functional>
#include <span>
#include <string>
#include <vector>

namespace dreamsense::speech {

struct AdaptationUtterance {
  std::string id;                // for messages; letters, digits, '_', '-', '.' (file names)
  std::vector<int16_t> samples;  // mono
  int sample_rate_hz = 0;
  std::string words;  // what was said, dictionary words separated by spaces
};

struct AcousticAdaptationOptions {
  // Base model, dictionary and front end: exactly the options the adapted model will be
  // decoded with (the features are computed by this recogniser's front end). Grammar, rejection
  // and confidence settings are not used.
  RecognizerOptions recognizer;
  // Debian package sphinxtrain: bw and map_adapt.
  std::filesystem::path sphinxtrain_dir = "/usr/lib/sphinxtrain";
  // Debian package pocketsphinx: binary -> text model definition.
  std::filesystem::path mdef_convert = "/usr/bin/pocketsphinx_mdef_convert";
  // Fewer utterances than this is an error (MAP on a handful of frames barely moves the
  // means; 10 is a minute of commands).
  int min_utterances = 10;
  // Keep the working folder (features, statistics, tool logs) as OUT/work for inspection.
  bool keep_work_dir = false;
  Status check() const;
};

struct AdaptationReport {
  int utterances = 0;          // given
  int trained_utterances = 0;  // aligned by bw (the others reached no final state)
  double audio_seconds = 0;
  double seconds = 0;  // wall time of the whole adaptation
  std::filesystem::path model_dir;
  std::vector<std::string> skipped;  // ids of utterances bw could not align
};

// Writes the adapted model to `out_dir` (created; must not exist or be empty). Errors: missing
// tools or model files (naming the Debian package), words not in the dictionary (listed), too
// few utterances, a tool that failed (its name and the end of its log).
Result<AdaptationReport> adapt_acoustic_model(
    std::span<const AdaptationUtterance> utterances, const AcousticAdaptationOptions& options,
    const std::filesystem::path& out_dir, const std::function<void(double)>& progress = nullptr);

}  // namespace dreamsense::speech
