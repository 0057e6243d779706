// face-api's 68-point CNN behind the Landmarker interface (landmarker.hpp).
#include "dreamsense/face_landmarks/landmarker.hpp"
#include "dreamsense/vision/face_api_net.hpp"

#include <opencv2/imgproc.hpp>

#include <cmath>
#include <mutex>

namespace dreamsense::face_landmarks {
namespace {

cv::Rect2d extent_of(const std::vector<cv::Point2d>& pts) {
  double x0 = 1e300, y0 = 1e300, x1 = -1e300, y1 = -1e300;
  for (const cv::Point2d& p : pts) {
    x0 = std::min(x0, p.x), y0 = std::min(y0, p.y);
    x1 = std::max(x1, p.x), y1 = std::max(y1, p.y);
  }
  return {x0, y0, x1 - x0, y1 - y0};
}

class FaceApiLandmarker final : public Landmarker {
 public:
  FaceApiLandmarker(vision::FaceApiLandmarkNet net, FaceApiLandmarkerOptions o)
      : net_(std::move(net)), options_(std::move(o)) {}
  std::string_view name() const override { return "face_api_68"; }
  int point_count() const override { return 68; }

  cv::Rect2d box_for_extent(const cv::Rect2d& e) const override {
    const double m = options_.margin;
    return {e.x - m * e.width, e.y - m * e.height, e.width * (1 + 2 * m), e.height * (1 + 2 * m)};
  }

  Result<std::optional<std::vector<cv::Point2d>>> fit(const cv::Mat& image,
                                                      const cv::Rect2d& box) const override {
    auto f = fit_with_spread(image, box);
    if (!f) return tl::unexpected(f.error());
    if (!*f) return std::optional<std::vector<cv::Point2d>>{};
    return std::optional<std::vector<cv::Point2d>>{std::move((*f)->points)};
  }

  Result<std::optional<LandmarkFit>> fit_with_spread(const cv::Mat& image,
                                                     const cv::Rect2d& box) const override {
    if (image.type() != CV_8UC3 && image.type() != CV_8UC1)
      return make_error(ErrorCode::kInvalidArgument,
                        "FaceApiLandmarker: image type {} (need CV_8UC3 BGR or CV_8UC1)",
                        image.type());
    std::vector<cv::Point2d> prev, pts;
    cv::Rect2d b = box;
    for (int pass = 0; pass <= options_.refit_passes; ++pass) {
      const cv::Rect crop =
          cv::Rect(cv::Point(static_cast<int>(std::floor(b.x)), static_cast<int>(std::floor(b.y))),
                   cv::Point(static_cast<int>(std::ceil(b.br().x)),
                             static_cast<int>(std::ceil(b.br().y)))) &
          cv::Rect(0, 0, image.cols, image.rows);
      if (crop.width < options_.min_box_px || crop.height < options_.min_box_px)
        return pass == 0 ? Result<std::optional<LandmarkFit>>(std::optional<LandmarkFit>{})
                         : Result<std::optional<LandmarkFit>>(LandmarkFit{pts});
      if (pass == 0) {  // contrast: a uniform patch carries no landmark information
        cv::Mat grey;
        if (image.channels() == 3)
          cv::cvtColor(image(crop), grey, cv::COLOR_BGR2GRAY);
        else
          grey = image(crop);
        cv::Scalar mean, sd;
        cv::meanStdDev(grey, mean, sd);
        if (sd[0] < options_.min_contrast) return std::optional<LandmarkFit>{};
      }
      prev = std::move(pts);
      {
        std::lock_guard lock(mutex_);
        pts = net_.fit(image(crop));
      }
      for (cv::Point2d& p : pts) p += cv::Point2d(crop.x, crop.y);
      b = box_for_extent(extent_of(pts));
    }
    LandmarkFit out{pts};
    if (!prev.empty()) {
      const double d = cv::norm(pts[36] - pts[45]);
      double sum = 0;
      for (size_t k = 0; k < pts.size(); ++k) sum += cv::norm(pts[k] - prev[k]);
      if (d > 0) out.spread = sum / static_cast<double>(pts.size()) / d;
    }
    return std::optional<LandmarkFit>{std::move(out)};
  }

 private:
  mutable vision::FaceApiLandmarkNet net_;
  FaceApiLandmarkerOptions options_;
  mutable std::mutex mutex_;
};

}  // namespace

Status FaceApiLandmarkerOptions::check() const {
  if (!(margin >= 0 && margin < 1))
    return make_error(ErrorCode::kInvalidArgument, "FaceApiLandmarkerOptions: margin in [0, 1)");
  if (refit_passes < 0)
    return make_error(ErrorCode::kInvalidArgument, "FaceApiLandmarkerOptions: refit_passes >= 0");
  if (!(min_contrast >= 0))
    return make_error(ErrorCode::kInvalidArgument, "FaceApiLandmarkerOptions: min_contrast >= 0");
  if (!(min_box_px > 0))
    return make_error(ErrorCode::kInvalidArgument, "FaceApiLandmarkerOptions: min_box_px > 0");
  return ok_status();
}

Result<std::unique_ptr<Landmarker>> make_face_api_landmarker(const FaceApiLandmarkerOptions& o) {
  if (auto s = o.check(); !s) return tl::unexpected(s.error());
  auto net = vision::FaceApiLandmarkNet::load(
      o.model_dir.empty() ? vision::default_face_api_model_dir() : o.model_dir);
  if (!net) return tl::unexpected(net.error());
  return std::unique_ptr<Landmarker>(new FaceApiLandmarker(std::move(*net), o));
}

}  // namespace dreamsense::face_landmarks
