#include "dreamsense/gaze/mutual_gaze.hpp"

#include "dreamsense/perception/gaze.hpp"

#include <algorithm>
#include <cmath>

namespace dreamsense::gaze {

Status MutualGazeOptions::check() const {
  std::string bad;
  if (!(radius_m > 0)) bad += " radius_m must be > 0;";
  if (!(rect_x_min_m < rect_x_max_m && rect_y_min_m < rect_y_max_m))
    bad += " the camera-plane rectangle is empty;";
  if (!(onset_s >= 0 && release_s >= 0)) bad += " onset_s and release_s must be >= 0;";
  if (!std::isfinite(robot_head_m[0] + robot_head_m[1] + robot_head_m[2]))
    bad += " robot_head_m must be finite;";
  if (!bad.empty()) return make_error(ErrorCode::kInvalidArgument, "MutualGazeOptions:" + bad);
  return ok_status();
}

bool gaze_hits_robot_3d(const GazeRay& ray, const MutualGazeOptions& options, double& miss_m) {
  const cv::Vec3d to_robot = options.robot_head_m - ray.origin_world_m;
  const double along = to_robot.dot(ray.direction_world);
  // Behind the eyes the ray does not exist: the distance is to its origin.
  const double distance =
      along <= 0 ? cv::norm(to_robot) : cv::norm(to_robot - along * ray.direction_world);
  miss_m = std::max(0.0, distance - options.radius_m);
  return distance <= options.radius_m;
}

bool gaze_hits_camera_rect(const GazeRay& ray, const CameraModel& reference_camera,
                           const MutualGazeOptions& options, double& miss_m) {
  const cv::Vec3d o = reference_camera.to_camera(ray.origin_world_m);
  const cv::Vec3d d = reference_camera.R * ray.direction_world;
  miss_m = std::numeric_limits<double>::infinity();
  if (!(std::abs(d[2]) > 1e-9)) return false;  // parallel to the plane
  const double t = -o[2] / d[2];
  if (!(t > 0)) return false;  // the plane is behind the eyes
  const double x = o[0] + t * d[0], y = o[1] + t * d[1];
  const double dx = std::max({options.rect_x_min_m - x, 0.0, x - options.rect_x_max_m});
  const double dy = std::max({options.rect_y_min_m - y, 0.0, y - options.rect_y_max_m});
  miss_m = std::hypot(dx, dy);
  return miss_m == 0.0;
}

MutualGaze MutualGazeTracker::update(Timestamp stamp, bool raw, double miss_m) {
  if (!state_since_.is_set()) state_since_ = stamp;
  if (raw == state_) {
    pending_since_ = Timestamp::unset();
  } else {
    if (!pending_since_.is_set()) pending_since_ = stamp;
    const double needed = state_ ? options_.release_s : options_.onset_s;
    if ((stamp - pending_since_).seconds() >= needed - 1e-9) {
      state_ = raw;
      // The change began when the test first flipped, not when the hold rule accepted it.
      state_since_ = pending_since_;
      pending_since_ = Timestamp::unset();
    }
  }
  MutualGaze m;
  m.mutual = state_;
  m.raw = raw;
  m.held_s = state_ ? (stamp - state_since_).seconds() : 0.0;
  m.miss_distance_m = miss_m;
  m.mode = options_.mode == MutualGazeMode::k3d ? "3d" : "camera_plane";
  return m;
}

void MutualGazeTracker::reset() {
  state_ = false;
  state_since_ = Timestamp::unset();
  pending_since_ = Timestamp::unset();
}

}  // namespace dreamsense::gaze
