#pragma once
// World gaze rays from eye centres, landmarks and head pose: eq. (4) per eye (eye_angles.hpp),
// composed with the head rotation (world_from_head, which already contains the camera's
// extrinsics), both eyes fused by averaging their directions (the DREAM Paladyn paper).

#include "dreamsense/core/camera_model.hpp"
#include "dreamsense/gaze/eye_angles.hpp"
#include "dreamsense/gaze/eyeball_model.hpp"
#include "dreamsense/perception/eye_centers.hpp"
#include "dreamsense/perception/face_landmarks.hpp"
#include "dreamsense/perception/gaze.hpp"
#include "dreamsense/perception/head_pose.hpp"

#include <filesystem>
#include <optional>
#include <string>

namespace dreamsense::gaze {

enum class GazeMethod {
  kEq4,     // D4.2 eq. (4) on the pupil offset from the eye-corner midpoint (eye_angles.hpp)
  kEyeball  // the pupil ray on a 3-D eyeball rigid with the head (eyeball_model.hpp)
};

struct GazeEstimatorOptions {
  GazeMethod method = GazeMethod::kEq4;
  OffsetPlane plane = OffsetPlane::kHeadPlane;
  // Fitted on demo seeds that are not evaluated (README.md: `dreamsense train gaze`).
  EyeAngleModel right_eye;
  EyeAngleModel left_eye;
  // Half the distance between the eyeball centres (a child's interpupillary distance is about
  // 50-55 mm, an adult's 63 mm); the per-eye ray origins are at +-this along head x.
  double half_ipd_m = 0.029;
  // kEyeball: the subject's eyeballs (fitted by `dreamsense train gaze`; no useful default).
  EyeballModel right_eyeball{{-0.029, 0, 0.012}, 0.012};
  EyeballModel left_eyeball{{0.029, 0, 0.012}, 0.012};
  Status check() const;
};

// Gaze of the selected face. `pupils`: from the eye-centre locator; eyes with found = false get
// invalid rays; `both` is valid when at least one eye is. nullopt when no eye is usable.
std::optional<EyeGaze> estimate_gaze(const FaceLandmarks& landmarks, const EyeCenters& pupils,
                                     const HeadPose& head, const CameraModel& camera,
                                     const GazeEstimatorOptions& options);

// The normalised offsets of both eyes (right, left) as used by estimate_gaze; for fitting.
struct EyeOffsets {
  std::optional<cv::Vec2d> right, left;
};
EyeOffsets eye_offsets(const FaceLandmarks& landmarks, const EyeCenters& pupils,
                       const HeadPose& head, const CameraModel& camera, OffsetPlane plane);

// Gaze model file (YAML, written by `dreamsense train gaze`): format "dreamsense-gaze-model",
// version 1, the plane the offsets were measured in, the head-model rotation offset of the
// subject, one EyeAngleModel per eye, optionally one EyeballModel per eye (right_eyeball,
// left_eyeball: centre_head_m [x, y, z], radius_m), and a free-text provenance.
struct GazeModelFile {
  OffsetPlane plane = OffsetPlane::kHeadPlane;
  // When both are present the file selects GazeMethod::kEyeball, else kEq4.
  std::optional<EyeballModel> right_eyeball, left_eyeball;
  // Subject calibration of the head pose (HeadPoseAnalyzerOptions::model_from_head).
  cv::Matx33d model_from_head = cv::Matx33d::eye();
  EyeAngleModel right_eye, left_eye;
  std::string provenance;
  int samples = 0;
  // The eyeballs were placed by anatomy, not fitted to known targets: the gaze analyser learns
  // their sideways bias from fixations on the robot (FixationYawOptions::enabled; key
  // `fixation_yaw`, written by the self-calibration).
  bool fixation_yaw = false;
  // The sideways correction an earlier session of this child learnt for these eyeballs (deg; key
  // `fixation_yaw_start_deg`, written by `analyze --save-subject`): applied from the first tick
  // until this session's own fixations take over (FixationYawOptions::start_deg).
  double fixation_yaw_start_deg = 0;
};
Status write_gaze_model(const std::filesystem::path& path, const GazeModelFile& model);
Result<GazeModelFile> read_gaze_model(const std::filesystem::path& path);

}  // namespace dreamsense::gaze
