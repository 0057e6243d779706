#include "eye_patch.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>

namespace dreamsense::eye_centers {

bool EyeRegion::finite() const {
  for (const cv::Point2d& p : contour_px)
    if (!std::isfinite(p.x) || !std::isfinite(p.y)) return false;
  return true;
}

EyeRegion eye_region_from_contour(std::span<const cv::Point2d> contour_px) {
  DS_CHECK_EQ(contour_px.size(), size_t{6});
  EyeRegion r;
  cv::Point2d c(0, 0);
  for (size_t i = 0; i < 6; ++i) {
    r.contour_px[i] = contour_px[i];
    c += contour_px[i];
  }
  r.center_px = c * (1.0 / 6);
  const cv::Point2d d = r.contour_px[3] - r.contour_px[0];
  r.width_px = std::hypot(d.x, d.y);
  r.angle_rad = std::atan2(d.y, d.x);
  r.opening_px = 0.5 * (cv::norm(r.contour_px[1] - r.contour_px[5]) +
                        cv::norm(r.contour_px[2] - r.contour_px[4]));
  return r;
}

Status EyeRegionOptions::check() const {
  auto bad = [](const char* what) {
    return make_error(ErrorCode::kInvalidArgument, "EyeRegionOptions: {}", what);
  };
  if (!(min_work_width_px >= 8) || !(max_work_width_px >= min_work_width_px))
    return bad("need 8 <= min_work_width_px <= max_work_width_px");
  if (!(min_eye_width_px >= 0)) return bad("min_eye_width_px must be >= 0");
  if (!(min_opening_px >= 0) || !(min_opening_ratio >= 0) || !(min_opening_ratio < 1))
    return bad("min_opening_px must be >= 0 and min_opening_ratio in [0, 1)");
  if (!(min_contrast >= 0)) return bad("min_contrast must be >= 0");
  if (!(corner_inset >= 0) || !(corner_inset < 0.5)) return bad("corner_inset must be in [0, 0.5)");
  if (!(vertical_slack >= 0) || !(vertical_slack <= 1))
    return bad("vertical_slack must be in [0, 1]");
  if (!(min_iris_radius > 0) || !(max_iris_radius > min_iris_radius) || !(max_iris_radius <= 1))
    return bad("need 0 < min_iris_radius < max_iris_radius <= 1");
  return ok_status();
}

namespace detail {

Result<EyePatch> make_eye_patch(const cv::Mat& image, std::span<const cv::Point2d> contour,
                                const EyeRegionOptions& o, double pad_beyond_r_max) {
  if (image.empty()) return make_error(ErrorCode::kInvalidArgument, "eye centre: empty image");
  if (image.type() != CV_8UC1 && image.type() != CV_8UC3)
    return make_error(ErrorCode::kInvalidArgument,
                      "eye centre: image type {} is not CV_8UC1 or CV_8UC3", image.type());
  if (contour.size() != 6)
    return make_error(ErrorCode::kInvalidArgument, "eye centre: {} contour points, need 6",
                      contour.size());
  const EyeRegion region = eye_region_from_contour(contour);
  if (!region.finite())
    return make_error(ErrorCode::kInvalidArgument, "eye centre: non-finite contour point");

  EyePatch p;
  if (region.width_px < std::max(o.min_eye_width_px, 1.0)) {
    p.rejection = EyeRejection::kTooSmall;
    return p;
  }
  if (region.opening_px < o.min_opening_px || region.opening_ratio() < o.min_opening_ratio) {
    p.rejection = EyeRejection::kClosed;
    return p;
  }
  p.scale = std::clamp(region.width_px, o.min_work_width_px, o.max_work_width_px) / region.width_px;
  p.width = region.width_px * p.scale;
  p.r_min = o.min_iris_radius * p.width;
  p.r_max = o.max_iris_radius * p.width;
  p.pad = static_cast<int>(std::ceil(p.r_max + pad_beyond_r_max)) + 1;

  // Contour in the eye frame (origin: centroid, x along the corner line), patch pixels.
  const cv::Point2d u(std::cos(region.angle_rad), std::sin(region.angle_rad));
  const cv::Point2d v(-u.y, u.x);
  std::array<cv::Point2d, 6> q;
  for (size_t i = 0; i < 6; ++i) {
    const cv::Point2d d = region.contour_px[i] - region.center_px;
    q[i] = cv::Point2d(d.dot(u), d.dot(v)) * p.scale;
  }
  const double inset = o.corner_inset * p.width, slack = o.vertical_slack * p.width;
  const double x0 = q[0].x + inset, x1 = q[3].x - inset;
  const double y0 = std::min(q[1].y, q[2].y) - slack, y1 = std::max(q[4].y, q[5].y) + slack;
  int xl = static_cast<int>(std::ceil(x0)), xh = static_cast<int>(std::floor(x1));
  int yl = static_cast<int>(std::ceil(y0)), yh = static_cast<int>(std::floor(y1));
  if (xl > xh) xl = xh = static_cast<int>(std::lround(0.5 * (x0 + x1)));
  if (yl > yh) yl = yh = static_cast<int>(std::lround(0.5 * (y0 + y1)));
  p.candidates = cv::Rect(p.pad, p.pad, xh - xl + 1, yh - yl + 1);
  const cv::Size size(p.candidates.width + 2 * p.pad, p.candidates.height + 2 * p.pad);

  // patch (i, j) -> eye frame (i - pad + xl, j - pad + yl) / scale -> image.
  const cv::Point2d a = u * (1 / p.scale), b = v * (1 / p.scale);
  const cv::Point2d t =
      region.center_px + a * static_cast<double>(xl - p.pad) + b * static_cast<double>(yl - p.pad);
  p.image_from_patch = cv::Matx23d(a.x, b.x, t.x, a.y, b.y, t.y);

  // Source region: the patch's bounding box in the image, plus the smoothing support.
  const double blur_sigma = p.scale < 1 ? 0.6 * std::sqrt(1 / (p.scale * p.scale) - 1) : 0;
  const int border = 2 + static_cast<int>(std::ceil(3 * blur_sigma));
  double bx0 = 1e300, by0 = 1e300, bx1 = -1e300, by1 = -1e300;
  for (const cv::Point2d c :
       {cv::Point2d(0, 0), cv::Point2d(size.width - 1, 0), cv::Point2d(0, size.height - 1),
        cv::Point2d(size.width - 1, size.height - 1)}) {
    const cv::Point2d ip = to_image(p, c);
    bx0 = std::min(bx0, ip.x), by0 = std::min(by0, ip.y);
    bx1 = std::max(bx1, ip.x), by1 = std::max(by1, ip.y);
  }
  const cv::Rect want(static_cast<int>(std::floor(bx0)) - border,
                      static_cast<int>(std::floor(by0)) - border,
                      static_cast<int>(std::ceil(bx1 - bx0)) + 2 * border + 2,
                      static_cast<int>(std::ceil(by1 - by0)) + 2 * border + 2);
  const cv::Rect roi = want & cv::Rect(0, 0, image.cols, image.rows);
  if (roi.area() == 0) {
    p.rejection = EyeRejection::kNoContrast;  // the eye is outside the image
    return p;
  }
  cv::Mat src;
  if (image.channels() == 3)
    cv::cvtColor(image(roi), src, cv::COLOR_BGR2GRAY);
  else
    src = image(roi);
  src.convertTo(src, CV_32F);
  if (blur_sigma > 0) cv::GaussianBlur(src, src, cv::Size(), blur_sigma);
  cv::Matx23d m = p.image_from_patch;
  m(0, 2) -= roi.x;
  m(1, 2) -= roi.y;
  cv::warpAffine(src, p.grey, cv::Mat(m), size, cv::INTER_LINEAR | cv::WARP_INVERSE_MAP,
                 cv::BORDER_REPLICATE);
  cv::Scalar mean, sd;
  cv::meanStdDev(p.grey, mean, sd);
  if (sd[0] < o.min_contrast) {
    p.rejection = EyeRejection::kNoContrast;
    p.grey.release();
    return p;
  }
  // Spread of the grey levels where the eye can be (candidate window grown by the iris radius).
  const cv::Rect win = cv::Rect(p.candidates.x - static_cast<int>(p.r_min),
                                p.candidates.y - static_cast<int>(p.r_min),
                                p.candidates.width + 2 * static_cast<int>(p.r_min),
                                p.candidates.height + 2 * static_cast<int>(p.r_min)) &
                       cv::Rect(0, 0, p.grey.cols, p.grey.rows);
  std::vector<float> g;
  g.reserve(static_cast<size_t>(win.area()));
  for (int y = win.y; y < win.y + win.height; ++y) {
    const float* r = p.grey.ptr<float>(y);
    g.insert(g.end(), r + win.x, r + win.x + win.width);
  }
  if (!g.empty()) {
    const auto lo = static_cast<std::ptrdiff_t>(0.01 * (g.size() - 1));
    const auto hi = static_cast<std::ptrdiff_t>(0.99 * (g.size() - 1));
    std::nth_element(g.begin(), g.begin() + lo, g.end());
    const float g_lo = g[static_cast<size_t>(lo)];
    std::nth_element(g.begin(), g.begin() + hi, g.end());
    p.range = g[static_cast<size_t>(hi)] - g_lo;
  }
  return p;
}

cv::Point2d to_image(const EyePatch& patch, cv::Point2d q) {
  const cv::Matx23d& m = patch.image_from_patch;
  return {m(0, 0) * q.x + m(0, 1) * q.y + m(0, 2), m(1, 0) * q.x + m(1, 1) * q.y + m(1, 2)};
}

namespace {
double parabola_offset(double a, double b, double c) {  // values at -1, 0, +1
  const double den = a - 2 * b + c;
  if (!(den < 0)) return 0;  // not a maximum
  return std::clamp(0.5 * (a - c) / den, -0.5, 0.5);
}
}  // namespace

Peak find_peak(const cv::Mat& score, const cv::Rect& candidates) {
  DS_CHECK_EQ(score.type(), CV_64F);
  DS_CHECK_EQ(score.cols, candidates.width + 2);
  DS_CHECK_EQ(score.rows, candidates.height + 2);
  Peak pk;
  pk.value = -1e300;
  for (int y = 1; y <= candidates.height; ++y)
    for (int x = 1; x <= candidates.width; ++x)
      if (score.at<double>(y, x) > pk.value) {
        pk.value = score.at<double>(y, x);
        pk.best = {x, y};
      }
  const int x = pk.best.x, y = pk.best.y;
  const double dx =
      parabola_offset(score.at<double>(y, x - 1), pk.value, score.at<double>(y, x + 1));
  const double dy =
      parabola_offset(score.at<double>(y - 1, x), pk.value, score.at<double>(y + 1, x));
  pk.refined = cv::Point2d(candidates.x - 1 + x + dx, candidates.y - 1 + y + dy);
  return pk;
}

std::vector<double> gaussian_taps(double sigma_px, double step_px, int& half_width) {
  const double s = sigma_px / step_px;
  half_width = std::max(1, static_cast<int>(std::ceil(3 * s)));
  std::vector<double> g(2 * half_width + 1);
  double sum = 0;
  for (int j = -half_width; j <= half_width; ++j)
    sum += g[j + half_width] = std::exp(-0.5 * j * j / (s * s));
  for (double& x : g) x /= sum;
  return g;
}

}  // namespace detail
}  // namespace dreamsense::eye_centers
