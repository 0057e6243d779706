#include "dreamsense/voice_id/speaker_tracks.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>

namespace dreamsense::voice_id {

Status SpeakerTrackOptions::check() const {
  std::string bad;
  if (!(angle_tolerance_deg > 0 && angle_tolerance_deg < 180))
    bad += " angle_tolerance_deg must be in (0, 180);";
  if (!(memory_s > 0 && std::isfinite(memory_s))) bad += " memory_s must be > 0;";
  if (!(max_track_frames >= 1 && std::isfinite(max_track_frames)))
    bad += " max_track_frames must be >= 1;";
  if (!(max_exclusive_speakers >= 1 && max_exclusive_speakers <= 20))
    bad += " max_exclusive_speakers must be in [1, 20];";
  if (!(child_place_tolerance_deg > 0 && child_place_tolerance_deg < 90))
    bad += " child_place_tolerance_deg must be in (0, 90);";
  if (!bad.empty()) return make_error(ErrorCode::kInvalidArgument, "SpeakerTrackOptions:{}", bad);
  return ok_status();
}

double azimuth_difference_deg(double a_deg, double b_deg) {
  const double d = std::fmod(std::abs(a_deg - b_deg), 360.0);
  return d > 180 ? 360 - d : d;
}

SpeakerTracker::SpeakerTracker(const SpeakerTrackOptions& options, double threshold)
    : options_(options), threshold_(threshold) {
  const Status s = options_.check();
  if (!s) throw CheckFailure(s.error().message);
  DS_CHECK(std::isfinite(threshold));
}

bool SpeakerTracker::live(const VoiceTrack& t, Timestamp now) const {
  return (now - t.last).seconds() <= options_.memory_s;
}

bool SpeakerTracker::known(const VoiceTrack& t) const {
  if (t.last_known) return true;
  for (const auto& [id, e] : t.evidence)
    if (e / t.frames >= threshold_) return true;
  return false;
}

TrackDecision SpeakerTracker::add(const UtteranceEvidence& u) {
  DS_CHECK_GT(u.frames, 0);
  DS_CHECK(!u.scores.empty());
  // 1. The track: the nearest live one within the tolerance, else a new one.
  size_t which = tracks_.size();
  if (u.azimuth_deg) {
    double nearest = options_.angle_tolerance_deg;
    for (size_t k = 0; k < tracks_.size(); ++k) {
      const VoiceTrack& t = tracks_[k];
      if (!t.has_direction || !live(t, u.start)) continue;
      const double d = azimuth_difference_deg(t.azimuth_deg, *u.azimuth_deg);
      if (d <= nearest) nearest = d, which = k;
    }
  }
  if (which == tracks_.size()) {
    tracks_.emplace_back();
    tracks_.back().has_direction = u.azimuth_deg.has_value();
  }
  // 2. Evidence, the direction (the last utterance's: the track follows a moving talker), the
  // cap.
  VoiceTrack& t = tracks_[which];
  const double frames = u.frames;
  if (u.azimuth_deg) t.azimuth_deg = *u.azimuth_deg;
  for (const SpeakerScore& s : u.scores) t.evidence[s.id] += frames * s.llr;
  t.frames += frames;
  t.last = u.end;
  ++t.utterances;
  if (t.frames > options_.max_track_frames) {
    const double keep = options_.max_track_frames / t.frames;
    for (auto& [id, e] : t.evidence) e *= keep;
    t.frames = options_.max_track_frames;
  }

  TrackDecision d;
  d.track = static_cast<int>(which);
  d.track_utterances = t.utterances;
  d.track_frames = t.frames;
  d.azimuth_deg = t.has_direction ? t.azimuth_deg : std::numeric_limits<double>::quiet_NaN();
  for (const auto& [id, e] : t.evidence) d.scores.push_back({id, e / t.frames});
  std::stable_sort(d.scores.begin(), d.scores.end(),
                   [](const SpeakerScore& a, const SpeakerScore& b) { return a.llr > b.llr; });
  d.best_id = d.scores.front().id;
  const auto own =
      std::max_element(u.scores.begin(), u.scores.end(),
                       [](const SpeakerScore& a, const SpeakerScore& b) { return a.llr < b.llr; });
  const bool own_known = own->llr >= threshold_;
  t.last_known = own_known;
  // The child seen at the utterance's place decides, before the voice's open-set test.
  const std::string& child = options_.child_speaker_id;
  const bool child_enrolled = !child.empty() && t.evidence.count(child) > 0;
  const std::optional<double> offset = child_enrolled ? u.seen_child_offset_deg : std::nullopt;
  if (offset && *offset <= options_.child_place_tolerance_deg) {
    d.speaker_id = child;
    d.llr = t.evidence[child] / t.frames;
    d.inherited = !own_known || own->id != child;
    d.by_place = true;
    return d;
  }
  const bool away_from_child = offset && *offset > 2 * options_.child_place_tolerance_deg;
  // 3. Open set: the utterance's own voice or its track's evidence fits an enrolled speaker.
  if (!known(t)) {
    d.speaker_id = kUnknownSpeaker;
    d.llr = d.scores.front().llr;
    d.inherited = own_known;
    return d;
  }
  // 4. Names: jointly over the live tracks that pass, or the track's best.
  std::vector<size_t> passing;
  for (size_t k = 0; k < tracks_.size(); ++k) {
    const VoiceTrack& o = tracks_[k];
    if (k != which && (!live(o, u.start) || !o.has_direction || !t.has_direction)) continue;
    if (known(o)) passing.push_back(k);
  }
  d.speaker_id = options_.exclusive ? assign(passing, which) : d.best_id;
  if (away_from_child && d.speaker_id == child) {
    // Not where the child is seen: the track's best other speaker, if its evidence is enough.
    const auto other = std::find_if(d.scores.begin(), d.scores.end(),
                                    [&](const SpeakerScore& sc) { return sc.id != child; });
    d.by_place = true;
    if (other == d.scores.end() || other->llr < threshold_) {
      d.speaker_id = kUnknownSpeaker;
      d.llr = d.scores.front().llr;
      d.inherited = own_known;
      return d;
    }
    d.speaker_id = other->id;
  }
  d.llr = t.evidence[d.speaker_id] / t.frames;
  d.inherited = !own_known || d.speaker_id != own->id;
  return d;
}

std::string SpeakerTracker::assign(const std::vector<size_t>& passing, size_t which) const {
  const VoiceTrack& mine = tracks_[which];
  // The speakers (every utterance scores all of them, so every track holds the same ids).
  std::vector<std::string> ids;
  for (const auto& [id, e] : mine.evidence) ids.push_back(id);
  auto best_of = [&](const VoiceTrack& t) {
    std::string id;
    double best = -std::numeric_limits<double>::infinity();
    for (const auto& [sid, e] : t.evidence)
      if (e > best) best = e, id = sid;
    return std::pair{id, best};
  };
  const size_t K = ids.size(), N = passing.size();
  if (N <= 1 || K > static_cast<size_t>(options_.max_exclusive_speakers))
    return best_of(mine).first;
  // Dynamic programme over the passing tracks with the set of speakers already given out:
  // value[mask] = largest total evidence; a track either gets a speaker not in mask or, left
  // without one, its own best. choice[i][mask] remembers the move (K = unmatched).
  const size_t states = size_t{1} << K;
  const double kNone = -std::numeric_limits<double>::infinity();
  std::vector<double> value(states, kNone), next(states);
  std::vector<std::vector<int>> choice(N, std::vector<int>(states, -1));
  std::vector<std::vector<size_t>> from(N, std::vector<size_t>(states, 0));
  value[0] = 0;
  for (size_t i = 0; i < N; ++i) {
    const VoiceTrack& t = tracks_[passing[i]];
    const double own_best = best_of(t).second;
    std::fill(next.begin(), next.end(), kNone);
    for (size_t mask = 0; mask < states; ++mask) {
      if (value[mask] == kNone) continue;
      auto relax = [&](size_t to, double v, int c) {
        if (v > next[to]) next[to] = v, choice[i][to] = c, from[i][to] = mask;
      };
      relax(mask, value[mask] + own_best, static_cast<int>(K));
      for (size_t s = 0; s < K; ++s) {
        if (mask & (size_t{1} << s)) continue;
        const auto e = t.evidence.find(ids[s]);
        relax(mask | (size_t{1} << s), value[mask] + (e == t.evidence.end() ? kNone : e->second),
              static_cast<int>(s));
      }
    }
    value.swap(next);
  }
  // As many distinct speakers as possible, then the most evidence.
  const int want = static_cast<int>(std::min(N, K));
  size_t end = states;
  for (size_t mask = 0; mask < states; ++mask)
    if (std::popcount(mask) == want && value[mask] != kNone &&
        (end == states || value[mask] > value[end]))
      end = mask;
  if (end == states) return best_of(mine).first;
  for (size_t i = N; i-- > 0;) {
    const int c = choice[i][end];
    if (passing[i] == which) return c == static_cast<int>(K) ? best_of(mine).first : ids[c];
    end = from[i][end];
  }
  return best_of(mine).first;  // not reached: `which` is among the passing tracks
}

}  // namespace dreamsense::voice_id
