#pragma once
// The subject's 3-D face model from calibration recordings with a known head pose (the demo's
// truth.jsonl): `dreamsense train face`. Every `frame_step`-th frame of every camera is searched
// for the face (full frame, OpenCV cascade), fitted with dlib's 68 landmarks, and paired with the
// truth head pose at that stamp; head_pose::fit_face_shape turns the views into the model.
// Views are taken from every camera, not only the one the pipeline would select: more directions
// per landmark make its depth better determined.

#include "dreamsense/core/status.hpp"
#include "dreamsense/head_pose/face_shape_fit.hpp"

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace dreamsense::eval {

struct FaceModelFitOptions {
  int frame_step = 2;  // every n-th frame of each camera
  // Colour streams used; empty = every colour stream with a calibration file.
  std::vector<std::string> cameras{"camera_left", "camera_middle", "camera_right"};
  head_pose::FaceShapeFitOptions shape;
  Status check() const;
};

struct FaceModelFitResult {
  head_pose::FaceShapeFit fit;
  int frames_searched = 0;  // camera frames with a truth head pose
  int views = 0;            // of them, with a face and landmarks
  std::string provenance;   // sessions and counts, for the model file
};

// `progress(done, total)` (frames of the session being read) may be empty. Errors: a session
// without truth or without calibrated cameras, too few usable views (fit_face_shape's message).
Result<FaceModelFitResult> fit_subject_face_model(
    const std::vector<std::filesystem::path>& sessions, const FaceModelFitOptions& options = {},
    const std::function<void(int64_t, int64_t)>& progress = {});

}  // namespace dreamsense::eval
