#pragma once
// Face detection analyser: faces in every camera (keys::kFaceDetections) and the selected camera
// (keys::kSelectedCamera). Method and numbers: modalities/face_detection/README.md.
//
// Per tick: every listed camera that has a frame in the MultiFrame is searched (one FaceTracker
// each; optionally in parallel over cameras; results do not depend on the thread count). A frame
// already searched in an earlier tick (same sequence) is not searched again: its result is reused.
// Between cascade searches, a tracked face is placed from the landmarks face_landmarks fitted to it
// in that camera's previous frame (keys::kFaceLandmarks / kFaceLandmarkViews of the last tick;
// FaceTrackerOptions::cascade_interval).
// Writes, stamped with the tick:
//  - no camera frame at all: nothing;
//  - frames but no face in any: absent entries for both keys;
//  - otherwise kFaceDetections (confidence = best score) listing every camera with a frame
//    (empty list = searched, no face), and kSelectedCamera (confidence = the chosen face's score).

#include "dreamsense/core/analyzer.hpp"
#include "dreamsense/core/camera_model.hpp"
#include "dreamsense/face_detection/camera_selection.hpp"
#include "dreamsense/face_detection/face_detector.hpp"
#include "dreamsense/face_detection/face_tracker.hpp"

#include <map>
#include <memory>
#include <vector>

namespace dreamsense::face_detection {

struct FaceDetectionAnalyzerOptions {
  // Colour streams searched (optional inputs: a camera the source lacks is skipped).
  std::vector<SensorId> cameras{"camera_left", "camera_middle", "camera_right"};
  FaceDetectorOptions detector;
  // full_search_phase is set per camera by the analyser (cameras spread over the interval).
  FaceTrackerOptions tracker;
  CameraSelectorOptions selection;
  // Calibrated cameras: camera selection then rates faces by the head yaw relative to each camera
  // (D4.2), from the last head pose (keys::kHeadPose of an earlier tick, at most
  // head_pose_max_age old); without models or a recent pose, by the frontalness proxy. A face
  // rated by the yaw skips the proxy (the costly part of tracking), and its DetectedFace::
  // frontalness is frontalness_from_yaw(yaw) instead.
  std::map<SensorId, CameraModel> camera_models;
  Duration head_pose_max_age = Duration::from_ms(200);
  // Extrapolate each camera's head yaw from the last two poses to the current tick (linear, at
  // most max_yaw_prediction_deg): the pose is a frame old when the cameras are rated.
  bool predict_head_yaw = true;
  double max_yaw_prediction_deg = 10;
  // true: one task per camera (cv::parallel_for_). false: the cameras one after the other, each
  // search spread over the cores by OpenCV's own parallel detectMultiScale; faster in wall time
  // (-7 % for the whole pipeline, same CPU), because a camera's full search (~30 ms) left the
  // other core idle once the other cameras' ROI searches (~2 ms) were done. Same output.
  bool parallel = false;
  Status check() const;
};

// Loads the cascades once per camera; errors name the missing file and the Debian package.
Result<std::unique_ptr<Analyzer>> make_face_detection_analyzer(
    const FaceDetectionAnalyzerOptions& options = {});

}  // namespace dreamsense::face_detection
