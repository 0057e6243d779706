#include "dreamsense/geometry/plane.hpp"

#include "dreamsense/core/file_storage_check.hpp"
#include "dreamsense/core/opencv_error.hpp"
#include "dreamsense/geometry/calibration_io.hpp"

#include <cmath>
#include <exception>

namespace dreamsense::geometry {

Result<Plane> plane_from_points(const cv::Vec3d& p1, const cv::Vec3d& p2, const cv::Vec3d& p3,
                                double min_height_m) {
  for (const auto& p : {p1, p2, p3})
    if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2]))
      return make_error(ErrorCode::kInvalidArgument, "plane: a point is not finite");
  const cv::Vec3d n = (p2 - p1).cross(p3 - p1);
  const double area2 = cv::norm(n);  // twice the triangle's area
  const double longest = std::max({cv::norm(p2 - p1), cv::norm(p3 - p1), cv::norm(p3 - p2)});
  // Smallest height of the triangle = 2 * area / longest side.
  if (longest <= 0 || area2 / longest < min_height_m)
    return make_error(ErrorCode::kInvalidArgument,
                      "plane: the three points are collinear or coincident (smallest triangle "
                      "height {:.2g} m < {:.2g} m)",
                      longest > 0 ? area2 / longest : 0.0, min_height_m);
  Plane pl;
  pl.normal = n / area2;
  pl.offset = -pl.normal.dot(p1);
  return pl;
}

Result<Plane> fit_plane(const std::vector<cv::Vec3d>& points, double min_spread_m) {
  if (points.size() < 3)
    return make_error(ErrorCode::kInvalidArgument, "plane: {} points given, at least 3 needed",
                      points.size());
  cv::Vec3d c(0, 0, 0);
  for (const auto& p : points) {
    if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2]))
      return make_error(ErrorCode::kInvalidArgument, "plane: a point is not finite");
    c += p;
  }
  c *= 1.0 / static_cast<double>(points.size());
  cv::Mat A(static_cast<int>(points.size()), 3, CV_64F);
  for (int i = 0; i < A.rows; ++i)
    for (int j = 0; j < 3; ++j) A.at<double>(i, j) = points[static_cast<size_t>(i)][j] - c[j];
  cv::Mat w, u, vt;
  cv::SVD::compute(A, w, u, vt);
  const double n = std::sqrt(static_cast<double>(points.size()));
  if (w.at<double>(1) / n < min_spread_m)
    return make_error(ErrorCode::kInvalidArgument,
                      "plane: the points are collinear (spread across the line {:.2g} m)",
                      w.at<double>(1) / n);
  Plane pl;
  pl.normal = cv::Vec3d(vt.at<double>(2, 0), vt.at<double>(2, 1), vt.at<double>(2, 2));
  pl.normal /= cv::norm(pl.normal);
  pl.offset = -pl.normal.dot(c);
  return pl;
}

Plane oriented_towards(const Plane& plane, const cv::Vec3d& viewpoint) {
  if (plane.signed_distance(viewpoint) >= 0) return plane;
  return Plane{-plane.normal, -plane.offset};
}

std::optional<cv::Vec3d> intersect(const Ray& ray, const Plane& plane, double min_cos) {
  const double len = cv::norm(ray.direction);
  if (!(len > 0)) return std::nullopt;
  const cv::Vec3d d = ray.direction / len;
  const double denom = plane.normal.dot(d);
  if (std::abs(denom) < min_cos) return std::nullopt;  // parallel
  const double s = -plane.signed_distance(ray.origin) / denom;
  if (s < 0) return std::nullopt;  // the plane is behind the ray's origin
  return ray.origin + s * d;
}

