#include "dreamsense/eye_centers/eye_center_locator.hpp"

#include "dreamsense/perception/eye_centers.hpp"
#include "dreamsense/perception/face_landmarks.hpp"

#include <algorithm>
#include <cmath>

namespace dreamsense::eye_centers {

std::string_view to_string(EyeCenterMethod method) {
  switch (method) {
    case EyeCenterMethod::kImprovedIntegroDifferential:
      return "improved_integro_differential";
    case EyeCenterMethod::kDaugman:
      return "daugman";
    case EyeCenterMethod::kTimmBarth:
      return "timm_barth";
  }
  return "unknown";
}

std::optional<EyeCenterMethod> eye_center_method_from_string(std::string_view name) {
  if (name == "improved" || name == "improved_integro_differential")
    return EyeCenterMethod::kImprovedIntegroDifferential;
  if (name == "daugman") return EyeCenterMethod::kDaugman;
  if (name == "timm_barth") return EyeCenterMethod::kTimmBarth;
  return std::nullopt;
}

std::string_view to_string(EyeRejection rejection) {
  switch (rejection) {
    case EyeRejection::kNone:
      return "none";
    case EyeRejection::kTooSmall:
      return "too_small";
    case EyeRejection::kClosed:
      return "closed";
    case EyeRejection::kNoContrast:
      return "no_contrast";
    case EyeRejection::kNoEdge:
      return "no_edge";
  }
  return "unknown";
}

Status IrisSizePrior::check() const {
  if (!(diameter_mm > 0) || !std::isfinite(diameter_mm))
    return make_error(ErrorCode::kInvalidArgument, "IrisSizePrior: diameter_mm {} must be > 0",
                      diameter_mm);
  if (!(min_ratio > 0) || !(max_ratio > min_ratio) || !std::isfinite(max_ratio))
    return make_error(ErrorCode::kInvalidArgument,
                      "IrisSizePrior: need 0 < min_ratio < max_ratio (are {}, {})", min_ratio,
                      max_ratio);
  return ok_status();
}

EyeRegionOptions with_expected_iris_radius(const EyeRegionOptions& region,
                                           std::span<const cv::Point2d> contour,
                                           double expected_radius_px, const IrisSizePrior& prior) {
  const double width = eye_region_from_contour(contour).width_px;
  if (!(expected_radius_px > 0) || !std::isfinite(expected_radius_px) || !(width > 0))
    return region;
  const double lo = std::max(region.min_iris_radius, prior.min_ratio * expected_radius_px / width);
  const double hi = std::min(region.max_iris_radius, prior.max_ratio * expected_radius_px / width);
  if (!(hi > lo)) return region;
  EyeRegionOptions out = region;
  out.min_iris_radius = lo;
  out.max_iris_radius = hi;
  return out;
}

Status EyeCenterLocatorOptions::check() const {
  if (to_string(method) == "unknown")
    return make_error(ErrorCode::kInvalidArgument, "EyeCenterLocatorOptions: unknown method");
  if (auto s = region.check(); !s) return s;
  if (auto s = iris_size.check(); !s) return s;
  if (auto s = improved.check(); !s) return s;
  if (auto s = daugman.check(); !s) return s;
  return timm_barth.check();
}

std::optional<double> pixels_per_mm_at(const CameraModel& camera, const cv::Vec3d& point_world_m) {
  const double depth_m = camera.to_camera(point_world_m)[2];
  if (!(depth_m > 0.05) || !std::isfinite(depth_m)) return std::nullopt;
  return camera.K(0, 0) / (1000.0 * depth_m);
}

Result<EyeCenterLocator> EyeCenterLocator::create(const EyeCenterLocatorOptions& options) {
  if (auto s = options.check(); !s) return tl::unexpected(s.error());
  return EyeCenterLocator(options);
}

Result<EyeLocation> EyeCenterLocator::locate(const cv::Mat& image,
                                             std::span<const cv::Point2d> contour,
                                             std::optional<double> pixels_per_mm) const {
  DS_CHECK_EQ(contour.size(), size_t{6});
  if (pixels_per_mm) {
    const EyeRegionOptions sized = with_expected_iris_radius(
        options_.region, contour, 0.5 * options_.iris_size.diameter_mm * *pixels_per_mm,
        options_.iris_size);
    auto r = locate_in(image, contour, sized);
    const bool narrowed = sized.min_iris_radius != options_.region.min_iris_radius ||
                          sized.max_iris_radius != options_.region.max_iris_radius;
    if (!r || !narrowed || !options_.iris_size.fall_back_without_pupil ||
        (r->found && r->pupil_found))
      return r;  // (not narrowed: the width-relative search has just run)
    auto plain = locate_in(image, contour, options_.region);
    if (!plain || plain->found || !r->found) return plain;
    return r;
  }
  return locate_in(image, contour, options_.region);
}

Result<EyeLocation> EyeCenterLocator::locate_in(const cv::Mat& image,
                                                std::span<const cv::Point2d> contour,
                                                const EyeRegionOptions& region) const {
  switch (options_.method) {
    case EyeCenterMethod::kImprovedIntegroDifferential:
      return locate_improved_integro_differential(image, contour, region, options_.improved);
    case EyeCenterMethod::kDaugman:
      return locate_daugman(image, contour, region, options_.daugman);
    case EyeCenterMethod::kTimmBarth:
      return locate_timm_barth(image, contour, region, options_.timm_barth);
  }
  return make_error(ErrorCode::kInternal, "EyeCenterLocator: unknown method");
}

Result<EyeCenters> EyeCenterLocator::locate_both(const cv::Mat& image,
                                                 const FaceLandmarks& landmarks,
                                                 std::optional<double> pixels_per_mm) const {
  DS_CHECK_EQ(landmarks.points_px.size(), static_cast<size_t>(kFaceLandmarkCount));
  const std::span<const cv::Point2d> pts(landmarks.points_px);
  auto right = locate(image, pts.subspan(36, 6), pixels_per_mm);
  if (!right) return tl::unexpected(right.error());
  auto left = locate(image, pts.subspan(42, 6), pixels_per_mm);
  if (!left) return tl::unexpected(left.error());
  EyeCenters out;
  out.camera = landmarks.camera;
  out.frame_stamp = landmarks.frame_stamp;
  out.frame_sequence = landmarks.frame_sequence;
  out.right = right->to_eye_center();
  out.left = left->to_eye_center();
  out.method = std::string(to_string(options_.method));
  out.pupil_stage = options_.method == EyeCenterMethod::kImprovedIntegroDifferential &&
                    options_.improved.pupil.enabled;
  return out;
}

}  // namespace dreamsense::eye_centers
