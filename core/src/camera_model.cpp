#include "dreamsense/core/camera_model.hpp"

#include "dreamsense/core/file_storage_check.hpp"
#include "dreamsense/core/opencv_error.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <opencv2/calib3d.hpp>

#include <algorithm>
#include <cmath>
#include <exception>
#include <sstream>
#include <string>
#include <vector>

namespace dreamsense {

std::optional<cv::Point2d> CameraModel::project_camera_point(const cv::Vec3d& cam) const {
  if (cam[2] <= 1e-9) return std::nullopt;
  std::vector<cv::Point3d> pts{cv::Point3d(cam[0], cam[1], cam[2])};
  std::vector<cv::Point2d> px;
  cv::projectPoints(pts, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), cv::Mat(K), distortion, px);
  return px.front();
}

cv::Vec3d CameraModel::pixel_ray(const cv::Point2d& px) const {
  std::vector<cv::Point2d> in{px}, out;
  cv::undistortPoints(in, out, cv::Mat(K), distortion);
  cv::Vec3d ray(out[0].x, out[0].y, 1.0);
  return ray / cv::norm(ray);
}

double CameraModel::yaw_towards_deg(const cv::Vec3d& direction_world) const {
  const cv::Vec3d d = R * direction_world;
  return std::atan2(-d[0], -d[2]) * 180.0 / CV_PI;
}

Status CameraModel::check() const {
  // Plausible ranges (docs/session_format.md, "Damaged recordings"): everything finite, image up
  // to 100000 px a side, focal lengths in (0, 1e6) px, the camera within 1 km of the world origin.
  std::vector<std::string> bad;
  auto finite = [](const auto& m) {
    for (int i = 0; i < m.rows * m.cols; ++i)
      if (!std::isfinite(m.val[i])) return false;
    return true;
  };
  if (image_size.width <= 0 || image_size.height <= 0 || image_size.width > 100000 ||
      image_size.height > 100000)
    bad.emplace_back(
        fmt::format("image size {}x{} is not plausible", image_size.width, image_size.height));
  if (!finite(K))
    bad.emplace_back("camera_matrix holds a non-finite number");
  else if (K(0, 0) <= 0 || K(1, 1) <= 0 || K(0, 0) > 1e6 || K(1, 1) > 1e6)
    bad.emplace_back("focal lengths must be positive and below 1e6 px");
  if (!distortion.empty() && !cv::checkRange(distortion))
    bad.emplace_back("distortion_coefficients hold a non-finite number");
  if (!finite(R)) {
    bad.emplace_back("camera_from_world_R holds a non-finite number");
  } else {
    const cv::Matx33d should_be_identity = R * R.t();
    if (cv::norm(should_be_identity - cv::Matx33d::eye()) > 1e-6 || cv::determinant(R) < 0)
      bad.emplace_back("camera_from_world_R is not a rotation matrix");
  }
  if (!finite(t))
    bad.emplace_back("camera_from_world_t holds a non-finite number");
  else if (cv::norm(t) > 1000)
    bad.emplace_back("camera_from_world_t is more than 1 km from the world origin");
  if (!bad.empty())
    return make_error(ErrorCode::kInvalidArgument, "camera model '{}': {}", frame,
                      fmt::join(bad, "; "));
  return ok_status();
}

namespace {
// Reads one key, turning OpenCV's parser exceptions into a message that names the key.
template <typename T>
Status read_key(const cv::FileStorage& fs, const char* key, T& out,
                const std::filesystem::path& path) {
  try {
    const cv::FileNode n = fs[key];
    if (!n.empty()) n >> out;
    return ok_status();
  } catch (const std::exception&) {
    return make_error(ErrorCode::kCorruptData, "{}: key '{}' does not hold a valid value",
                      path.string(), key);
  }
}
}  // namespace

