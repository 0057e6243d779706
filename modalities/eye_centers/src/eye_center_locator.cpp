#include "dreamsense/eye_centers/eye_center_locator.hpp"

#include "dreamsense/perception/eye_centers.hpp"
#include "dreamsense/perception/face_landmarks.hpp"

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

Status EyeCenterLocatorOptions::check() const {
  if (to_string(method) == "unknown")
    return make_error(ErrorCode::kInvalidArgument, "EyeCenterLocatorOptions: unknown method");
  if (auto s = region.check(); !s) return s;
  if (auto s = improved.check(); !s) return s;
  if (auto s = daugman.check(); !s) return s;
  return timm_barth.check();
}

Result<EyeCenterLocator> EyeCenterLocator::create(const EyeCenterLocatorOptions& options) {
  if (auto s = options.check(); !s) return tl::unexpected(s.error());
  return EyeCenterLocator(options);
}

Result<EyeLocation> EyeCenterLocator::locate(const cv::Mat& image,
                                             std::span<const cv::Point2d> contour) const {
  DS_CHECK_EQ(contour.size(), size_t{6});
  switch (options_.method) {
    case EyeCenterMethod::kImprovedIntegroDifferential:
      return locate_improved_integro_differential(image, contour, options_.region,
                                                  options_.improved);
    case EyeCenterMethod::kDaugman:
      return locate_daugman(image, contour, options_.region, options_.daugman);
    case EyeCenterMethod::kTimmBarth:
      return locate_timm_barth(image, contour, options_.region, options_.timm_barth);
  }
  return make_error(ErrorCode::kInternal, "EyeCenterLocator: unknown method");
}

Result<EyeCenters> EyeCenterLocator::locate_both(const cv::Mat& image,
                                                 const FaceLandmarks& landmarks) const {
  DS_CHECK_EQ(landmarks.points_px.size(), static_cast<size_t>(kFaceLandmarkCount));
  const std::span<const cv::Point2d> pts(landmarks.points_px);
  auto right = locate(image, pts.subspan(36, 6));
  if (!right) return tl::unexpected(right.error());
  auto left = locate(image, pts.subspan(42, 6));
  if (!left) return tl::unexpected(left.error());
  EyeCenters out;
  out.camera = landmarks.camera;
  out.frame_stamp = landmarks.frame_stamp;
  out.frame_sequence = landmarks.frame_sequence;
  out.right = right->to_eye_center();
  out.left = left->to_eye_center();
  out.method = std::string(to_string(options_.method));
  return out;
}

}  // namespace dreamsense::eye_centers
