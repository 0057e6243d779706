// dlib's HOG frontal face detector. dlib headers stay in this file (slow to compile).

#include "dreamsense/face_detection/hog_face_detector.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <dlib/image_processing/frontal_face_detector.h>
#include <dlib/opencv/cv_image.h>

namespace dreamsense::face_detection {

struct HogFaceDetector::Impl {
  HogFaceDetectorOptions options;
  dlib::frontal_face_detector detector = dlib::get_frontal_face_detector();
};

HogFaceDetector::HogFaceDetector(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
HogFaceDetector::HogFaceDetector(HogFaceDetector&&) noexcept = default;
HogFaceDetector& HogFaceDetector::operator=(HogFaceDetector&&) noexcept = default;
HogFaceDetector::~HogFaceDetector() = default;

Status HogFaceDetectorOptions::check() const {
  std::string bad;
  auto add = [&](const std::string& s) { bad += (bad.empty() ? "" : "; ") + s; };
  if (!(min_face_px >= 10)) add(fmt::format("min_face_px {} < 10", min_face_px));
  if (max_work_side_px < 160) add(fmt::format("max_work_side_px {} < 160", max_work_side_px));
  if (!std::isfinite(adjust_threshold)) add("adjust_threshold not finite");
  if (!(score_slope > 0)) add("score_slope must be > 0");
  if (!bad.empty())
    return make_error(ErrorCode::kInvalidArgument, "HogFaceDetectorOptions: " + bad);
  return ok_status();
}

Result<HogFaceDetector> HogFaceDetector::create(const HogFaceDetectorOptions& options) {
  if (auto s = options.check(); !s) return tl::unexpected(s.error());
  auto impl = std::make_unique<Impl>();
  impl->options = options;
  return HogFaceDetector(std::move(impl));
}

const HogFaceDetectorOptions& HogFaceDetector::options() const { return impl_->options; }

std::vector<DetectedFace> HogFaceDetector::detect(const cv::Mat& image) {
  if (image.empty() || image.depth() != CV_8U) return {};
  cv::Mat grey;
  if (image.channels() == 3)
    cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
  else if (image.channels() == 4)
    cv::cvtColor(image, grey, cv::COLOR_BGRA2GRAY);
  else if (image.channels() == 1)
    grey = image;
  else
    return {};
  const HogFaceDetectorOptions& o = impl_->options;
  const double longer = std::max(grey.cols, grey.rows);
  const double scale = std::min(80.0 / o.min_face_px, o.max_work_side_px / longer);
  cv::Mat work;
  if (std::abs(scale - 1.0) < 1e-3)
    work = grey;
  else
    cv::resize(grey, work, cv::Size(), scale, scale, scale < 1 ? cv::INTER_AREA : cv::INTER_LINEAR);
  if (work.cols < 80 || work.rows < 80) return {};
  if (!work.isContinuous()) work = work.clone();
  std::vector<dlib::rect_detection> found;
  impl_->detector(dlib::cv_image<unsigned char>(work), found, o.adjust_threshold);
  std::vector<DetectedFace> faces;
  for (const dlib::rect_detection& d : found) {
    DetectedFace f;
    // dlib rectangles are inclusive integer boxes.
    f.box_px = cv::Rect2d(d.rect.left() / scale, d.rect.top() / scale, d.rect.width() / scale,
                          d.rect.height() / scale);
    f.score =
        static_cast<float>(1.0 / (1.0 + std::exp(-o.score_slope * (d.detection_confidence + 0.5))));
    f.view = FaceView::kFrontal;
    f.frontalness = 1.f;
    faces.push_back(f);
  }
  std::sort(faces.begin(), faces.end(),
            [](const DetectedFace& a, const DetectedFace& b) { return a.score > b.score; });
  return faces;
}

}  // namespace dreamsense::face_detection
