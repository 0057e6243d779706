// Table plane from depth (RANSAC + least squares), pixel lifting, polygon projection.

#include "dreamsense/objects/table_geometry.hpp"

#include <opencv2/calib3d.hpp>

#include <cmath>
#include <random>

namespace dreamsense::objects {
namespace {

// The same plane with the normal reversed. (Not `p = {-p.normal, -p.offset}`: the braced
// assignment may build the new value in place and read half-written members.)
geometry::Plane flipped(const geometry::Plane& p) {
  geometry::Plane f;
  f.normal = -p.normal;
  f.offset = -p.offset;
  return f;
}

}  // namespace

Status TablePlaneFitOptions::check() const {
  std::string bad;
  auto need = [&bad](bool ok, const char* what) {
    if (!ok) bad += bad.empty() ? what : std::string("; ") + what;
  };
  need(pixel_step >= 1, "pixel_step must be >= 1");
  need(min_depth_m > 0 && max_depth_m > min_depth_m, "need 0 < min_depth_m < max_depth_m");
  need(inlier_distance_m > 0, "inlier_distance_m must be > 0");
  need(iterations >= 1, "iterations must be >= 1");
  need(neighbourhood_px >= 0, "neighbourhood_px must be >= 0");
  need(max_normal_angle_deg > 0 && max_normal_angle_deg <= 90,
       "max_normal_angle_deg must be in (0, 90]");
  need(min_inliers >= 3, "min_inliers must be >= 3");
  if (!bad.empty()) return make_error(ErrorCode::kInvalidArgument, "table plane fit: {}", bad);
  return ok_status();
}

Result<TablePlaneFit> fit_table_plane_from_depth(const cv::Mat& depth_mm, const CameraModel& cam,
                                                 const TablePlaneFitOptions& o) {
  if (auto s = o.check(); !s) return tl::unexpected(s.error());
  if (depth_mm.empty() || depth_mm.type() != CV_16UC1)
    return make_error(ErrorCode::kInvalidArgument, "table plane fit: depth must be CV_16UC1 (mm)");
  // Back-project (undistorted rays) every n-th pixel with a valid depth into the world.
  std::vector<cv::Vec3d> pts;
  // Where each sampled pixel's point is (-1: no valid depth), for sampling neighbours.
  const int gw = (depth_mm.cols + o.pixel_step - 1) / o.pixel_step;
  const int gh = (depth_mm.rows + o.pixel_step - 1) / o.pixel_step;
  std::vector<int> grid(static_cast<size_t>(gw) * static_cast<size_t>(gh), -1);
  std::vector<cv::Point> cell_of;
  for (int v = 0; v < depth_mm.rows; v += o.pixel_step) {
    const uint16_t* row = depth_mm.ptr<uint16_t>(v);
    for (int u = 0; u < depth_mm.cols; u += o.pixel_step) {
      const double z = row[u] * 1e-3;
      if (z < o.min_depth_m || z > o.max_depth_m) continue;
      const cv::Vec3d ray = cam.pixel_ray({static_cast<double>(u), static_cast<double>(v)});
      grid[static_cast<size_t>(v / o.pixel_step) * static_cast<size_t>(gw) +
           static_cast<size_t>(u / o.pixel_step)] = static_cast<int>(pts.size());
      cell_of.emplace_back(u / o.pixel_step, v / o.pixel_step);
      pts.push_back(cam.to_world(ray * (z / ray[2])));
    }
  }
  if (pts.size() < static_cast<size_t>(o.min_inliers))
    return make_error(ErrorCode::kNotFound, "table plane fit: only {} valid depth pixels",
                      pts.size());
  const cv::Vec3d up =
      o.up_prior ? cv::normalize(*o.up_prior) : cv::normalize(cam.R.t() * cv::Vec3d(0, 0, -1));
  const double min_cos = std::cos(o.max_normal_angle_deg * CV_PI / 180.0);
  std::mt19937_64 rng(o.seed);
  std::uniform_int_distribution<size_t> pick(0, pts.size() - 1);
  // The table may cover a small part of the image (a front sensor sees mostly the child, the
  // room and the wall): three points drawn from the whole image all lie on it too rarely. Every
  // other draw takes the second and third points near the first in the image (NAPSAC, Myatt et
  // al. 2002), so a surface is hit whenever its first point is.
  std::uniform_int_distribution<int> near(-o.neighbourhood_px / o.pixel_step,
                                          o.neighbourhood_px / o.pixel_step);
  auto neighbour = [&](size_t first) -> size_t {
    for (int tries = 0; tries < 20; ++tries) {
      const cv::Point c = cell_of[first] + cv::Point(near(rng), near(rng));
      if (c.x < 0 || c.y < 0 || c.x >= gw || c.y >= gh) continue;
      const int k =
          grid[static_cast<size_t>(c.y) * static_cast<size_t>(gw) + static_cast<size_t>(c.x)];
      if (k >= 0) return static_cast<size_t>(k);
    }
    return pick(rng);
  };
  geometry::Plane best;
  int best_count = 0;
  for (int it = 0; it < o.iterations; ++it) {
    const size_t a = pick(rng);
    const bool local = it % 2 == 1 && o.neighbourhood_px > 0;
    const size_t b = local ? neighbour(a) : pick(rng);
    const size_t c = local ? neighbour(a) : pick(rng);
    auto p = geometry::plane_from_points(pts[a], pts[b], pts[c], 0.02);
    if (!p) continue;
    geometry::Plane pl = *p;
    if (pl.normal.dot(up) < 0) pl = flipped(pl);
    if (pl.normal.dot(up) < min_cos) continue;
    int count = 0;
    for (const auto& q : pts) count += pl.distance(q) < o.inlier_distance_m ? 1 : 0;
    // Among planes with the normal allowed, the most supported; ties: the lower one (a table
    // under toys, not the toys' tops).
    if (count > best_count) best_count = count, best = pl;
  }
  if (best_count < o.min_inliers)
    return make_error(ErrorCode::kNotFound,
                      "table plane fit: no plane within {:.0f} deg of the expected normal has "
                      "{} inliers (best {})",
                      o.max_normal_angle_deg, o.min_inliers, best_count);
  // Least squares on the inliers, then again on a narrower band around each refit (the RANSAC
  // band also admits things lying on the table, which tilt the first fit).
  TablePlaneFit fit;
  fit.plane = best;
  for (double band : {o.inlier_distance_m, 0.5 * o.inlier_distance_m, 0.3 * o.inlier_distance_m}) {
    std::vector<cv::Vec3d> in;
    for (const auto& q : pts)
      if (fit.plane.distance(q) < band) in.push_back(q);
    if (in.size() < 3) break;
    auto refined = geometry::fit_plane(in);
    if (!refined) return tl::unexpected(refined.error());
    fit.plane = refined->normal.dot(up) < 0 ? flipped(*refined) : *refined;
    fit.inlier_points = std::move(in);
  }
  double ss = 0;
  for (const auto& q : fit.inlier_points)
    ss += fit.plane.signed_distance(q) * fit.plane.signed_distance(q);
  fit.inliers = static_cast<int>(fit.inlier_points.size());
  fit.rms_m = std::sqrt(ss / std::max(1, fit.inliers));
  return fit;
}

std::optional<cv::Vec3d> pixel_on_plane(const CameraModel& cam, const cv::Point2d& pixel,
                                        const geometry::Plane& plane, double height_m) {
  const cv::Vec3d dir = cam.R.t() * cam.pixel_ray(pixel);
  const geometry::Plane raised{plane.normal, plane.offset - height_m};
  return geometry::intersect(geometry::Ray{cam.centre_world(), dir}, raised);
}

std::vector<cv::Point2f> project_polygon(const CameraModel& cam,
                                         const std::vector<cv::Vec3d>& extent) {
  std::vector<cv::Point2f> out;
  for (const auto& p : extent) {
    const auto px = cam.project(p);
    if (!px) return {};
    out.emplace_back(static_cast<float>(px->x), static_cast<float>(px->y));
  }
  return out;
}

}  // namespace dreamsense::objects
