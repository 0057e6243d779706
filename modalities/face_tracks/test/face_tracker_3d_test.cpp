// face_tracks: the assignment, the 3-D Kalman tracker (ids, velocity, crossing, deletion) and
// F23 track_face.

#include "dreamsense/face_tracks/face_tracker_3d.hpp"

#include "dreamsense/face_tracks/assignment.hpp"
#include "dreamsense/perception/face_tracks.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>

namespace dreamsense::face_tracks {
namespace {

constexpr double kRateHz = 25;

Timestamp tick(int i) { return Timestamp::from_seconds(1.0 + i / kRateHz); }

cv::Vec3d noisy(const cv::Vec3d& p, std::mt19937& rng, double sigma) {
  std::normal_distribution<double> n(0, sigma);
  return p + cv::Vec3d(n(rng), n(rng), n(rng));
}

TEST(MinCostAssignment, MatchesBruteForceAndRespectsTheGate) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0, 1);
  for (int trial = 0; trial < 200; ++trial) {
    const size_t rows = 1 + trial % 4, cols = 1 + (trial / 4) % 4;
    std::vector<std::vector<double>> cost(rows, std::vector<double>(cols));
    for (auto& r : cost)
      for (double& c : r) c = u(rng);
    const double gate = 0.6;
    const std::vector<int> m = min_cost_assignment(cost, gate);
    // Brute force over permutations of the larger side: most gated pairs, then least cost.
    int best_n = -1;
    double best_cost = 0;
    std::vector<size_t> perm(std::max(rows, cols));
    std::iota(perm.begin(), perm.end(), 0);
    do {
      int n = 0;
      double total = 0;
      for (size_t r = 0; r < rows; ++r)
        if (perm[r] < cols && cost[r][perm[r]] <= gate) {
          ++n;
          total += cost[r][perm[r]];
        }
      if (n > best_n || (n == best_n && total < best_cost - 1e-12)) {
        best_n = n;
        best_cost = total;
      }
    } while (std::next_permutation(perm.begin(), perm.end()));
    int n = 0;
    double total = 0;
    std::vector<bool> col_used(cols, false);
    for (size_t r = 0; r < rows; ++r) {
      if (m[r] < 0) continue;
      const auto c = static_cast<size_t>(m[r]);
      ASSERT_LT(c, cols);
      EXPECT_FALSE(col_used[c]) << "column used twice";
      col_used[c] = true;
      EXPECT_LE(cost[r][c], gate);
      ++n;
      total += cost[r][c];
    }
    EXPECT_EQ(n, best_n) << "trial " << trial;
    EXPECT_NEAR(total, best_cost, 1e-9) << "trial " << trial;
  }
  EXPECT_TRUE(min_cost_assignment({}, 1).empty());
  EXPECT_EQ(min_cost_assignment({{2.0}}, 1), std::vector<int>{-1});
}

TEST(FaceTrackerOptions, CheckNamesEveryBadField) {
  EXPECT_TRUE(FaceTrackerOptions{}.check());
  FaceTrackerOptions o;
  o.gate_m = 0;
  o.confirm_hits = 0;
  auto s = o.check();
  ASSERT_FALSE(s);
  EXPECT_NE(s.error().message.find("gate_m"), std::string::npos);
  EXPECT_NE(s.error().message.find("confirm_hits"), std::string::npos);
}

TEST(FaceTracker3d, IdStableOverANoisyStraightWalk) {
  // A face walks 2 m across the room at 0.36 m/s for 8 s, observed at 25 Hz with 2 cm noise.
  const cv::Vec3d start(-1.0, -0.1, 1.6), v(0.3, 0.0, -0.2);
  for (unsigned seed = 1; seed <= 10; ++seed) {
    std::mt19937 rng(seed);
    FaceTracker3d tracker;
    std::vector<int> ids;
    for (int i = 0; i < 200; ++i) {
      const auto r = tracker.update(tick(i), {noisy(start + v * (i / kRateHz), rng, 0.02)});
      ASSERT_EQ(r.size(), 1u);
      ids.push_back(r[0]);
    }
    const int confirm = tracker.options().confirm_hits;
    for (int i = 0; i < confirm - 1; ++i) EXPECT_EQ(ids[i], 0) << "tentative before confirmation";
    for (size_t i = static_cast<size_t>(confirm - 1); i < ids.size(); ++i)
      ASSERT_EQ(ids[i], 1) << "seed " << seed << " tick " << i;
    const FaceTracks t = tracker.tracks();
    ASSERT_EQ(t.tracks.size(), 1u);
    EXPECT_EQ(t.tracks[0].hits, 200);
    EXPECT_LT(cv::norm(t.tracks[0].position_world_m - (start + v * (199 / kRateHz))), 0.03);
  }
}

