#pragma once
// Facial landmarks on a face box: the Landmarker interface (so another landmarker can replace
// dlib) and the dlib 68-point ensemble-of-regression-trees implementation (Kazemi & Sullivan,
// CVPR 2014). Method and numbers: modalities/face_landmarks/README.md.

#include "dreamsense/core/status.hpp"

#include <opencv2/core.hpp>

#include <filesystem>
#include <limits>
#include <memory>
#include <optional>
#include <string_view>
#include <vector>

namespace dreamsense::face_landmarks {

// A fit with its consistency: `spread` = mean distance of the points of the separate fits (the
// initialisations, or the last two box re-derivation passes) from the returned points, divided by
// the outer-eye-corner distance of the returned points (68-point models; NaN when there was one
// fit only). A face the model cannot explain (occluded, turned beyond the model) gives fits that
// disagree: a large spread is a low confidence (README "Real faces").
struct LandmarkFit {
  std::vector<cv::Point2d> points;
  double spread = std::numeric_limits<double>::quiet_NaN();
};

// Confidence of a fit from its spread: 1 up to spread_ok, falling linearly to 0 at spread_bad;
// 1 for a NaN spread (one fit, nothing to compare). On AFW (300-W annotations) the pipeline's
// landmarker spread (refit_passes 1) ranks failed fits (NME > 0.08) above good ones with ROC AUC
// 0.98, and no fit with spread <= 0.03 failed (README "Real faces").
double spread_confidence(double spread, double spread_ok = 0.03, double spread_bad = 0.10);

// Mean distance of `points` from `other` (same size, 68 points), over the distance of points'
// outer eye corners (36, 45): a spread of two landmarkers' fits of one face. +inf when the
// corners coincide.
double mean_point_distance(const std::vector<cv::Point2d>& points,
                           const std::vector<cv::Point2d>& other);

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
  // fit() with the spread of the fits (see LandmarkFit). Default: fit(), spread NaN.
  virtual Result<std::optional<LandmarkFit>> fit_with_spread(const cv::Mat& image,
                                                             const cv::Rect2d& box_px) const;
  // The box in this landmarker's own convention for a face whose landmarks span `extent` (the
  // bounding box of its points), e.g. to start from annotated points. Default: `extent`.
  virtual cv::Rect2d box_for_extent(const cv::Rect2d& extent) const { return extent; }
};

struct DlibLandmarkerOptions {
  // dlib's 68-point model trained on iBUG 300-W (Debian package libdlib-data).
  std::filesystem::path model = "/usr/share/dlib/shape_predictor_68_face_landmarks.dat";
  // The model was trained on dlib HOG-detector boxes. After the first fit on the given box, the
  // box is re-derived from the fitted points (the box that maps the model's mean shape onto the
  // points' extent) and the fit repeated this many times; 0 = use the given box only.
  int refit_passes = 1;
  // Test-time augmentation (off in the pipeline; `eval landmarks` measures it): the cascade is
  // also run from boxes scaled by each factor of box_scales (about the box centre; 1 is always
  // run) and, with mirror, on the mirrored face (points mapped back, left/right swapped); the
  // result is the per-coordinate median of the fits. Each fit costs one more cascade run.
  std::vector<double> box_scales{};
  bool mirror = false;
  double min_box_px = 20;       // boxes narrower than this: nullopt (too few pixels per landmark)
  double min_contrast = 4.0;    // grey-level standard deviation inside the box below this: nullopt
  double min_box_inside = 0.5;  // fraction of the box area that must lie inside the image
  // The regression trees' leaves (~65 MB of floats; loading them is most of a fit's time) held
  // as int16 with one scale per leaf: half the memory traffic, fits ~15-25 % faster. Quantisation
  // moves points by ~1e-4 px, but the cascade is chaotic, so some fits move by tenths of a pixel
  // (accuracy unchanged on AFW and the demo: README "Quantised leaves"). false = dlib's float
  // leaves, bit-identical to dlib's own cascade (the baseline).
  bool quantized_leaves = true;
  Status check() const;
  bool operator==(const DlibLandmarkerOptions&) const = default;
};

// Loads the model (~100 MB, about a second): create once and share. A missing model file is an
// error naming the file and the Debian package.
Result<std::unique_ptr<Landmarker>> make_dlib_landmarker(const DlibLandmarkerOptions& options = {});

// The process's one dlib landmarker for these options, loaded on first use and kept until the
// process ends (thread-safe): the self-calibration and the face_landmarks analyser of one
// analysis share it instead of loading the model twice (about a second of CPU each).
Result<std::shared_ptr<const Landmarker>> shared_dlib_landmarker(
    const DlibLandmarkerOptions& options = {});

// The 68-point CNN of the npm package @vladmandic/face-api (MIT; vision/face_api_net.hpp), as a
// Landmarker: the box is cropped (clipped to the image), padded to a square, run at 112x112; then
// the crop is re-derived from the fitted points (their extent grown by `margin` of its size on
// each side) and the net run again `refit_passes` times. spread = mean distance of the last two
// passes' points / outer-corner distance. Measured against dlib in `eval landmarks` (README "Real
// faces"); not used by the pipeline. fit() serialises calls (one cv::dnn::Net).
struct FaceApiLandmarkerOptions {
  std::filesystem::path model_dir;  // empty = vision::default_face_api_model_dir()
  double margin = 0.1;              // the package's own FaceLandmarks.align() crop margin
  int refit_passes = 1;
  double min_box_px = 20;     // crops narrower or lower than this: nullopt
  double min_contrast = 4.0;  // grey-level s.d. in the first crop below this: nullopt
  Status check() const;
};
// The package's weights missing: kNotFound naming the manifest and the npm package.
Result<std::unique_ptr<Landmarker>> make_face_api_landmarker(
    const FaceApiLandmarkerOptions& options = {});

}  // namespace dreamsense::face_landmarks
