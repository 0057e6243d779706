#include "dreamsense/vision/face_locator.hpp"

namespace dreamsense::vision {

Result<std::shared_ptr<const face_landmarks::Landmarker>> load_landmarker(
    const FaceLocatorOptions& options) {
  return face_landmarks::shared_dlib_landmarker(options.landmarks);
}

face_detection::FaceDetectorOptions crop_finder_options(const FaceCropOptions& crop,
                                                        const FaceLocatorOptions& options) {
  face_detection::FaceDetectorOptions d = options.detector;
  d.min_face_px = crop.min_face_fraction * crop.working_px;
  d.detection_width = std::max(d.detection_width, 4 * crop.working_px);
  d.estimate_frontalness = false;
  return d;
}

Result<FaceCropAligner> make_face_crop_aligner(
    const FaceCropOptions& crop, std::shared_ptr<const face_landmarks::Landmarker> landmarker,
    const FaceLocatorOptions& options) {
  if (auto s = crop.check(); !s) return tl::unexpected(s.error());
  if (!landmarker)
    return make_error(ErrorCode::kInvalidArgument, "make_face_crop_aligner: no landmarker");
  auto detector = face_detection::FaceDetector::create(crop_finder_options(crop, options));
  if (!detector) return tl::unexpected(detector.error());
  auto shared_detector = std::make_shared<face_detection::FaceDetector>(std::move(*detector));
  FaceFinder finder = [shared_detector](const cv::Mat& grey) -> Result<std::vector<cv::Rect2d>> {
    std::vector<cv::Rect2d> boxes;
    for (const auto& f : shared_detector->detect(grey, std::nullopt, false))
      boxes.push_back(f.box_px);
    return boxes;
  };
  LandmarkFitter fitter = [landmarker](const cv::Mat& grey, const cv::Rect2d& box)
      -> Result<std::optional<std::vector<cv::Point2d>>> { return landmarker->fit(grey, box); };
  return FaceCropAligner(crop, std::move(finder), std::move(fitter));
}

}  // namespace dreamsense::vision
