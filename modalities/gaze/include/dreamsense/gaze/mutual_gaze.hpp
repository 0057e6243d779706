#pragma once
// Mutual gaze with the robot (F1), in both DREAM modes (spec/primitives.md):
//  - 3-D: the gaze ray passes within `radius_m` of the robot head (a point in world);
//  - camera plane (DREAM's shipped setting): the gaze ray, in the reference camera's frame, hits
//    the plane z = 0 of that camera inside a rectangle (DREAM: x in [-180, 70] mm,
//    y in [-50, 450] mm).
// A hold rule turns the per-frame test into a stable state: mutual gaze starts after the test
// has held for `onset_s` and ends after it has failed for `release_s`; `held_s` counts how long
// the state has lasted (D1.3 asks for a ~3 s hold option: compare held_s with it).

#include "dreamsense/core/camera_model.hpp"
#include "dreamsense/core/timestamp.hpp"
#include "dreamsense/perception/gaze.hpp"

#include <optional>

namespace dreamsense::gaze {

enum class MutualGazeMode { k3d, kCameraPlane };

struct MutualGazeOptions {
  MutualGazeMode mode = MutualGazeMode::k3d;
  cv::Vec3d robot_head_m{0.0, -0.14, 0.13};  // DREAM's RobotHead (mm -> m); set per setup
  double radius_m = 0.20;                    // DREAM's GazeRadius
  // Camera-plane mode: rectangle in the reference camera's frame (metres).
  double rect_x_min_m = -0.18, rect_x_max_m = 0.07, rect_y_min_m = -0.05, rect_y_max_m = 0.45;
  double onset_s = 0.04;    // test must hold this long before mutual gaze starts
  double release_s = 0.12;  // and fail this long before it ends (blinks, one-frame misses)
  // Eye contact shows the pupils: when the eye-centre locator has a pupil stage and found the
  // pupil in neither eye, the frame's test fails whatever the gaze ray says. Eyes whose pupils
  // are hidden under the lids look down (toys, table), and there the iris-centre gaze is
  // biased upwards (modalities/gaze/README.md, "Mutual gaze needs a visible pupil").
  bool require_visible_pupil = true;
  Status check() const;
};

// Per-frame tests. `miss_m` receives the distance by which the test missed (0 when it passed).
bool gaze_hits_robot_3d(const GazeRay& ray, const MutualGazeOptions& options, double& miss_m);
bool gaze_hits_camera_rect(const GazeRay& ray, const CameraModel& reference_camera,
                           const MutualGazeOptions& options, double& miss_m);

// The hold rule over time.
class MutualGazeTracker {
 public:
  explicit MutualGazeTracker(MutualGazeOptions options) : options_(options) {}
  // One observation; `raw` = this frame's test. Returns the state after it.
  MutualGaze update(Timestamp stamp, bool raw, double miss_m);
  // No gaze observed (no face): the state is dropped.
  void reset();

 private:
  MutualGazeOptions options_;
  bool state_ = false;
  Timestamp state_since_ = Timestamp::unset();
  Timestamp pending_since_ = Timestamp::unset();  // raw disagreeing with state since
};

}  // namespace dreamsense::gaze