Result<CameraModel> read_camera_model(const std::filesystem::path& path) {
  if (!std::filesystem::exists(path))
    return make_error(ErrorCode::kNotFound, "{}: missing calibration file", path.string());
  DS_ASSIGN_OR_RETURN(const cv::FileStorage fs, open_file_storage(path));
  CameraModel m;
  cv::Mat K, R, t;
  DS_RETURN_IF_ERROR(read_key(fs, "frame", m.frame, path));
  DS_RETURN_IF_ERROR(read_key(fs, "image_width", m.image_size.width, path));
  DS_RETURN_IF_ERROR(read_key(fs, "image_height", m.image_size.height, path));
  DS_RETURN_IF_ERROR(read_key(fs, "camera_matrix", K, path));
  DS_RETURN_IF_ERROR(read_key(fs, "distortion_coefficients", m.distortion, path));
  DS_RETURN_IF_ERROR(read_key(fs, "camera_from_world_R", R, path));
  DS_RETURN_IF_ERROR(read_key(fs, "camera_from_world_t", t, path));
  if (K.empty() || K.rows != 3 || K.cols != 3)
    return make_error(ErrorCode::kCorruptData, "{}: key 'camera_matrix' missing or not 3x3",
                      path.string());
  if ((!R.empty() && (R.rows != 3 || R.cols != 3)) || (!t.empty() && t.total() != 3))
    return make_error(ErrorCode::kCorruptData,
                      "{}: keys 'camera_from_world_R'/'camera_from_world_t' must be 3x3 and 3x1",
                      path.string());
  K.convertTo(K, CV_64F);
  m.K = cv::Matx33d(K);
  if (m.distortion.empty()) m.distortion = cv::Mat::zeros(1, 5, CV_64F);
  m.distortion.convertTo(m.distortion, CV_64F);
  if (!R.empty()) {
    R.convertTo(R, CV_64F);
    m.R = cv::Matx33d(R);
  }
  if (!t.empty()) {
    t.convertTo(t, CV_64F);
    m.t = cv::Vec3d(t.reshape(1, 3));
  }
  if (auto st = m.check(); !st)
    return make_error(ErrorCode::kCorruptData, "{}: {}", path.string(), st.error().message);
  return m;
}

void write_camera_model_keys(cv::FileStorage& fs, const CameraModel& m) {
  fs << "frame" << m.frame;
  fs << "image_width" << m.image_size.width << "image_height" << m.image_size.height;
  fs << "camera_matrix" << cv::Mat(m.K);
  fs << "distortion_coefficients" << m.distortion;
  fs.writeComment("Extrinsics: camera_from_world, X_cam = R * X_world + t (metres)");
  fs << "camera_from_world_R" << cv::Mat(m.R);
  fs << "camera_from_world_t" << cv::Mat(m.t);
}

Status write_camera_model(const std::filesystem::path& path, const CameraModel& m) {
  try {
    cv::FileStorage fs(path.string(), cv::FileStorage::WRITE);
    if (!fs.isOpened())
      return make_error(ErrorCode::kIoError, "{}: cannot write calibration file", path.string());
    write_camera_model_keys(fs, m);
    return ok_status();
  } catch (const std::exception& e) {
    return make_error(ErrorCode::kIoError, "{}: {}", path.string(), opencv_reason(e));
  }
}

cv::Matx33d rotation_from_ypr_deg(double yaw, double pitch, double roll) {
  const double y = yaw * CV_PI / 180, p = pitch * CV_PI / 180, r = roll * CV_PI / 180;
  const cv::Matx33d Ry(std::cos(y), 0, std::sin(y), 0, 1, 0, -std::sin(y), 0, std::cos(y));
  const cv::Matx33d Rx(1, 0, 0, 0, std::cos(p), -std::sin(p), 0, std::sin(p), std::cos(p));
  const cv::Matx33d Rz(std::cos(r), -std::sin(r), 0, std::sin(r), std::cos(r), 0, 0, 0, 1);
  return Ry * Rx * Rz;
}

void look_at(const cv::Vec3d& eye, const cv::Vec3d& target, const cv::Vec3d& down,
             cv::Matx33d& R_cam_from_world, cv::Vec3d& t_cam_from_world) {
  cv::Vec3d z = target - eye;
  z /= cv::norm(z);
  cv::Vec3d x = down.cross(z);  // y (down) x z (forward) = x (right)
  if (cv::norm(x) < 1e-9) x = cv::Vec3d(1, 0, 0).cross(z);
  x /= cv::norm(x);
  const cv::Vec3d y = z.cross(x);
  // Rows of R are the camera axes expressed in world.
  R_cam_from_world = cv::Matx33d(x[0], x[1], x[2], y[0], y[1], y[2], z[0], z[1], z[2]);
  t_cam_from_world = -(R_cam_from_world * eye);
}

std::optional<cv::Vec3d> parse_vec3(std::string text) {
  std::replace(text.begin(), text.end(), ',', ' ');
  std::istringstream in(text);
  cv::Vec3d v;
  if (!(in >> v[0] >> v[1] >> v[2])) return std::nullopt;
  std::string rest;
  if (in >> rest) return std::nullopt;
  for (int i = 0; i < 3; ++i)
    if (!std::isfinite(v[i])) return std::nullopt;
  return v;
}

}  // namespace dreamsense
