#include "dreamsense/face_tracks/face_tracker_3d.hpp"

#include "dreamsense/face_tracks/assignment.hpp"
#include "dreamsense/perception/face_tracks.hpp"

#include <opencv2/video/tracking.hpp>

#include <algorithm>
#include <cmath>
#include <string>

namespace dreamsense::face_tracks {

struct FaceTracker3d::Track {
  int id = 0;  // 0 while tentative
  cv::KalmanFilter kf;
  Timestamp last_update;
  int hits = 0;

  cv::Vec3d position() const {
    const cv::Mat& s = kf.statePost;
    return {s.at<double>(0), s.at<double>(1), s.at<double>(2)};
  }
  cv::Vec3d velocity() const {
    const cv::Mat& s = kf.statePost;
    return {s.at<double>(3), s.at<double>(4), s.at<double>(5)};
  }
  cv::Vec3d predicted(Timestamp t) const {
    return position() + velocity() * (t - last_update).seconds();
  }
  FaceTrack to_face_track() const {
    return FaceTrack{id, position(), velocity(), last_update, hits};
  }
};

namespace {

// Discrete white-noise-acceleration model (Bar-Shalom): per axis x' = x + v dt,
// Q = sigma_a^2 [dt^4/4, dt^3/2; dt^3/2, dt^2].
void set_motion_model(cv::KalmanFilter& kf, double dt, double sigma_a) {
  kf.transitionMatrix = cv::Mat::eye(6, 6, CV_64F);
  kf.processNoiseCov = cv::Mat::zeros(6, 6, CV_64F);
  const double q = sigma_a * sigma_a;
  for (int i = 0; i < 3; ++i) {
    kf.transitionMatrix.at<double>(i, i + 3) = dt;
    kf.processNoiseCov.at<double>(i, i) = q * dt * dt * dt * dt / 4;
    kf.processNoiseCov.at<double>(i, i + 3) = q * dt * dt * dt / 2;
    kf.processNoiseCov.at<double>(i + 3, i) = q * dt * dt * dt / 2;
    kf.processNoiseCov.at<double>(i + 3, i + 3) = q * dt * dt;
  }
}

}  // namespace

Status FaceTrackerOptions::check() const {
  std::string bad;
  if (!(gate_m > 0)) bad += " gate_m must be > 0;";
  if (confirm_hits < 1) bad += " confirm_hits must be >= 1;";
  if (!(max_unseen_s > 0)) bad += " max_unseen_s must be > 0;";
  if (!(tentative_max_unseen_s > 0)) bad += " tentative_max_unseen_s must be > 0;";
  if (!(measurement_noise_m > 0)) bad += " measurement_noise_m must be > 0;";
  if (!(acceleration_noise_mps2 > 0)) bad += " acceleration_noise_mps2 must be > 0;";
  if (!(initial_velocity_std_mps > 0)) bad += " initial_velocity_std_mps must be > 0;";
  if (!bad.empty()) return make_error(ErrorCode::kInvalidArgument, "FaceTrackerOptions:{}", bad);
  return ok_status();
}

FaceTracker3d::FaceTracker3d(FaceTrackerOptions options) : options_(options) {
  if (auto s = options_.check(); !s) throw CheckFailure(s.error().message);
}
FaceTracker3d::~FaceTracker3d() = default;
FaceTracker3d::FaceTracker3d(FaceTracker3d&&) noexcept = default;
FaceTracker3d& FaceTracker3d::operator=(FaceTracker3d&&) noexcept = default;

std::vector<int> FaceTracker3d::update(Timestamp stamp,
                                       const std::vector<cv::Vec3d>& observations_world_m) {
  DS_CHECK(stamp.is_set());
  if (last_stamp_.is_set()) DS_CHECK_GE(stamp.ns(), last_stamp_.ns());
  last_stamp_ = stamp;

  // Delete tracks unseen for too long (before association: they may not absorb anything now).
  std::erase_if(tracks_, [&](const std::unique_ptr<Track>& t) {
    const double unseen = (stamp - t->last_update).seconds();
    return unseen > (t->id != 0 ? options_.max_unseen_s : options_.tentative_max_unseen_s);
  });

  std::vector<int> result(observations_world_m.size(), 0);
  std::vector<bool> used(observations_world_m.size(), false);
  const double max_cost = options_.gate_m * options_.gate_m;

  // Matching cascade: confirmed tracks first, then tentative ones take what is left.
  for (const bool confirmed : {true, false}) {
    std::vector<Track*> rows;
    for (auto& t : tracks_)
      if ((t->id != 0) == confirmed) rows.push_back(t.get());
    std::vector<size_t> cols;
    for (size_t i = 0; i < observations_world_m.size(); ++i)
      if (!used[i]) cols.push_back(i);
    if (rows.empty() || cols.empty()) continue;
    std::vector<std::vector<double>> cost(rows.size(), std::vector<double>(cols.size()));
    for (size_t r = 0; r < rows.size(); ++r) {
      const cv::Vec3d p = rows[r]->predicted(stamp);
      for (size_t c = 0; c < cols.size(); ++c) {
        const cv::Vec3d d = observations_world_m[cols[c]] - p;
        cost[r][c] = d.dot(d);
      }
    }
    const std::vector<int> match = min_cost_assignment(cost, max_cost);
    for (size_t r = 0; r < rows.size(); ++r) {
      if (match[r] < 0) continue;
      const size_t obs = cols[static_cast<size_t>(match[r])];
      Track& t = *rows[r];
      set_motion_model(t.kf, (stamp - t.last_update).seconds(), options_.acceleration_noise_mps2);
      t.kf.predict();
      const cv::Vec3d& z = observations_world_m[obs];
      t.kf.correct((cv::Mat_<double>(3, 1) << z[0], z[1], z[2]));
      t.last_update = stamp;
      ++t.hits;
      if (t.id == 0 && t.hits >= options_.confirm_hits) t.id = next_id_++;
      used[obs] = true;
      result[obs] = t.id;
    }
  }

  // New tentative tracks for what nobody absorbed.
  const double r2 = options_.measurement_noise_m * options_.measurement_noise_m;
  const double v2 = options_.initial_velocity_std_mps * options_.initial_velocity_std_mps;
  for (size_t i = 0; i < observations_world_m.size(); ++i) {
    if (used[i]) continue;
    auto t = std::make_unique<Track>();
    t->kf.init(6, 3, 0, CV_64F);
    t->kf.measurementMatrix = cv::Mat::eye(3, 6, CV_64F);
    t->kf.measurementNoiseCov = cv::Mat::eye(3, 3, CV_64F) * r2;
    const cv::Vec3d& z = observations_world_m[i];
    t->kf.statePost = (cv::Mat_<double>(6, 1) << z[0], z[1], z[2], 0, 0, 0);
    t->kf.errorCovPost = cv::Mat::diag((cv::Mat_<double>(6, 1) << r2, r2, r2, v2, v2, v2));
    t->last_update = stamp;
    t->hits = 1;
    if (options_.confirm_hits <= 1) t->id = next_id_++;
    result[i] = t->id;
    tracks_.push_back(std::move(t));
  }
  return result;
}

FaceTracks FaceTracker3d::tracks() const {
  FaceTracks out;
  for (const auto& t : tracks_)
    if (t->id != 0) out.tracks.push_back(t->to_face_track());
  std::sort(out.tracks.begin(), out.tracks.end(), [](const FaceTrack& a, const FaceTrack& b) {
    if (a.last_update != b.last_update) return a.last_update > b.last_update;
    return a.id < b.id;
  });
  return out;
}

size_t FaceTracker3d::size() const { return tracks_.size(); }

void FaceTracker3d::reset() {
  tracks_.clear();
  next_id_ = 1;
  last_stamp_ = Timestamp::unset();
}

cv::Vec3d predict(const FaceTrack& track, double dt_s) {
  return track.position_world_m + track.velocity_world_mps * dt_s;
}

std::optional<cv::Vec3d> track_face(const FaceTracks& tracks, const cv::Vec3d& seed_m, double dt_s,
                                    double max_seed_distance_m) {
  const FaceTrack* best = nullptr;
  double best_d = 0;
  for (const FaceTrack& t : tracks.tracks) {
    const double d = cv::norm(t.position_world_m - seed_m);
    if (d > max_seed_distance_m) continue;
    if (best == nullptr || d < best_d || (d == best_d && t.id < best->id)) {
      best = &t;
      best_d = d;
    }
  }
  if (best == nullptr) return std::nullopt;
  return predict(*best, dt_s);
}

}  // namespace dreamsense::face_tracks
