#pragma once
// Per-camera ROI tracking around FaceDetector: after a face is found, the next frames are searched
// only around it (and only at similar sizes); the full frame is searched every
// full_search_interval frames (new faces), and whenever nothing is tracked.

#include "dreamsense/face_detection/face_detector.hpp"
#include "dreamsense/perception/face_detection.hpp"

#include <functional>
#include <optional>
#include <utility>
#include <vector>

namespace dreamsense::face_detection {

struct FaceTrackerOptions {
  // Full-frame search at least every this many frames while faces are tracked (finds new faces:
  // a person entering is found within 2 s at 25 fps). It was 25 until landmark-guided frames;
  // 50 halves the costliest searches (README "Landmark-guided frames").
  int full_search_interval = 50;
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
  // only every turned_away_search_interval frames: the frontal cascade rarely finds faces
  // turned that far (demo: 2 of 71 frames at 60-75 deg), and a full search is the costliest
  // step. 45 since 2026-12-02 (was 60): a child whose side cameras lose the face early (glasses)
  // costs a third less face detection, accuracy unchanged on 8 seeds (README.md).
  // turned_away_search_interval = 1 searches every frame as without a head pose (baseline).
  double turned_away_yaw_deg = 45;
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
  // Landmark-guided frames: when every tracked face has a guide (its place in this frame from the
  // landmarks fitted to it in the previous frame, see FaceGuide), the cascade searches its region
  // only every cascade_interval frames and the faces are placed from the guides in between.
  // 1 = the cascade searches every frame (the baseline). A periodic full search still runs when
  // due; without guides (no landmarks) every frame is searched.
  int cascade_interval = 5;
  // A guide whose box overlaps its face's last box by less than this IoU is not used (the face
  // moved far or the fit went astray): the cascade searches that frame.
  double guide_min_iou = 0.5;
  // Rolled faces (head tilted sideways): the frontal cascade finds faces within about +-15
  // degrees of upright. A tracked face whose roll (from its landmarks' eye line, FaceGuide::
  // roll_deg, or the angle it was found at) is at least roll_min_deg is searched in its region
  // rotated upright; when that finds nothing, at its roll +- roll_step_deg before anything else
  // (a head that tilts further). While nothing is tracked and an upright full search finds
  // nothing, the full frame is also searched rotated by +-lost_roll_deg: in the first such frame
  // and every lost_roll_search_interval such frames (a full search costs ~25 ms). roll_step_deg
  // 0 and lost_roll_deg 0 turn the rotated searches off (the baseline: upright only). Gating the
  // steps and the first lost search on how far the face leaned cost the held-out demo child
  // half a point of face recall (README "Tilted heads").
  double roll_min_deg = 10;
  double roll_step_deg = 20;
  double lost_roll_deg = 25;
  int lost_roll_search_interval = 5;
  // ... and only while the head faces this camera within this yaw, when a head pose gives it.
  double lost_roll_max_yaw_deg = 45;
  Status check() const;
};

// Where a tracked face is in this frame, from the landmarks fitted to it in the previous frame.
struct FaceGuide {
  cv::Rect2d tracked_box;  // the face's box as the tracker returned it for the previous frame
  cv::Rect2d box;          // its box in this frame, in the cascade's convention
  // In-plane angle of the face (deg), eye_line_roll_deg of its fit (perception/face_landmarks.hpp).
  double roll_deg = 0;
};

// `box` grown by margin x its larger side on every side (the region searched around a face).
cv::Rect2d grown_by(const cv::Rect2d& box, double margin);

// Faces found in `image` rotated by roll_deg about the centre of `region` (so that a face rolled
// by roll_deg stands upright), searched over `region`'s size around that centre at face sizes
// [min_face_px, max_face_px] (0 = the detector's limits); boxes (axis-aligned, same size) mapped
// back to `image`. roll_deg 0 is the plain search of `region`.
std::vector<DetectedFace> detect_rolled(FaceDetector& detector, const cv::Mat& image,
                                        const cv::Rect& region, double roll_deg,
                                        double min_face_px = 0, double max_face_px = 0);

// How a cascade box sits on the extent (bounding box) of the landmarks fitted from it: centre
// offset in extent sizes and size ratio. Learned on a searched frame, it turns a later fit's
// extent into a box in the cascade's convention (place_box).
struct BoxOnExtent {
  double dx = 0, dy = 0;  // (box centre - extent centre) / extent width, height
  double sx = 1, sy = 1;  // box width / extent width, box height / extent height
};
// nullopt for an empty extent.
std::optional<BoxOnExtent> box_on_extent(const cv::Rect2d& box, const cv::Rect2d& extent);
cv::Rect2d place_box(const BoxOnExtent& relation, const cv::Rect2d& extent);

struct TrackedFrameFaces {
  std::vector<DetectedFace> faces;  // best score first; empty = nothing found
  bool full_search = false;         // the full frame was searched for this frame
  bool guided = false;              // placed from guides, no cascade search in this frame
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
  // `guides`: see FaceTrackerOptions::cascade_interval; a guided face keeps its last score and
  // view.
  TrackedFrameFaces process(const cv::Mat& image, const KnownFrontalness& known = {},
                            std::optional<double> head_yaw_deg = std::nullopt,
                            const std::vector<FaceGuide>& guides = {});
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
    float score = 0.f;
    FaceView view = FaceView::kFrontal;
    double roll_deg = 0;  // the face's in-plane angle (FaceGuide::roll_deg)
  };
  // Searches around one tracked face (narrow sizes, then wide), rotated by roll_deg.
  std::vector<DetectedFace> search_region(const cv::Mat& image, const Track& track,
                                          double roll_deg);
  // The tracked faces placed from `guides`; empty unless every tracked face has a usable guide.
  // (Each with its guide's roll.)
  std::vector<std::pair<DetectedFace, double>> guided_faces(
      const std::vector<FaceGuide>& guides) const;
  std::vector<Track> tracked_;
  cv::Size last_size_;
  int64_t frame_index_ = 0;
  int64_t frames_since_full_ = 0;
  int guided_in_a_row_ = 0;     // frames placed from guides since the last cascade search
  int lost_full_searches_ = 0;  // upright full searches that found nothing, in a row
};

}  // namespace dreamsense::face_detection
