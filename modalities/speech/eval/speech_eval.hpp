#pragma once
// `dreamsense eval speech --dataset pocketsphinx DIR`: grammar recognition on Debian's
// pocketsphinx-testdata layout (or its copy with TRANSCRIPTS.txt), JSON of spec/cli.md.

#include "dreamsense/core/status.hpp"
#include "dreamsense/speech/recognizer.hpp"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <functional>

namespace dreamsense::speech {

struct SpeechEvalOptions {
  std::string dataset = "pocketsphinx";  // only layout supported here
  std::filesystem::path dir;
  RecognizerOptions recognizer;
};

// In-grammar items: cards/*.wav under cards/cards.gram (references cards.transcription) and
// goforward.raw under goforward.gram ("go forward ten meters"). Out-of-grammar items, per
// grammar: the other grammar's utterances, numbers.raw, something.raw, librivox/*.wav, 3 s of
// near-silence and 3 s of white noise (-30 dBFS).
// Metrics: grammar_sentence_accuracy (in-grammar utterances decoded exactly and accepted),
// false_accept_rate (out-of-grammar items given any result), accuracy (all items handled
// correctly: in-grammar exact, out-of-grammar rejected); timing.rtf = decode time / audio time.
Result<nlohmann::json> run_speech_eval(const SpeechEvalOptions& options,
                                       const std::function<void(double)>& progress = {});

}  // namespace dreamsense::speech
