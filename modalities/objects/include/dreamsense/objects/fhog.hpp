#pragma once
// Felzenszwalb's HOG variant ("fHOG": P. Felzenszwalb, R. Girshick, D. McAllester and
// D. Ramanan, "Object Detection with Discriminatively Trained Part-Based Models", TPAMI 32(9),
// 2010, §6.1), in the form correlation-filter trackers use it (Dollar's toolbox `fhog`): per
// cell, 18 contrast-sensitive and 9 contrast-insensitive orientation channels and 4 texture
// (gradient energy) channels, each normalised by the four 2x2-cell blocks around the cell and
// truncated at 0.2. 31 channels (the always-zero truncation channel is left out).

#include <opencv2/core.hpp>

#include <vector>

namespace dreamsense::objects {

inline constexpr int kFhogChannels = 31;

// Cells of a grey image: floor(rows / cell) x floor(cols / cell).
inline cv::Size fhog_cells(cv::Size image, int cell) {
  return {image.width / cell, image.height / cell};
}

// `grey`: CV_8U or CV_32F, one channel. Writes kFhogChannels x cells.height x cells.width floats,
// channel-major, to `out`. Gradients by central differences, orientation linearly interpolated
// between the two nearest of 18 bins, magnitude spread bilinearly over the four nearest cells.
void compute_fhog(const cv::Mat& grey, int cell, float* out);
// The same as one CV_32F map per channel. The maps are views into `storage` (re-used between
// calls of the same size).
void compute_fhog(const cv::Mat& grey, int cell, std::vector<cv::Mat>& channels, cv::Mat& storage);
// Convenience form that owns its storage.
void compute_fhog(const cv::Mat& grey, int cell, std::vector<cv::Mat>& channels);

}  // namespace dreamsense::objects
