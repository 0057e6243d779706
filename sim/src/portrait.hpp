#pragma once
// Internal helpers shared by the planar and mesh face renderers.

#include <opencv2/core.hpp>

#include <string>
#include <vector>

namespace dreamsense::sim::detail {

// cv::imread(path, IMREAD_COLOR) with stderr muted: Debian's astronaut.png carries an sRGB profile
// that libpng calls "known incorrect" on every read, on stderr, bypassing our logger.
cv::Mat read_portrait_image(const std::string& path);

// BGRA crop of `img` with an elliptic alpha mask (centre and semi-axes in image pixels) feathered
// by a Gaussian of sigma 2.5 px, optionally multiplied by `subject` (CV_8U, crop size, 255 =
// keep), then progressively pre-blurred copies (sigma 0, 0.7, 1.2, 2, 3) for minification.
// texture_level() picks one from the magnification (image px per texture px).
std::vector<cv::Mat> make_texture_levels(const cv::Mat& img, const cv::Rect& crop,
                                         const cv::Point2d& mask_centre,
                                         const cv::Size2d& mask_axes,
                                         const cv::Mat& subject = cv::Mat());
int texture_level(double scale);

}  // namespace dreamsense::sim::detail
