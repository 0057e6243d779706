#pragma once
// `dreamsense eval speech --dataset pocketsphinx|fsdd|speech-commands DIR`: grammar recognition
// on Debian's pocketsphinx-testdata, the Free Spoken Digit Dataset and the Speech Commands
// layout; JSON of spec/cli.md. Protocols and measured numbers: modalities/speech/README.md.

#include "dreamsense/audio/speech_presence.hpp"
#include "dreamsense/core/status.hpp"
#include "dreamsense/eval/report.hpp"
#include "dreamsense/eval/speaker_batch.hpp"
#include "dreamsense/eval/speech_datasets.hpp"
#include "dreamsense/speech/acoustic_adaptation.hpp"
#include "dreamsense/speech/recognizer.hpp"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <functional>
#include <optional>

namespace dreamsense::speech {

struct SpeechEvalOptions {
  std::string dataset = "pocketsphinx";  // pocketsphinx | fsdd | speech-commands
  std::filesystem::path dir;
  // Base recogniser options. The layouts override a few (below) unless set here.
  RecognizerOptions recognizer;
  // Layout defaults when unset: pocketsphinx 1.0 / 0; fsdd: closed set (no rejection);
  // speech-commands: kCommandsGarbageWeight / kCommandsMinConfidence.
  std::optional<double> garbage_phone_weight, min_confidence;
  FsddSelection fsdd;                    // fsdd: speakers and take indices
  std::string fsdd_model = "tidigits";   // fsdd: tidigits (default) | en-us (options above) | a
                                         // TIDIGITS-family model folder
  std::optional<double> pad_seconds;     // fsdd: silence added at both ends (kFsddPadSeconds)
  std::optional<double> frequency_warp;  // fsdd: overrides kFsddTidigitsWarp
  bool fsdd_oh = false;                  // fsdd: "oh" as a second word for 0
  // fsdd: unsupervised batch speaker adaptation (neighbour vote among each speaker's clips).
  // Off by default: it is transductive (it looks at the other test clips of the same speaker),
  // which a live recogniser cannot do, so the headline accuracy is clip by clip.
  bool fsdd_speaker_adapt = false;
  NeighbourVoteOptions fsdd_vote;
  // speech-commands: when recognizer.model_dir is left at Debian's en-us, decode with the
  // shipped model adapted on the development clips (commands_model_dir()); false = as given.
  bool commands_shipped_model = true;
  // speech-commands: decoy words decoded beside the ten commands; a decoy heard means
  // _unknown_ (an explicit out-of-vocabulary model next to the phone loop). nullopt = the
  // model folder's decoys.txt when it has one; an empty list = none.
  std::optional<std::vector<std::string>> decoy_words;
  audio::SpeechPresenceOptions presence;  // speech-commands: the silence check
  double trim_margin_s = -1;      // speech-commands: decode the active span +- this (<0: all)
  bool list_items = true;         // per-item records in the JSON ("items")
  std::filesystem::path grammar;  // list: the grammar every listed utterance is decoded under
};

// FSDD protocol constants, tuned on speaker george only (leave-speaker-out; README).
inline const std::filesystem::path kTidigitsModel =
    "/usr/share/pocketsphinx/test/data/tidigits/hmm";
inline const std::filesystem::path kTidigitsDictionary =
    "/usr/share/pocketsphinx/test/data/tidigits/lm/tidigits.dic";
// Filter-bank warp (PocketSphinx inverse_linear: mel(f / warp), i.e. the filters' mel knee at
// 700 * warp Hz): 1.4, chosen leave-one-speaker-out with the speaker vote (README); 1.2-1.6
// all help every speaker.
inline constexpr double kFsddTidigitsWarp = 1.4;
inline constexpr double kFsddPadSeconds = 0.2;
inline constexpr double kFsddPadRms = 10.0;  // about -70 dBFS

// The recogniser `eval speech --dataset fsdd` decodes with (model, dictionary, 8 kHz front end
// and warp per SpeechEvalOptions::fsdd_model; closed set), a description for the JSON, and the
// digit words of the grammar. `train speech --dataset fsdd` adapts with the same front end.
struct FsddRecognizer {
  RecognizerOptions options;
  std::string description;
  std::vector<std::string> words;  // "zero".."nine" (+ "oh" with fsdd_oh)
};
Result<FsddRecognizer> fsdd_recognizer(const SpeechEvalOptions& options);
// An FSDD clip as it is decoded: 8 kHz mono, padded at both ends with `pad_seconds` of quiet
// noise (kFsddPadRms) drawn from a generator seeded with `seed` (deterministic per clip).
Result<Audio> fsdd_clip(const AudioItem& item, double pad_seconds, size_t seed);
// "0".."9" -> "zero".."nine" (empty for anything else).
std::string fsdd_digit_word(const std::string& label);
// Audio of a listed utterance: any libsndfile format (channel 0 of several), or a headerless
// 16 kHz s16le mono .raw (PocketSphinx's test files).
Result<Audio> read_utterance_audio(const std::filesystem::path& path);

// FSDD items as enrolment utterances for adapt_acoustic_model (train speech): each clip as it
// is decoded (fsdd_clip, seeded by its position), its digit word, its file name as the id.
Result<std::vector<AdaptationUtterance>> fsdd_enrolment(const std::vector<AudioItem>& items,
                                                        double pad_seconds = kFsddPadSeconds);
// The utterances of a list file (load_utterance_list; every line needs words) as enrolment
// utterances, ids "line<N>"; unreadable audio is "FILE:LINE: problem".
Result<std::vector<AdaptationUtterance>> list_enrolment(const std::filesystem::path& list);

// The acoustic model `train speech` adapted on the Speech Commands development clips, with its
// decoys.txt (data/models/speech_commands/MODEL_CARD.md).
std::filesystem::path commands_model_dir();
// Words of a decoy list: one per line, '#' starts a comment; a file that cannot be read or holds
// no word is an error naming it.
Result<std::vector<std::string>> read_decoy_words(const std::filesystem::path& path);

// Speech Commands decision constants, chosen on the synthetic espeak-ng *tuning* voices plus
// FSDD speaker george's digits (real speech, all out of the 10-word grammar); see README.md.
inline constexpr double kCommandsGarbageWeight = 0.01;
// 0.3 since the decoys and the adapted model (issue 16): chosen by 2-fold speaker-disjoint
// cross-validation on the development clips (modalities/speech/models/speech_commands/).
inline constexpr double kCommandsMinConfidence = 0.3;

// FSDD (`digit_speaker_index.wav`, 8 kHz): each clip, padded with kFsddPadSeconds of quiet
// noise, scored against the ten digit words (zero ... nine; "oh" too with fsdd_oh), closed set;
// by default with PocketSphinx's TIDIGITS model at 8 kHz, warp kFsddTidigitsWarp (fsdd_model
// "en-us": the en-us model with `recognizer`'s resampler / front end). With
// fsdd_speaker_adapt (opt-in, --speaker-adapt) each clip's word posterior is then combined with
// those of its nearest clips of the same speaker (speaker_batch.hpp; unsupervised, transductive).
// Metrics accuracy, per-speaker accuracy, no_result_rate, confusion, per_utterance (before
// the vote); per_class.<digit>.recall.
// Speech Commands (12 class folders, 16 kHz): silence check (detect_speech) -> _silence_;
// otherwise the 10-word grammar with phone-loop rejection and min_confidence: accepted word ->
// that word, anything else -> _unknown_. accuracy over all 12 classes, false_accept_rate =
// _unknown_ and _silence_ clips given a command word, per_class.<label>.recall, confusion.

// In-grammar items: cards/*.wav under cards/cards.gram (references cards.transcription) and
// goforward.raw under goforward.gram ("go forward ten meters"). Out-of-grammar items, per
// grammar: the other grammar's utterances, numbers.raw, something.raw, librivox/*.wav, 3 s of
// near-silence and 3 s of white noise (-30 dBFS).
// Metrics: grammar_sentence_accuracy (in-grammar utterances decoded exactly and accepted),
// false_accept_rate (out-of-grammar items given any result), accuracy (all items handled
// correctly: in-grammar exact, out-of-grammar rejected); timing.rtf = decode time / audio time.
Result<eval::EvalReport> run_speech_eval(const SpeechEvalOptions& options,
                                         const std::function<void(double)>& progress = {});

}  // namespace dreamsense::speech
