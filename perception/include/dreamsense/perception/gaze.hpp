#pragma once
// Eye gaze and mutual gaze (modalities/gaze): V7.
// Blackboard types of one modality (perception layer: below the modalities, which never include
// each other's headers). docs/blackboard.md maps the keys onto DREAM's global buffer (V1-V29).

#include "dreamsense/core/blackboard.hpp"
#include "dreamsense/core/sensor_frame.hpp"

#include <map>
#include <optional>
#include <string>
#include <vector>

namespace dreamsense {

// One gaze ray in world. Eye-in-head angles follow the head pose convention
// (perception/head_pose.hpp): direction_head = rotation_from_ypr_deg(theta, phi, 0) * (0, 0, -1),
// so positive theta turns the gaze towards the subject's right (head -x) and positive phi looks
// down.
struct GazeRay {
  bool valid = false;
  // Per eye: the pupil (eyeball method: on the eyeball; eq. 4: the eye's place in the head's
  // frontal plane). Fused: the head's position.
  cv::Vec3d origin_world_m{0, 0, 0};
  cv::Vec3d direction_world{0, 0, -1};  // unit
  double theta_deg = 0;                 // eye-in-head horizontal angle (D4.2 eq. 4)
  double phi_deg = 0;                   // eye-in-head vertical angle
  cv::Vec2d features{0, 0};             // the normalised pupil offset eq. (4) was applied to
};

// Eye gaze of the selected face: each eye from its pupil centre, and both eyes fused.
struct EyeGaze {
  SensorId camera;  // the camera whose image was used
  Timestamp frame_stamp;
  GazeRay right;  // the subject's right eye
  GazeRay left;
  GazeRay both;  // fused: origin between the eyes, mean direction of the valid eyes
  std::string method;
  // Eye-in-head yaw (deg) added to every ray: the bias learnt from fixations on the robot
  // (gaze/fixation_yaw.hpp); 0 when off or still learning.
  double fixation_yaw_deg = 0;
};

// Mutual gaze with the robot (F1). `mutual` applies the hold rule to `raw` (this frame's test).
struct MutualGaze {
  bool mutual = false;
  bool raw = false;
  double held_s = 0;           // how long `mutual` has been true (0 when false)
  double miss_distance_m = 0;  // 3-D mode: ray-to-robot-head distance; camera-plane mode: distance
                               // of the plane hit from the rectangle (0 inside)
  std::string mode;            // "3d" or "camera_plane"
  std::string target = "robot";
};

namespace keys {
// Absent when there are no eye centres or no head pose in this tick.
inline constexpr Key<EyeGaze> kEyeGaze{"face.eye_gaze"};
// Absent when there is no gaze in this tick (no face: F1 legacy [-1]).
inline constexpr Key<MutualGaze> kMutualGaze{"face.mutual_gaze"};
}  // namespace keys

}  // namespace dreamsense
