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
  // Sizes searched first around a tracked face (same region); the range above is searched only
  // when this finds nothing. A face 25 % larger or smaller from one frame to the next would have
  // to move at metres per second; the narrow pass costs ~40 % of the wide one (fewer pyramid
  // levels, a smaller image). roi_narrow_first = false searches the wide range at once (baseline).
  bool roi_narrow_first = true;
  double roi_narrow_min_scale = 0.8, roi_narrow_max_scale = 1.25;
  // The narrow pass's faces are kept only if their size changed by at most this fraction (either
  // way) from the last; otherwise the wide range is searched: near the narrow range's edges its
  // windows stop and the box comes out too close to the last size (a face magnified 1.4x came
  // out 1.12x).
  double roi_narrow_max_change = 0.1;
  // While nothing is tracked and the head is known to be turned away from this camera (|yaw|
  // above turned_away_yaw_deg, given by the caller from a head pose), the full frame is searched
  // only every turned_away_search_interval frames: the frontal cascade does not find faces
  // turned that far (demo: 2 of 71 such frames), and a full search is the costliest step.
  // turned_away_search_interval = 1 searches every frame as without a head pose (baseline).
  double turned_away_yaw_deg = 60;
  int turned_away_search_interval = 10;
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
  // `head_yaw_deg`: the head's yaw relative to this camera (0 = facing it), when a head pose
  // gives it; only used to search less often while the face is lost and turned away.
  TrackedFrameFaces process(const cv::Mat& image, const KnownFrontalness& known = {},
                            std::optional<double> head_yaw_deg = std::nullopt);
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
