#include "dreamsense/vision/face_alignment.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <tuple>

namespace dreamsense::vision {

Status AlignmentOptions::check() const {
  std::string bad;
  if (size < 16 || size > 1024) bad += " size must be in [16, 1024];";
  if (!(eye_distance > 0.05 && eye_distance < 0.95))
    bad += " eye_distance must be in (0.05, 0.95);";
  if (!(eye_row > 0.05 && eye_row < 0.95)) bad += " eye_row must be in (0.05, 0.95);";
  if (!(template_padding >= 0 && template_padding <= 2)) bad += " template_padding in [0, 2];";
  if (!bad.empty()) return make_error(ErrorCode::kInvalidArgument, "AlignmentOptions:{}", bad);
  return ok_status();
}

namespace {

// dlib's mean face (image_transforms/interpolation.h, get_face_chip_details) for landmarks 17-67,
// in [0, 1] coordinates of the face region.
constexpr double kMeanFaceX[51] = {
    0.000213256, 0.0752622, 0.18113,  0.29077,  0.393397, 0.586856, 0.689483, 0.799124, 0.904991,
    0.98004,     0.490127,  0.490127, 0.490127, 0.490127, 0.36688,  0.426036, 0.490127, 0.554217,
    0.613373,    0.121737,  0.187122, 0.265825, 0.334606, 0.260918, 0.182743, 0.645647, 0.714428,
    0.793132,    0.858516,  0.79751,  0.719335, 0.254149, 0.340985, 0.428858, 0.490127, 0.551395,
    0.639268,    0.726104,  0.642159, 0.556721, 0.490127, 0.423532, 0.338094, 0.290379, 0.428096,
    0.490127,    0.552157,  0.689874, 0.553364, 0.490127, 0.42689};
constexpr double kMeanFaceY[51] = {
    0.106454, 0.038915, 0.0187482, 0.0344891, 0.0773906, 0.0773906, 0.0344891, 0.0187482, 0.038915,
    0.106454, 0.203352, 0.307009,  0.409805,  0.515625,  0.587326,  0.609345,  0.628106,  0.609345,
    0.587326, 0.216423, 0.178758,  0.179852,  0.231733,  0.245099,  0.244077,  0.231733,  0.179852,
    0.178758, 0.216423, 0.244077,  0.245099,  0.780233,  0.745405,  0.727388,  0.742578,  0.727388,
    0.745405, 0.780233, 0.864805,  0.902192,  0.909281,  0.902192,  0.864805,  0.784792,  0.778746,
    0.785343, 0.778746, 0.784792,  0.824182,  0.831803,  0.824182};

bool template_point(int i) { return i >= 27 && !(i >= 55 && i <= 59) && !(i >= 65 && i <= 67); }

cv::Point2d template_position(int i, const AlignmentOptions& o) {
  const double p = o.template_padding, k = o.size / (2 * p + 1);
  return {(p + kMeanFaceX[i - 17]) * k, (p + kMeanFaceY[i - 17]) * k};
}

}  // namespace

std::vector<cv::Point2d> mean_face_landmarks(double size) {
  std::vector<cv::Point2d> pts(kLandmarkCount68);
  for (int i = 0; i < 17; ++i) {  // jaw: from the right temple down round the chin to the left
    const double a = CV_PI * i / 16.0;
    pts[i] = cv::Point2d((0.5 - 0.5 * std::cos(a)) * size, (0.25 + 0.78 * std::sin(a)) * size);
  }
  for (int i = 17; i < kLandmarkCount68; ++i)
    pts[i] = cv::Point2d(kMeanFaceX[i - 17] * size, kMeanFaceY[i - 17] * size);
  return pts;
}

std::pair<double, double> eye_geometry(const AlignmentOptions& o) {
  if (!o.dlib_template) return {o.eye_distance, o.eye_row};
  cv::Point2d right(0, 0), left(0, 0);
  for (int i = 0; i < 6; ++i) {
    right += template_position(36 + i, o);
    left += template_position(42 + i, o);
  }
  right *= 1.0 / 6, left *= 1.0 / 6;
  return {(left.x - right.x) / o.size, 0.5 * (left.y + right.y) / o.size};
}

std::optional<cv::Matx23d> similarity_from_landmarks(const std::vector<cv::Point2d>& landmarks,
                                                     const AlignmentOptions& o) {
  if (landmarks.size() != static_cast<size_t>(kLandmarkCount68)) return std::nullopt;
  if (!o.dlib_template) {
    const auto [right, left] = eye_centres(landmarks);
    return similarity_from_eyes(right, left, o);
  }
  // Least squares: q = [a -b; b a] p + t, p = image landmark, q = template point.
  cv::Point2d pm(0, 0), qm(0, 0);
  int n = 0;
  for (int i = 0; i < kLandmarkCount68; ++i)
    if (template_point(i)) pm += landmarks[i], qm += template_position(i, o), ++n;
  pm *= 1.0 / n, qm *= 1.0 / n;
  double sxx = 0, sa = 0, sb = 0;
  for (int i = 0; i < kLandmarkCount68; ++i) {
    if (!template_point(i)) continue;
    const cv::Point2d p = landmarks[i] - pm, q = template_position(i, o) - qm;
    sxx += p.dot(p);
    sa += p.x * q.x + p.y * q.y;
    sb += p.x * q.y - p.y * q.x;
  }
  if (!(sxx > 1e-9)) return std::nullopt;
  const double a = sa / sxx, b = sb / sxx;
  return cv::Matx23d(a, -b, qm.x - (a * pm.x - b * pm.y), b, a, qm.y - (b * pm.x + a * pm.y));
}

const char* to_string(AlignmentSource source) {
  switch (source) {
    case AlignmentSource::kLandmarks:
      return "landmarks";
    case AlignmentSource::kLandmarksFromCrop:
      return "landmarks_from_crop";
    case AlignmentSource::kCropGeometry:
      return "crop_geometry";
  }
  return "unknown";
}

std::pair<cv::Point2d, cv::Point2d> eye_centres(const std::vector<cv::Point2d>& landmarks) {
  DS_CHECK_EQ(landmarks.size(), static_cast<size_t>(kLandmarkCount68));
  cv::Point2d right(0, 0), left(0, 0);
  for (int i = 0; i < 6; ++i) {
    right += landmarks[36 + i];
    left += landmarks[42 + i];
  }
  return {right * (1.0 / 6), left * (1.0 / 6)};
}

std::optional<cv::Matx23d> similarity_from_eyes(cv::Point2d right_eye, cv::Point2d left_eye,
                                                const AlignmentOptions& options) {
  AlignmentOptions o = options;
  std::tie(o.eye_distance, o.eye_row) = eye_geometry(options);
  const cv::Point2d d = left_eye - right_eye;
  const double len = std::hypot(d.x, d.y);
  if (!(len > 1e-6)) return std::nullopt;
  const double s = o.size * o.eye_distance / len;
  // Rotation taking d to the +x axis, scaled: [a -b; b a] with a = s cos(-t), b = s sin(-t).
  const double a = s * d.x / len, b = -s * d.y / len;
  const cv::Point2d target_right((0.5 - o.eye_distance / 2) * o.size, o.eye_row * o.size);
  const double tx = target_right.x - (a * right_eye.x - b * right_eye.y);
  const double ty = target_right.y - (b * right_eye.x + a * right_eye.y);
  return cv::Matx23d(a, -b, tx, b, a, ty);
}

Result<cv::Mat> to_grey(const cv::Mat& image) {
  cv::Mat grey;
  switch (image.type()) {
    case CV_8UC1:
      return image;
    case CV_8UC3:
      cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
      return grey;
    case CV_8UC4:
      cv::cvtColor(image, grey, cv::COLOR_BGRA2GRAY);
      return grey;
    default:
      return make_error(ErrorCode::kInvalidArgument,
                        "face image of OpenCV type {} (need 8-bit grey, BGR or BGRA)",
                        image.type());
  }
}

Result<FaceRegion> face_region(const cv::Mat& image, const std::vector<cv::Point2d>& landmarks,
                               double margin) {
  FaceRegion r;
  if (landmarks.empty() || image.empty()) return r;
  double x0 = landmarks[0].x, x1 = x0, y0 = landmarks[0].y, y1 = y0;
  for (const auto& p : landmarks) {
    x0 = std::min(x0, p.x), x1 = std::max(x1, p.x);
    y0 = std::min(y0, p.y), y1 = std::max(y1, p.y);
  }
  const double grow = margin * std::max(x1 - x0, y1 - y0);
  const cv::Rect box = cv::Rect(cv::Point(static_cast<int>(std::floor(x0 - grow)),
                                          static_cast<int>(std::floor(y0 - grow))),
                                cv::Point(static_cast<int>(std::ceil(x1 + grow)) + 1,
                                          static_cast<int>(std::ceil(y1 + grow)) + 1)) &
                       cv::Rect(0, 0, image.cols, image.rows);
  if (box.empty()) return r;
  auto grey = to_grey(image(box));
  if (!grey) return tl::unexpected(grey.error());
  r.grey = grey->isContinuous() && grey->data != image.data ? *grey : grey->clone();
  r.landmarks.reserve(landmarks.size());
  for (const auto& p : landmarks) r.landmarks.emplace_back(p.x - box.x, p.y - box.y);
  return r;
}

std::vector<cv::Point2d> transform_points(const cv::Matx23d& t,
                                          const std::vector<cv::Point2d>& points) {
  std::vector<cv::Point2d> out;
  out.reserve(points.size());
  for (const cv::Point2d& p : points)
    out.emplace_back(t(0, 0) * p.x + t(0, 1) * p.y + t(0, 2),
                     t(1, 0) * p.x + t(1, 1) * p.y + t(1, 2));
  return out;
}

AlignedFace warp_face(const cv::Mat& grey, const cv::Matx23d& crop_from_image,
                      const AlignmentOptions& o, AlignmentSource source) {
  AlignedFace face;
  cv::warpAffine(grey, face.grey, cv::Mat(crop_from_image), cv::Size(o.size, o.size),
                 cv::INTER_LINEAR, cv::BORDER_REPLICATE);
  face.crop_from_image = crop_from_image;
  face.source = source;
  return face;
}

cv::Mat resample_face(const cv::Mat& image_grey, const AlignedFace& aligned, int size) {
  DS_CHECK(size > 0 && !aligned.grey.empty());
  if (size == aligned.grey.cols) return aligned.grey;
  const cv::Matx23d t = aligned.crop_from_image * (static_cast<double>(size) / aligned.grey.cols);
  cv::Mat out;
  cv::warpAffine(image_grey, out, cv::Mat(t), cv::Size(size, size), cv::INTER_LINEAR,
                 cv::BORDER_REPLICATE);
  return out;
}

int mirrored_landmark_index(int i) {
  static const int kMirror[kLandmarkCount68] = {
      16, 15, 14, 13, 12, 11, 10, 9,  8,  7,  6,  5,  4, 3, 2, 1, 0,  // jaw
      26, 25, 24, 23, 22, 21, 20, 19, 18, 17,                         // brows
      27, 28, 29, 30, 35, 34, 33, 32, 31,                             // nose
      45, 44, 43, 42, 47, 46, 39, 38, 37, 36, 41, 40,                 // eyes
      54, 53, 52, 51, 50, 49, 48, 59, 58, 57, 56, 55,                 // outer lips
      64, 63, 62, 61, 60, 67, 66, 65};                                // inner lips
  DS_CHECK(i >= 0 && i < kLandmarkCount68);
  return kMirror[i];
}

AlignedFace mirror_face(const AlignedFace& face) {
  AlignedFace m;
  cv::flip(face.grey, m.grey, 1);
  const double w = face.grey.cols - 1;
  const cv::Matx33d flip(-1, 0, w, 0, 1, 0, 0, 0, 1);
  const cv::Matx33d t(face.crop_from_image(0, 0), face.crop_from_image(0, 1),
                      face.crop_from_image(0, 2), face.crop_from_image(1, 0),
                      face.crop_from_image(1, 1), face.crop_from_image(1, 2), 0, 0, 1);
  const cv::Matx33d ft = flip * t;
  m.crop_from_image = cv::Matx23d(ft(0, 0), ft(0, 1), ft(0, 2), ft(1, 0), ft(1, 1), ft(1, 2));
  m.source = face.source;
  if (face.landmarks.size() == static_cast<size_t>(kLandmarkCount68)) {
    m.landmarks.resize(face.landmarks.size());
    for (int i = 0; i < kLandmarkCount68; ++i) {
      const cv::Point2d& p = face.landmarks[static_cast<size_t>(mirrored_landmark_index(i))];
      m.landmarks[static_cast<size_t>(i)] = cv::Point2d(w - p.x, p.y);
    }
  }
  return m;
}

Result<std::optional<AlignedFace>> align_face(const cv::Mat& image,
                                              const std::vector<cv::Point2d>& landmarks,
                                              const AlignmentOptions& options) {
  if (auto s = options.check(); !s) return tl::unexpected(s.error());
  auto grey = to_grey(image);
  if (!grey) return tl::unexpected(grey.error());
  if (grey->empty() || landmarks.size() != static_cast<size_t>(kLandmarkCount68))
    return std::optional<AlignedFace>{};
  const auto t = similarity_from_landmarks(landmarks, options);
  if (!t) return std::optional<AlignedFace>{};
  AlignedFace face = warp_face(*grey, *t, options, AlignmentSource::kLandmarks);
  face.landmarks = transform_points(*t, landmarks);
  return std::optional<AlignedFace>{std::move(face)};
}

}  // namespace dreamsense::vision
