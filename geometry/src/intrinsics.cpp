#include "dreamsense/geometry/intrinsics.hpp"

#include "dreamsense/core/log.hpp"
#include "dreamsense/core/opencv_error.hpp"

#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>

namespace dreamsense::geometry {

const char* to_string(DistortionModel model) {
  return model == DistortionModel::kRadial2 ? "radial2" : "standard5";
}

Result<DistortionModel> parse_distortion_model(const std::string& name) {
  if (name == "radial2") return DistortionModel::kRadial2;
  if (name == "standard5") return DistortionModel::kStandard5;
  return make_error(ErrorCode::kInvalidArgument,
                    "unknown distortion model '{}' (expected radial2 or standard5)", name);
}

Status IntrinsicsOptions::check() const {
  std::string bad;
  if (board.width < 2 || board.height < 2) bad += " board must have >= 2x2 inner corners;";
  if (!(square_size > 0)) bad += " square_size must be > 0;";
  if (subpixel_window != 0 && (subpixel_window < 3 || subpixel_window % 2 == 0))
    bad += " subpixel_window must be 0 or odd >= 3;";
  if (!(reject_factor > 1)) bad += " reject_factor must be > 1;";
  if (!(reject_min_px >= 0)) bad += " reject_min_px must be >= 0;";
  if (min_views < 1) bad += " min_views must be >= 1;";
  if (!bad.empty()) return make_error(ErrorCode::kInvalidArgument, "intrinsics options:{}", bad);
  return ok_status();
}

int calibration_flags(const IntrinsicsOptions& o) {
  int flags = 0;
  if (o.model == DistortionModel::kRadial2) flags |= cv::CALIB_ZERO_TANGENT_DIST | cv::CALIB_FIX_K3;
  if (o.fix_aspect_ratio) flags |= cv::CALIB_FIX_ASPECT_RATIO;
  return flags;
}

std::vector<cv::Point3f> chessboard_object_points(cv::Size board, double square) {
  std::vector<cv::Point3f> pts;
  for (int r = 0; r < board.height; ++r)
    for (int c = 0; c < board.width; ++c)
      pts.emplace_back(static_cast<float>(c * square), static_cast<float>(r * square), 0.f);
  return pts;
}

std::optional<std::vector<cv::Point2f>> detect_chessboard(const cv::Mat& image, cv::Size board,
                                                          int subpixel_window) {
  cv::Mat gray;
  if (image.channels() == 3)
    cv::cvtColor(image, gray, cv::COLOR_BGR2GRAY);
  else if (image.channels() == 4)
    cv::cvtColor(image, gray, cv::COLOR_BGRA2GRAY);
  else
    gray = image;
  std::vector<cv::Point2f> corners;
  const bool found = cv::findChessboardCorners(
      gray, board, corners,
      cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE | cv::CALIB_CB_FAST_CHECK);
  if (!found) return std::nullopt;
  if (subpixel_window > 0) {
    const int half = subpixel_window / 2;
    cv::cornerSubPix(gray, corners, cv::Size(half, half), cv::Size(-1, -1),
                     cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 30, 0.01));
  }
  return corners;
}

