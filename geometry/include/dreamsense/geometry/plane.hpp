#pragma once
// Planes, rays and the table frame (D4.2 V19: the desk plane from three selected points; used by
// getObjectTableDistance and getHeadGaze with a plane). Units: metres, in the world frame.

#include "dreamsense/core/status.hpp"
#include "dreamsense/geometry/transform.hpp"

#include <opencv2/core.hpp>

#include <filesystem>
#include <optional>
#include <vector>

namespace dreamsense::geometry {

// Points x with normal . x + offset = 0; |normal| = 1.
struct Plane {
  cv::Vec3d normal{0, 0, 1};
  double offset = 0;

  // Positive on the side the normal points to.
  double signed_distance(const cv::Vec3d& p) const { return normal.dot(p) + offset; }
  double distance(const cv::Vec3d& p) const { return std::abs(signed_distance(p)); }
  cv::Vec3d project(const cv::Vec3d& p) const { return p - signed_distance(p) * normal; }
};

struct Ray {
  cv::Vec3d origin{0, 0, 0};
  cv::Vec3d direction{0, 0, 1};  // need not be unit length; must not be zero
};

// Plane through three points, normal = (p2 - p1) x (p3 - p1) normalised. Error (kInvalidArgument)
// if the points are (nearly) collinear or coincident: the triangle's smallest height below
// `min_height_m`.
Result<Plane> plane_from_points(const cv::Vec3d& p1, const cv::Vec3d& p2, const cv::Vec3d& p3,
                                double min_height_m = 1e-3);
// Least-squares plane through >= 3 points (SVD); error if they do not span a plane. The normal's
// sign is arbitrary: orient it with `oriented_towards`.
Result<Plane> fit_plane(const std::vector<cv::Vec3d>& points, double min_spread_m = 1e-3);
// The same plane with its normal flipped if needed so that `viewpoint` is on the positive side.
Plane oriented_towards(const Plane& plane, const cv::Vec3d& viewpoint);

// Intersection of a ray with a plane. Absence is a value: nullopt when the ray is parallel to the
// plane (|cos| < min_cos) or the plane is behind the origin (parameter s < 0).
std::optional<cv::Vec3d> intersect(const Ray& ray, const Plane& plane, double min_cos = 1e-6);

// Table frame: origin at p1, x towards p2 (in the plane), z = plane normal pointing to the side
// of `up_viewpoint` (default: the world origin, i.e. the front sensor above the table), y = z x x.
struct TableFrame {
  Plane plane;  // normal = table z (points up, away from the table top)
  RigidTransform world_from_table;
  std::vector<cv::Vec3d> points;  // the points it was made from (world, m)
  // Height above the table (negative below): getObjectTableDistance.
  double height(const cv::Vec3d& world) const { return plane.signed_distance(world); }
};
Result<TableFrame> table_frame_from_points(const std::vector<cv::Vec3d>& points,
                                           const cv::Vec3d& up_viewpoint = {0, 0, 0});

// OpenCV FileStorage YAML: frame, parent, plane_normal, plane_offset, world_from_table_R,
// world_from_table_t, points. Written atomically (temp file + rename).
Status write_table_frame(const std::filesystem::path& path, const TableFrame& table);
Result<TableFrame> read_table_frame(const std::filesystem::path& path);

}  // namespace dreamsense::geometry
