#pragma once
// `eval calibration` (cli.md task "calibration"): the reports of the two protocols, built from
// the geometry library's calibration evaluations (geometry/calibration_eval.hpp).
//  - zhang DIR: intrinsics from Zhang's published corners vs his published calibration;
//  - demo [SESSION]: extrinsics of the demo cameras (built-in, or a session's calib/*.yaml)
//    from seeded synthetic correspondences vs the true camera_from_world.

#include "dreamsense/core/camera_model.hpp"
#include "dreamsense/core/status.hpp"
#include "dreamsense/eval/report.hpp"

#include <cstdint>
#include <filesystem>
#include <vector>

namespace dreamsense::eval {

Result<EvalReport> run_zhang_calibration_eval(const std::filesystem::path& dir);

struct DemoExtrinsicsEvalOptions {
  std::filesystem::path session;  // empty: the built-in demo cameras (sim::make_demo_cameras)
  int points = 20;                // correspondences per camera, >= 6
  double noise_px = 1.0;          // pixel noise sigma, >= 0
  double outliers = 0.2;          // outlier fraction, [0, 0.5]
  uint64_t seed = 1;
  Status check() const;
};
Result<EvalReport> run_demo_extrinsics_eval(const DemoExtrinsicsEvalOptions& options);

// The cameras of a session: calib/*.yaml except mic_array.yaml, sorted by file name; a file
// without a frame name gets its stem.
Result<std::vector<CameraModel>> session_cameras(const std::filesystem::path& session);

}  // namespace dreamsense::eval
