#pragma once
// Synthetic correspondences for tests, the benchmark and `eval calibration --dataset demo`.

#include "dreamsense/core/camera_model.hpp"

#include <opencv2/core.hpp>

#include <cstdint>
#include <vector>

namespace dreamsense::geometry {

struct SyntheticPnpOptions {
  int points = 20;              // correspondences (>= 1)
  double noise_px = 1.0;        // Gaussian pixel noise sigma on inliers (>= 0)
  double outlier_fraction = 0;  // share replaced by uniformly random pixels, [0, 1)
  double min_depth_m = 0.8;     // 3-D points: random pixel, random depth in [min, max]
  double max_depth_m = 3.0;
  double min_outlier_px = 20;  // an outlier pixel is at least this far from its true projection
  uint64_t seed = 1;
};

struct SyntheticPnp {
  std::vector<cv::Point3d> world;
  std::vector<cv::Point2d> pixels;
  std::vector<bool> is_outlier;
};

// Points seen by `truth` (uniform over the image, depth uniform in [min, max]), projected with
// its full model (distortion included), then noise and outliers. Deterministic in `seed`.
SyntheticPnp make_synthetic_correspondences(const CameraModel& truth,
                                            const SyntheticPnpOptions& options);

}  // namespace dreamsense::geometry
