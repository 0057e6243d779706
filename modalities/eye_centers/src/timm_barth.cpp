// Timm & Barth (VISAPP 2011): the centre of a circular dark object is where most image gradients
// point radially away from. Objective (their eq. 3-4, with the dark-centre weight):
//   c* = argmax_c w_c / N * sum_i max(0, d_i(c) . g_i)^2.
// As in the authors' description and the widely used reference implementation (T. Hume,
// eyeLike), gradients are central differences, weak gradients are dropped by a dynamic threshold
// and negative dot products (bright-centre evidence) are ignored.

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>

#include "eye_patch.hpp"

namespace dreamsense::eye_centers {

Status TimmBarthOptions::check() const {
  if (!(gradient_threshold_sd >= 0) || !(gradient_threshold_sd <= 5))
    return make_error(ErrorCode::kInvalidArgument,
                      "TimmBarthOptions: gradient_threshold_sd must be in [0, 5]");
  if (!(weight_blur_sigma_px >= 0) || !(weight_blur_sigma_px <= 10))
    return make_error(ErrorCode::kInvalidArgument,
                      "TimmBarthOptions: weight_blur_sigma_px must be in [0, 10]");
  if (!(full_confidence_objective > 0) || !(min_objective >= 0))
    return make_error(ErrorCode::kInvalidArgument,
                      "TimmBarthOptions: need full_confidence_objective > 0, min_objective >= 0");
  return ok_status();
}

Result<EyeLocation> locate_timm_barth(const cv::Mat& image, std::span<const cv::Point2d> contour,
                                      const EyeRegionOptions& region, const TimmBarthOptions& o) {
  // The patch border (r_max beyond the candidates) holds the iris edge of any candidate.
  auto patch = detail::make_eye_patch(image, contour, region, 2);
  if (!patch) return tl::unexpected(patch.error());
  const detail::EyePatch& p = *patch;
  EyeLocation loc;
  if (p.rejection != EyeRejection::kNone) {
    loc.rejection = p.rejection;
    return loc;
  }
  const cv::Mat& g = p.grey;
  // Central-difference gradients (one-sided at the border), their magnitudes and threshold.
  struct Grad {
    float x, y, gx, gy;
  };
  std::vector<Grad> all;
  all.reserve(static_cast<size_t>(g.rows) * g.cols);
  std::vector<double> mags;
  mags.reserve(all.capacity());
  for (int y = 0; y < g.rows; ++y) {
    const float* r = g.ptr<float>(y);
    const float* up = g.ptr<float>(std::max(0, y - 1));
    const float* dn = g.ptr<float>(std::min(g.rows - 1, y + 1));
    const double sy = (y == 0 || y == g.rows - 1) ? 1.0 : 0.5;
    for (int x = 0; x < g.cols; ++x) {
      const int xl = std::max(0, x - 1), xr = std::min(g.cols - 1, x + 1);
      const double gx = (r[xr] - r[xl]) / static_cast<double>(xr - xl);
      const double gy = (dn[x] - up[x]) * sy;
      all.push_back({static_cast<float>(x), static_cast<float>(y), static_cast<float>(gx),
                     static_cast<float>(gy)});
      mags.push_back(std::hypot(gx, gy));
    }
  }
  double mean = 0, var = 0;
  for (double m : mags) mean += m;
  mean /= static_cast<double>(mags.size());
  for (double m : mags) var += (m - mean) * (m - mean);
  const double threshold =
      mean + o.gradient_threshold_sd * std::sqrt(var / static_cast<double>(mags.size()));
  std::vector<Grad> strong;
  for (size_t i = 0; i < all.size(); ++i)
    if (mags[i] > threshold && mags[i] > 1e-6)
      strong.push_back({all[i].x, all[i].y, static_cast<float>(all[i].gx / mags[i]),
                        static_cast<float>(all[i].gy / mags[i])});
  if (strong.empty()) {
    loc.rejection = EyeRejection::kNoContrast;
    return loc;
  }
  cv::Mat smooth;
  if (o.weight_blur_sigma_px > 0)
    cv::GaussianBlur(g, smooth, cv::Size(), o.weight_blur_sigma_px);
  else
    smooth = g;

  const cv::Rect grown(p.candidates.x - 1, p.candidates.y - 1, p.candidates.width + 2,
                       p.candidates.height + 2);
  cv::Mat score(grown.size(), CV_64F), objective(grown.size(), CV_64F);
  const double n = static_cast<double>(strong.size());
  for (int y = 0; y < grown.height; ++y)
    for (int x = 0; x < grown.width; ++x) {
      const float cx = static_cast<float>(grown.x + x), cy = static_cast<float>(grown.y + y);
      double sum = 0;
      for (const Grad& s : strong) {
        const float dx = s.x - cx, dy = s.y - cy;
        const float d2 = dx * dx + dy * dy;
        if (d2 == 0) continue;
        const float dot = (dx * s.gx + dy * s.gy) / std::sqrt(d2);
        if (dot > 0) sum += dot * dot;
      }
      const double obj = sum / n;
      const double w =
          o.use_weight ? std::max(0.0, 255.0 - smooth.at<float>(grown.y + y, grown.x + x)) : 1.0;
      objective.at<double>(y, x) = obj;
      score.at<double>(y, x) = w * obj;
    }
  const detail::Peak pk = detail::find_peak(score, p.candidates);
  loc.score = objective.at<double>(pk.best);
  if (!(loc.score >= o.min_objective)) {
    loc.rejection = EyeRejection::kNoEdge;
    return loc;
  }
  loc.found = true;
  loc.center_px = detail::to_image(p, pk.refined);
  loc.iris_center_px = loc.center_px;
  loc.confidence = std::clamp(loc.score / o.full_confidence_objective, 0.0, 1.0);
  return loc;
}

}  // namespace dreamsense::eye_centers
