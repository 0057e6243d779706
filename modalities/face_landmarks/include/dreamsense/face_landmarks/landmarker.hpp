#pragma once
// Facial landmarks on a face box: the Landmarker interface (so another landmarker can replace
// dlib) and the dlib 68-point ensemble-of-regression-trees implementation (Kazemi & Sullivan,
// CVPR 2014). Method and numbers: modalities/face_landmarks/README.md.

#include "dreamsense/core/status.hpp"

#include <opencv2/core.hpp>

#include <filesystem>
#include <memory>
#include <optional>
#include <string_view>
#include <vector>

namespace dreamsense::face_landmarks {

// Fits landmarks to one face. fit() is const and may be called from several threads at once.
class Landmarker {
 public:
  virtual ~Landmarker() = default;
  virtual std::string_view name() const = 0;
  virtual int point_count() const = 0;
  // `image`: CV_8UC3 BGR or CV_8UC1 grey, full resolution; `box_px`: the face box in it (any
  // detector's convention; the dlib implementation re-derives its own box, see options).
  // Returns point_count() points in `image` pixels (iBUG 300-W order for 68 points), or nullopt
  // when the box is too small, mostly outside the image, or has no contrast (absence, not an
  // error). An unsupported image type is an error.
  virtual Result<std::optional<std::vector<cv::Point2d>>> fit(const cv::Mat& image,
                                                              const cv::Rect2d& box_px) const = 0;
};

struct DlibLandmarkerOptions {
  // dlib's 68-point model trained on iBUG 300-W (Debian package libdlib-data).
  std::filesystem::path model = "/usr/share/dlib/shape_predictor_68_face_landmarks.dat";
  // The model was trained on dlib HOG-detector boxes. After the first fit on the given box, the
  // box is re-derived from the fitted points (the box that maps the model's mean shape onto the
  // points' extent) and the fit repeated this many times; 0 = use the given box only.
  int refit_passes = 1;
  double min_box_px = 20;       // boxes narrower than this: nullopt (too few pixels per landmark)
  double min_contrast = 4.0;    // grey-level standard deviation inside the box below this: nullopt
  double min_box_inside = 0.5;  // fraction of the box area that must lie inside the image
  Status check() const;
};

// Loads the model (~100 MB, about a second): create once and share. A missing model file is an
// error naming the file and the Debian package.
Result<std::unique_ptr<Landmarker>> make_dlib_landmarker(const DlibLandmarkerOptions& options = {});

}  // namespace dreamsense::face_landmarks
