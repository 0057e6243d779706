#pragma once
// Voice identification analyser (F21 identifyVoice): cuts the audio stream into utterances with
// the shared utterance segmenter (audio/utterance_segmenter.hpp) and writes keys::kSpeakerIdentity
// once per utterance. Two methods, chosen explicitly (never as a silent fallback):
//  - kGmmUbm: the GMM-UBM speaker models of a trained VoiceModel (voice_model.hpp); an
//    utterance whose best log-likelihood ratio is below the model's threshold is "unknown".
//  - kDirectionRule: DREAM's identifyVoice rule on keys::kSoundDirection (original-dream.md
//    2.2 #21): |azimuth| > angle_deg with confidence > min_confidence -> therapist (seated at
//    the side); |azimuth| < angle_deg, azimuth != 0, confidence > min_confidence -> child (in
//    front); anything else decides nothing. Each direction written during the utterance votes;
//    the majority wins, no vote (or a tie) gives "unknown". Needs the sound direction analyser
//    to run before this one on the same stream.
// Silence writes nothing; so does (gmm_ubm) an utterance without a single speech-like frame.
// The entry is written at the tick the utterance ends (hangover_s after its last loud frame);
// start/end are the loud part's stamps.

#include "dreamsense/audio/reference_gate.hpp"
#include "dreamsense/audio/utterance_segmenter.hpp"
#include "dreamsense/core/analyzer.hpp"
#include "dreamsense/voice_id/speaker_tracks.hpp"
#include "dreamsense/voice_id/voice_model.hpp"

#include <filesystem>
#include <memory>

namespace dreamsense::voice_id {

enum class VoiceIdMethod { kGmmUbm, kDirectionRule };
const char* to_string(VoiceIdMethod m);  // "gmm_ubm", "direction_rule"
Result<VoiceIdMethod> parse_voice_id_method(const std::string& s);

enum class VoiceDecision { kUtterance, kTracks };
const char* to_string(VoiceDecision d);  // "utterance", "tracks"
Result<VoiceDecision> parse_voice_decision(const std::string& s);

struct DirectionRuleOptions {
  double angle_deg = 20;        // DREAM: child within +-20 deg of the array's broadside
  double min_confidence = 0.5;  // DREAM: confidence > 0.5
  Status check() const;
};

// The segmenter's settings for voice identification: the shared segmenter's defaults (0.15 s of
// speech opens, 0.25 s pre-roll, 0.5 s hangover, 10 s at most) with the tree's one VAD (energy
// gate: 10 dB over a floor rising at most 3 dB/s), which keeps a reader's long sentence in one
// piece (measured in README.md).
inline audio::UtteranceSegmenterOptions default_voice_segmenter() { return {}; }

struct VoiceIdAnalyzerOptions {
  SensorId audio_sensor = "mic_array";
  VoiceIdMethod method = VoiceIdMethod::kGmmUbm;
  // kGmmUbm: the model, in memory or as a file written by `dreamsense train voices`.
  std::shared_ptr<const VoiceModel> model;
  std::filesystem::path model_file;
  DirectionRuleOptions direction;
  // Utterances (audio::UtteranceSegmenter, as the speech analyser) on channel 0; the stream's
  // rate is filled in from the first chunk.
  audio::UtteranceSegmenterOptions segmenter = default_voice_segmenter();
  // Privacy: speaker_id is always the public id (public_speaker_id: role word or speaker_<k>);
  // name is the enrolled name only when this is set (`--include-names`), else the public id.
  bool include_names = false;
  // The robot's own voice (issue 16): the reference stream the robot's loudspeaker plays (role
  // robot_audio; empty: none). Utterances are trimmed to their longest robot-free part and
  // dropped when less than min_free_speech_s of their speech is left (audio/reference_gate.hpp).
  SensorId reference_sensor;
  audio::ReferenceGateOptions robot_gate;
  double min_free_speech_s = 0.3;
  // Issue 16: the utterance decision on the mean of the array's channels (about 6 dB less noise:
  // a quiet child is cut whole, as in the speech analyser); channel 0 is still what is scored.
  bool vad_on_channel_mean = true;
  // kGmmUbm, issue 16 item 2: how an utterance's scores become a speaker.
  //  - kUtterance: each utterance alone (its best LLR, unknown below the model's threshold):
  //    the method until issue 16, kept as the measured baseline.
  //  - kTracks: voice tracks (speaker_tracks.hpp): utterances from the same direction
  //    (keys::kSoundDirection of the previous ticks, read as feedback: without a sound direction
  //    analyser every utterance stands alone, = kUtterance) accumulate frame-weighted evidence,
  //    and distinct places heard in the same stretch get distinct speakers.
  VoiceDecision decision = VoiceDecision::kTracks;
  SpeakerTrackOptions tracks;
  // kTracks, issue 16: the child seen by the cameras as a cue to who spoke. With the array's
  // extrinsics (the microphone array's calibration) and a speaker whose role id is "child", the
  // head positions of keys::kHeadPose (earlier ticks, world) are turned into azimuths in the
  // array frame; an utterance's offset from the seen child's azimuth (during its speech, or up
  // to seen_child_lookback_s before it) goes to the tracker (tracks.child_speaker_id,
  // tracks.child_place_tolerance_deg). Without extrinsics or a head pose: no cue.
  bool use_seen_child = true;
  std::optional<cv::Matx33d> array_from_world_R;
  cv::Vec3d array_from_world_t{0, 0, 0};
  // Mics on a line (Kinect, along x): the sound direction is the angle from the axis, reported
  // in the front half-plane; the head is converted the same way.
  bool array_is_linear = true;
  double seen_child_lookback_s = 1.0;
  Status check() const;
};

Result<std::unique_ptr<Analyzer>> make_voice_id_analyzer(const VoiceIdAnalyzerOptions& options);

}  // namespace dreamsense::voice_id
