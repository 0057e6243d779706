#pragma once
// Where the table is and where things on it are, in metres (world frame of the calibration).
//
//  - The table plane comes from, in this order: a desk calibration (`calibrate desk`, D4.2 V19:
//    geometry::TableFrame), a depth stream looking down on the table (top sensor), or a depth
//    stream looking across it (front sensor): fit_table_plane_from_depth (RANSAC over
//    back-projected depth pixels with a prior on the normal, then least squares on the inliers).
//  - A pixel of a calibrated camera is lifted to 3-D by intersecting its ray with the table plane
//    raised by a height (the top face of a toy of known size).
//  - getObjectTableDistance, getGripLocation and trackObject's prediction are plain functions of
//    a tracked object (object_geometry below).

#include "dreamsense/core/camera_model.hpp"
#include "dreamsense/core/status.hpp"
#include "dreamsense/geometry/plane.hpp"

#include <opencv2/core.hpp>

#include <optional>
#include <vector>

namespace dreamsense::objects {

struct TablePlaneFitOptions {
  int pixel_step = 4;  // use every n-th pixel in x and y
  double min_depth_m = 0.3, max_depth_m = 3.0;
  double inlier_distance_m = 0.01;  // RANSAC inlier band
  int iterations = 600;
  // Every other RANSAC draw takes its second and third points within this many pixels of the
  // first (0: every draw from the whole image).
  int neighbourhood_px = 64;
  // Prior on the table normal (world, pointing up, i.e. towards the camera side): the plane's
  // normal must be within `max_normal_angle_deg` of it. Unset: the direction from the scene to
  // the camera that took the depth (-optical axis), right for a top sensor looking down; for a
  // front sensor pass its "up" (-y of an upright camera, in world).
  std::optional<cv::Vec3d> up_prior;
  double max_normal_angle_deg = 35;
  int min_inliers = 500;
  uint64_t seed = 1;
  Status check() const;
};

struct TablePlaneFit {
  geometry::Plane plane;  // normal points up (towards the camera side)
  int inliers = 0;
  double rms_m = 0;
  std::vector<cv::Vec3d> inlier_points;  // world, subsampled
};

// Error (kNotFound) when no plane with enough inliers matches the prior (e.g. no table in view).
Result<TablePlaneFit> fit_table_plane_from_depth(const cv::Mat& depth_mm, const CameraModel& camera,
                                                 const TablePlaneFitOptions& options = {});

// The world point where the ray through `pixel` meets the plane raised by `height_m` along its
// normal; nullopt when the ray is parallel to it or points away.
std::optional<cv::Vec3d> pixel_on_plane(const CameraModel& camera, const cv::Point2d& pixel,
                                        const geometry::Plane& plane, double height_m = 0);

// Image polygon of the part of the plane a camera sees inside `extent` (world points on the
// plane, e.g. table corners), or empty when it does not see it.
std::vector<cv::Point2f> project_polygon(const CameraModel& camera,
                                         const std::vector<cv::Vec3d>& extent);

}  // namespace dreamsense::objects
