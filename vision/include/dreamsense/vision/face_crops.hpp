#pragma once
// Alignment of images that are already face crops (CK+48, FER2013, AT&T, Yale) or small photos
// of one person (enrolment). The face detector and the landmarker are injected as functions, so
// this base library does not depend on the analysers; vision/face_locator.hpp wires in the
// project's Viola-Jones cascade (modalities/face_detection) and dlib 68-point landmarker
// (modalities/face_landmarks).
//
// Order of attempts (AlignedFace::source says which one succeeded):
//  1. the image is scaled so that its shorter side is working_px; the finder's largest face
//     (at least min_face_fraction of the shorter side) gets landmarks; if they are plausible
//     (eye distance, roll, mouth below the eyes, see FaceCropOptions) -> kLandmarks;
//  2. assume_crop only: landmarks fitted on crop_face_box (the face is assumed to fill the crop);
//     if plausible -> kLandmarksFromCrop;
//  3. assume_crop only: kCropGeometry, the crop warped as if its eyes were at (crop_eye_row,
//     0.5 -/+ crop_eye_distance / 2) of its size: the typical geometry of tight face crops
//     (CK+48, FER2013), documented rather than guessed per image.
// An empty, tiny (< min_image_px) or flat (grey-level standard deviation < min_contrast) image
// has no face (nullopt, not an error); an unsupported image type is an error.

#include "dreamsense/core/status.hpp"
#include "dreamsense/vision/face_alignment.hpp"

#include <opencv2/core.hpp>

#include <functional>
#include <optional>
#include <vector>

namespace dreamsense::vision {

struct FaceCropOptions {
  AlignmentOptions alignment;
  // Scale of the search: shorter side of the image brought to this many px (48 px crops x3.3;
  // dlib's landmarker and the cascade want faces of ~100 px).
  int working_px = 160;
  // Images are face crops: fall back to steps 2 and 3 when nothing is detected. false (photos):
  // a face must be detected.
  bool assume_crop = true;
  // Detections narrower than this fraction of the working image's shorter side are ignored.
  double min_face_fraction = 0.3;
  // Step 2: the face box assumed in a crop, relative to the crop (x, y, width, height).
  cv::Rect2d crop_face_box{0.0, 0.0, 1.0, 1.0};
  // Plausible landmarks: eye distance / box width in [min_eye_distance, max_eye_distance],
  // eye-line roll <= max_roll_deg, mouth centre at least min_mouth_drop eye distances below the
  // eye line (in the eye-aligned frame), every point within the box grown by half its size.
  double min_eye_distance = 0.2, max_eye_distance = 0.75;
  double max_roll_deg = 35;
  double min_mouth_drop = 0.5;
  // Step 3 geometry (fractions of the crop's width / height).
  double crop_eye_row = 0.38, crop_eye_distance = 0.42;
  int min_image_px = 24;
  double min_contrast = 4.0;
  Status check() const;
};

// Face boxes in a grey image, best first (may be empty).
using FaceFinder = std::function<Result<std::vector<cv::Rect2d>>(const cv::Mat& grey)>;
// 68 landmarks in a grey image from a face box, or nullopt when it rejects the box.
using LandmarkFitter = std::function<Result<std::optional<std::vector<cv::Point2d>>>(
    const cv::Mat& grey, const cv::Rect2d& box)>;

// Plausibility test of step 1/2 (exposed for tests).
bool plausible_landmarks(const std::vector<cv::Point2d>& landmarks, const cv::Rect2d& box,
                         const FaceCropOptions& options);

// Not thread-safe when the injected functions are not (the cascade is not): one per thread.
class FaceCropAligner {
 public:
  // Either function may be empty: that step is skipped.
  FaceCropAligner(FaceCropOptions options, FaceFinder finder, LandmarkFitter fitter);
  Result<std::optional<AlignedFace>> align(const cv::Mat& image) const;
  const FaceCropOptions& options() const { return options_; }

 private:
  FaceCropOptions options_;
  FaceFinder finder_;
  LandmarkFitter fitter_;
};

}  // namespace dreamsense::vision
