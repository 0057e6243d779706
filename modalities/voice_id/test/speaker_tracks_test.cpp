// SpeakerTracker (issue 16 item 2): voice tracks from directions, evidence accumulated over a
// track, distinct places named as distinct speakers; negative cases: speakers at different
// places are not merged, a moving speaker, no direction, an unknown voice.

#include "dreamsense/voice_id/speaker_tracks.hpp"

#include <gtest/gtest.h>

#include <optional>

namespace dreamsense::voice_id {
namespace {

constexpr double kThreshold = -0.25;

// An utterance at [start, start + frames/100] s from `azimuth` with LLRs (child, therapist).
UtteranceEvidence utt(double start, int frames, std::optional<double> azimuth, double child,
                      double therapist) {
  UtteranceEvidence u;
  u.start = Timestamp::from_seconds(start);
  u.end = Timestamp::from_seconds(start + frames / 100.0);
  u.azimuth_deg = azimuth;
  u.frames = frames;
  u.scores = {{"child", child}, {"therapist", therapist}};
  return u;
}

TEST(SpeakerTracks, OptionsAreChecked) {
  EXPECT_TRUE(SpeakerTrackOptions{}.check());
  SpeakerTrackOptions o;
  o.angle_tolerance_deg = 0;
  o.memory_s = -1;
  const Status s = o.check();
  ASSERT_FALSE(s);
  EXPECT_NE(s.error().message.find("angle_tolerance_deg"), std::string::npos);
  EXPECT_NE(s.error().message.find("memory_s"), std::string::npos);
  EXPECT_THROW(SpeakerTracker(o, kThreshold), CheckFailure);
  SpeakerTracker t({}, kThreshold);
  EXPECT_THROW(t.add(utt(0, 0, 0.0, 0, 0)), CheckFailure) << "no frames";
}

// The demo's miss (issue 16): the therapist's long sentence at the side, then a short child
// command in front whose own LLRs favour the therapist. The places are distinct, so the child's
// place gets the other speaker; today's per-utterance answer would be "therapist".
TEST(SpeakerTracks, ShortUtteranceAtAnotherPlaceIsNotTheSpeakerAlreadyThere) {
  SpeakerTracker t({}, kThreshold);
  const auto a = t.add(utt(2.5, 348, -56.0, -1.38, 0.44));
  EXPECT_EQ(a.speaker_id, "therapist");
  EXPECT_FALSE(a.inherited);
  const auto b = t.add(utt(8.1, 135, 0.8, -0.93, -0.005));
  EXPECT_EQ(b.speaker_id, "child");
  EXPECT_TRUE(b.inherited);
  EXPECT_NE(a.track, b.track);
  EXPECT_NEAR(b.llr, -0.93, 1e-9);
  EXPECT_EQ(b.best_id, "therapist") << "its own evidence still says therapist";
  // Her next sentence goes on her track and stays hers.
  const auto c = t.add(utt(12.5, 458, -54.0, -1.03, 0.09));
  EXPECT_EQ(c.track, a.track);
  EXPECT_EQ(c.speaker_id, "therapist");
  EXPECT_EQ(c.track_utterances, 2);
  EXPECT_EQ(t.tracks().size(), 2u);
}

// Negative case: the same two utterances with exclusivity off, or without directions, give the
// per-utterance answer (the short one is called the therapist).
TEST(SpeakerTracks, WithoutExclusivityOrDirectionsEachVoiceDecidesAlone) {
  SpeakerTrackOptions o;
  o.exclusive = false;
  SpeakerTracker t(o, kThreshold);
  t.add(utt(2.5, 348, -56.0, -1.38, 0.44));
  EXPECT_EQ(t.add(utt(8.1, 135, 0.8, -0.93, -0.005)).speaker_id, "therapist");
  SpeakerTracker n({}, kThreshold);
  n.add(utt(2.5, 348, std::nullopt, -1.38, 0.44));
  const auto b = n.add(utt(8.1, 135, std::nullopt, -0.93, -0.005));
  EXPECT_EQ(b.speaker_id, "therapist");
  EXPECT_FALSE(b.inherited);
  EXPECT_EQ(n.tracks().size(), 2u) << "no direction: a track of its own";
  n.add(utt(12.0, 100, std::nullopt, -0.9, 0.1));
  EXPECT_EQ(n.tracks().size(), 3u) << "no direction joins nothing";
}

// Two speakers at different places are never merged into one track, however alike their
// voices score; each keeps its own evidence.
TEST(SpeakerTracks, TwoPlacesAreTwoTracks) {
  SpeakerTracker t({}, kThreshold);
  const auto a = t.add(utt(0, 200, 0.0, 0.3, -1.0));
  const auto b = t.add(utt(3, 200, 35.0, -1.0, 0.3));
  const auto c = t.add(utt(6, 200, 2.0, 0.2, -0.9));
  const auto d = t.add(utt(9, 200, 33.0, -0.8, 0.2));
  EXPECT_EQ(a.speaker_id, "child");
  EXPECT_EQ(b.speaker_id, "therapist");
  EXPECT_EQ(c.speaker_id, "child");
  EXPECT_EQ(d.speaker_id, "therapist");
  EXPECT_EQ(a.track, c.track);
  EXPECT_EQ(b.track, d.track);
  EXPECT_NE(a.track, b.track);
  EXPECT_NEAR(t.tracks()[static_cast<size_t>(a.track)].azimuth_deg, 2.0, 1e-6);
  EXPECT_EQ(t.tracks()[static_cast<size_t>(a.track)].frames, 400);
}

// A short utterance inherits its track's identity: the evidence is frame-weighted, so 1 s of
// contrary voice does not undo 4 s established at the same place.
TEST(SpeakerTracks, ShortUtteranceInheritsItsTrack) {
  SpeakerTracker t({}, kThreshold);
  t.add(utt(0, 400, 1.0, 0.3, -1.0));
  const auto b = t.add(utt(6, 100, -2.0, -0.6, -0.2));
  EXPECT_EQ(b.speaker_id, "child");
  EXPECT_TRUE(b.inherited);
  EXPECT_NEAR(b.llr, (400 * 0.3 + 100 * -0.6) / 500.0, 1e-9);
  EXPECT_EQ(b.track_utterances, 2);
  // ...but a longer one outweighs it, and the cap (600 frames) lets the place change hands.
  SpeakerTrackOptions o;
  o.max_track_frames = 600;
  SpeakerTracker u(o, kThreshold);
  u.add(utt(0, 100, 1.0, 0.3, -1.0));
  const auto c = u.add(utt(6, 500, 0.0, -1.0, 0.3));
  EXPECT_EQ(c.speaker_id, "therapist");
  EXPECT_LE(c.track_frames, 600);
}

// A speaker who moves: a slow drift stays on one track (its direction follows); a jump while
// her old place is still live and someone else holds the other name keeps her own voice's
// answer (more places than speakers: the surplus place takes its own best); once the old place
// has expired (memory_s), the new one is named from its own evidence.
TEST(SpeakerTracks, SpeakerWhoMoves) {
  SpeakerTracker t({}, kThreshold);
  int track = -1;
  for (int k = 0; k < 6; ++k) {  // 30, 38, 46, ... 70 deg: steps of 8 deg
    const auto d = t.add(utt(3.0 * k, 200, 30.0 + 8 * k, -1.0, 0.3));
    EXPECT_EQ(d.speaker_id, "therapist");
    if (k == 0) track = d.track;
    EXPECT_EQ(d.track, track) << "step " << k;
  }
  t.add(utt(20, 150, 0.0, 0.3, -1.0));                      // the child in front
  const auto jump = t.add(utt(24, 300, -40.0, -1.0, 0.3));  // she moves to the other side
  EXPECT_NE(jump.track, track);
  EXPECT_EQ(jump.speaker_id, "therapist");
  EXPECT_EQ(t.add(utt(28, 100, 0.0, 0.2, -0.8)).speaker_id, "child");

  SpeakerTrackOptions o;
  o.memory_s = 10;
  SpeakerTracker m(o, kThreshold);
  m.add(utt(0, 300, 45.0, -1.0, 0.3));
  m.add(utt(4, 100, 0.0, 0.3, -1.0));
  const auto later = m.add(utt(30, 120, -40.0, -0.6, -0.1));  // both old places expired
  EXPECT_EQ(later.speaker_id, "therapist");
  EXPECT_FALSE(later.inherited);
}

// Open set on the track's evidence: a voice that fits nobody is unknown and takes no name from
// the other places.
TEST(SpeakerTracks, UnknownVoiceStaysUnknown) {
  SpeakerTracker t({}, kThreshold);
  t.add(utt(0, 300, 40.0, -1.0, 0.3));
  const auto s = t.add(utt(5, 200, 0.0, -0.9, -0.7));
  EXPECT_EQ(s.speaker_id, kUnknownSpeaker);
  EXPECT_EQ(s.best_id, "therapist");
  EXPECT_NEAR(s.llr, -0.7, 1e-9);
  // Alone it is unknown too.
  SpeakerTracker a({}, kThreshold);
  EXPECT_EQ(a.add(utt(0, 200, 0.0, -0.9, -0.7)).speaker_id, kUnknownSpeaker);
  a.reset();
  EXPECT_TRUE(a.tracks().empty());
}

// The open-set test passes on the utterance's own voice or on its track's evidence: a voice that
// fits the child is not made unknown by a poorly fitting one before it at the same place (demo
// seed 137: cards/004 unknown, then cards/002).
TEST(SpeakerTracks, OpenSetOnTheUtteranceOrItsTrack) {
  SpeakerTracker t({}, kThreshold);
  EXPECT_EQ(t.add(utt(1.6, 103, 2.0, -0.73, -0.51)).speaker_id, kUnknownSpeaker);
  EXPECT_EQ(t.add(utt(4.3, 459, 51.0, -0.93, 0.04)).speaker_id, "therapist");
  const auto c = t.add(utt(10.9, 171, 0.6, -0.02, -1.02));
  EXPECT_EQ(c.speaker_id, "child");
  EXPECT_LT(c.llr, kThreshold) << "the track's mean alone would say unknown";
  EXPECT_FALSE(c.inherited);
}

// Three speakers, three places: the joint assignment gives each place a distinct speaker by the
// largest total evidence, not greedily by each place's best.
TEST(SpeakerTracks, JointAssignmentOverThreeSpeakers) {
  SpeakerTracker t({}, kThreshold);
  auto three = [](double start, int frames, double az, double a, double b, double c) {
    UtteranceEvidence u;
    u.start = Timestamp::from_seconds(start);
    u.end = Timestamp::from_seconds(start + frames / 100.0);
    u.azimuth_deg = az;
    u.frames = frames;
    u.scores = {{"a", a}, {"b", b}, {"c", c}};
    return u;
  };
  EXPECT_EQ(t.add(three(0, 300, -50, 0.5, 0.4, -1.0)).speaker_id, "a");
  EXPECT_EQ(t.add(three(4, 300, 0, 0.45, -1.0, -1.0)).speaker_id, "a")
      << "place 2 fits nobody but a, so place 1 gives a up";
  // Place 3 fits b best, but b is what place 1 can give up at the least cost: totals (p1, p2,
  // p3) = (b, a, c): 120 + 135 - 60 = 195 beat (c, a, b): -300 + 135 + 90 = -75 and every
  // other assignment of distinct speakers.
  const auto d = t.add(three(8, 300, 50, 0.1, 0.3, -0.2));
  EXPECT_EQ(d.speaker_id, "c");
}

// The child seen by the cameras (issue 16): the first utterance of a session, a short command
// whose voice alone is unknown, comes from where the child's head is seen: it is the child's. The
// same voice from 40 deg away from the seen child is not. Wherever the child sits: here at
// +35 deg, the therapist straight ahead (DREAM's direction rule assumes the opposite).
TEST(SpeakerTracks, TheChildSeenAtTheUtterancesPlaceDecides) {
  SpeakerTrackOptions o;
  o.child_speaker_id = "child";
  o.child_place_tolerance_deg = 15;
  auto seen_at = [](UtteranceEvidence u, double child_azimuth) {
    u.seen_child_offset_deg = std::abs(*u.azimuth_deg - child_azimuth);
    return u;
  };
  // Voice alone: unknown (both LLRs under the threshold), therapist a little ahead.
  const UtteranceEvidence first = utt(1.0, 90, 36.0, -0.6, -0.4);
  {
    SpeakerTracker without({}, kThreshold);  // no cue: today's answer
    EXPECT_EQ(without.add(first).speaker_id, kUnknownSpeaker);
  }
  SpeakerTracker t(o, kThreshold);
  const auto a = t.add(seen_at(first, 35.0));
  EXPECT_EQ(a.speaker_id, "child");
  EXPECT_TRUE(a.by_place);
  EXPECT_TRUE(a.inherited);
  // The therapist straight ahead, 35 deg from the seen child: her voice names her.
  const auto b = t.add(seen_at(utt(4.0, 300, 0.0, -1.2, 0.4), 35.0));
  EXPECT_EQ(b.speaker_id, "therapist");
  EXPECT_NE(a.track, b.track);
  // A voice that fits the child best but comes from 40 deg away from the seen child: the
  // track's best other speaker if it passes the threshold, else unknown.
  const auto c = t.add(seen_at(utt(8.0, 120, -40.0, 0.3, -0.1), 0.0));
  EXPECT_EQ(c.speaker_id, "therapist");
  EXPECT_TRUE(c.by_place);
  const auto d = t.add(seen_at(utt(30.0, 120, -80.0, 0.3, -0.9), 0.0));
  EXPECT_EQ(d.speaker_id, kUnknownSpeaker);
  // Between one and two tolerances: no decision by place, the voice decides.
  const auto e = t.add(seen_at(utt(40.0, 200, 60.0, 0.2, -0.5), 40.0));
  EXPECT_FALSE(e.by_place);
  EXPECT_EQ(e.speaker_id, "child");
  // Not seen (no offset): the voice decides.
  const auto f = t.add(utt(50.0, 200, -20.0, -0.9, 0.3));
  EXPECT_FALSE(f.by_place);
  EXPECT_EQ(f.speaker_id, "therapist");
  // A child id that is not enrolled gives no cue.
  SpeakerTrackOptions other = o;
  other.child_speaker_id = "kid";
  SpeakerTracker u(other, kThreshold);
  EXPECT_EQ(u.add(seen_at(first, 35.0)).speaker_id, kUnknownSpeaker);
  other.child_place_tolerance_deg = 0;
  EXPECT_FALSE(other.check());
}

}  // namespace
}  // namespace dreamsense::voice_id
