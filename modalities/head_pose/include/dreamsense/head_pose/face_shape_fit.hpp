#pragma once
// A subject's own 3-D face model (FaceModel3d) from landmarks seen with a known head pose.
//
// Why: PnP against a generic face leaves a view-dependent error when the subject's face has other
// proportions (on the demo child, 8-19 deg median with the generic model, the error changing with
// the camera: the depths of nose and brows decide how the pose reads). With the subject's own
// landmark geometry PnP has nothing left to explain but landmark noise.
//
// Method: every observation of landmark i (a pixel in a calibrated camera at a moment whose head
// pose is known) is a ray; expressed in the head frame, all rays of landmark i pass near the
// landmark's fixed head-frame position. That position is the least-squares point of the rays
// (sum over rays of (I - d d^T)(X - o) = 0, a 3x3 linear system), refitted once without the
// observations farthest from it (trimmed least squares against landmark-fit outliers). Head poses
// come from a calibration recording with known pose (the demo's truth, a motion-capture marker,
// ...). Views where the face is turned far from the camera are left out: dlib's contour points
// slide there.

#include "dreamsense/core/camera_model.hpp"
#include "dreamsense/core/status.hpp"
#include "dreamsense/head_pose/face_model.hpp"

#include <opencv2/core.hpp>

#include <filesystem>
#include <string>
#include <vector>

namespace dreamsense::head_pose {

// 68 landmarks of one face in one camera image, with the head pose at that frame.
struct LandmarkView {
  const CameraModel* camera = nullptr;  // intrinsics + extrinsics of the image
  cv::Matx33d world_from_head = cv::Matx33d::eye();
  cv::Vec3d head_position_world_m{0, 0, 0};  // head-frame origin in world
  std::vector<cv::Point2d> landmarks_px;     // 68, iBUG order; non-finite = missing
};

struct FaceShapeFitOptions {
  // Landmarks to fit (iBUG indices); default: the 51 inner points of generic_face_model().
  std::vector<int> landmark_index = generic_face_model(false).landmark_index;
  // Views whose face normal is more than this from the direction to the camera are skipped.
  double max_view_angle_deg = 40;
  // A landmark needs at least this many views, and the views' rays must span at least
  // min_ray_spread_deg (else depth along the rays is undetermined).
  int min_views = 20;
  double min_ray_spread_deg = 10;
  // Fraction of each landmark's observations dropped (largest ray distance) before the refit.
  double trim_fraction = 0.2;
  Status check() const;
};

struct FaceShapeFit {
  FaceModel3d model;                       // points in the head frame of the given poses
  std::vector<int> views_per_point;        // per model point, after trimming
  std::vector<double> rms_ray_distance_m;  // per model point, after trimming
  int views_used = 0;                      // views within max_view_angle_deg
};

// Errors: bad options, a view without camera or without 68 landmarks, a landmark without enough
// (or too similar) views.
Result<FaceShapeFit> fit_face_shape(const std::vector<LandmarkView>& views,
                                    const FaceShapeFitOptions& options = {});

// Face model file (YAML): format "dreamsense-face-model", version 1, name, provenance, and per
// point its iBUG index and head-frame position in metres. Read checks the model (check()).
Status write_face_model(const std::string& path, const FaceModel3d& model,
                        const std::string& provenance);
Result<FaceModel3d> read_face_model(const std::string& path);

// The head-model offset of a subject calibration: `model_from_head` (rotation from the subject's
// head frame to the face model's frame) as `dreamsense train gaze` writes it into gaze.yaml;
// identity when the file has none. A matrix that is not a rotation is an error naming the file.
Result<cv::Matx33d> read_model_from_head(const std::filesystem::path& gaze_yaml);

}  // namespace dreamsense::head_pose
