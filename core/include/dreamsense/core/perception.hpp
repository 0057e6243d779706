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

// DREAM's camera ids (SelectCameraID): 0 camera_middle, 1 camera_left, 2 camera_right, -1 any
// other stream.
inline int dream_camera_id(const SensorId& camera) {
  if (camera == "camera_middle") return 0;
  if (camera == "camera_left") return 1;
  if (camera == "camera_right") return 2;
  return -1;
}

namespace keys {
// Written every tick with a camera frame; absent entry when no camera has a face.
inline constexpr Key<FaceDetections> kFaceDetections{"face.detections"};
// Absent entry when no camera has a face.
inline constexpr Key<SelectedCamera> kSelectedCamera{"face.selected_camera"};
}  // namespace keys

// ---- Facial landmarks (modalities/face_landmarks) and head pose (modalities/head_pose) ----

// Number of landmarks in the iBUG 300-W / dlib-68 mark-up.
inline constexpr int kFaceLandmarkCount = 68;

// 68 facial landmarks of the selected face in the selected camera's image, iBUG 300-W order as
// seen in the image: 0-16 jaw contour (image left to right), 17-21 and 22-26 brows, 27-30 nose
// bridge (27 top, 30 tip), 31-35 nostrils, 36-41 the eye on the image left (the subject's RIGHT
// eye for a face looking at the camera), 42-47 the other eye, 48-59 outer lips, 60-67 inner lips.
struct FaceLandmarks {
  SensorId camera;        // the camera whose image was fitted (keys::kSelectedCamera)
  Timestamp frame_stamp;  // stamp of that camera frame
  uint64_t frame_sequence = 0;
  cv::Size image_size;                 // of that frame
  cv::Rect2d box_px;                   // face box the landmarker started from
  std::vector<cv::Point2d> points_px;  // kFaceLandmarkCount points, full-resolution pixels
  // Centroid of the six contour points of the subject's right (36-41) / left (42-47) eye.
  cv::Point2d right_eye_px() const { return centroid(36); }
  cv::Point2d left_eye_px() const { return centroid(42); }

 private:
  cv::Point2d centroid(size_t first) const {
    cv::Point2d c(0, 0);
    if (points_px.size() < first + 6) return c;
    for (size_t i = first; i < first + 6; ++i) c += points_px[i];
    return c * (1.0 / 6);
  }
};

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
};

namespace keys {
// Landmarks on the selected camera's face; absent entry when no face is selected or the
// landmarker rejected it. Nothing is written in ticks without a selection entry.
inline constexpr Key<FaceLandmarks> kFaceLandmarks{"face.landmarks"};
// Head pose from the landmarks (F10 getHead, F11/F12 getHeadGaze); absent when no landmarks or
// the fit was rejected.
inline constexpr Key<HeadPose> kHeadPose{"face.head_pose"};
}  // namespace keys

// ---- Eye centres (modalities/eye_centers) ----

// Centre of one eye's pupil/iris in the image, or found = false (eye closed, too small, ...).
struct EyeCenter {
  bool found = false;
  cv::Point2d center_px;  // full-resolution pixels of the camera image
  double confidence = 0;  // [0, 1]
};

// Pupil centres of the selected face, from the landmarks' eye regions in the same frame.
struct EyeCenters {
  SensorId camera;  // = FaceLandmarks::camera
  Timestamp frame_stamp;
  uint64_t frame_sequence = 0;
  EyeCenter right;     // the subject's right eye (landmarks 36-41)
  EyeCenter left;      // the subject's left eye (landmarks 42-47)
  std::string method;  // which locator produced them (e.g. "improved_integro_differential")
};

namespace keys {
// Absent entry when there are no landmarks in this tick.
inline constexpr Key<EyeCenters> kEyeCenters{"face.eye_centers"};
}  // namespace keys

// ---- Eye gaze, mutual gaze and face tracks (modalities/gaze) ----

// One gaze ray in world. Eye-in-head angles follow the head pose convention (HeadPose above):
// direction_head = rotation_from_ypr_deg(theta, phi, 0) * (0, 0, -1), so positive theta turns the
// gaze towards the subject's right (head -x) and positive phi looks down.
struct GazeRay {
  bool valid = false;
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

// A tracked face: stable id and a constant-velocity state in world.
struct FaceTrack {
  int id = 0;
  cv::Vec3d position_world_m{0, 0, 0};
  cv::Vec3d velocity_world_mps{0, 0, 0};
  Timestamp last_update;
  int hits = 0;  // observations absorbed
};
struct FaceTracks {
  std::vector<FaceTrack> tracks;  // confirmed tracks, most recently updated first
};

namespace keys {
// Absent when there are no eye centres or no head pose in this tick.
inline constexpr Key<EyeGaze> kEyeGaze{"face.eye_gaze"};
// Absent when there is no gaze in this tick (no face: F1 legacy [-1]).
inline constexpr Key<MutualGaze> kMutualGaze{"face.mutual_gaze"};
// Written every tick with face detections (empty list = no tracks).
inline constexpr Key<FaceTracks> kFaceTracks{"face.tracks"};
}  // namespace keys

}  // namespace dreamsense

// ---- Speech recognised against a grammar (modalities/speech, F22 recognizeSpeech) ----

namespace dreamsense {

// One utterance recognised against the session's grammar. Out-of-grammar speech, silence and
// noise produce no RecognizedSpeech at all (absence, not an error).
struct RecognizedSpeech {
  std::string text;       // recognised words, lower case, single spaces ("go forward ten meters")
  std::string tag;        // the grammar's output string (SRGS <tag>, as DREAM emitted); = text
                          // when the grammar has no tag for that alternative
  double confidence = 0;  // [0, 1]: grammar path against a free phone loop; 0.5 = a tie
  Timestamp start, end;   // first and last frame of the recognised words (session clock)
  SensorId sensor;        // the audio stream it came from
};

namespace keys {
// F22 recognizeSpeech: written once per recognised utterance (no entry while nothing is heard).
inline constexpr Key<RecognizedSpeech> kRecognizedSpeech{"audio.speech"};
}  // namespace keys

// ---- Who spoke (modalities/voice_id, F21 identifyVoice) ----

// The speaker of one utterance. speaker_id is "child", "therapist" or "unknown" in a therapy
// session (any enrolled name in general); method says how it was decided: "gmm_ubm" (speaker
// models) or "direction_rule" (DREAM's fallback from the sound direction, chosen explicitly).
struct SpeakerIdentity {
  std::string speaker_id;
  std::string name;      // display name from the enrolment (= speaker_id when none)
  double score = 0;      // [0, 1]: confidence in speaker_id
  Timestamp start, end;  // the utterance (session clock)
  SensorId sensor;       // the audio stream it came from
  std::string method;
};

namespace keys {
// Written once per utterance heard (no entry while nobody speaks).
inline constexpr Key<SpeakerIdentity> kSpeakerIdentity{"audio.speaker"};
}  // namespace keys

}  // namespace dreamsense
