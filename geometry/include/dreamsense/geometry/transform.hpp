#pragma once
// Rigid transforms and the session's transform tree (D4.2 "Coordinate Transformation Module").
//
// Convention: a RigidTransform named `a_from_b` maps coordinates of a point expressed in frame b
// to frame a: X_a = R * X_b + t (metres). Composition reads right to left:
// a_from_c = a_from_b * b_from_c. A CameraModel's extrinsics are camera_from_world.

#include "dreamsense/core/camera_model.hpp"
#include "dreamsense/core/status.hpp"

#include <opencv2/core.hpp>

#include <map>
#include <string>
#include <vector>

namespace dreamsense::geometry {

struct RigidTransform {
  cv::Matx33d R = cv::Matx33d::eye();
  cv::Vec3d t{0, 0, 0};

  static RigidTransform identity() { return {}; }
  cv::Vec3d apply(const cv::Vec3d& p) const { return R * p + t; }  // points
  cv::Vec3d rotate(const cv::Vec3d& v) const { return R * v; }     // directions
  RigidTransform inverse() const { return {R.t(), -(R.t() * t)}; }
  RigidTransform operator*(const RigidTransform& rhs) const { return {R * rhs.R, R * rhs.t + t}; }
};

// camera_from_world of a camera model.
inline RigidTransform camera_from_world(const CameraModel& m) { return {m.R, m.t}; }

// Angle (degrees, in [0, 180]) of the rotation A^T * B.
double rotation_angle_deg(const cv::Matx33d& A, const cv::Matx33d& B);
// Nearest rotation (Frobenius norm, SVD with det = +1) to a 3x3 matrix.
cv::Matx33d nearest_rotation(const cv::Matx33d& M);
// max |M M^T - I| entry: 0 for a rotation.
double orthonormality_error(const cv::Matx33d& M);

// Standard frame names. Camera frames use the session's sensor ids; `world` is the root
// (by default the front depth sensor's optical frame, OpenCV axes: x right, y down, z forward).
namespace frames {
inline constexpr const char* kWorld = "world";
inline constexpr const char* kFrontColor = "front.color";
inline constexpr const char* kFrontDepth = "front.depth";
inline constexpr const char* kCameraLeft = "camera_left";
inline constexpr const char* kCameraMiddle = "camera_middle";
inline constexpr const char* kCameraRight = "camera_right";
inline constexpr const char* kTopColor = "top.color";
inline constexpr const char* kTable = "table";
inline constexpr const char* kRobotHead = "robot_head";
}  // namespace frames

// A tree of named frames. Each frame except the root stores parent_from_frame. Lookups between
// any two frames go through their common ancestors. Unknown frames are errors (kNotFound).
class TransformTree {
 public:
  explicit TransformTree(std::string root = frames::kWorld);

  const std::string& root() const { return root_; }
  bool has(const std::string& frame) const;
  std::vector<std::string> frame_names() const;  // root first, then sorted

  // Adds `child` under `parent` (which must exist). Error if `child` exists already.
  Status add(const std::string& parent, const std::string& child,
             const RigidTransform& parent_from_child);
  // Replaces the transform of an existing non-root frame (keeps its parent).
  Status update(const std::string& child, const RigidTransform& parent_from_child);

  // target_from_source.
  Result<RigidTransform> lookup(const std::string& target, const std::string& source) const;
  // root_from_frame ("global" = the root frame).
  Result<RigidTransform> global_from(const std::string& frame) const;

  // The seed's four operations (local = a named frame, global = the root).
  Result<cv::Vec3d> point_local_to_global(const std::string& local, const cv::Vec3d& p) const;
  Result<cv::Vec3d> point_global_to_local(const std::string& local, const cv::Vec3d& p) const;
  // Orientations: R_local is an orientation (e.g. head_in_local = local_from_head) expressed in
  // the local frame; returns global_from_local * R_local (and the inverse operation).
  Result<cv::Matx33d> rotation_local_to_global(const std::string& local,
                                               const cv::Matx33d& R_local) const;
  Result<cv::Matx33d> rotation_global_to_local(const std::string& local,
                                               const cv::Matx33d& R_global) const;

  // A tree whose root is `world` with every camera as a child (world_from_camera =
  // inverse(camera_from_world)). A camera whose frame is "world" or empty is an error.
  static Result<TransformTree> from_cameras(const std::vector<CameraModel>& cameras);

 private:
  struct Node {
    std::string parent;
    RigidTransform parent_from_this;
  };
  std::string root_;
  std::map<std::string, Node> nodes_;  // every frame except the root
};

}  // namespace dreamsense::geometry
