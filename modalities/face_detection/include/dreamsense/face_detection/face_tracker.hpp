#pragma once
// Per-camera ROI tracking around FaceDetector: after a face is found, the next frames are searched
// only around it (and only at similar sizes); the full frame is searched every
// full_search_interval frames (new faces), and whenever nothing is tracked.

#include "dreamsense/face_detection/face_detector.hpp"
#include "dreamsense/perception/face_detection.hpp"

#include <functional>
#include <optional>
#include <vector>

namespace dreamsense::face_detection {

struct FaceTrackerOptions {
  // Full-frame search at least every this many frames while faces are tracked (finds new faces).
  int full_search_interval = 25;
  // Offset of the periodic full search, in frames, so that several cameras do not all search
  // their full frame in the same tick (the analyser spreads its cameras over the interval).
  int full_search_phase = 0;
  // While nothing is tracked: full search every this many frames (1 = every frame).
  int lost_search_interval = 1;
  // Search region = last box grown by roi_margin x its size on every side.
  double roi_margin = 0.75;
  // Face sizes searched around a tracked face, relative to its last size.
  double roi_min_scale = 0.6, roi_max_scale = 1.6;
  // If the tracked faces are all missed in their regions, search the full frame at once (same
  // frame) before reporting nothing.
  bool full_search_on_miss = true;
  // Detections overlapping more than this (IoU) are the same face; the better score is kept.
  double merge_iou = 0.3;
  // The frontalness proxy (FaceDetector::frontalness, the costly part) of a tracked face is
  // re-estimated every this many frames and carried over in between (1 = every frame); a new
  // face always gets a fresh estimate. Ignored when the detector's estimate_frontalness is off.
  int frontalness_interval = 2;
  Status check() const;
};

struct TrackedFrameFaces {
  std::vector<DetectedFace> faces;  // best score first; empty = nothing found
  bool full_search = false;         // the full frame was searched for this frame
};

// Frontalness known without the proxy, e.g. from a head pose: called for each frontal-cascade
// face with the frame's final faces (best score first) and that face's index; returns the
// frontalness to give that face, or nullopt to use the proxy. A face with a known value skips the
// proxy (the costly part of a tracked frame); its track is marked so that the proxy is re-estimated
// in the first later frame where the value is not known.
using KnownFrontalness =
    std::function<std::optional<float>(const std::vector<DetectedFace>& faces, size_t index)>;

// One camera's face detection with ROI tracking. Not thread-safe; one per camera.
class FaceTracker {
 public:
  FaceTracker(FaceDetector detector, FaceTrackerOptions options);
  // Detects faces in the next frame of this camera. With `known`, faces it answers for get its
  // value instead of the frontalness proxy (also when the detector's estimate_frontalness is off).
  TrackedFrameFaces process(const cv::Mat& image, const KnownFrontalness& known = {});
  // Forget tracked faces (the next frame gets a full search).
  void reset();
  const FaceTrackerOptions& options() const { return options_; }

 private:
  FaceDetector detector_;
  FaceTrackerOptions options_;
  struct Track {
    cv::Rect2d box;
    float frontalness = 1.f;
    int frontalness_age = 0;  // frames since frontalness was estimated
  };
  std::vector<Track> tracked_;
  cv::Size last_size_;
  int64_t frame_index_ = 0;
  int64_t frames_since_full_ = 0;
};

}  // namespace dreamsense::face_detection
