#pragma once
// Camera pose from 2-D/3-D correspondences (D4.2 §5.2.1): EPnP (Lepetit, Moreno-Noguer & Fua,
// IJCV 2009) inside our own RANSAC loop (Fischler & Bolles 1981), then Levenberg-Marquardt
// refinement on the inliers. The seed's variant (EPnP on all points, repeated on random 60 %
// subsets while more than 40 % are outliers) is available for comparison.
//
// Output convention: camera_from_world, X_cam = R * X_world + t (units of the 3-D points).

#include "dreamsense/core/status.hpp"

#include <opencv2/core.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace dreamsense::geometry {

enum class PnpMethod {
  kRansacEpnp,      // ours: RANSAC over minimal EPnP samples, refit on inliers, LM
  kSeedDownsample,  // DREAM: EPnP on all, then on random subsets while outliers > 40 %
  kEpnpAll,         // plain EPnP on every point (no outlier handling), then LM
};
const char* to_string(PnpMethod method);
Result<PnpMethod> parse_pnp_method(const std::string& name);  // "ransac" | "seed" | "all"

struct PnpOptions {
  PnpMethod method = PnpMethod::kRansacEpnp;
  double inlier_threshold_px = 4.0;  // reprojection error under which a point is an inlier (> 0)
  int min_points = 6;                // fewer correspondences are an error (>= 4)
  int sample_size = 5;               // RANSAC sample for EPnP (>= 4; OpenCV also uses 5)
  int max_iterations = 1000;         // RANSAC iteration cap (>= 1)
  double confidence = 0.999;         // adaptive stop: P(at least one clean sample), (0, 1)
  bool refine_lm = true;             // Levenberg-Marquardt on the inliers (all methods)
  double seed_subsample_fraction = 0.6;    // seed variant: subset size, (0, 1]
  double seed_max_outlier_fraction = 0.4;  // seed variant: stop when outliers <= this, [0, 1)
  int seed_max_rounds = 200;               // seed variant: cap on down-sampling rounds (>= 1)
  uint64_t seed = 1;                       // RNG seed (results are deterministic)
  // true: fewer than min(sample_size, min_points) inliers is an error. false: the best pose is
  // returned anyway (what the seed did; used by the benchmark to measure its rotation error).
  bool require_consensus = true;
  Status check() const;
};

struct PnpResult {
  cv::Matx33d R = cv::Matx33d::eye();  // camera_from_world
  cv::Vec3d t{0, 0, 0};
  std::vector<bool> inliers;      // per correspondence
  std::vector<double> errors_px;  // per correspondence, reprojection error of the final pose
  int inlier_count = 0;
  double rms_px = 0;   // over the inliers
  int iterations = 0;  // RANSAC iterations or seed rounds
  cv::Vec3d centre_world() const { return -(R.t() * t); }
};

// Rejects inputs that cannot give a pose: size mismatch, fewer than `min_points`, non-finite
// values, 3-D points (nearly) collinear, or pixels (nearly) collinear (all points on a plane
// through the optical centre). Messages name the problem and the counts.
Status check_pnp_input(const std::vector<cv::Point3d>& world,
                       const std::vector<cv::Point2d>& pixels, int min_points = 6);

// Estimates camera_from_world. K: 3x3 intrinsics; distortion: OpenCV coefficients (may be empty).
// Errors: bad input (see check_pnp_input), or (require_consensus) no pose with enough inliers.
Result<PnpResult> estimate_pose(const std::vector<cv::Point3d>& world,
                                const std::vector<cv::Point2d>& pixels, const cv::Matx33d& K,
                                const cv::Mat& distortion, const PnpOptions& options = {});

// Reprojection error (px) of each correspondence for a pose; +inf for points behind the camera.
std::vector<double> reprojection_errors(const std::vector<cv::Point3d>& world,
                                        const std::vector<cv::Point2d>& pixels,
                                        const cv::Matx33d& K, const cv::Mat& distortion,
                                        const cv::Matx33d& R, const cv::Vec3d& t);

}  // namespace dreamsense::geometry