Result<TableFrame> table_frame_from_points(const std::vector<cv::Vec3d>& points,
                                           const cv::Vec3d& up_viewpoint) {
  if (points.size() < 3)
    return make_error(ErrorCode::kInvalidArgument,
                      "table: {} points given, three points on the table are needed",
                      points.size());
  Result<Plane> plane =
      points.size() == 3 ? plane_from_points(points[0], points[1], points[2]) : fit_plane(points);
  if (!plane) return make_error(ErrorCode::kInvalidArgument, "table {}", plane.error().message);
  if (std::abs(plane->signed_distance(up_viewpoint)) < 1e-6)
    return make_error(ErrorCode::kInvalidArgument,
                      "table: the viewpoint that defines 'up' lies on the table plane");
  TableFrame tf;
  tf.plane = oriented_towards(*plane, up_viewpoint);
  tf.points = points;
  const cv::Vec3d origin = tf.plane.project(points[0]);
  cv::Vec3d x = tf.plane.project(points[1]) - origin;
  x /= cv::norm(x);
  const cv::Vec3d z = tf.plane.normal;
  const cv::Vec3d y = z.cross(x);
  // Columns of world_from_table R are the table axes in world.
  tf.world_from_table.R = cv::Matx33d(x[0], y[0], z[0], x[1], y[1], z[1], x[2], y[2], z[2]);
  tf.world_from_table.t = origin;
  return tf;
}

Status write_table_frame(const std::filesystem::path& path, const TableFrame& table) {
  return write_atomically(path, [&](const std::filesystem::path& tmp) -> Status {
    try {
      cv::FileStorage fs(tmp.string(), cv::FileStorage::WRITE);
      if (!fs.isOpened()) return make_error(ErrorCode::kIoError, "{}: cannot write", path.string());
      fs.writeComment("Table plane: plane_normal . X + plane_offset = 0 (world, metres);");
      fs.writeComment("normal = table z, pointing up. world_from_table: X_world = R X_table + t");
      fs << "frame"
         << "table"
         << "parent"
         << "world";
      fs << "plane_normal" << cv::Mat(table.plane.normal);
      fs << "plane_offset" << table.plane.offset;
      fs << "world_from_table_R" << cv::Mat(table.world_from_table.R);
      fs << "world_from_table_t" << cv::Mat(table.world_from_table.t);
      cv::Mat pts(static_cast<int>(table.points.size()), 3, CV_64F);
      for (int i = 0; i < pts.rows; ++i)
        for (int j = 0; j < 3; ++j) pts.at<double>(i, j) = table.points[static_cast<size_t>(i)][j];
      fs << "points" << pts;
      return ok_status();
    } catch (const std::exception& e) {
      return make_error(ErrorCode::kIoError, "{}: {}", path.string(), opencv_reason(e));
    }
  });
}

Result<TableFrame> read_table_frame(const std::filesystem::path& path) {
  if (!std::filesystem::exists(path))
    return make_error(ErrorCode::kNotFound, "{}: missing table file", path.string());
  DS_ASSIGN_OR_RETURN(cv::FileStorage fs, open_file_storage(path));
  try {
    cv::Mat n, R, t, pts;
    fs["plane_normal"] >> n;
    fs["world_from_table_R"] >> R;
    fs["world_from_table_t"] >> t;
    fs["points"] >> pts;
    if (n.total() != 3 || R.rows != 3 || R.cols != 3 || t.total() != 3 ||
        fs["plane_offset"].empty())
      return make_error(ErrorCode::kCorruptData,
                        "{}: needs plane_normal, plane_offset, world_from_table_R and _t",
                        path.string());
    TableFrame tf;
    tf.plane.normal = cv::Vec3d(n.reshape(1, 3));
    tf.plane.offset = static_cast<double>(fs["plane_offset"]);
    tf.world_from_table.R = cv::Matx33d(R);
    tf.world_from_table.t = cv::Vec3d(t.reshape(1, 3));
    for (int i = 0; i < pts.rows && pts.cols == 3; ++i)
      tf.points.emplace_back(pts.at<double>(i, 0), pts.at<double>(i, 1), pts.at<double>(i, 2));
    if (std::abs(cv::norm(tf.plane.normal) - 1) > 1e-6 ||
        orthonormality_error(tf.world_from_table.R) > 1e-6)
      return make_error(ErrorCode::kCorruptData,
                        "{}: plane_normal is not unit or world_from_table_R is not a rotation",
                        path.string());
    return tf;
  } catch (const std::exception& e) {
    return make_error(ErrorCode::kCorruptData, "{}: {}", path.string(), opencv_reason(e));
  }
}

}  // namespace dreamsense::geometry
