#pragma once
// Correspondence files for `calibrate extrinsics` and `calibrate desk` (docs/calibration.md).
//
// CSV, comma separated, '#' starts a comment, an optional header line (any non-numeric first
// line). Column layouts, detected from the column count (every row must have the same count):
//   5 columns  u,v,x,y,z            pixel in the camera <-> 3-D world point (unit: --unit)
//   4 columns  u,v,u_front,v_front  pixel in the camera <-> pixel in the front RGB-D colour
//                                   image, lifted to 3-D through the registered depth image
//   3 columns  x,y,z                3-D points only (calibrate desk)
//   2 columns  u_front,v_front      front pixels only, lifted through depth (calibrate desk)

#include "dreamsense/core/camera_model.hpp"
#include "dreamsense/core/status.hpp"

#include <opencv2/core.hpp>

#include <filesystem>
#include <vector>

namespace dreamsense::geometry {

struct CsvTable {
  int columns = 0;
  std::vector<std::vector<double>> rows;
  std::vector<int> lines;  // 1-based line number of each row (for messages)
};

// Reads a numeric CSV; every row must have one of `allowed_columns` and the same count.
Result<CsvTable> read_numeric_csv(const std::filesystem::path& path,
                                  const std::vector<int>& allowed_columns);

// Depth image registered to the front colour image: 16-bit (millimetres, 0 = no reading) or
// 32-bit float (metres, 0 or NaN = no reading). Read with IMREAD_ANYDEPTH.
Result<cv::Mat> read_depth_image(const std::filesystem::path& path);

// 3-D world point (m) of a front colour pixel: depth at the nearest pixel along the pixel's ray
// (depth = z in the front camera), then front.to_world. Errors: pixel outside the image, no depth
// reading (0 / NaN), depth image size different from the front model's image size.
Result<cv::Vec3d> lift_front_pixel(const cv::Mat& depth, const CameraModel& front,
                                   const cv::Point2d& pixel);

struct Correspondences {
  std::vector<cv::Point2d> pixels;  // in the camera being calibrated
  std::vector<cv::Point3d> world;   // metres
  bool lifted = false;              // true when built from 2-D/2-D pairs through depth
};

// Builds 2-D/3-D pairs from a 5- or 4-column table. `unit_to_m` scales x,y,z (1 for metres,
// 0.001 for millimetres). The 4-column layout needs `depth` and `front`; a pixel without depth is
// an error naming the CSV line.
Result<Correspondences> make_correspondences(const CsvTable& table, double unit_to_m,
                                             const cv::Mat* depth, const CameraModel* front);

}  // namespace dreamsense::geometry
