#pragma once
// Head pose analyser: keys::kFaceLandmarks -> keys::kHeadPose.
//
// Per tick, reads kFaceLandmarks (written earlier in the same tick by face_landmarks):
//  - no landmarks entry stamped with this tick: writes nothing;
//  - absent landmarks, or the fit rejected: absent kHeadPose;
//  - otherwise kHeadPose (smoothed unless options.filter.enabled is false), confidence = the
//    landmarks' confidence * (1 - rms / (max_rms_per_interocular * inter-ocular px)).
// A landmarks camera without a CameraModel in options.cameras is an error (configuration).
// It also reads keys::kFaceLandmarkViews (the same face in the other cameras): with
// options.multi_view it fits one pose to every view that agrees; always, HeadPose::frontal_camera
// is the camera of these views the head turns least away from.

#include "dreamsense/core/analyzer.hpp"
#include "dreamsense/core/camera_model.hpp"
#include "dreamsense/head_pose/head_pose_estimator.hpp"
#include "dreamsense/head_pose/pose_filter.hpp"

#include <map>
#include <memory>

namespace dreamsense::head_pose {

struct HeadPoseAnalyzerOptions {
  std::map<SensorId, CameraModel> cameras;  // intrinsics + camera_from_world per colour stream
  HeadPoseEstimatorOptions estimator;
  PoseFilterOptions filter;
  // Subject calibration (`dreamsense train gaze`): rotation from the subject's head frame to the
  // face model's frame. A generic model's "straight ahead" differs from a given face's by a few
  // to ~15 degrees (face proportions); identity = uncalibrated.
  cv::Matx33d model_from_head = cv::Matx33d::eye();
  // Issue 15: when other calibrated cameras see the face at the same tick
  // (keys::kFaceLandmarkViews), one pose is fitted to all views at once
  // (refine_head_pose_multi_view); the single-view fit stands when no other view agrees.
  bool multi_view = true;
  Status check() const;
};

Result<std::unique_ptr<Analyzer>> make_head_pose_analyzer(const HeadPoseAnalyzerOptions& options);

}  // namespace dreamsense::head_pose
