#pragma once
// Reading face images of the datasets as grey: everything OpenCV decodes (PNG, JPEG, PGM, ... by
// content, whatever the file name), plus GIF (the Yale faces are GIF files named
// subjectNN.condition, which OpenCV 4.6 cannot decode) through giflib.

#include "dreamsense/core/status.hpp"

#include <opencv2/core.hpp>

#include <filesystem>

namespace dreamsense::vision {

// CV_8UC1 image; a missing, unreadable or undecodable file is an error naming it.
Result<cv::Mat> read_grey_image(const std::filesystem::path& path);
// The first frame of a GIF file as grey (palette mapped, luma of the RGB entries).
Result<cv::Mat> read_gif_grey(const std::filesystem::path& path);
// Writes a grey image as a GIF (256-level grey palette); for tests and synthetic Yale sets.
Status write_gif_grey(const std::filesystem::path& path, const cv::Mat& grey);

}  // namespace dreamsense::vision
