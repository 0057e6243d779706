#pragma once
// Head pose of the selected face (modalities/head_pose): V5, V11.
// Blackboard types of one modality (perception layer: below the modalities, which never include
// each other's headers). docs/blackboard.md maps the keys onto DREAM's global buffer (V1-V29).

#include "dreamsense/core/blackboard.hpp"
#include "dreamsense/core/sensor_frame.hpp"

#include <map>
#include <optional>
#include <string>
#include <vector>

namespace dreamsense {

// Head pose of the selected face. Head frame (the demo renderer's, docs/demo_session.md): origin
// between the eyes, at head pose (0, 0, 0) its axes are the world axes: x towards the subject's
// LEFT, y down, z towards the back of the head; the face looks along head -z.
// world_from_head = rotation_from_ypr_deg(yaw, pitch, roll) = Ry(yaw) * Rx(pitch) * Rz(roll):
// (0, 0, 0) looks at the front sensor (world -z); positive yaw turns the gaze towards world -x,
// positive pitch looks down; roll about the face's forward axis.
struct HeadPose {
  SensorId camera;  // the camera whose landmarks were used
  Timestamp frame_stamp;
  cv::Matx33d camera_from_head = cv::Matx33d::eye();
  cv::Vec3d position_camera_m{0, 0, 1};  // head-frame origin in that camera's frame
  cv::Matx33d world_from_head = cv::Matx33d::eye();
  cv::Vec3d position_world_m{0, 0, 1};              // head-frame origin (between the eyes) in world
  double yaw_deg = 0, pitch_deg = 0, roll_deg = 0;  // of world_from_head (convention above)
  // Head-gaze ray in world: origin between the eyes, direction = world_from_head * (0, 0, -1).
  cv::Vec3d gaze_origin_world_m{0, 0, 1};
  cv::Vec3d gaze_direction_world{0, 0, -1};
  double reprojection_rms_px = 0;  // of the raw (unsmoothed) fit
  int points_used = 0;             // landmarks used by the fit
  bool smoothed = false;           // true when a temporal filter changed the raw fit
  // The selected camera's own single-view fit (smoothed likewise), for measurements made in
  // that image: gaze's eye-in-head angles need the pose that explains this image's landmarks,
  // while the multi-view pose above explains every camera at once (measured: gaze 1-2 degrees
  // worse with it, modalities/head_pose/README.md). Unset: the pose itself (one view).
  struct ImagePose {
    cv::Matx33d camera_from_head = cv::Matx33d::eye();
    cv::Vec3d position_camera_m{0, 0, 1};
    cv::Matx33d world_from_head = cv::Matx33d::eye();
    cv::Vec3d position_world_m{0, 0, 1};
  };
  std::optional<ImagePose> image;
  int views_used = 1;  // cameras whose landmarks the pose explains
  // D4.2's camera selection made with this tick's pose: of the cameras with a landmark fit this
  // tick, the one towards which the head's yaw is smallest (CameraModel::yaw_towards_deg of the
  // head-gaze direction). The face chain's own camera (`camera`) was chosen by face detection
  // before this pose existed, from the previous tick's; during a head turn the two differ.
  // Empty when the pose has no camera models to compare.
  SensorId frontal_camera;
  // This pose with the image pose's rotation and positions in place of the multi-view ones
  // (yaw/pitch/roll and the head-gaze ray stay the multi-view pose's).
  HeadPose as_image_pose() const {
    HeadPose p = *this;
    if (!image) return p;
    p.camera_from_head = image->camera_from_head;
    p.position_camera_m = image->position_camera_m;
    p.world_from_head = image->world_from_head;
    p.position_world_m = image->position_world_m;
    p.image.reset();
    return p;
  }
};

namespace keys {
// Head pose from the landmarks (F10 getHead, F11/F12 getHeadGaze); absent when no landmarks or
// the fit was rejected.
inline constexpr Key<HeadPose> kHeadPose{"face.head_pose"};
}  // namespace keys

}  // namespace dreamsense
