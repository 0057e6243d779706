#pragma once
// Eye-centre analyser: keys::kFaceLandmarks + the landmarks' camera frame -> keys::kEyeCenters.
//
// Per tick, reads kFaceLandmarks (written earlier in the same tick by face_landmarks):
//  - no landmarks entry stamped with this tick: writes nothing;
//  - absent landmarks, or no frame of the landmarks' camera in this MultiFrame: absent
//    kEyeCenters;
//  - otherwise kEyeCenters with both eyes (each found or not: a closed or featureless eye is
//    found = false), confidence = landmarks' confidence * mean of the two eyes' confidences.
// A landmarks camera that is not a colour stream, a frame whose size differs from the landmarks'
// image_size, or landmarks without 68 points are errors.
// With calibrated cameras it also reads the last tick's head pose (keys::kHeadPose, feedback):
// the head's depth in the landmarks' camera gives the iris's size in pixels
// (EyeCenterLocatorOptions::iris_size); without a recent pose the width-relative prior applies.

#include "dreamsense/core/analyzer.hpp"
#include "dreamsense/core/camera_model.hpp"
#include "dreamsense/eye_centers/eye_center_locator.hpp"

#include <map>
#include <memory>
#include <vector>

namespace dreamsense::eye_centers {

struct EyeCenterAnalyzerOptions {
  // Colour streams the landmarks' camera may be (optional inputs of the contract).
  std::vector<SensorId> cameras{"camera_left", "camera_middle", "camera_right"};
  EyeCenterLocatorOptions locator;  // method (default: improved integro-differential)
  // Calibrated cameras: the iris is searched at its anatomical size at the head's depth (last
  // tick's head pose, at most head_pose_max_age old). Empty, or iris_size_from_depth false: the
  // width-relative prior alone (the baseline).
  std::map<SensorId, CameraModel> camera_models;
  bool iris_size_from_depth = true;
  Duration head_pose_max_age = Duration::from_ms(200);
  Status check() const;
};

Result<std::unique_ptr<Analyzer>> make_eye_center_analyzer(
    const EyeCenterAnalyzerOptions& options = {});

}  // namespace dreamsense::eye_centers
