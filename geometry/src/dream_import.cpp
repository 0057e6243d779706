#include "dreamsense/geometry/dream_import.hpp"

#include "dreamsense/core/file_storage_check.hpp"
#include "dreamsense/core/log.hpp"
#include "dreamsense/core/opencv_error.hpp"

#include <cmath>
#include <exception>
#include <sstream>

namespace dreamsense::geometry {

namespace {

// Numbers of a node: an opencv-matrix, a sequence, a number, or a string of numbers.
std::vector<double> numbers(const cv::FileNode& node) {
  std::vector<double> out;
  if (node.empty() || node.isNone()) return out;
  if (node.isMap()) {
    cv::Mat m;
    node >> m;
    if (!m.empty()) {
      m.convertTo(m, CV_64F);
      m = m.reshape(1, 1);
      out.assign(m.begin<double>(), m.end<double>());
    }
  } else if (node.isSeq()) {
    for (const auto& n : node) {
      auto sub = numbers(n);
      out.insert(out.end(), sub.begin(), sub.end());
    }
  } else if (node.isReal() || node.isInt()) {
    out.push_back(static_cast<double>(node));
  } else if (node.isString()) {
    std::stringstream ss(static_cast<std::string>(node));
    for (double v; ss >> v;) out.push_back(v);
  }
  return out;
}

cv::Mat matrix(const cv::FileNode& node) {
  cv::Mat m;
  if (node.isMap()) {
    node >> m;
    if (!m.empty()) m.convertTo(m, CV_64F);
  }
  return m;
}

Result<cv::FileStorage> open(const std::filesystem::path& path) {
  if (!std::filesystem::exists(path))
    return make_error(ErrorCode::kNotFound, "{}: missing DREAM calibration file", path.string());
  return open_file_storage(path);
}

void warn(std::vector<std::string>& warnings, const std::filesystem::path& path,
          std::string message) {
  log::warn("{}: {}", path.filename().string(), message);
  warnings.push_back(std::move(message));
}

}  // namespace

Result<DreamIntrinsics> read_dream_intrinsics(const std::filesystem::path& path,
                                              std::optional<cv::Size> image_size) {
  auto fs = open(path);
  if (!fs) return tl::unexpected(fs.error());
  try {
    DreamIntrinsics out;
    cv::Mat K = matrix((*fs)["KMat"]);
    if (K.rows != 3 || K.cols != 3)
      return make_error(ErrorCode::kCorruptData, "{}: KMat missing or not 3x3", path.string());
    out.K = cv::Matx33d(K);
    if (!(out.K(0, 0) > 0 && out.K(1, 1) > 0))
      return make_error(ErrorCode::kCorruptData, "{}: KMat has non-positive focal lengths",
                        path.string());
    if (!(*fs)["DeviceID"].empty()) out.device_id = static_cast<int>((*fs)["DeviceID"]);
    cv::Mat D = matrix((*fs)["DistortionCoeffMat"]);
    if (D.empty()) {
      warn(out.warnings, path, "DistortionCoeffMat missing: distortion set to zero");
    } else if (D.rows == 3 && D.cols == 3) {
      const bool copy_of_k = cv::norm(D, K, cv::NORM_INF) < 1e-9 * cv::norm(K, cv::NORM_INF) + 1e-9;
      warn(out.warnings, path,
           copy_of_k ? "DistortionCoeffMat is a 3x3 copy of KMat (known DREAM defect): "
                       "distortion set to zero; recalibrate this camera"
                     : "DistortionCoeffMat is 3x3, not a coefficient vector: distortion set to "
                       "zero; recalibrate this camera");
    } else if (D.total() == 4 || D.total() == 5 || D.total() == 8 || D.total() == 12 ||
               D.total() == 14) {
      out.distortion = D.reshape(1, 1).clone();
    } else {
      warn(out.warnings, path,
           fmt::format("DistortionCoeffMat has {} values (expected 4, 5, 8, 12 or 14): "
                       "distortion set to zero",
                       D.total()));
    }
    if (image_size) {
      const double dx = std::abs(out.K(0, 2) - (image_size->width - 1) / 2.0);
      const double dy = std::abs(out.K(1, 2) - (image_size->height - 1) / 2.0);
      if (dx > 0.12 * image_size->width || dy > 0.12 * image_size->height)
        warn(out.warnings, path,
             fmt::format("principal point ({:.0f}, {:.0f}) is far from the centre of a {}x{} "
                         "image: the calibration was probably made at another resolution or "
                         "crop; recalibrate",
                         out.K(0, 2), out.K(1, 2), image_size->width, image_size->height));
    }
    return out;
  } catch (const std::exception& e) {
    return make_error(ErrorCode::kCorruptData, "{}: {}", path.string(), opencv_reason(e));
  }
}

Result<DreamExtrinsics> read_dream_extrinsics(const std::filesystem::path& path) {
  auto fs = open(path);
  if (!fs) return tl::unexpected(fs.error());
  try {
    DreamExtrinsics out;
    cv::Mat R = matrix((*fs)["RMat"]);
    const auto t = numbers((*fs)["tMat"]);
    if (R.rows != 3 || R.cols != 3 || t.size() != 3)
      return make_error(ErrorCode::kCorruptData, "{}: needs RMat (3x3) and tMat (3x1)",
                        path.string());
    const cv::Matx33d Rm(R);
    out.orthonormality_error = orthonormality_error(Rm);
    if (!std::isfinite(out.orthonormality_error) || std::abs(cv::determinant(Rm)) < 1e-6)
      return make_error(ErrorCode::kCorruptData, "{}: RMat is singular", path.string());
    out.camera_from_world.R = Rm;
    if (out.orthonormality_error > 1e-3 || cv::determinant(Rm) < 0) {
      out.camera_from_world.R = nearest_rotation(Rm);
      warn(out.warnings, path,
           fmt::format("RMat is not orthonormal (max |R R^T - I| = {:.3f}, det = {:.3f}): "
                       "re-orthonormalised to the nearest rotation",
                       out.orthonormality_error, cv::determinant(Rm)));
    } else {
      out.camera_from_world.R = nearest_rotation(Rm);  // remove rounding noise
    }
    out.camera_from_world.t = cv::Vec3d(t[0], t[1], t[2]) * 0.001;  // mm -> m
    const std::string name = path.filename().string();
    if (name.rfind("Kinect1", 0) == 0)
      warn(out.warnings, path,
           "the top Kinect's extrinsics do not fit the USB cameras' convention (camera_from_world, "
           "world = Kinect0 colour); imported as-is, recalibrate before use");
    return out;
  } catch (const std::exception& e) {
    return make_error(ErrorCode::kCorruptData, "{}: {}", path.string(), opencv_reason(e));
  }
}

Result<DreamObjectFile> read_dream_object_file(const std::filesystem::path& path) {
  auto fs = open(path);
  if (!fs) return tl::unexpected(fs.error());
  try {
    DreamObjectFile out;
    const cv::FileStorage& f = *fs;
    const auto r = numbers(f["DeskWorld_R_mat"]);
    if (r.size() == 9) {
      const cv::Matx33d R(r.data());
      const double err = orthonormality_error(R);
      if (std::abs(cv::determinant(R)) < 1e-6)
        return make_error(ErrorCode::kCorruptData, "{}: DeskWorld_R_mat is singular",
                          path.string());
      out.desk_from_world.R = nearest_rotation(R);
      if (err > 1e-3)
        warn(out.warnings, path,
             fmt::format("DeskWorld_R_mat is not orthonormal (max |R R^T - I| = {:.3f}): "
                         "re-orthonormalised to the nearest rotation",
                         err));
    } else if (!r.empty()) {
      return make_error(ErrorCode::kCorruptData, "{}: DeskWorld_R_mat must have 9 values",
                        path.string());
    }
    const auto t = numbers(f["DeskWorld_T_mat"]);
    if (t.size() == 3) out.desk_from_world.t = cv::Vec3d(t[0], t[1], t[2]) * 0.001;
    auto vec3 = [&](const char* key) -> std::optional<cv::Vec3d> {
      const auto v = numbers(f[key]);
      if (v.size() != 3) return std::nullopt;
      return cv::Vec3d(v[0], v[1], v[2]) * 0.001;
    };
    auto scalar = [&](const char* key) -> std::optional<double> {
      const auto v = numbers(f[key]);
      if (v.size() != 1) return std::nullopt;
      return v[0];
    };
    out.point_c_m = vec3("Point_C");
    out.robot_head_m = vec3("RobotHead");
    if (auto g = scalar("GazeRadius")) out.gaze_radius_m = *g * 0.001;
    if (const auto roi = numbers(f["ROIRect"]); roi.size() == 4)
      out.roi = cv::Rect(static_cast<int>(roi[0]), static_cast<int>(roi[1]),
                         static_cast<int>(roi[2]), static_cast<int>(roi[3]));
    out.object_threshold = scalar("ObjectThreshold");
    out.face_size = scalar("FaceSize");
    if (auto u = scalar("UseCamMutualGazeFlag")) out.use_cam_mutual_gaze = *u != 0;
    auto minx = scalar("MutualGazeMinX"), maxx = scalar("MutualGazeMaxX");
    auto miny = scalar("MutualGazeMinY"), maxy = scalar("MutualGazeMaxY");
    if (minx && maxx && miny && maxy)
      out.mutual_gaze_box_m = cv::Vec4d(*minx, *maxx, *miny, *maxy) * 0.001;
    if (r.empty() && !out.point_c_m)
      return make_error(ErrorCode::kCorruptData,
                        "{}: neither DeskWorld_R_mat nor Point_C: not a DREAM ObjectFile",
                        path.string());
    return out;
  } catch (const std::exception& e) {
    return make_error(ErrorCode::kCorruptData, "{}: {}", path.string(), opencv_reason(e));
  }
}

}  // namespace dreamsense::geometry