Result<IntrinsicsResult> calibrate_from_points(
    const std::vector<std::vector<cv::Point3f>>& object_points,
    const std::vector<std::vector<cv::Point2f>>& image_points, cv::Size image_size,
    const IntrinsicsOptions& o, const std::vector<std::string>& names) {
  if (auto s = o.check(); !s) return tl::unexpected(s.error());
  if (object_points.size() != image_points.size())
    return make_error(ErrorCode::kInvalidArgument, "{} object-point views but {} image views",
                      object_points.size(), image_points.size());
  const size_t nv = object_points.size();
  for (size_t i = 0; i < nv; ++i)
    if (object_points[i].size() != image_points[i].size() || object_points[i].size() < 4)
      return make_error(ErrorCode::kInvalidArgument,
                        "view {}: {} object points and {} image points (need >= 4, equal)", i + 1,
                        object_points[i].size(), image_points[i].size());
  IntrinsicsResult res;
  res.flags = calibration_flags(o);
  res.views.resize(nv);
  for (size_t i = 0; i < nv; ++i) {
    res.views[i].name = i < names.size() ? names[i] : fmt::format("view {}", i + 1);
    res.views[i].board_found = true;
    res.views[i].used = true;
  }
  if (static_cast<int>(nv) < o.min_views)
    return make_error(ErrorCode::kInvalidArgument, "{} usable views, at least {} needed", nv,
                      o.min_views);
  for (int round = 0;; ++round) {
    std::vector<size_t> used;
    for (size_t i = 0; i < nv; ++i)
      if (res.views[i].used) used.push_back(i);
    std::vector<std::vector<cv::Point3f>> op;
    std::vector<std::vector<cv::Point2f>> ip;
    for (size_t i : used) {
      op.push_back(object_points[i]);
      ip.push_back(image_points[i]);
    }
    cv::Mat K = cv::Mat::eye(3, 3, CV_64F), dist;
    std::vector<cv::Mat> rvecs, tvecs;
    try {
      cv::calibrateCamera(
          op, ip, image_size, K, dist, rvecs, tvecs, res.flags,
          cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 100, 1e-12));
    } catch (const cv::Exception& e) {
      return make_error(ErrorCode::kInvalidArgument, "calibration failed: {}", opencv_reason(e));
    }
    double sq = 0;
    size_t npts = 0;
    std::vector<double> rms;
    for (size_t k = 0; k < used.size(); ++k) {
      std::vector<cv::Point2f> proj;
      cv::projectPoints(op[k], rvecs[k], tvecs[k], K, dist, proj);
      double s = 0;
      for (size_t j = 0; j < proj.size(); ++j) {
        const double e = cv::norm(proj[j] - ip[k][j]);
        s += e * e;
      }
      sq += s;
      npts += proj.size();
      ViewReport& v = res.views[used[k]];
      v.rms_px = std::sqrt(s / static_cast<double>(proj.size()));
      cv::Mat R;
      cv::Rodrigues(rvecs[k], R);
      v.R = cv::Matx33d(R);
      v.t = cv::Vec3d(tvecs[k].reshape(1, 3));
      rms.push_back(v.rms_px);
    }
    res.rms_px = std::sqrt(sq / static_cast<double>(npts));
    res.views_used = static_cast<int>(used.size());
    res.camera.image_size = image_size;
    res.camera.K = cv::Matx33d(K);
    res.camera.distortion = dist.reshape(1, 1).clone();
    // Reject views far worse than the median, then recalibrate.
    std::vector<double> sorted = rms;
    std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
    const double limit = std::max(o.reject_min_px, o.reject_factor * sorted[sorted.size() / 2]);
    std::vector<size_t> bad;
    for (size_t k = 0; k < used.size(); ++k)
      if (rms[k] > limit) bad.push_back(used[k]);
    if (bad.empty() || round >= 3 || static_cast<int>(used.size() - bad.size()) < o.min_views)
      break;
    for (size_t i : bad) {
      log::warn("calibration: rejecting {} (reprojection RMS {:.2f} px > {:.2f} px)",
                res.views[i].name, res.views[i].rms_px, limit);
      res.views[i].used = false;
    }
  }
  return res;
}

Result<IntrinsicsResult> calibrate_from_images(const std::vector<std::filesystem::path>& images,
                                               const IntrinsicsOptions& o) {
  if (auto s = o.check(); !s) return tl::unexpected(s.error());
  if (images.empty()) return make_error(ErrorCode::kInvalidArgument, "no images given");
  cv::Size size;
  std::string size_from;
  std::vector<std::vector<cv::Point2f>> found_pts;
  std::vector<std::string> found_names;
  std::vector<ViewReport> all;
  const auto board_pts = chessboard_object_points(o.board, o.square_size);
  for (const auto& p : images) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(p, ec))
      return make_error(ErrorCode::kNotFound, "{}: missing image", p.string());
    cv::Mat img = cv::imread(p.string(), cv::IMREAD_GRAYSCALE);
    if (img.empty())
      return make_error(ErrorCode::kNotFound, "{}: missing or unreadable image", p.string());
    if (size.empty()) {
      size = img.size();
      size_from = p.string();
    } else if (img.size() != size) {
      return make_error(ErrorCode::kInvalidArgument,
                        "{} is {}x{} but {} is {}x{}: all images must come from one camera "
                        "mode",
                        p.string(), img.cols, img.rows, size_from, size.width, size.height);
    }
    ViewReport v;
    v.name = p.filename().string();
    auto corners = detect_chessboard(img, o.board, o.subpixel_window);
    v.board_found = corners.has_value();
    if (corners) {
      found_pts.push_back(std::move(*corners));
      found_names.push_back(v.name);
    } else {
      log::warn("calibration: no {}x{} chessboard found in {}", o.board.width, o.board.height,
                p.string());
    }
    all.push_back(v);
  }
  if (found_pts.empty())
    return make_error(ErrorCode::kInvalidArgument,
                      "no {}x{} chessboard (inner corners) found in any of the {} images; check "
                      "--board COLSxROWS",
                      o.board.width, o.board.height, images.size());
  if (static_cast<int>(found_pts.size()) < o.min_views)
    return make_error(ErrorCode::kInvalidArgument,
                      "chessboard found in only {} of {} images, at least {} needed",
                      found_pts.size(), images.size(), o.min_views);
  std::vector<std::vector<cv::Point3f>> obj(found_pts.size(), board_pts);
  auto r = calibrate_from_points(obj, found_pts, size, o, found_names);
  if (!r) return r;
  // Merge back the views without a board, in input order.
  std::vector<ViewReport> merged;
  size_t k = 0;
  for (auto& v : all) merged.push_back(v.board_found ? r->views[k++] : v);
  r->views = std::move(merged);
  return r;
}

}  // namespace dreamsense::geometry
