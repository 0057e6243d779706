#pragma once
// 3-D face positions (world) from one tick's face detections, for the face tracker.
//
//  - The selected face (keys::kSelectedCamera) is placed at the head pose position
//    (keys::kHeadPose: the PnP translation, between the eyes) when a head pose from that camera is
//    given; without a selection, a head pose is attached to the face box of its camera that
//    holds the projection of the head position.
//  - Every other face is placed by its box size: depth z = fx * face_width_m / box width (px),
//    on the camera ray through the (undistorted) box centre, then moved to world with the
//    camera's extrinsics.
//  - Observations of different cameras closer than merge_distance_m are one face (never two
//    faces of the same camera): the merged position is the head-pose one if the group has it,
//    otherwise the score-weighted mean.

#include "dreamsense/core/camera_model.hpp"
#include "dreamsense/core/status.hpp"
#include "dreamsense/perception/face_detection.hpp"
#include "dreamsense/perception/head_pose.hpp"

#include <map>
#include <vector>

namespace dreamsense::face_tracks {

struct FaceObservationOptions {
  // Real width (m) spanned by a face detector box (adult ~0.15; a child's face ~0.13).
  double face_width_m = 0.15;
  // Observations of different cameras closer than this (m) are the same face.
  double merge_distance_m = 0.3;
  Status check() const;
};

// One camera's view of a face that contributed to an observation.
struct FaceView3d {
  SensorId camera;
  size_t face_index = 0;  // into FaceDetections::cameras[camera].faces
};

struct FaceObservation3d {
  cv::Vec3d position_world_m{0, 0, 0};
  bool from_head_pose = false;  // position is the head pose's (else from box size)
  float score = 0.f;            // best detection score among its views
  std::vector<FaceView3d> views;
};

// Observations of every face in `detections`. `selected` and `head` may be null. A camera of
// `detections` (or the head pose) without a model in `cameras` is an error (configuration).
Result<std::vector<FaceObservation3d>> face_observations(
    const FaceDetections& detections, const SelectedCamera* selected, const HeadPose* head,
    const std::map<SensorId, CameraModel>& cameras, const FaceObservationOptions& options);

// Position (world) of a face box from its size alone (see above); nullopt for an empty box.
std::optional<cv::Vec3d> position_from_box(const cv::Rect2d& box_px, const cv::Size& image_size,
                                           const CameraModel& camera, double face_width_m);

}  // namespace dreamsense::face_tracks
