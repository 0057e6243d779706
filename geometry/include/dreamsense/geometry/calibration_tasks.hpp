#pragma once
// The work behind `dreamsense calibrate intrinsics|extrinsics|desk` (docs/calibration.md), so the
// verbs only parse flags, call these and print: reading the inputs (images, correspondence CSV,
// front camera and depth image), estimating, comparing methods, and writing the calibration
// files (OpenCV YAML with the provenance fields).

#include "dreamsense/core/camera_model.hpp"
#include "dreamsense/core/status.hpp"
#include "dreamsense/geometry/intrinsics.hpp"
#include "dreamsense/geometry/plane.hpp"
#include "dreamsense/geometry/pnp.hpp"

#include <opencv2/core.hpp>

#include <filesystem>
#include <string>
#include <vector>

namespace dreamsense::geometry {

// "9x6" -> (9, 6) (board corners, image sizes). `what` names the flag in the error.
Result<cv::Size> parse_board_size(const std::string& text, const char* what);
// Length with an optional unit: "0.03", "0.03m", "30mm", "3cm" -> metres (> 0).
Result<double> parse_length(const std::string& text, const char* what);
// "m" -> 1, "mm" -> 0.001.
Result<double> parse_unit_scale(const std::string& unit);

// The intrinsics file: the camera plus rms_px, distortion model, flags, board, square size and
// one record per view (file, board_found, used, rms_px).
Status write_intrinsics_yaml(const std::filesystem::path& path, const IntrinsicsResult& result,
                             const IntrinsicsOptions& options);

struct ExtrinsicsRequest {
  std::filesystem::path intrinsics;    // calibration YAML of the camera (K, distortion)
  std::filesystem::path points;        // CSV u,v,x,y,z or u,v,u_front,v_front
  std::filesystem::path front, depth;  // for 4-column CSVs: front colour YAML, depth image
  double unit_to_m = 1.0;              // unit of x,y,z in the CSV
  PnpOptions pnp;
  bool compare = false;  // also run the other methods (reported, never used)
  std::string frame;     // frame name to store (empty: the intrinsics file's)
};

struct ComparedPose {
  PnpMethod method;
  PnpResult pose;
  double rotation_diff_deg = 0;  // to the chosen method's pose
  double centre_diff_m = 0;
};

struct ExtrinsicsCalibration {
  CameraModel camera;  // intrinsics + camera_from_world (R, t) + frame
  PnpResult pose;
  int correspondences = 0;
  bool lifted = false;  // built from 2-D/2-D pairs through the depth image
  std::vector<ComparedPose> compared;
};

// Errors name the file (CSV: file and line).
Result<ExtrinsicsCalibration> calibrate_extrinsics(const ExtrinsicsRequest& request);
Status write_extrinsics_yaml(const std::filesystem::path& path, const ExtrinsicsCalibration& c,
                             const ExtrinsicsRequest& request);

struct DeskRequest {
  std::filesystem::path points;        // CSV x,y,z (world) or u_front,v_front
  std::filesystem::path front, depth;  // for 2-column CSVs
  double unit_to_m = 1.0;
};

struct DeskCalibration {
  TableFrame table;
  std::vector<cv::Vec3d> points;  // world, metres
  double max_point_plane_distance_m = 0;
};

Result<DeskCalibration> calibrate_desk(const DeskRequest& request);

}  // namespace dreamsense::geometry
