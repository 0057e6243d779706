#pragma once
// Faces per camera and the selected camera (modalities/face_detection): V1-V3, V6, V18.
// Blackboard types of one modality (perception layer: below the modalities, which never include
// each other's headers). docs/blackboard.md maps the keys onto DREAM's global buffer (V1-V29).

#include "dreamsense/core/blackboard.hpp"
#include "dreamsense/core/sensor_frame.hpp"

#include <map>
#include <optional>
#include <string>
#include <vector>

namespace dreamsense {

// Which detector found a face. A profile face is turned so far that the frontal detector missed
// it; kProfileNoseLeft / kProfileNoseRight say where the nose points in the image.
enum class FaceView { kFrontal, kProfileNoseLeft, kProfileNoseRight };

// One face found in one camera image.
struct DetectedFace {
  cv::Rect2d box_px;  // full-resolution pixels of that camera's image (x, y, width, height)
  float score = 0.f;  // detection score in [0, 1] (higher = more certain it is a face)
  FaceView view = FaceView::kFrontal;
  // [0, 1], 1 = facing the camera: the detector's proxy, or 1 - |yaw| / 90 from the last head
  // pose when one was available (face_detection README).
  float frontalness = 0.f;
};

// What the face detector saw in one camera frame. An empty `faces` means "looked, found nothing".
struct CameraFaces {
  Timestamp frame_stamp;  // stamp of the camera frame that was searched
  uint64_t frame_sequence = 0;
  cv::Size image_size;              // of that frame (the box coordinates refer to it)
  std::vector<DetectedFace> faces;  // best score first
  // Index in `faces` of the face that holds the projection of the last head pose (calibrated
  // cameras and a recent pose): the tracked child's face in this camera, whatever its score (a
  // therapist in view may score higher). nullopt when no pose is known or no face holds it.
  std::optional<size_t> head_face;
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
