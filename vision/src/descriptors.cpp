#include "dreamsense/vision/descriptors.hpp"

#include <opencv2/imgproc.hpp>
#include <opencv2/objdetect.hpp>

#include <cmath>

namespace dreamsense::vision {

Status TanTriggsOptions::check() const {
  std::string bad;
  if (!(gamma > 0 && gamma <= 1)) bad += " gamma in (0, 1];";
  if (!(sigma_inner > 0 && sigma_outer > sigma_inner))
    bad += " need 0 < sigma_inner < sigma_outer;";
  if (!(alpha > 0 && alpha <= 1)) bad += " alpha in (0, 1];";
  if (!(tau > 0)) bad += " tau > 0;";
  if (!bad.empty()) return make_error(ErrorCode::kInvalidArgument, "TanTriggsOptions:{}", bad);
  return ok_status();
}

cv::Mat tan_triggs(const cv::Mat& grey, const TanTriggsOptions& o) {
  DS_CHECK_EQ(grey.type(), CV_8UC1);
  cv::Mat x;
  grey.convertTo(x, CV_32F);
  cv::pow(x, o.gamma, x);
  cv::Mat inner, outer;
  cv::GaussianBlur(x, inner, cv::Size(), o.sigma_inner, o.sigma_inner, cv::BORDER_REPLICATE);
  cv::GaussianBlur(x, outer, cv::Size(), o.sigma_outer, o.sigma_outer, cv::BORDER_REPLICATE);
  x = inner - outer;
  cv::Mat t;
  cv::pow(cv::abs(x), o.alpha, t);
  double m = cv::mean(t)[0];
  x /= std::pow(std::max(m, 1e-12), 1.0 / o.alpha);
  t = cv::min(cv::abs(x), o.tau);
  cv::pow(t, o.alpha, t);
  m = cv::mean(t)[0];
  x /= std::pow(std::max(m, 1e-12), 1.0 / o.alpha);
  float* p = x.ptr<float>(0);  // continuous (freshly allocated)
  const float tau = static_cast<float>(o.tau);
  for (size_t i = 0; i < x.total(); ++i) p[i] = tau * std::tanh(p[i] / tau);
  return x;
}

Status HogOptions::check(cv::Size s) const {
  if (cell_px < 2 || bins < 2 || bins > 36)
    return make_error(ErrorCode::kInvalidArgument, "HogOptions: cell_px >= 2, bins in [2, 36]");
  if (s.width < 2 * cell_px || s.height < 2 * cell_px || s.width % cell_px || s.height % cell_px)
    return make_error(ErrorCode::kInvalidArgument,
                      "HogOptions: image {}x{} must be a multiple of cell_px {} (>= 2 cells)",
                      s.width, s.height, cell_px);
  return ok_status();
}

size_t hog_length(cv::Size s, const HogOptions& o) {
  const size_t bx = static_cast<size_t>(s.width / o.cell_px - 1);
  const size_t by = static_cast<size_t>(s.height / o.cell_px - 1);
  return bx * by * 4 * static_cast<size_t>(o.bins);
}

void hog_descriptor(const cv::Mat& grey, const HogOptions& o, std::vector<float>& out) {
  DS_CHECK_EQ(grey.type(), CV_8UC1);
  DS_CHECK(o.check(grey.size()).has_value());
  const cv::Size cell(o.cell_px, o.cell_px);
  cv::HOGDescriptor hog(grey.size(), cell * 2, cell, cell, o.bins);
  std::vector<float> d;
  hog.compute(grey, d, grey.size(), cv::Size(0, 0));
  DS_CHECK_EQ(d.size(), hog_length(grey.size(), o));
  out.insert(out.end(), d.begin(), d.end());
}

void landmark_geometry(const std::vector<cv::Point2d>& pts, int size, double eye_row,
                       std::vector<float>& out) {
  if (pts.size() != kLandmarkGeometryLength / 2) {
    out.insert(out.end(), kLandmarkGeometryLength, 0.f);
    return;
  }
  for (const cv::Point2d& p : pts) {
    out.push_back(static_cast<float>(p.x / size - 0.5));
    out.push_back(static_cast<float>(p.y / size - eye_row));
  }
}

}  // namespace dreamsense::vision
