#pragma once
// dlib's HOG + linear SVM frontal face detector (N. Dalal, B. Triggs, CVPR 2005; dlib's trained
// 5-filter model compiled into libdlib, no model file). Turned and side-lit faces are found more
// often than by the Haar cascade, and its boxes are the convention dlib's 68-point landmark model
// was trained on. Slower than the Haar search (README): used by `eval landmarks`, not by the
// pipeline's default detector.

#include "dreamsense/core/status.hpp"
#include "dreamsense/perception/face_detection.hpp"

#include <opencv2/core.hpp>

#include <memory>
#include <vector>

namespace dreamsense::face_detection {

struct HogFaceDetectorOptions {
  // Smallest face searched, in image pixels. dlib's window is 80 px, so the image is enlarged by
  // 80 / min_face_px (capped by max_work_side_px) before the search: 40 -> x2.
  double min_face_px = 40;
  // The (enlarged or reduced) image searched has at most this many pixels on its longer side;
  // huge images are shrunk to it (faces smaller than 80 px there are then not found).
  int max_work_side_px = 1600;
  // Added to dlib's SVM threshold (0 = dlib's default; negative finds more faces, and more false
  // ones).
  double adjust_threshold = 0.0;
  // score = 1 / (1 + exp(-score_slope * (svm_score + 0.5))): dlib's threshold (svm 0) scores 0.73.
  double score_slope = 2.0;
  Status check() const;
};

// Not safe to use from two threads at once (dlib's scanner keeps scratch state): one per thread.
class HogFaceDetector {
 public:
  static Result<HogFaceDetector> create(const HogFaceDetectorOptions& options = {});
  HogFaceDetector(HogFaceDetector&&) noexcept;
  HogFaceDetector& operator=(HogFaceDetector&&) noexcept;
  ~HogFaceDetector();

  // Faces in `image` (CV_8UC1, CV_8UC3 BGR or CV_8UC4 BGRA), best score first, boxes in `image`
  // pixels; frontalness 1 (the detector does not estimate it). Empty or unsupported: empty list.
  std::vector<DetectedFace> detect(const cv::Mat& image);
  const HogFaceDetectorOptions& options() const;

 private:
  struct Impl;
  explicit HogFaceDetector(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace dreamsense::face_detection
