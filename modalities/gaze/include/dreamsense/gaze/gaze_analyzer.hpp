#pragma once
// Gaze analyser: keys::kFaceLandmarks + keys::kEyeCenters + keys::kHeadPose -> keys::kEyeGaze
// and keys::kMutualGaze.
//
// Per tick, when all three inputs were written in this tick for the same camera frame: the gaze
// (gaze_estimator.hpp) and the mutual-gaze state. When the landmarks entry of this tick is absent
// (no face) or any input is missing, both outputs are absent and the hold state is reset. Ticks
// without a landmarks entry write nothing.

#include "dreamsense/core/analyzer.hpp"
#include "dreamsense/core/camera_model.hpp"
#include "dreamsense/gaze/fixation_yaw.hpp"
#include "dreamsense/gaze/gaze_estimator.hpp"
#include "dreamsense/gaze/gaze_filter.hpp"
#include "dreamsense/gaze/mutual_gaze.hpp"

#include <map>
#include <memory>

namespace dreamsense::gaze {

struct GazeAnalyzerOptions {
  std::map<SensorId, CameraModel> cameras;  // intrinsics + extrinsics per colour stream
  GazeEstimatorOptions estimator;
  // Smoothing of the fused (both-eyes) ray, which getEyeGaze and mutual gaze use; the per-eye
  // rays stay unfiltered.
  GazeFilterOptions filter;
  MutualGazeOptions mutual;
  // 3-D mode: the eyes' sideways bias learnt from fixations on mutual.robot_head_m
  // (fixation_yaw.hpp); EyeGaze::fixation_yaw_deg reports it.
  FixationYawOptions fixation_yaw;
  // Camera-plane mode: the camera whose plane holds the rectangle; empty = the selected camera
  // of each frame (DREAM).
  SensorId reference_camera;
  Status check() const;
};

Result<std::unique_ptr<Analyzer>> make_gaze_analyzer(const GazeAnalyzerOptions& options);

}  // namespace dreamsense::gaze
