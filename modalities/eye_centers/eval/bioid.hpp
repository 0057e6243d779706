#pragma once
// The BioID face database layout (O. Jesorsky, K. Kirchberg, R. Frischholz, "Robust face
// detection using the Hausdorff distance", AVBPA 2001): BioID_NNNN.pgm (384x286 grey) and
// BioID_NNNN.eye, a text file
//   #LX	LY	RX	RY
//   232	110	161	110
// where L is the PERSON's left eye, i.e. the eye on the image RIGHT (larger x), and R the
// person's right eye (image left). BioID writes integers; the synthetic set writes two decimals.
// Pixel centres are at integer coordinates.

#include "dreamsense/core/status.hpp"

#include <opencv2/core.hpp>

#include <filesystem>
#include <string>
#include <vector>

namespace dreamsense::eye_centers {

struct BioIdEyes {
  cv::Point2d left_px;   // the subject's left eye (LX, LY; image right)
  cv::Point2d right_px;  // the subject's right eye (RX, RY; image left)
};

struct BioIdItem {
  std::string id;  // "BioID_0000"
  std::filesystem::path image;
  BioIdEyes eyes;
};

// Parses one .eye file (header line starting with '#', then four numbers).
Result<BioIdEyes> read_bioid_eye_file(const std::filesystem::path& path);
Status write_bioid_eye_file(const std::filesystem::path& path, const BioIdEyes& eyes);

// Every BioID_*.pgm in `dir` with its .eye file, sorted by name. No images is kNotFound; an image
// without a readable .eye file is kCorruptData naming the file.
Result<std::vector<BioIdItem>> load_bioid(const std::filesystem::path& dir);

}  // namespace dreamsense::eye_centers
