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

#include "dreamsense/core/analyzer.hpp"
#include "dreamsense/eye_centers/eye_center_locator.hpp"

#include <memory>
#include <vector>

namespace dreamsense::eye_centers {

struct EyeCenterAnalyzerOptions {
  // Colour streams the landmarks' camera may be (optional inputs of the contract).
  std::vector<SensorId> cameras{"camera_left", "camera_middle", "camera_right"};
  EyeCenterLocatorOptions locator;  // method (default: improved integro-differential)
  Status check() const;
};

Result<std::unique_ptr<Analyzer>> make_eye_center_analyzer(
    const EyeCenterAnalyzerOptions& options = {});

}  // namespace dreamsense::eye_centers
