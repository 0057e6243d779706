#pragma once
// Speech analyser (F22 recognizeSpeech): cuts the audio stream into utterances with the shared
// audio::UtteranceSegmenter and decodes each finished utterance against the grammar; writes
// keys::kRecognizedSpeech only when something in the grammar was said (out-of-grammar speech and
// noise write nothing).
//
// Voice activity is decided on the mean of the channels (for an array: an unsteered beam, whose
// noise is ~10 log10(M) dB lower than one microphone's while speech below ~1 kHz passes from any
// direction).
//
// Beamforming: with a microphone array (mic_positions_m, > 1 channel) and steer_to_sound_direction,
// the analyser reads keys::kSoundDirection (written by the sound-direction analyser, which must run
// before it in the same tick), averages the directions heard during the utterance's speech
// (confidence-weighted unit vectors) and steers an audio::Beamformer (delay-and-sum) at it before
// decoding. Without a direction during the utterance, or without an array, it decodes channel 0
// (the array's microphones are 15-23 cm apart: averaging them unsteered would comb-filter the
// speech of an off-axis talker). Measured on the demo sessions: audio/README.md.

#include "dreamsense/audio/beamformer.hpp"
#include "dreamsense/audio/reference_gate.hpp"
#include "dreamsense/audio/utterance_segmenter.hpp"
#include "dreamsense/core/analyzer.hpp"
#include "dreamsense/speech/recognizer.hpp"

#include <opencv2/core.hpp>

#include <filesystem>
#include <memory>
#include <vector>

namespace dreamsense::speech {

// The segmenter's defaults for speech: the tree's one VAD (audio::VoiceActivityDetector, the
// energy gate voice_id uses too) on the mean of all channels (vad_channel -1); the stream's rate
// and channel count are filled in from the first chunk.
inline audio::UtteranceSegmenterOptions default_speech_segmenter() {
  audio::UtteranceSegmenterOptions o;
  o.vad_channel = -1;
  return o;
}

// The recogniser's defaults in the pipeline: the phone-loop rejection at weight 0.5 instead of
// the recogniser's 1. At 1, once the pre-roll was faded in, the phone loop rejected 5 of the
// demo child's 77 in-grammar commands (4 of them "five five", confidence 0.45-0.49). At 0.5
// it rejected none, accepted none of the demo therapist's out-of-grammar sentences, and the
// pocketsphinx test data keep 0 false accepts (0.3 accepts 1 of 24). Measured in README.md.
inline RecognizerOptions default_speech_recognizer() {
  RecognizerOptions o;
  o.garbage_phone_weight = 0.5;
  return o;
}

struct SpeechAnalyzerOptions {
  SensorId audio_sensor = "mic_array";
  std::filesystem::path grammar;  // JSGF, or SRGS (.grxml) as DREAM used
  RecognizerOptions recognizer = default_speech_recognizer();
  audio::UtteranceSegmenterOptions segmenter = default_speech_segmenter();
  // Microphone positions (metres, array frame, channel order) of the audio stream; empty = no
  // array (decode channel 0).
  std::vector<cv::Vec3d> mic_positions_m;
  bool steer_to_sound_direction = true;  // beamform toward keys::kSoundDirection
  audio::BeamformerMethod beamformer = audio::BeamformerMethod::kDelayAndSum;
  // Directions from this long before the utterance's speech to this long after it are used.
  Duration direction_margin = Duration::from_ms(200);
  // The robot's own voice (issue 16): the reference stream its loudspeaker plays (role
  // robot_audio; empty: none). Utterances are cut to their longest robot-free part and not
  // decoded when less than min_free_speech_s of their speech is left (audio/reference_gate.hpp).
  SensorId reference_sensor;
  audio::ReferenceGateOptions robot_gate;
  double min_free_speech_s = 0.3;
  // Issue 16: the decoded (beamformed) utterance passes the noise suppressor first
  // (audio/noise_suppressor.hpp; its noise estimate starts on the 0.25 s pre-roll). Off by
  // default: measured no better than PocketSphinx's own noise removal (README.md).
  bool noise_suppression = false;
  // The utterance's pre-roll is faded in over at most this long before decoding
  // (audio::fade_in_pre_roll; 0 = off): its abrupt start was decoded as a word.
  double fade_in_s = 0.1;
  // Decode each utterance on a background thread and report it at the first tick after the
  // decode finished, instead of at the tick that closed it: the decode (~0.1-0.2 s) then no
  // longer stalls that tick's other analysers. Reports then depend on timing, so it is for live
  // analyses only (the plan turns it on there: PlanContext::live, option
  // live_background_decode); a replay decodes at the closing tick and stays reproducible.
  bool background_decode = false;
  bool beamforming() const { return steer_to_sound_direction && mic_positions_m.size() > 1; }
  Status check() const;
};

Result<std::unique_ptr<Analyzer>> make_speech_analyzer(const SpeechAnalyzerOptions& options);

}  // namespace dreamsense::speech
