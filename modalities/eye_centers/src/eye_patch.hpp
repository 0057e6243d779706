#pragma once
// Internal: the resampled eye patch every locator works on, and helpers shared by the methods.

#include "dreamsense/eye_centers/eye_center_locator.hpp"

#include <opencv2/core.hpp>

namespace dreamsense::eye_centers::detail {

// The eye resampled so that its corner line is the patch x axis, at `scale` patch pixels per
// image pixel (eye width in [min_work_width_px, max_work_width_px]). Candidate centres are the
// integer patch pixels of `candidates`, which lies `pad` pixels inside every patch border.
struct EyePatch {
  cv::Mat grey;                  // CV_32F, continuous, grey levels 0-255
  cv::Matx23d image_from_patch;  // patch pixel (x, y, 1) -> image pixel
  double scale = 1;              // patch pixels per image pixel
  double width = 0;              // eye width in patch pixels
  double r_min = 0, r_max = 0;   // iris radius prior, patch pixels
  cv::Rect candidates;           // in patch pixels
  int pad = 0;
  double range = 0;  // grey-level spread of the candidate window: 99th - 1st percentile
  EyeRejection rejection = EyeRejection::kNone;  // != kNone: grey is empty, nothing to search
};

// Rejects too small / closed eyes before resampling; `pad_beyond_r_max` is added to the radius
// prior to get the patch border (the methods' kernels must stay inside the patch).
Result<EyePatch> make_eye_patch(const cv::Mat& image, std::span<const cv::Point2d> contour,
                                const EyeRegionOptions& options, double pad_beyond_r_max);

cv::Point2d to_image(const EyePatch& patch, cv::Point2d patch_px);

// Argmax of `score` (CV_64F, one value per pixel of `patch.candidates` grown by one pixel on
// each side) over the candidates themselves, refined by a 1-D parabola in x and in y.
struct Peak {
  cv::Point best;       // integer position in the grown map
  cv::Point2d refined;  // sub-pixel position in patch pixels
  double value = 0;
};
Peak find_peak(const cv::Mat& score, const cv::Rect& candidates);

// Discrete Gaussian g_j, j = -J..J (sum 1), J = ceil(3 sigma / step), returned with J.
std::vector<double> gaussian_taps(double sigma_px, double step_px, int& half_width);

}  // namespace dreamsense::eye_centers::detail
