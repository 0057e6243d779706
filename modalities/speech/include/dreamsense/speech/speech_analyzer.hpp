#pragma once
// Speech analyser (F22 recognizeSpeech): cuts the audio stream into utterances with an energy
// gate and decodes each finished utterance against the grammar; writes keys::kRecognizedSpeech
// only when something in the grammar was said (out-of-grammar speech and noise write nothing).

#include "dreamsense/core/analyzer.hpp"
#include "dreamsense/speech/recognizer.hpp"

#include <filesystem>
#include <memory>

namespace dreamsense::speech {

struct UtteranceGateOptions {
  double frame_s = 0.02;          // energy frames
  double threshold_db = 10.0;     // speech when a frame is this far above the noise floor
  double min_speech_s = 0.15;     // shorter bursts are ignored
  double hangover_s = 0.5;        // silence that ends an utterance
  double padding_s = 0.25;        // audio kept before the detected start
  double max_utterance_s = 10.0;  // longer utterances are cut and decoded
  Status check() const;
};

struct SpeechAnalyzerOptions {
  SensorId audio_sensor = "mic_array";
  std::filesystem::path grammar;  // JSGF, or SRGS (.grxml) as DREAM used
  RecognizerOptions recognizer;
  UtteranceGateOptions gate;
  Status check() const;
};

Result<std::unique_ptr<Analyzer>> make_speech_analyzer(const SpeechAnalyzerOptions& options);

}  // namespace dreamsense::speech
