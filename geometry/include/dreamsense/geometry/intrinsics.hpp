#pragma once
// Intrinsic calibration from chessboard views (Zhang, "A flexible new technique for camera
// calibration", TPAMI 22(11), 2000, as implemented by OpenCV calibrateCamera), with sub-pixel
// corner refinement, per-view reprojection error and rejection of bad views.

#include "dreamsense/core/camera_model.hpp"
#include "dreamsense/core/status.hpp"

#include <opencv2/core.hpp>

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace dreamsense::geometry {

enum class DistortionModel {
  kRadial2,    // k1, k2 (Zhang 2000): CALIB_ZERO_TANGENT_DIST | CALIB_FIX_K3
  kStandard5,  // k1, k2, p1, p2, k3 (OpenCV default)
};
const char* to_string(DistortionModel model);
Result<DistortionModel> parse_distortion_model(const std::string& name);  // "radial2" | "standard5"

struct IntrinsicsOptions {
  cv::Size board{9, 6};        // inner corners, columns x rows (each >= 2)
  double square_size = 0.030;  // square side (m; any unit works, it only scales R,t) (> 0)
  DistortionModel model = DistortionModel::kStandard5;
  bool fix_aspect_ratio = false;  // fx = fy (CALIB_FIX_ASPECT_RATIO with ratio 1)
  int subpixel_window = 11;       // cornerSubPix window side (odd, >= 3); 0 disables refinement
  double reject_factor = 3.0;     // a view is rejected when its RMS > factor * median RMS ...
  double reject_min_px = 1.0;     // ... and > this (px). Rejection repeats until stable.
  int min_views = 3;              // fewer usable views is an error (>= 1)
  Status check() const;
};

int calibration_flags(const IntrinsicsOptions& options);

struct ViewReport {
  std::string name;  // file name or "view N"
  bool board_found = false;
  bool used = false;  // false when rejected (or board not found)
  double rms_px = 0;  // reprojection RMS of this view (with the final model if used)
  cv::Matx33d R = cv::Matx33d::eye();  // camera_from_board (if used)
  cv::Vec3d t{0, 0, 0};                // board units (square_size unit)
};

struct IntrinsicsResult {
  CameraModel camera;  // K, distortion, image size; extrinsics identity
  double rms_px = 0;   // over all points of the used views
  std::vector<ViewReport> views;
  int views_used = 0;
  int flags = 0;  // OpenCV calibration flags used
};

// Inner corners of the board's object points (z = 0), row-major, OpenCV order.
std::vector<cv::Point3f> chessboard_object_points(cv::Size board, double square_size);

// Chessboard corners in a grey or colour image; nullopt when the board is not found.
std::optional<std::vector<cv::Point2f>> detect_chessboard(const cv::Mat& image, cv::Size board,
                                                          int subpixel_window = 11);

// Calibrates from given correspondences (one vector per view). `names` may be empty.
Result<IntrinsicsResult> calibrate_from_points(
    const std::vector<std::vector<cv::Point3f>>& object_points,
    const std::vector<std::vector<cv::Point2f>>& image_points, cv::Size image_size,
    const IntrinsicsOptions& options, const std::vector<std::string>& names = {});

// Reads the images, detects the board, calibrates. Errors: unreadable image, images of different
// sizes (names both), board found in fewer than `min_views` images (none: says so).
Result<IntrinsicsResult> calibrate_from_images(const std::vector<std::filesystem::path>& images,
                                               const IntrinsicsOptions& options);

}  // namespace dreamsense::geometry
