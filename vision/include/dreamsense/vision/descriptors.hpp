#pragma once
// Image descriptors of an aligned face besides LBP (lbp.hpp): illumination normalisation,
// histograms of oriented gradients and the landmark geometry.

#include "dreamsense/core/status.hpp"

#include <opencv2/core.hpp>

#include <vector>

namespace dreamsense::vision {

// Illumination normalisation of X. Tan and B. Triggs, "Enhanced local texture feature sets for
// face recognition under difficult lighting conditions", IEEE TIP 2010: gamma correction,
// difference of Gaussians, two-stage contrast equalisation, tanh compression to (-tau, tau).
struct TanTriggsOptions {
  double gamma = 0.2;
  double sigma_inner = 1.0, sigma_outer = 2.0;
  double alpha = 0.1;
  double tau = 10.0;
  Status check() const;
};
// CV_8UC1 in, CV_32FC1 out (same size; values in (-tau, tau)).
cv::Mat tan_triggs(const cv::Mat& grey, const TanTriggsOptions& options = {});

// Histograms of oriented gradients (N. Dalal, B. Triggs, CVPR 2005; OpenCV's HOGDescriptor) over
// the whole image: cells of cell_px, blocks of 2x2 cells moved by one cell, `bins` unsigned
// orientations, L2-Hys block normalisation. The image side minus the block must be a multiple of
// the cell (checked by HogOptions::check for the given size).
struct HogOptions {
  int cell_px = 8;
  int bins = 9;
  Status check(cv::Size image_size) const;
};
size_t hog_length(cv::Size image_size, const HogOptions& options);
// Appends the descriptor of a CV_8UC1 image to `out`.
void hog_descriptor(const cv::Mat& grey, const HogOptions& options, std::vector<float>& out);

// Shape of the face: the 68 landmarks of an aligned crop of side `size`, as (x / size - 0.5,
// y / size - eye_row) pairs (136 values), appended to `out`. Empty landmarks append zeros.
void landmark_geometry(const std::vector<cv::Point2d>& crop_landmarks, int size, double eye_row,
                       std::vector<float>& out);
inline constexpr size_t kLandmarkGeometryLength = 136;

}  // namespace dreamsense::vision