TEST(FaceTracker3d, VelocityWithinTenPercentAfterOneSecond) {
  // Walking speed 0.5 m/s, 1 cm observation noise (head pose PnP translation), 25 Hz.
  const cv::Vec3d start(0.5, 0.0, 1.2), v(-0.4, 0.05, 0.3);
  std::vector<double> rel;
  for (unsigned seed = 1; seed <= 50; ++seed) {
    std::mt19937 rng(seed);
    FaceTracker3d tracker;
    for (int i = 0; i <= 25; ++i)
      tracker.update(tick(i), {noisy(start + v * (i / kRateHz), rng, 0.01)});
    const FaceTracks t = tracker.tracks();
    ASSERT_EQ(t.tracks.size(), 1u);
    rel.push_back(cv::norm(t.tracks[0].velocity_world_mps - v) / cv::norm(v));
  }
  std::sort(rel.begin(), rel.end());
  std::cout << "[1 s, 1 cm noise, 0.5 m/s] relative velocity error median " << rel[rel.size() / 2]
            << ", max " << rel.back() << " over " << rel.size() << " seeds\n";
  EXPECT_LT(rel.back(), 0.10);
}

TEST(FaceTracker3d, TwoFacesCrossingKeepTheirIds) {
  // Child and therapist walk past each other through the same point, 0.4 m/s each (closing speed
  // 0.8 m/s), 2 cm noise; observations are given in a shuffled order. While the two are closer
  // than the noise (a tick or two around the meeting point) the per-tick labels are a coin toss;
  // before and after, each face keeps its id (the constant-velocity prediction carries it through).
  const cv::Vec3d a0(-0.8, 0.0, 1.5), va(0.4, 0.0, 0.0);
  const cv::Vec3d b0(0.8, 0.0, 1.5), vb(-0.4, 0.0, 0.0);
  int ambiguous_swaps = 0;
  for (unsigned seed = 1; seed <= 20; ++seed) {
    std::mt19937 rng(seed);
    FaceTracker3d tracker;
    int id_a = 0, id_b = 0;
    for (int i = 0; i < 100; ++i) {  // 4 s: they meet at 2 s
      const double t = i / kRateHz;
      const cv::Vec3d a = a0 + va * t, b = b0 + vb * t;
      std::vector<cv::Vec3d> obs{noisy(a, rng, 0.02), noisy(b, rng, 0.02)};
      const bool swap = rng() % 2 == 1;
      if (swap) std::swap(obs[0], obs[1]);
      auto ids = tracker.update(tick(i), obs);
      if (swap) std::swap(ids[0], ids[1]);
      if (ids[0] == 0 || ids[1] == 0) continue;
      if (id_a == 0) {
        id_a = ids[0];
        id_b = ids[1];
        ASSERT_NE(id_a, id_b);
      }
      if (cv::norm(a - b) < 0.1) {
        ambiguous_swaps += ids[0] != id_a;
        continue;
      }
      ASSERT_EQ(ids[0], id_a) << "seed " << seed << " t " << t;
      ASSERT_EQ(ids[1], id_b) << "seed " << seed << " t " << t;
    }
    const FaceTracks tracks = tracker.tracks();
    ASSERT_EQ(tracks.tracks.size(), 2u);
    for (const FaceTrack& tr : tracks.tracks)  // a ends on the right moving right
      EXPECT_EQ(tr.velocity_world_mps[0] > 0, tr.id == id_a);
  }
  std::cout << "[crossing] ticks with labels swapped while < 10 cm apart: " << ambiguous_swaps
            << " (20 runs)\n";
}

