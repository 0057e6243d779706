#pragma once
// Camera selection (D4.2 Camera Selection Module): the camera with the best face, i.e. highest
// detection score and most frontal, with hysteresis so that the choice does not flicker.

#include "dreamsense/core/status.hpp"
#include "dreamsense/perception/face_detection.hpp"

#include <optional>
#include <vector>

namespace dreamsense::face_detection {

// Faces scoring at least this are "confident": they compete on frontalness alone. (The score of
// a tracked face depends on the scale it was searched at, ROI or full frame, so it is not
// compared finely between cameras.)
inline constexpr float kConfidentFaceScore = 0.5f;
// Selection criterion of one face, in [0, 1]: frontalness x min(1, score / kConfidentFaceScore).
float selection_quality(const DetectedFace& face);

// Head yaw of the face relative to each camera (degrees, 0 = facing it), from a head pose: the
// D4.2 criterion "the most frontal face image is the image that has the smallest angle of yaw".
// Only for the face whose box holds the projected head position.
struct HeadYawHint {
  SensorId camera;
  cv::Rect2d face_box_px;  // the face it applies to (the box that holds the head's projection)
  double yaw_deg = 0;
};

// Frontalness from a head yaw relative to the camera: clamp(1 - |yaw| / 90, 0, 1).
float frontalness_from_yaw(double yaw_deg);

// Quality of a face from its head yaw instead of the frontalness proxy: frontalness_from_yaw(yaw)
// in [0, 1] (the detection score does not enter: see camera_selection.cpp).
float selection_quality_from_yaw(const DetectedFace& face, double yaw_deg);

struct CameraSelectorOptions {
  // Another camera replaces the current one only when its best face's quality exceeds the
  // current camera's by more than switch_margin for switch_ticks consecutive updates. If the
  // current camera has no face (or no frame) in an update, the best other camera takes over at
  // once.
  double switch_margin = 0.05;
  int switch_ticks = 2;
  // The same rule when both cameras are rated from the head yaw (a pose is more reliable than
  // the proxy, so a smaller margin suffices): 0.02 = 1.8 deg of yaw.
  double yaw_switch_margin = 0.02;
  int yaw_switch_ticks = 1;
  Status check() const;
};

class CameraSelector {
 public:
  explicit CameraSelector(CameraSelectorOptions options = {});
  // Chooses among the cameras of `detections` that have a face; nullopt when none has one.
  // Ties are broken by camera id order (deterministic). Faces with a yaw hint are rated by
  // selection_quality_from_yaw, the others by selection_quality.
  std::optional<SelectedCamera> update(const FaceDetections& detections,
                                       const std::vector<HeadYawHint>& yaw_hints = {});
  void reset();
  const CameraSelectorOptions& options() const { return options_; }

 private:
  CameraSelectorOptions options_;
  std::optional<SensorId> current_;
  std::optional<SensorId> challenger_;
  int challenger_ticks_ = 0;
};

}  // namespace dreamsense::face_detection
