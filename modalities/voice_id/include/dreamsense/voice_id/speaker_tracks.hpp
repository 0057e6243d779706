#pragma once
// Speaker decisions over voice tracks (issue 16 item 2): a short utterance inherits the identity
// established by the longer ones heard from the same place, and two places heard in the same
// stretch of the session are two people.
//
// What it represents: the utterances of one session, in order, each with the per-speaker average
// log-likelihood ratios of the GMM-UBM scoring (voice_model.hpp), its number of speech frames and
// the direction it came from (keys::kSoundDirection, when a sound direction analyser ran).
//  1. Track: an utterance joins the live track (last utterance at most memory_s before this one
//     starts) whose direction is nearest, if within angle_tolerance_deg; otherwise it opens a new
//     track. A track's direction is its last utterance's (each already a mean over the ticks of
//     the utterance), so a speaker who shifts by less than the tolerance per utterance stays on
//     one track. An utterance without a direction is a track of its own that no later
//     utterance joins (= today's per-utterance decision).
//  2. Evidence: a track holds, per enrolled speaker, the frame-weighted sum of its utterances'
//     LLRs, E_s = sum_u T_u * LLR_u,s, and its frame count F = sum_u T_u; when F exceeds
//     max_track_frames both are scaled down to it (old evidence fades, so a track can change
//     its mind when someone else takes the place). The track's mean LLR is E_s / F: the
//     frame-weighted mean over its utterances, so a 1 s utterance weighs a quarter of a 4 s one.
//  3. Open set: the utterance is "unknown" when neither its own best LLR nor its track's best
//     mean LLR reaches the model's threshold (today's test, on the utterance or on its
//     track's accumulated evidence: a poorly fitting short utterance is known when its place
//     is, and a well fitting one is not made unknown by poorer ones before it). A track is
//     "known" by the same test on its last utterance or its evidence.
//  4. Names (exclusive = true): the live known tracks get the enrolled
//     speakers by a joint assignment: as many distinct speakers as possible (min(tracks,
//     speakers)), and among those assignments the one with the largest total evidence
//     sum_k E_k,s(k); a track left without a distinct speaker (more places than people: someone
//     moved) takes its own best speaker. With exclusive = false each track takes its best.
//     The utterance is named as its track.
// Deterministic; no state but the tracks. Limitation (README.md): a speaker who moves to a new
// place while the old one is still live, with nobody else heard, is given another enrolled
// speaker's name on the new place until the old track expires (memory_s).

#include "dreamsense/core/status.hpp"
#include "dreamsense/core/timestamp.hpp"
#include "dreamsense/voice_id/voice_model.hpp"

#include <map>
#include <optional>
#include <string>
#include <vector>

namespace dreamsense::voice_id {

struct SpeakerTrackOptions {
  // Utterances within this angle of a track's direction join it. The sound direction of a
  // talker at rest wanders by a few degrees (demo: 1.6 deg mean error); people seated apart are
  // further apart (DREAM: child in front, therapist 30-60 deg to the side).
  double angle_tolerance_deg = 15;
  // A track not heard for this long is closed (its speaker may have left or moved).
  double memory_s = 60;
  // Evidence kept per track, in speech frames (10 ms): 6 s of speech.
  double max_track_frames = 600;
  // Distinct live tracks get distinct speakers where possible (step 4 above).
  bool exclusive = true;
  // Assignment by exhaustive search over speaker subsets: at most this many enrolled speakers
  // (2^speakers states); with more, each track takes its best speaker.
  int max_exclusive_speakers = 12;
  // The child seen by the cameras (issue 16): the enrolled speaker who is the child (role id
  // "child"; empty: no such cue). An utterance whose direction is within
  // child_place_tolerance_deg of where the cameras see the child's head
  // (UtteranceEvidence::seen_child_offset_deg) is the child's, whatever the voice says; one more
  // than twice that away is not the child's (its track's best other speaker, or unknown).
  // Assumes one person at the child's place (DREAM: the therapist sits 30-60 deg aside).
  std::string child_speaker_id;
  double child_place_tolerance_deg = 15;
  Status check() const;
};

// The smaller angle between two azimuths, in [0, 180] degrees.
double azimuth_difference_deg(double a_deg, double b_deg);

// One utterance as scored by identify(): per-speaker average LLR (nats per frame).
struct UtteranceEvidence {
  Timestamp start, end;               // speech part
  std::optional<double> azimuth_deg;  // where it came from (none: unknown)
  int frames = 0;                     // speech frames scored (> 0)
  std::vector<SpeakerScore> scores;   // every enrolled speaker (any order)
  // Angle between azimuth_deg and the azimuth of the child's head seen by the cameras during
  // the utterance (none: not seen, or no direction).
  std::optional<double> seen_child_offset_deg;
};

struct TrackDecision {
  std::string speaker_id;            // enrolled id, or kUnknownSpeaker (open set)
  std::string best_id;               // the track's best speaker by its own evidence (closed set)
  double llr = 0;                    // the track's mean LLR of speaker_id (of best_id when unknown)
  int track = -1;                    // index of the track (order of creation)
  int track_utterances = 0;          // utterances on the track, this one included
  double track_frames = 0;           // frames of evidence on the track (after the cap)
  double azimuth_deg = 0;            // the track's direction (NaN without a direction)
  bool inherited = false;            // speaker_id differs from what this utterance alone would say
  bool by_place = false;             // the seen child's place decided (child_speaker_id)
  std::vector<SpeakerScore> scores;  // the track's mean LLR per speaker, best first
};

struct VoiceTrack {
  double azimuth_deg = 0;
  bool has_direction = false;
  Timestamp last;  // end of its last utterance
  int utterances = 0;
  double frames = 0;
  std::map<std::string, double> evidence;  // per speaker: sum over frames of the LLR
  bool last_known = false;  // its last utterance's own best LLR reached the threshold
};

class SpeakerTracker {
 public:
  // `threshold`: the open-set threshold (VoiceModel::threshold, nats per frame).
  // Precondition: options.check() is ok (checked, throws otherwise).
  SpeakerTracker(const SpeakerTrackOptions& options, double threshold);
  // Adds the next utterance (utterances in time order) and returns its decision.
  // Precondition: u.frames > 0 and u.scores not empty.
  TrackDecision add(const UtteranceEvidence& u);
  void reset() { tracks_.clear(); }
  const std::vector<VoiceTrack>& tracks() const { return tracks_; }

 private:
  bool live(const VoiceTrack& t, Timestamp now) const;
  bool known(const VoiceTrack& t) const;  // step 3
  // Step 4 over the live tracks that pass the open-set test; returns the speaker of `which`.
  std::string assign(const std::vector<size_t>& passing, size_t which) const;

  SpeakerTrackOptions options_;
  double threshold_;
  std::vector<VoiceTrack> tracks_;
};

}  // namespace dreamsense::voice_id