TEST(FaceTracker3d, TrackDeletedAfterMaxUnseen) {
  FaceTrackerOptions o;
  o.max_unseen_s = 0.5;
  FaceTracker3d tracker(o);
  for (int i = 0; i < 10; ++i) tracker.update(tick(i), {cv::Vec3d(0, 0, 1.5)});
  ASSERT_EQ(tracker.tracks().tracks.size(), 1u);
  // 0.48 s without the face: still reported, with its last state (not moved).
  tracker.update(tick(9 + 12), {});
  ASSERT_EQ(tracker.tracks().tracks.size(), 1u);
  EXPECT_EQ(tracker.tracks().tracks[0].last_update, tick(9));
  // 0.52 s: deleted; a face reappearing there starts a new track with a new id.
  tracker.update(tick(9 + 13), {});
  EXPECT_TRUE(tracker.tracks().tracks.empty());
  EXPECT_EQ(tracker.size(), 0u);
  std::vector<int> ids;
  for (int i = 0; i < 3; ++i) ids = tracker.update(tick(30 + i), {cv::Vec3d(0, 0, 1.5)});
  EXPECT_EQ(ids, std::vector<int>{2});
}

TEST(FaceTracker3d, SpuriousDetectionsAreNeverConfirmed) {
  FaceTracker3d tracker;
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-2, 2);
  // One real face plus a false detection at a random place every third tick.
  for (int i = 0; i < 100; ++i) {
    std::vector<cv::Vec3d> obs{cv::Vec3d(0.2, 0, 1.4)};
    if (i % 3 == 0) obs.push_back(cv::Vec3d(u(rng), u(rng), 2 + u(rng)));
    tracker.update(tick(i), obs);
  }
  const FaceTracks t = tracker.tracks();
  ASSERT_EQ(t.tracks.size(), 1u);
  EXPECT_EQ(t.tracks[0].id, 1);
}

TEST(TrackFace, PicksTheTrackNearestTheSeedAndPredicts) {
  FaceTracks tracks;
  tracks.tracks.push_back({1, {0, 0, 1.5}, {0.2, 0, 0}, tick(10), 10});
  tracks.tracks.push_back({2, {0.5, 0, 1.5}, {0, -0.1, 0}, tick(10), 10});
  // Seed near track 2: track 2 predicted 0.5 s ahead.
  auto p = track_face(tracks, {0.45, 0.02, 1.5}, 0.5, 0.2);
  ASSERT_TRUE(p);
  EXPECT_LT(cv::norm(*p - cv::Vec3d(0.5, -0.05, 1.5)), 1e-12);
  // Seed near track 1, dt = 0: its position.
  p = track_face(tracks, {0.05, 0, 1.45}, 0.0, 0.2);
  ASSERT_TRUE(p);
  EXPECT_LT(cv::norm(*p - cv::Vec3d(0, 0, 1.5)), 1e-12);
  // Equidistant seed: the lower id.
  p = track_face(tracks, {0.25, 0, 1.5}, 1.0, 0.3);
  ASSERT_TRUE(p);
  EXPECT_LT(cv::norm(*p - cv::Vec3d(0.2, 0, 1.5)), 1e-12);
  // Nothing within reach, or no tracks: nullopt.
  EXPECT_FALSE(track_face(tracks, {2, 0, 1.5}, 0.5, 0.3));
  EXPECT_FALSE(track_face(FaceTracks{}, {0, 0, 1.5}, 0.5, 10));
}

TEST(TrackFace, PredictionFromALiveTrackerFollowsTheFace) {
  const cv::Vec3d start(-0.3, 0, 1.3), v(0.25, 0, 0.1);
  std::mt19937 rng(11);
  FaceTracker3d tracker;
  for (int i = 0; i < 50; ++i)
    tracker.update(tick(i), {noisy(start + v * (i / kRateHz), rng, 0.01)});
  const auto p = track_face(tracker.tracks(), start + v * (49 / kRateHz), 1.0, 0.3);
  ASSERT_TRUE(p);
  EXPECT_LT(cv::norm(*p - (start + v * (49 / kRateHz + 1.0))), 0.05);
}

}  // namespace
}  // namespace dreamsense::face_tracks
