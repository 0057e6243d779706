#pragma once
// Evaluations behind `dreamsense eval calibration`:
//  - zhang: intrinsics from Zhang's published corners (Model.txt, data1-5.txt) compared with his
//    published calibration (completecalibration.txt).
//  - demo: each demo camera's extrinsics estimated from seeded synthetic correspondences with
//    our EPnP+RANSAC and compared with the true model.

#include "dreamsense/core/camera_model.hpp"
#include "dreamsense/core/status.hpp"
#include "dreamsense/geometry/intrinsics.hpp"
#include "dreamsense/geometry/pnp.hpp"
#include "dreamsense/geometry/synthetic.hpp"

#include <opencv2/core.hpp>

#include <filesystem>
#include <string>
#include <vector>

namespace dreamsense::geometry {

struct ZhangDataset {
  std::vector<cv::Point3f> model;               // 256 corners, inches, z = 0
  std::vector<std::vector<cv::Point2f>> views;  // data1..N, px, same order as model
  cv::Size image_size{640, 480};
  // Published result: alpha, gamma (skew), beta, u0, v0; k1, k2; per view R, t (inches).
  double alpha = 0, gamma = 0, beta = 0, u0 = 0, v0 = 0, k1 = 0, k2 = 0;
  std::vector<cv::Matx33d> R;
  std::vector<cv::Vec3d> t;
};
// Errors name the missing or malformed file.
Result<ZhangDataset> read_zhang_dataset(const std::filesystem::path& dir);

struct ZhangViewEval {
  std::string name;
  double rms_px = 0;            // ours
  double published_rms_px = 0;  // Zhang's published model reprojected on the same corners
  double rot_err_deg = 0;
  double trans_rel_err = 0;
};

struct ZhangEval {
  IntrinsicsResult calibration;
  double rms_px = 0;            // over all points
  double published_rms_px = 0;  // Zhang's model (with skew) on the same corners
  double fx_rel_err = 0, fy_rel_err = 0, cx_err_px = 0, cy_err_px = 0;
  double rot_err_deg_max = 0, trans_rel_err_max = 0;
  std::vector<ZhangViewEval> views;
  double seconds = 0;
};

// Options: Zhang's model has two radial terms and no tangential ones (kRadial2); rejection is
// disabled (reject_factor huge) so that every published view is compared.
IntrinsicsOptions zhang_intrinsics_options();
Result<ZhangEval> evaluate_zhang(const ZhangDataset& data,
                                 const IntrinsicsOptions& options = zhang_intrinsics_options());

struct ExtrinsicsEvalOptions {
  SyntheticPnpOptions synthetic{20, 1.0, 0.2, 0.8, 3.0, 20, 1};  // 20 pts, 1 px, 20 % outliers
  PnpOptions pnp;
};

struct CameraExtrinsicsEval {
  std::string frame;
  double rot_err_deg = 0;
  double trans_err_m = 0;    // |t - t_true|
  double trans_rel_err = 0;  // |t - t_true| / |t_true| (0 when |t_true| < 1 cm)
  double centre_err_m = 0;   // camera centre in world
  int points = 0, outliers_injected = 0, inliers = 0, true_outliers_rejected = 0;
  double rms_px = 0;
  double ms = 0;
};

// One estimate per camera; the seed of camera i is synthetic.seed + i.
Result<std::vector<CameraExtrinsicsEval>> evaluate_extrinsics_synthetic(
    const std::vector<CameraModel>& truth, const ExtrinsicsEvalOptions& options = {});

}  // namespace dreamsense::geometry
