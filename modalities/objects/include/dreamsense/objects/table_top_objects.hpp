#pragma once
// The toys on the table, frame by frame, from the top camera: detection (table_detector.hpp),
// identification (identification.hpp), association into tracks with a history (D4.2 V21, V22,
// V25, V26), 3-D positions on the table plane, and the geometry the primitives need:
// getObjects (F13/F14), getObjectTableDistance (F15), getGripLocation (F8), identifyObject (F19),
// trackObject (F25).
//
// Tracking. Each frame the candidates are matched to the tracks by the overlap of their boxes
// with the tracks' predicted boxes (constant velocity in the image). A candidate nobody claims is
// identified; a known toy that reappears is given back its old track (re-detection after an
// occlusion or after leaving the view). A track without a candidate (a hand over the toy, the toy
// pushed together with an arm) is carried by the `dreamsense` visual tracker, started on the last
// frame it was seen in, for at most `max_missing_frames`; then it is dropped. Identities are a
// vote over the track's identifications, so one bad crop does not rename a toy.
//
// 3-D. The top face's centre lies on the table plane raised by the toy's height; the box centre
// of a blob (top face plus the visible sides) is the projection of the toy's mid-height centre,
// so the ray through it is cut with the plane raised by half the height and the point lifted by
// the other half. Without depth this assumes the toy rests on the table (getObjectTableDistance
// then reports `measured = false`).

#include "dreamsense/core/camera_model.hpp"
#include "dreamsense/geometry/plane.hpp"
#include "dreamsense/objects/identification.hpp"
#include "dreamsense/objects/table_detector.hpp"

#include <deque>
#include <map>
#include <memory>
#include <optional>

namespace dreamsense::objects {

class Tracker;

struct ObjectState {
  int64_t stamp_ns = 0;
  int track_id = -1;
  int id = kUnknownObject;  // DREAM / enrolled id; -1 unknown
  std::string label = "unknown";
  double id_score = 0;                  // fraction of the track's identifications that agree
  cv::Rect2d box;                       // top camera, px
  double image_angle_deg = 0;           // footprint's long side in the image
  std::optional<cv::Vec3d> position_m;  // top face centre (world); needs calibration + table
  std::optional<cv::Vec3d> axis_m;      // unit vector along the top face's long side (world)
  cv::Vec3d velocity_mps{0, 0, 0};
  cv::Vec3d size_m{0.10, 0.075, 0.03};
  bool detected = true;  // false: carried by the visual tracker or predicted
  int missing_frames = 0;
};

struct TableTopObjectsOptions {
  TableTopDetectorOptions detector;
  std::string identifier = "gallery";  // "gallery" (ours) or "hog_svm" (the seed's)
  int reidentify_every = 10;           // frames between re-identifications of a matched toy
  double match_iou = 0.2;              // candidate <-> predicted track box
  int max_missing_frames = 45;         // then the track is dropped
  bool visual_tracker = true;          // carry undetected toys with the `dreamsense` tracker
  int confirm_frames = 3;              // an unknown blob is reported after this many frames
  size_t history = 300;                // states kept per track (V26)
  double velocity_window_s = 0.5;      // velocity: least-squares line over this much history
  // Areas of plausible toys follow from the calibration when there is one: a top face between
  // min_side_m and max_side_m at the table's distance.
  double min_side_m = 0.03, max_side_m = 0.30;
  Status check() const;
};

class TableTopObjects {
 public:
  // `gallery` may be null: then every toy is `unknown`. Without `camera` or `table` there are
  // no 3-D positions (image boxes only).
  static Result<std::unique_ptr<TableTopObjects>> create(
      const TableTopObjectsOptions& options, std::shared_ptr<const ObjectGallery> gallery,
      std::optional<CameraModel> camera, std::optional<geometry::Plane> table);
  ~TableTopObjects();

  // One top-camera frame (BGR). Returns the toys currently on the table (confirmed tracks).
  Result<std::vector<ObjectState>> process(const cv::Mat& bgr, int64_t stamp_ns);
  // The states of a track, oldest first (empty for an unknown id).
  const std::deque<ObjectState>& history(int track_id) const;
  const std::optional<geometry::Plane>& table() const { return table_; }
  void reset();

 private:
  TableTopObjects() = default;
  struct Track;
  void finish_state(Track& t, int64_t stamp_ns);

  TableTopObjectsOptions o_;
  std::shared_ptr<const ObjectGallery> gallery_;
  std::optional<CameraModel> camera_;
  std::optional<geometry::Plane> table_;
  TableTopDetector detector_;
  std::vector<std::unique_ptr<Track>> tracks_;
  std::map<int, std::deque<ObjectState>> histories_;
  cv::Mat previous_;
  int64_t previous_stamp_ = 0;
  int next_track_ = 0;
  uint64_t frame_ = 0;
};

// ---- geometry of one object (pure functions) ----

// F15: heights above the table plane. `top_m` = the top face's height; `lift_m` = the bottom's
// (0 for a toy resting on the table). `measured` = false when the position was computed assuming
// the toy rests on the table (no depth), so `lift_m` is 0 by construction.
struct TableDistance {
  double top_m = 0;
  double lift_m = 0;
  bool measured = false;
};
std::optional<TableDistance> table_distance(const ObjectState& object, const geometry::Plane& table,
                                            bool measured = false);

// F8: where a robot hand should grip the toy. Rule (DREAM had none): a pinch from above
// across the top face's short side, at mid-height: point = top-face centre lowered by half the
// height; approach = down the table normal; closing axis = horizontal, perpendicular to the long
// side; opening = the short side + clearance. When the short side does not fit the hand's
// opening but the long side does, it grips across the long side; when neither fits, nullopt.
struct GripOptions {
  double max_opening_m = 0.12;
  double clearance_m = 0.02;
  Status check() const;
};
struct Grip {
  cv::Vec3d point_m;
  cv::Vec3d approach;      // unit, world
  cv::Vec3d closing_axis;  // unit, world
  double opening_m = 0;
};
std::optional<Grip> grip_location(const ObjectState& object, const geometry::Plane& table,
                                  const GripOptions& options = {});

// F25: position after `dt_s` by a constant-velocity model: a least-squares line through the
// track's positions over the last `window_s` (at least two states; one: it stays), evaluated at
// the last stamp + dt_s and kept on the plane of the track's last position parallel to the table.
std::optional<cv::Vec3d> predict_position(const std::deque<ObjectState>& history, double dt_s,
                                          double window_s = 0.5,
                                          const std::optional<geometry::Plane>& table = {});

// Least-squares velocity (m/s) over the last `window_s` of a history (0 with < 2 states).
cv::Vec3d estimate_velocity(const std::deque<ObjectState>& history, double window_s);

// F13/F14: the objects whose position is within `radius_m` of `centre_m`, measured in the table
// plane (the height above the table is ignored), nearest first.
std::vector<ObjectState> objects_in_circle(const std::vector<ObjectState>& objects,
                                           const cv::Vec3d& centre_m, double radius_m,
                                           const geometry::Plane& table);

}  // namespace dreamsense::objects
