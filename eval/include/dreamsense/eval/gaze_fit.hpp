#pragma once
// Fits the gaze constants of D4.2 eq. (4) (gamma, epsilon and the pupil rest offsets, per eye)
// from analysed sessions with known gaze targets: `dreamsense train gaze`.
//
// Samples: ticks where getEyeGaze and getHeadGaze are ok. The true eye-in-head angles are the
// truth eye-gaze direction expressed in the ESTIMATED head frame (as a calibration with targets
// would have it: the target is known, the head pose is measured), so the fit also absorbs a
// constant bias of the head pose.

#include "dreamsense/core/status.hpp"
#include "dreamsense/gaze/gaze_estimator.hpp"

#include <filesystem>
#include <vector>

namespace dreamsense::eval {

struct GazeFitInput {
  std::filesystem::path session_dir;   // holds truth.jsonl
  std::filesystem::path analysis_dir;  // holds primitives.jsonl of an analysis with gaze
};

// Errors: missing files, no usable sample, analyses made with different offset planes.
Result<gaze::GazeModelFile> fit_gaze_model(const std::vector<GazeFitInput>& inputs);

}  // namespace dreamsense::eval
