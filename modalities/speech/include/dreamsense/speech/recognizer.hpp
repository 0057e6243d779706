#pragma once
// Speech recognition against a grammar (F22 recognizeSpeech) with Debian's PocketSphinx
// (0.8+5prealpha API) and the en-us continuous model. See README.md for the method.
//
// Out-of-grammar rejection: the grammar's finite-state graph gets a parallel garbage branch, a
// free loop over the 39 CMU phones (each phone a one-phone "word"), from the start state to the
// final state. The decoder's best path is then either a grammar sentence or a phone string;
// a phone string means "not in the grammar" and yields no result. Confidence (0..1) is a
// logistic of the per-frame path-score margin between the best grammar path and the best
// garbage path (a second pass over the garbage branch alone, run only when the grammar won);
// 0.5 = tie. ps_get_prob() is no use here: with FSG searches it returns 0 (posterior 1).

#include "dreamsense/core/status.hpp"
#include "dreamsense/core/timestamp.hpp"
#include "dreamsense/perception/speech.hpp"
#include "dreamsense/speech/srgs.hpp"

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace dreamsense::speech {

// How inputs at another rate than the front end's are converted.
enum class Resampler {
  kSoxr,  // libsoxr, very-high quality (linear phase, 28-bit), no dither: the default
  kSinc,  // our windowed-sinc interpolator (Kaiser beta 8, 32 zero crossings per side)
};
Result<Resampler> parse_resampler(std::string_view name);  // "soxr" | "sinc"
std::string_view to_string(Resampler r);

struct RecognizerOptions {
  // Debian package pocketsphinx-en-us.
  std::filesystem::path model_dir = "/usr/share/pocketsphinx/model/en-us/en-us";
  std::filesystem::path dictionary = "/usr/share/pocketsphinx/model/en-us/cmudict-en-us.dict";
  // Gaussian means read instead of model_dir's own (a means-only adapted model: small enough to
  // ship, the rest from the Debian package; acoustic_model.hpp). Empty = model_dir/means.
  std::filesystem::path means_file;
  int model_rate_hz = 16000;  // the acoustic model's rate; other input rates are resampled
  // Rate of the MFCC front end; 0 = model_rate_hz. Setting 8000 runs the front end natively on
  // narrow-band audio (no upsampling); the mel filters then end at front_end_upper_hz. Inputs
  // at any other rate are resampled to this rate.
  int front_end_rate_hz = 0;
  // Upper edge of the mel filter bank (Hz); 0 = the model's feat.params (6800 Hz for en-us).
  // Must be below half the front-end rate.
  double front_end_upper_hz = 0;
  Resampler resampler = Resampler::kSoxr;
  // PocketSphinx's own energy VAD (-remove_silence): drops frames it judges silent before
  // the search. On by default (as in PocketSphinx).
  bool remove_silence = true;
  // PocketSphinx's spectral subtraction (-remove_noise); its noise estimate starts from the
  // first frames, which in tightly trimmed clips are already speech.
  bool remove_noise = true;
  // Vocal-tract-length warp of the filter bank (PocketSphinx -warp_type inverse_linear,
  // filters at f / warp); 1 = off. A speaker/channel normalisation tuned per model (README).
  double frequency_warp = 1.0;
  bool reject_out_of_grammar = true;
  // Weight of each phone in the garbage loop (FSG transition probability, (0, 1]). Higher =
  // more rejections (fewer false accepts, more false rejects). 1 was measured best (README).
  double garbage_phone_weight = 1.0;
  // Optional extra threshold on the confidence, on top of the garbage-branch decision (which
  // alone decides with the default 0). The confidence pass searches the garbage branch alone,
  // so it can find a slightly better phone string than survived the joint beam: accepted
  // utterances can have confidences a little under 0.5 (cards/004: 0.47).
  double min_confidence = 0.0;
  // Run the second (garbage-only) pass that gives the confidence. Without it a closed-set
  // decode (reject_out_of_grammar false) costs half as much; the confidence is then 1 and the
  // margin 0. Ignored when rejecting (the decision needs it only with min_confidence, but the
  // reported confidence always does).
  bool confidence_pass = true;
  // Score units per 10 ms frame that map to one logistic unit in the confidence.
  double confidence_scale = 10.0;
  // When set, PocketSphinx writes the cepstra of every decode pass here as NNNNNNNNN.mfc
  // (-mfclogdir; passes numbered from 0). Used to train on exactly what the decoder sees
  // (acoustic_adaptation.hpp); empty = off.
  std::filesystem::path feature_log_dir;
  Status check() const;
};

// A grammar in the form the recogniser consumes: JSGF text plus, when it came from SRGS, the
// SRGS tree that maps words back to tags.
struct Grammar {
  std::string jsgf;
  std::optional<SrgsGrammar> srgs;
  std::string source;  // file name or "<string>", for messages

  static Result<Grammar> from_jsgf(std::string jsgf, std::string source = "<string>");
  static Result<Grammar> from_jsgf_file(const std::filesystem::path& path);
  static Result<Grammar> from_srgs(const std::string& xml, std::string source = "<string>");
  static Result<Grammar> from_srgs_file(const std::filesystem::path& path);
  // .grxml / .xml -> SRGS, anything else -> JSGF.
  static Result<Grammar> from_file(const std::filesystem::path& path);
};

// What one decode produced, including rejected hypotheses (for evaluation and logs).
struct Decoding {
  std::string grammar_hypothesis;  // best grammar sentence (empty if the garbage path won or
                                   // nothing was heard)
  bool heard_speech = false;       // the decoder produced any word (grammar or garbage)
  bool accepted = false;           // grammar path won and confidence >= min_confidence
  double confidence = 0;
  double score_per_frame = 0;   // best path's log score (PocketSphinx units) per 10 ms frame
  double margin_per_frame = 0;  // (grammar - garbage-alone path score) per frame of the input
  int first_frame = -1, last_frame = -1;  // 10 ms frames of the grammar words
  double decode_seconds = 0;
};

class Recognizer {
 public:
  // Loads the model and compiles the grammar. Missing model: kNotFound naming the path and the
  // Debian package; words missing from the dictionary: kInvalidArgument listing them.
  static Result<std::unique_ptr<Recognizer>> create(const RecognizerOptions& options,
                                                    const Grammar& grammar);
  ~Recognizer();
  Recognizer(const Recognizer&) = delete;
  Recognizer& operator=(const Recognizer&) = delete;

  // Decodes one whole utterance (mono). `start` is the stamp of the first sample.
  // Returns nullopt when nothing in the grammar was said (silence, noise, other speech).
  // Errors only for bad input (rate <= 0) or a decoder failure.
  Result<std::optional<RecognizedSpeech>> recognize(std::span<const int16_t> samples,
                                                    int sample_rate_hz,
                                                    Timestamp start = Timestamp::from_ns(0));
  // Float samples in [-1, 1].
  Result<std::optional<RecognizedSpeech>> recognize(std::span<const float> samples,
                                                    int sample_rate_hz,
                                                    Timestamp start = Timestamp::from_ns(0));
  // Same decode, with the details.
  Result<Decoding> decode(std::span<const int16_t> samples, int sample_rate_hz);

 private:
  struct Impl;
  explicit Recognizer(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

// Band-limited resampling (low-pass at the lower Nyquist), e.g. 8 kHz telephone/FSDD audio to
// the model's 16 kHz. Output length floor(in.size() * to_hz / from_hz); both methods are
// linear phase with the delay compensated (output sample 0 = input sample 0).
std::vector<int16_t> resample(std::span<const int16_t> in, int from_hz, int to_hz,
                              Resampler method = Resampler::kSoxr);

}  // namespace dreamsense::speech
