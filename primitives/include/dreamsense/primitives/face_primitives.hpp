#pragma once
// getFaces (F7) from the face detector's per-camera boxes (keys::kFaceDetections,
// keys::kSelectedCamera).
//
// Until landmarks and head pose exist, a face's 3-D position is estimated monocularly from the
// box size: distance = fx * face_width_m / box_width_px along the ray through the box centre,
// moved into world with the camera's extrinsics. Faces seen by several cameras are one face when
// their estimates agree within same_face_distance_m; the position is the score-weighted mean.

#include "dreamsense/core/camera_model.hpp"
#include "dreamsense/core/perception.hpp"

#include <map>
#include <optional>
#include <vector>

namespace dreamsense::primitives {

struct FaceGeometryOptions {
  // Physical width that a frontal-cascade box spans. 0.15 m fits an adult face (and the demo's
  // portrait); children's faces are smaller (~0.12-0.13 m): set it per study.
  double face_width_m = 0.15;
  double same_face_distance_m = 0.3;
  Status check() const;
};

// World position of a face from its box in one camera; nullopt for an empty box.
std::optional<cv::Vec3d> face_position_from_box(const CameraModel& camera, const cv::Rect2d& box,
                                                double face_width_m);

struct FaceObservation {
  cv::Vec3d position_m;
  float score = 0.f;                     // best detection score among its views
  SensorId camera;                       // camera of the best view
  std::map<SensorId, cv::Rect2d> boxes;  // one box per camera that sees it
};

// Faces across cameras, best first (the selected camera's face first when there is one).
std::vector<FaceObservation> associate_faces(const FaceDetections& detections,
                                             const SelectedCamera* selected,
                                             const std::map<SensorId, CameraModel>& cameras,
                                             const FaceGeometryOptions& options);

}  // namespace dreamsense::primitives
