#pragma once
// Multi-face tracking in world coordinates with stable integer ids, and F23 trackFace.
//
// WHAT THIS OBJECT REPRESENTS
// FaceTracker3d keeps one constant-velocity Kalman filter (state x, y, z, vx, vy, vz in world,
// metres and m/s) per face. Each update(stamp, observations):
//  1. predicts every track to `stamp` (position + velocity * (stamp - last_update));
//  2. matches observations to tracks by minimum total squared distance (Hungarian method), pairs
//     farther apart than options.gate_m never matched;
//  3. corrects the matched tracks' filters (predict over the elapsed time, then correct);
//  4. starts a tentative track for each unmatched observation; a track is confirmed (and gets its
//     public id, 1, 2, 3, ... in order of confirmation) after options.confirm_hits observations;
//  5. deletes confirmed tracks not observed for options.max_unseen_s and tentative ones not
//     observed for options.tentative_max_unseen_s.
// A track that is not observed keeps its last filtered state (it is not extrapolated in place):
// FaceTrack::position_world_m / velocity_world_mps are the state at FaceTrack::last_update, and
// predict(track, dt) extrapolates from there.
//
// Limits (README.md): association is by distance only (no appearance), so two faces that meet
// and stop within the gate may exchange ids; faces crossing at walking speed keep theirs.

#include "dreamsense/core/status.hpp"
#include "dreamsense/core/timestamp.hpp"
#include "dreamsense/perception/face_tracks.hpp"

#include <opencv2/core.hpp>

#include <memory>
#include <optional>
#include <vector>

namespace dreamsense::face_tracks {

struct FaceTrackerOptions {
  // Largest distance (m) between a track's predicted position and an observation it absorbs.
  double gate_m = 0.3;
  // Observations a track needs before it is confirmed (reported, given a public id).
  int confirm_hits = 3;
  // A confirmed track not observed for this long (s) is deleted (T).
  double max_unseen_s = 1.0;
  // A tentative (unconfirmed) track not observed for this long (s) is deleted.
  double tentative_max_unseen_s = 0.2;
  // Standard deviation (m, per axis) of one observation.
  double measurement_noise_m = 0.03;
  // Standard deviation (m/s^2, per axis) of the white-noise acceleration driving the
  // constant-velocity model (how quickly a face may change speed).
  double acceleration_noise_mps2 = 0.5;
  // Standard deviation (m/s, per axis) of a new track's velocity (initialised to 0).
  double initial_velocity_std_mps = 0.5;
  Status check() const;
};

class FaceTracker3d {
 public:
  // Requires options.check() to pass (CheckFailure otherwise).
  explicit FaceTracker3d(FaceTrackerOptions options = {});
  ~FaceTracker3d();
  FaceTracker3d(FaceTracker3d&&) noexcept;
  FaceTracker3d& operator=(FaceTracker3d&&) noexcept;

  // One observation step at `stamp` with the face positions seen then (world, metres; possibly
  // none). Requires: stamp is set and not earlier than the previous update's stamp.
  // Returns, per observation, the public id of the confirmed track that absorbed it, or 0 when
  // that track is still tentative.
  std::vector<int> update(Timestamp stamp, const std::vector<cv::Vec3d>& observations_world_m);

  // Confirmed tracks, most recently updated first (then by id).
  FaceTracks tracks() const;
  // Number of tracks including tentative ones.
  size_t size() const;
  void reset();
  const FaceTrackerOptions& options() const { return options_; }

 private:
  struct Track;
  FaceTrackerOptions options_;
  std::vector<std::unique_ptr<Track>> tracks_;
  int next_id_ = 1;
  Timestamp last_stamp_ = Timestamp::unset();
};

// Position of `track` dt_s seconds after its last update (constant velocity); dt_s may be < 0.
cv::Vec3d predict(const FaceTrack& track, double dt_s);

// F23 trackFace(seed, dt): the track whose position (at its last update) is nearest to `seed_m`,
// if within max_seed_distance_m, predicted dt_s seconds after its last update; nullopt when no
// track is that close. Ties go to the lower id.
std::optional<cv::Vec3d> track_face(const FaceTracks& tracks, const cv::Vec3d& seed_m, double dt_s,
                                    double max_seed_distance_m);

}  // namespace dreamsense::face_tracks
