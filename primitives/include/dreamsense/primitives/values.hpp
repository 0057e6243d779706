#pragma once
// Typed values and queries of the 25 primitives (../shared/spec/primitives.md). A primitive's
// answer stays typed until the edge: JSON (export/primitive_json), CSV (export/), DDS (publish/)
// and DREAM's legacy vectors (dream/) are produced from these types by one adapter each.
// Units: metres, degrees, seconds; positions and directions in the session's world frame.

#include "dreamsense/core/sensor_frame.hpp"

#include <opencv2/core.hpp>

#include <array>
#include <map>
#include <optional>
#include <string>
#include <variant>
#include <vector>

namespace dreamsense::primitives {

// F1 checkMutualGaze.
struct MutualGazeValue {
  bool mutual = false;  // after the hold rule
  bool raw = false;     // this frame's test
  double held_s = 0;
  double miss_distance_m = 0;
  std::string mode;  // "3d" | "camera_plane"
  std::string target = "robot";
};

// F2 getArmAngle: the upper arm relative to the torso frame, per arm (absent: not tracked).
struct ArmAngle {
  double azimuth_deg = 0, elevation_deg = 0;
};
struct ArmAnglesValue {
  std::optional<ArmAngle> left, right;
};

// F3 getBody.
struct BodyValue {
  cv::Vec3d position_m{0, 0, 0};
  int bodies_in_view = 0;
};

// F4 getBodyPose: the ten DREAM joints in legacy order (untracked joints have confidence 0).
struct JointPosition {
  JointId joint = JointId::kShoulderCenter;
  cv::Vec3d position_m{0, 0, 0};
  float confidence = 0.f;
};
struct BodyPoseValue {
  std::vector<JointPosition> joints;
};

// F5 getEyeGaze: the fused ray of both eyes, and each eye's own ray when valid.
struct EyeRay {
  cv::Vec3d origin_m{0, 0, 0};
  cv::Vec3d direction{0, 0, -1};
  double theta_deg = 0, phi_deg = 0;  // eye-in-head angles
  cv::Vec2d offset{0, 0};             // the normalised pupil offset the angles came from
};
struct EyeGazeValue {
  EyeRay both;
  std::optional<EyeRay> right, left;
  SensorId camera;
  std::string method;
  double fixation_yaw_deg = 0;  // the eyes' yaw bias learnt from fixations on the robot, applied
};

// F6 getEyes: pixel centres in the selected camera; 3-D positions when a gaze exists.
struct EyesValue {
  SensorId camera;
  std::optional<cv::Point2d> right_px, left_px;
  std::optional<cv::Vec3d> right_m, left_m;
  bool right_valid = false, left_valid = false;  // the 3-D eye rays were valid
  std::string method;
};

// F7 getFaces: faces across cameras (best first), what each camera saw, the selected camera.
struct FaceInWorld {
  cv::Vec3d position_m{0, 0, 0};
  float score = 0.f;
  SensorId camera;                       // camera of the best view
  std::map<SensorId, cv::Rect2d> boxes;  // one box per camera that sees it
};
struct CameraFace {
  cv::Rect2d box_px;
  float score = 0.f;
  float frontalness = 0.f;
};
struct FacesValue {
  std::vector<FaceInWorld> faces;
  std::map<SensorId, std::vector<CameraFace>> cameras;
  std::optional<SensorId> selected_camera;
};

// F8 getGripLocation (the rule: modalities/objects/README.md).
struct GripLocationValue {
  cv::Vec3d position_m{0, 0, 0};
  cv::Vec3d approach_direction{0, -1, 0};  // unit, world: the direction the gripper moves in
  double width_m = 0;                      // opening the grip needs
  int object_id = -1;
  cv::Vec3d closing_axis{1, 0, 0};  // unit, world: the fingers close along it
  int track_id = -1;
};

// F9 getHands.
struct HandsValue {
  std::optional<cv::Vec3d> left, right;
};

// F10 getHead.
struct HeadValue {
  cv::Vec3d position_m{0, 0, 0};
  SensorId camera;
};

// F11 getHeadGaze.
struct HeadGazeValue {
  cv::Vec3d origin_m{0, 0, 0};
  cv::Vec3d direction{0, 0, -1};
  double roll_deg = 0, yaw_deg = 0, pitch_deg = 0;
  SensorId camera;
};

// F12 getHeadGaze (plane).
struct HeadGazePlaneValue {
  cv::Vec3d point_m{0, 0, 0};
  double distance_m = 0;  // along the head ray
  SensorId camera;
};

// F13/F14 getObjects, F19 identifyObject: toys on the table (DREAM ids 0 car, 1 cup, 2 flower,
// 3 plane; enrolled toys get further ids; -1 = unknown).
struct ObjectValue {
  int id = -1;
  std::string label;
  cv::Vec3d position_m{0, 0, 0};  // top face centre
  double score = 0;               // identification agreement of the track
  int track_id = -1;
  cv::Rect2d box_px;     // in the table camera's image (the record's source)
  bool detected = true;  // false: carried by the visual tracker (e.g. under a hand)
};
struct ObjectsValue {
  std::vector<ObjectValue> objects;  // getObjects: by track id; circle: nearest first
};
struct ObjectIdentityValue {
  int id = -1;
  std::string label;
  double score = 0;
  int track_id = -1;
};

// F15 getObjectTableDistance.
struct ObjectTableDistanceValue {
  double distance_m = 0;  // of the object's position (top face centre) above the table plane
  int object_id = -1;
  double lift_m = 0;      // of its bottom (0: resting on the table)
  bool measured = false;  // false: the position assumed the toy rests on the table (no depth)
  int track_id = -1;
};

// F16 getSoundDirection.
struct SoundDirectionValue {
  double azimuth_deg = 0;
  std::optional<double> elevation_deg;
  double confidence = 0;
  cv::Vec3d direction{0, 0, 1};  // unit, world
};

// F17 identifyFace.
struct FaceIdentityValue {
  int id = -1;  // -1 = unknown
  std::string name;
  double score = 0;
};

// F18 identifyFaceExpression, F20 identifyTrajectory: a label among classes, with scores.
struct ClassLabelValue {
  std::string label;
  int id = -1;  // the DREAM id of the label (-1: none in DREAM's list)
  std::map<std::string, double> scores;
};

// F21 identifyVoice.
struct VoiceValue {
  std::string speaker_id;
  std::string name;
  double score = 0;
  int64_t start_ns = 0, end_ns = 0;
  std::string method;
};

// F22 recognizeSpeech.
struct SpeechValue {
  std::string text;
  std::string tag;
  double confidence = 0;
  int64_t start_ns = 0, end_ns = 0;
};

// F23 trackFace, F24 trackHand, F25 trackObject: a predicted position.
struct TrackValue {
  cv::Vec3d position_m{0, 0, 0};
  cv::Vec3d velocity_mps{0, 0, 0};
  int track_id = -1;  // face/object track (-1 for hands)
  std::string hand;   // trackHand: "left" | "right"
  int samples = 0;    // trackHand: history samples of the fit
};

using PrimitiveValue =
    std::variant<std::monostate, MutualGazeValue, ArmAnglesValue, BodyValue, BodyPoseValue,
                 EyeGazeValue, EyesValue, FacesValue, GripLocationValue, HandsValue, HeadValue,
                 HeadGazeValue, HeadGazePlaneValue, ObjectsValue, ObjectIdentityValue,
                 ObjectTableDistanceValue, SoundDirectionValue, FaceIdentityValue, ClassLabelValue,
                 VoiceValue, SpeechValue, TrackValue>;

// ---- Queries of the parametrised primitives ----

// F5 getEyeGaze(eye).
struct EyeQuery {
  std::string eye = "both";  // "both" | "left" | "right"
};
// F12 getHeadGaze(p1, p2, p3): the plane through three points (world, m).
struct PlaneQuery {
  std::array<cv::Vec3d, 3> points{cv::Vec3d(0, 0, 0), cv::Vec3d(1, 0, 0), cv::Vec3d(0, 1, 0)};
};
// F14 getObjects(centre, radius): objects whose table position lies within the circle.
struct CircleQuery {
  cv::Vec3d centre_m{0, 0.3, 0.6};
  double radius_m = 0.15;
};
// F8, F15, F19: the object nearest to this position; F17, F18: the face nearest to it (nullopt:
// the selected face / the object the evaluator answers for by default).
struct PositionQuery {
  std::optional<cv::Vec3d> position_m;
};
// F16 getSoundDirection(threshold).
struct ThresholdQuery {
  double threshold = 0.5;
};
// F20 identifyTrajectory(window).
struct WindowQuery {
  double window_s = 0;  // 0: the classifier's own window
};
// F23-F25 track*(seed, dt): the track nearest to the seed, predicted dt ahead.
struct TrackQuery {
  cv::Vec3d seed_m{0, 0, 0};
  double dt_s = 0.2;
};

using PrimitiveQuery = std::variant<std::monostate, EyeQuery, PlaneQuery, CircleQuery,
                                    PositionQuery, ThresholdQuery, WindowQuery, TrackQuery>;

}  // namespace dreamsense::primitives
