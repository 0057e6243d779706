#pragma once
// Core perception types that analysers exchange through the blackboard, and their keys.
// Analysers never include each other's headers: they agree on these types only.
// docs/blackboard.md maps the keys onto DREAM's global buffer (D4.2 V1-V29).

#include "dreamsense/core/blackboard.hpp"
#include "dreamsense/core/sensor_frame.hpp"

#include <map>
#include <optional>
#include <string>
#include <vector>

namespace dreamsense {

// The tracked child's skeleton in world (metres), chosen among the bodies a tracker reports.
struct BodyState {
  SkeletonBody body;       // joints in world
  SensorId sensor;         // the skeleton stream it came from
  int bodies_in_view = 0;  // how many bodies the tracker reported
};

// Direction of the dominant sound source (speech) seen from a microphone array.
// Array frame: azimuth 0 = broadside (+z), positive towards the array's +x; elevation positive
// upwards. A linear array (Kinect v1) cannot measure elevation (nullopt) and cannot tell front
// from back: its azimuth is in [-90, 90] and its direction assumes elevation 0.
struct SoundDirection {
  double azimuth_deg = 0;
  std::optional<double> elevation_deg;
  cv::Vec3d direction_array{0, 0, 1};  // unit vector, array frame
  cv::Vec3d direction_world{0, 0, 1};  // unit vector, world (through the array's extrinsics)
  double srp_power = 0;                // SRP-PHAT at the peak (mean pair coherence, <= 1)
  SensorId sensor;                     // the audio stream it came from
};

namespace keys {
// V17: sound direction (null entry: the analyser ran and heard no voice).
inline constexpr Key<SoundDirection> kSoundDirection{"audio.sound_direction"};
// V20/V29: skeleton joints of the child and their history (history via the blackboard).
inline constexpr Key<BodyState> kChildBody{"body.child"};
}  // namespace keys

// ---- Faces per camera and the selected camera (modalities/face_detection) ----

// Which detector found a face. A profile face is turned so far that the frontal detector missed
// it; kProfileNoseLeft / kProfileNoseRight say where the nose points in the image.
enum class FaceView { kFrontal, kProfileNoseLeft, kProfileNoseRight };

// One face found in one camera image.
struct DetectedFace {
  cv::Rect2d box_px;  // full-resolution pixels of that camera's image (x, y, width, height)
  float score = 0.f;  // detection score in [0, 1] (higher = more certain it is a face)
  FaceView view = FaceView::kFrontal;
  float frontalness = 0.f;  // [0, 1], 1 = facing the camera (a proxy, not a head pose)
};

// What the face detector saw in one camera frame. An empty `faces` means "looked, found nothing".
struct CameraFaces {
  Timestamp frame_stamp;  // stamp of the camera frame that was searched
  uint64_t frame_sequence = 0;
  cv::Size image_size;              // of that frame (the box coordinates refer to it)
  std::vector<DetectedFace> faces;  // best score first
};

// Faces in every camera that had a frame in this tick (cameras without a frame in this
// tick are not listed: not observed, not "no face").
struct FaceDetections {
  std::map<SensorId, CameraFaces> cameras;
  size_t face_count() const {
    size_t n = 0;
    for (const auto& [id, c] : cameras) n += c.faces.size();
    return n;
  }
};

// The camera whose face is best for face analysis (D4.2: highest score, most frontal), with the
// face chosen in it. DREAM's SelectCameraID: 0 camera_middle, 1 camera_left, 2 camera_right.
struct SelectedCamera {
  SensorId camera;
  size_t face_index = 0;  // index into FaceDetections::cameras[camera].faces
  DetectedFace face;      // copy of that face
  float quality = 0.f;    // the selection criterion of that face, [0, 1]
};

namespace keys {
// Written every tick with a camera frame; absent entry when no camera has a face.
inline constexpr Key<FaceDetections> kFaceDetections{"face.detections"};
// Absent entry when no camera has a face.
inline constexpr Key<SelectedCamera> kSelectedCamera{"face.selected_camera"};
}  // namespace keys

}  // namespace dreamsense
