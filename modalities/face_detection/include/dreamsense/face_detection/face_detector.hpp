#pragma once
// Viola-Jones face detection on one image (OpenCV cascades from Debian's opencv-data), with a
// detection score and a frontalness proxy per face. Method, models and measured numbers:
// modalities/face_detection/README.md.

#include "dreamsense/core/status.hpp"
#include "dreamsense/perception/face_detection.hpp"

#include <opencv2/core.hpp>

#include <filesystem>
#include <memory>
#include <optional>
#include <vector>

namespace dreamsense::face_detection {

struct FaceDetectorOptions {
  // Frontal cascade; DREAM used haarcascade_frontalface_alt2.xml (Debian package opencv-data).
  std::filesystem::path frontal_cascade =
      "/usr/share/opencv4/haarcascades/haarcascade_frontalface_alt2.xml";
  // Profile cascade (detects faces whose nose points to the image left; run on the mirrored
  // image too for the other side). Used only when use_profile is true, and only in a search
  // region where the frontal cascade found nothing.
  std::filesystem::path profile_cascade =
      "/usr/share/opencv4/haarcascades/haarcascade_profileface.xml";
  bool use_profile = false;
  // Images wider than this are shrunk by an integer factor k = ceil(width / detection_width)
  // (block average) before detection: 1280x960 -> 320x240 with the default.
  int detection_width = 320;
  // Cascade pyramid step. 1.05 rather than OpenCV's usual 1.1: turned faces (35-45 deg of yaw)
  // collect too few windows at the coarser step (demo seed 77: recall 0.966 -> 0.981, no false
  // positives; pipeline 44 -> 34 fps).
  double scale_factor = 1.05;
  // A face is a cluster of at least this many raw cascade windows (OpenCV's minNeighbors + 1).
  int min_neighbors = 3;
  // Face sizes searched, in full-resolution pixels; max_face_px 0 = up to the image height.
  // (The lower bound is also limited by the cascade window: 20 px at the detection scale.)
  double min_face_px = 80;
  double max_face_px = 0;
  // score = 1 - exp(-neighbours / score_neighbours): 3 windows 0.31, 8 0.63, 20 0.92, 30 0.98.
  double score_neighbours = 8;
  double min_score = 0;  // faces scoring below this are dropped
  // Frontalness proxy (see README): the frontal cascade is re-run on the face, stretched
  // horizontally by each factor of frontalness_stretches, with the face frontalness_patch_px
  // wide; c = response-weighted mean of ln(stretch) (a turned face is foreshortened, so it
  // answers best when stretched); frontalness = clamp(1 - c / frontalness_log_range, 0, 1).
  bool estimate_frontalness = true;
  std::vector<double> frontalness_stretches{0.85, 1.0, 1.15, 1.3, 1.5};
  double frontalness_patch_px = 48;
  double frontalness_log_range = 0.3;
  float profile_frontalness = 0.1f;  // frontalness given to profile-cascade faces
  Status check() const;
};

// A search restricted to part of the image and to a range of face sizes (ROI tracking). With
// min_face_px set, the region is shrunk further than detection_width asks, so that a face of
// min_face_px is about the cascade window (20 px): cheaper, and as reliable for a known face.
struct SearchRegion {
  cv::Rect region_px;                       // full-resolution pixels; clipped to the image
  double min_face_px = 0, max_face_px = 0;  // 0 = the detector's own limits
  // false: the image is shrunk as for a full-frame search (detection_width only), so the cascade
  // windows at the sizes searched are exactly those of a full-frame search; only the sizes
  // outside [min_face_px, max_face_px] are skipped.
  bool shrink_to_min_face = true;
};

// Detects faces in one image. Holds OpenCV cascades, which are not safe to use from two threads
// at once: give each thread (camera) its own FaceDetector.
class FaceDetector {
 public:
  static Result<FaceDetector> create(const FaceDetectorOptions& options);
  FaceDetector(FaceDetector&&) noexcept;
  FaceDetector& operator=(FaceDetector&&) noexcept;
  ~FaceDetector();

  // Faces in `image` (CV_8UC1, CV_8UC3 BGR or CV_8UC4 BGRA; any size), best score first, boxes
  // in `image` pixels. With `search`, only faces whose box centre lies in search->region_px are
  // returned. An empty or unusable (too small, wrong depth) image gives an empty list.
  // `with_frontalness` overrides options().estimate_frontalness (when false, frontal faces get
  // frontalness 1 and the caller may fill it with frontalness()).
  std::vector<DetectedFace> detect(const cv::Mat& image,
                                   const std::optional<SearchRegion>& search = std::nullopt,
                                   std::optional<bool> with_frontalness = std::nullopt);
  // The frontalness proxy of a face box in `image` (see FaceDetectorOptions), in [0, 1].
  float frontalness(const cv::Mat& image, const cv::Rect2d& box_px);
  const FaceDetectorOptions& options() const;

 private:
  struct Impl;
  explicit FaceDetector(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

// Intersection over union of two boxes (0 when either is empty).
double box_iou(const cv::Rect2d& a, const cv::Rect2d& b);

}  // namespace dreamsense::face_detection
