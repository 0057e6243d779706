#pragma once
// Local binary patterns: uniform LBP (P = 8 neighbours on a circle of radius R, bilinear
// interpolation; T. Ojala, M. Pietikainen, T. Maenpaa, "Multiresolution gray-scale and rotation
// invariant texture classification with local binary patterns", PAMI 2002) and grid histograms
// (T. Ahonen, A. Hadid, M. Pietikainen, "Face description with local binary patterns", PAMI 2006)
// - the descriptor of DREAM's FaceAnalysis (elbp + spatial_histogram, 59 bins, 8x8 grid).

#include <opencv2/core.hpp>

#include <vector>

namespace dreamsense::vision {

// Labels of uniform LBP(8, R): 0..57 = the 58 uniform codes (at most two 0/1 transitions around
// the circle) in ascending order of their 8-bit code, 58 = every non-uniform code.
inline constexpr int kUniformLbpBins = 59;
// Label of an 8-bit LBP code.
int uniform_lbp_label(unsigned code);

// Raw 8-bit LBP(8, radius) codes: bit n (n = 0..7) is set when the neighbour at angle 2 pi n / 8
// (x = R cos, y = -R sin; bilinear) is >= the centre (the seed's elbp). Input CV_8UC1 or CV_32FC1;
// output CV_8UC1 of (rows - 2 ceil(R)) x (cols - 2 ceil(R)) (empty when the image is too small).
cv::Mat lbp_codes(const cv::Mat& grey, double radius = 1.0);
// The same codes mapped to uniform labels (0..58).
cv::Mat uniform_lbp_labels(const cv::Mat& grey, double radius = 1.0);

// Histograms of `labels` (values < bins) over a grid of grid_cols x grid_rows cells of
// near-equal size, row by row, each normalised to sum 1 (an empty cell gives zeros); with
// `sqrt_normalise` the square root of each bin (Hellinger). Appended to `out`.
void grid_histograms(const cv::Mat& labels, int bins, int grid_cols, int grid_rows,
                     bool sqrt_normalise, std::vector<float>& out);

}  // namespace dreamsense::vision
