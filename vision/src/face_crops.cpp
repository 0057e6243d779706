#include "dreamsense/vision/face_crops.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>

namespace dreamsense::vision {

Status FaceCropOptions::check() const {
  if (auto s = alignment.check(); !s) return s;
  std::string bad;
  if (working_px < 32 || working_px > 2048) bad += " working_px must be in [32, 2048];";
  if (!(min_face_fraction >= 0 && min_face_fraction < 1)) bad += " min_face_fraction in [0, 1);";
  if (!(crop_face_box.width > 0 && crop_face_box.height > 0)) bad += " crop_face_box empty;";
  if (!(min_eye_distance > 0 && max_eye_distance > min_eye_distance))
    bad += " need 0 < min_eye_distance < max_eye_distance;";
  if (!(max_roll_deg > 0 && max_roll_deg <= 90)) bad += " max_roll_deg in (0, 90];";
  if (!(crop_eye_row > 0 && crop_eye_row < 1)) bad += " crop_eye_row in (0, 1);";
  if (!(crop_eye_distance > 0 && crop_eye_distance < 1)) bad += " crop_eye_distance in (0, 1);";
  if (min_image_px < 8) bad += " min_image_px must be >= 8;";
  if (!(min_contrast >= 0)) bad += " min_contrast must be >= 0;";
  if (!bad.empty()) return make_error(ErrorCode::kInvalidArgument, "FaceCropOptions:{}", bad);
  return ok_status();
}

bool plausible_landmarks(const std::vector<cv::Point2d>& pts, const cv::Rect2d& box,
                         const FaceCropOptions& o) {
  if (pts.size() != static_cast<size_t>(kLandmarkCount68) || !(box.width > 0)) return false;
  const auto [right, left] = eye_centres(pts);
  const cv::Point2d d = left - right;
  const double iod = std::hypot(d.x, d.y);
  if (!(d.x > 0) || iod < o.min_eye_distance * box.width || iod > o.max_eye_distance * box.width)
    return false;
  const double roll_deg = std::atan2(d.y, d.x) * 180.0 / CV_PI;
  if (std::abs(roll_deg) > o.max_roll_deg) return false;
  cv::Point2d mouth(0, 0);
  for (int i = 48; i < 68; ++i) mouth += pts[i];
  mouth *= 1.0 / 20;
  const cv::Point2d down(-d.y / iod, d.x / iod);
  if ((mouth - (left + right) * 0.5).dot(down) < o.min_mouth_drop * iod) return false;
  const cv::Rect2d grown(box.x - box.width / 2, box.y - box.height / 2, box.width * 2,
                         box.height * 2);
  return std::all_of(pts.begin(), pts.end(),
                     [&](const cv::Point2d& p) { return grown.contains(p); });
}

FaceCropAligner::FaceCropAligner(FaceCropOptions options, FaceFinder finder, LandmarkFitter fitter)
    : options_(std::move(options)), finder_(std::move(finder)), fitter_(std::move(fitter)) {}

Result<std::optional<AlignedFace>> FaceCropAligner::align(const cv::Mat& image) const {
  using Out = std::optional<AlignedFace>;
  const FaceCropOptions& o = options_;
  if (auto s = o.check(); !s) return tl::unexpected(s.error());
  if (image.empty()) return Out{};
  auto grey_or = to_grey(image);
  if (!grey_or) return tl::unexpected(grey_or.error());
  const cv::Mat& grey = *grey_or;
  if (std::min(grey.rows, grey.cols) < o.min_image_px) return Out{};
  cv::Scalar mean, sd;
  cv::meanStdDev(grey, mean, sd);
  if (sd[0] < o.min_contrast) return Out{};

  const double scale = static_cast<double>(o.working_px) / std::min(grey.rows, grey.cols);
  cv::Mat work;
  cv::resize(grey, work, cv::Size(), scale, scale, scale > 1 ? cv::INTER_CUBIC : cv::INTER_AREA);

  // Landmarks fitted in `work`, mapped back to image pixels, aligned from the image itself.
  auto from_landmarks = [&](const cv::Rect2d& box, AlignmentSource source) -> Result<Out> {
    if (!fitter_) return Out{};
    auto pts = fitter_(work, box);
    if (!pts) return tl::unexpected(pts.error());
    if (!*pts || !plausible_landmarks(**pts, box, o)) return Out{};
    std::vector<cv::Point2d> in_image = **pts;
    for (cv::Point2d& p : in_image) p *= 1.0 / scale;
    auto face = align_face(grey, in_image, o.alignment);
    if (!face) return tl::unexpected(face.error());
    if (*face) (*face)->source = source;
    return std::move(*face);
  };

  if (finder_) {
    auto boxes = finder_(work);
    if (!boxes) return tl::unexpected(boxes.error());
    std::vector<cv::Rect2d> usable;
    for (const cv::Rect2d& b : *boxes)
      if (b.width >= o.min_face_fraction * o.working_px) usable.push_back(b);
    std::stable_sort(usable.begin(), usable.end(),
                     [](const cv::Rect2d& a, const cv::Rect2d& b) { return a.area() > b.area(); });
    if (usable.size() > 3) usable.resize(3);
    for (const cv::Rect2d& b : usable) {
      auto face = from_landmarks(b, AlignmentSource::kLandmarks);
      if (!face || *face) return face;
    }
  }
  if (!o.assume_crop) return Out{};
  const cv::Rect2d box(o.crop_face_box.x * work.cols, o.crop_face_box.y * work.rows,
                       o.crop_face_box.width * work.cols, o.crop_face_box.height * work.rows);
  {
    auto face = from_landmarks(box, AlignmentSource::kLandmarksFromCrop);
    if (!face || *face) return face;
  }
  const double w = grey.cols, h = grey.rows;
  const cv::Point2d right((0.5 - o.crop_eye_distance / 2) * w, o.crop_eye_row * h);
  const cv::Point2d left((0.5 + o.crop_eye_distance / 2) * w, o.crop_eye_row * h);
  const auto t = similarity_from_eyes(right, left, o.alignment);
  if (!t) return Out{};
  return Out{warp_face(grey, *t, o.alignment, AlignmentSource::kCropGeometry)};
}

}  // namespace dreamsense::vision
