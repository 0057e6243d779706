#include "dreamsense/head_pose/face_shape_fit.hpp"

#include "dreamsense/core/file_storage_check.hpp"
#include "dreamsense/core/opencv_error.hpp"

#include <opencv2/calib3d.hpp>

#include <algorithm>
#include <cmath>
#include <exception>
#include <filesystem>
#include <fstream>
#include <set>

namespace dreamsense::head_pose {
namespace {
constexpr double kDegToRad = CV_PI / 180.0;
constexpr const char* kFaceModelFormat = "dreamsense-face-model";

struct Ray {
  cv::Vec3d origin, direction;  // head frame, direction unit
};

double distance(const Ray& r, const cv::Vec3d& x) {
  const cv::Vec3d v = x - r.origin;
  return cv::norm(v - r.direction * v.dot(r.direction));
}

// Least-squares point of rays and the smallest eigenvalue of the normal matrix over the ray count
// (sin^2 of half the rays' angular spread).
std::pair<cv::Vec3d, double> closest_point(const std::vector<Ray>& rays) {
  cv::Matx33d A = cv::Matx33d::zeros();
  cv::Vec3d b(0, 0, 0);
  for (const Ray& r : rays) {
    const cv::Matx33d P = cv::Matx33d::eye() - r.direction * r.direction.t();
    A += P;
    b += P * r.origin;
  }
  cv::Vec3d eig;
  cv::eigen(A, eig);
  const double n = static_cast<double>(rays.size());
  return {A.solve(b, cv::DECOMP_SVD), eig[2] / n};
}
}  // namespace

Status FaceShapeFitOptions::check() const {
  std::string bad;
  std::set<int> seen;
  if (landmark_index.size() < 4) bad += " landmark_index needs >= 4 points;";
  for (int i : landmark_index)
    if (i < 0 || i >= 68 || !seen.insert(i).second) {
      bad += " landmark_index has an index out of [0, 68) or repeated;";
      break;
    }
  if (!(max_view_angle_deg > 0 && max_view_angle_deg < 90))
    bad += " max_view_angle_deg must be in (0, 90);";
  if (min_views < 2) bad += " min_views must be >= 2;";
  if (!(min_ray_spread_deg >= 0 && min_ray_spread_deg < 90))
    bad += " min_ray_spread_deg must be in [0, 90);";
  if (!(trim_fraction >= 0 && trim_fraction < 0.9)) bad += " trim_fraction must be in [0, 0.9);";
  if (!bad.empty()) return make_error(ErrorCode::kInvalidArgument, "FaceShapeFitOptions:{}", bad);
  return ok_status();
}

Result<FaceShapeFit> fit_face_shape(const std::vector<LandmarkView>& views,
                                    const FaceShapeFitOptions& options) {
  if (auto s = options.check(); !s) return tl::unexpected(s.error());
  const size_t n_points = options.landmark_index.size();
  std::vector<std::vector<Ray>> rays(n_points);
  FaceShapeFit fit;
  for (size_t v = 0; v < views.size(); ++v) {
    const LandmarkView& view = views[v];
    if (view.camera == nullptr)
      return make_error(ErrorCode::kInvalidArgument, "fit_face_shape: view {} has no camera", v);
    if (view.landmarks_px.size() != 68)
      return make_error(ErrorCode::kInvalidArgument, "fit_face_shape: view {} has {} landmarks", v,
                        view.landmarks_px.size());
    const CameraModel& cam = *view.camera;
    const cv::Matx33d head_from_world = view.world_from_head.t();
    const cv::Vec3d centre = cam.centre_world();
    const cv::Vec3d to_camera = centre - view.head_position_world_m;
    const cv::Vec3d forward = view.world_from_head * cv::Vec3d(0, 0, -1);
    if (forward.dot(to_camera) <
        std::cos(options.max_view_angle_deg * kDegToRad) * cv::norm(to_camera))
      continue;
    ++fit.views_used;
    std::vector<cv::Point2d> px, normalised;
    std::vector<size_t> which;
    for (size_t k = 0; k < n_points; ++k) {
      const cv::Point2d& p = view.landmarks_px[static_cast<size_t>(options.landmark_index[k])];
      if (!std::isfinite(p.x) || !std::isfinite(p.y)) continue;
      px.push_back(p);
      which.push_back(k);
    }
    if (px.empty()) continue;
    cv::undistortPoints(px, normalised, cv::Mat(cam.K), cam.distortion);
    const cv::Vec3d origin = head_from_world * (centre - view.head_position_world_m);
    for (size_t j = 0; j < px.size(); ++j) {
      cv::Vec3d d = head_from_world * (cam.R.t() * cv::Vec3d(normalised[j].x, normalised[j].y, 1));
      rays[which[j]].push_back({origin, d / cv::norm(d)});
    }
  }
  fit.model.name = "subject_" + std::to_string(n_points);
  for (size_t k = 0; k < n_points; ++k) {
    const int index = options.landmark_index[k];
    std::vector<Ray>& r = rays[k];
    if (static_cast<int>(r.size()) < options.min_views)
      return make_error(ErrorCode::kNotFound,
                        "fit_face_shape: landmark {} seen in {} usable views (need {})", index,
                        r.size(), options.min_views);
    auto [x, spread] = closest_point(r);
    const double spread_deg = 2 * std::asin(std::sqrt(std::max(spread, 0.0))) / kDegToRad;
    if (spread_deg < options.min_ray_spread_deg)
      return make_error(ErrorCode::kNotFound,
                        "fit_face_shape: the views of landmark {} span {:.1f} deg (need {}): "
                        "record the head turning, or with more cameras",
                        index, spread_deg, options.min_ray_spread_deg);
    const auto keep = static_cast<size_t>(
        std::ceil(static_cast<double>(r.size()) * (1.0 - options.trim_fraction)));
    if (keep < r.size()) {
      const cv::Vec3d x0 = x;
      std::sort(r.begin(), r.end(),
                [&](const Ray& a, const Ray& b) { return distance(a, x0) < distance(b, x0); });
      r.resize(std::max<size_t>(keep, 2));
      x = closest_point(r).first;
    }
    double ss = 0;
    for (const Ray& ray : r) ss += std::pow(distance(ray, x), 2);
    fit.model.landmark_index.push_back(index);
    fit.model.points_m.emplace_back(x[0], x[1], x[2]);
    fit.views_per_point.push_back(static_cast<int>(r.size()));
    fit.rms_ray_distance_m.push_back(std::sqrt(ss / static_cast<double>(r.size())));
  }
  return fit;
}

Status write_face_model(const std::string& path, const FaceModel3d& model,
                        const std::string& provenance) {
  if (auto s = model.check(); !s) return s;
  const std::string partial = path + ".partial";
  try {
    cv::FileStorage fs(partial, cv::FileStorage::WRITE | cv::FileStorage::FORMAT_YAML);
    if (!fs.isOpened())
      return make_error(ErrorCode::kIoError, "{}: cannot write the face model", path);
    fs << "format" << kFaceModelFormat << "version" << 1 << "name" << model.name << "provenance"
       << provenance << "points"
       << "[";
    for (size_t i = 0; i < model.points_m.size(); ++i) {
      const cv::Point3d& p = model.points_m[i];
      fs << "{:"
         << "index" << model.landmark_index[i] << "x" << p.x << "y" << p.y << "z" << p.z << "}";
    }
    fs << "]";
    fs.release();
  } catch (const std::exception& e) {
    return make_error(ErrorCode::kIoError, "{}: {}", path, opencv_reason(e));
  }
  std::error_code ec;
  std::filesystem::rename(partial, path, ec);
  if (ec) return make_error(ErrorCode::kIoError, "{}: {}", path, ec.message());
  return ok_status();
}

Result<FaceModel3d> read_face_model(const std::string& path) {
  if (!std::ifstream(path))
    return make_error(ErrorCode::kNotFound, "{}: face model not found", path);
  DS_ASSIGN_OR_RETURN(cv::FileStorage fs, open_file_storage(path));
  FaceModel3d m;
  try {
    if (static_cast<std::string>(fs["format"]) != kFaceModelFormat)
      return make_error(ErrorCode::kCorruptData, "{}: not a dreamsense face model (format: {})",
                        path, kFaceModelFormat);
    if (static_cast<int>(fs["version"]) != 1)
      return make_error(ErrorCode::kUnsupported, "{}: face model version {} (this build reads 1)",
                        path, static_cast<int>(fs["version"]));
    m.name = fs["name"].empty() ? "subject" : static_cast<std::string>(fs["name"]);
    const cv::FileNode points = fs["points"];
    if (points.type() != cv::FileNode::SEQ)
      return make_error(ErrorCode::kCorruptData, "{}: 'points' must be a list", path);
    for (const cv::FileNode& p : points) {
      if (p["index"].empty() || p["x"].empty() || p["y"].empty() || p["z"].empty())
        return make_error(ErrorCode::kCorruptData, "{}: every point needs index, x, y, z", path);
      m.landmark_index.push_back(static_cast<int>(p["index"]));
      m.points_m.emplace_back(static_cast<double>(p["x"]), static_cast<double>(p["y"]),
                              static_cast<double>(p["z"]));
    }
  } catch (const std::exception& e) {
    return make_error(ErrorCode::kCorruptData, "{}: {}", path, opencv_reason(e));
  }
  if (auto s = m.check(); !s)
    return make_error(ErrorCode::kCorruptData, "{}: {}", path, s.error().message);
  return m;
}

Result<cv::Matx33d> read_model_from_head(const std::filesystem::path& gaze_yaml) {
  if (!std::ifstream(gaze_yaml))
    return make_error(ErrorCode::kNotFound, "{}: gaze calibration not found", gaze_yaml.string());
  DS_ASSIGN_OR_RETURN(cv::FileStorage fs, open_file_storage(gaze_yaml));
  try {
    if (fs["model_from_head"].empty()) return cv::Matx33d::eye();
    cv::Mat R;
    fs["model_from_head"] >> R;
    if (R.rows != 3 || R.cols != 3 || R.type() != CV_64F)
      return make_error(ErrorCode::kCorruptData, "{}: model_from_head must be a 3x3 matrix",
                        gaze_yaml.string());
    const cv::Matx33d m(R);
    if (cv::norm(cv::Mat(m * m.t() - cv::Matx33d::eye())) > 1e-6 || cv::determinant(m) < 0)
      return make_error(ErrorCode::kCorruptData, "{}: model_from_head is not a rotation",
                        gaze_yaml.string());
    return m;
  } catch (const std::exception&) {
    return make_error(ErrorCode::kCorruptData, "{}: not a readable gaze calibration (YAML)",
                      gaze_yaml.string());
  }
}

}  // namespace dreamsense::head_pose
