#pragma once
// The demo scene as pure functions of (seed, time): head pose, actions, skeleton, table objects.
// Nothing here renders; demo_session.cpp turns this script into images, audio and truth.
// The layout is documented in docs/demo_session.md. World = front RGB-D sensor optical frame
// (x right, y down, z forward, metres).

#include "dreamsense/core/camera_model.hpp"
#include "dreamsense/core/sensor_frame.hpp"
#include "dreamsense/core/status.hpp"

#include <opencv2/core.hpp>

#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace dreamsense::sim {

// 64-bit mix of a seed and a tag (splitmix64 finaliser): independent streams per component.
uint64_t sub_seed(uint64_t seed, std::string_view tag, uint64_t index = 0);

struct DemoGeometry {
  cv::Vec3d robot_head_m{0.0, -0.05, 0.15};
  double gaze_radius_m = 0.20;
  cv::Vec3d head_rest_m{0.0, -0.05, 1.10};  // child's eye midpoint, mean position
  // The therapist's head (a gaze target, not rendered): x = side * therapist_head_m[0] with a
  // seed-dependent side (DemoScript::therapist_side(), also the side the therapist speaks from).
  cv::Vec3d therapist_head_m{0.80, -0.30, 0.55};
  // Table: top plane y = table_top_y_m, rectangle x in [x_min, x_max], z in [z_min, z_max].
  double table_top_y_m = 0.30;
  double table_x_min_m = -0.55, table_x_max_m = 0.55;
  double table_z_min_m = 0.30, table_z_max_m = 0.95;
  // Room (shoebox, also used by the acoustics): world x in [-2.5, 2.5], y (down) in
  // [-2.0, 1.0] (floor at y = 1.0), z in [-1.5, 2.5] (back wall behind the child at 2.5 m).
  cv::Vec3d room_min_m{-2.5, -2.0, -1.5};
  cv::Vec3d room_max_m{2.5, 1.0, 2.5};
  // Kinect v1 microphone array: mics on the array's x axis; array frame axes = world axes.
  cv::Vec3d mic_array_m{0.0, 0.05, 0.0};
  std::array<double, 4> mic_x_m{0.113, -0.036, -0.076, -0.113};
  cv::Vec3d room_from_world(const cv::Vec3d& world) const { return world - room_min_m; }
  cv::Vec3d room_size_m() const { return room_max_m - room_min_m; }
};

// kCoverEyes, kDriveCar, kDrink and kCustom appear only when DemoScriptOptions asks for them
// (the default demo keeps the original three).
enum class DemoAction {
  kNone,
  kWave,
  kFly,
  kHandsOnHead,
  kCoverEyes,
  kDriveCar,
  kDrink,
  kCustom,
};
// "none", "wave", "fly", "hands_on_head", "cover_eyes", "drive_car", "drink", "custom"
std::string_view action_label(DemoAction action);
// identifyTrajectory index (primitives.md F20): 0, 1, 4, 3, 2, 5, 6; kCustom: 7 (the script's
// segment_dream_id adds the custom gesture's index).
int action_dream_id(DemoAction action);

struct ActionSegment {
  double start_s = 0, end_s = 0;
  DemoAction action = DemoAction::kNone;
  int custom = -1;  // kCustom: index into DemoScriptOptions::custom
};

// A scripted gesture for tests and new gestures: each wrist follows a closed loop of key points
// relative to its shoulder (world axes: +x = the child's left, -y = up, -z = forward, towards
// the robot), one loop per period_s, through a Catmull-Rom spline; the hand extends along the
// forearm. An empty loop leaves that arm resting on the table.
struct CustomGesture {
  std::string label;
  std::vector<cv::Vec3d> right_wrist, left_wrist;
  double period_s = 1.5;
};

// Which gestures the demo child performs. The defaults reproduce the original demo exactly.
struct DemoScriptOptions {
  enum class GestureSet {
    kClassic,  // wave, fly, hands_on_head (the original demo, byte-identical output)
    kDream,    // all six DREAM gestures: also cover_eyes, drive_car, drink
    // DREAM's gestures that leave the face in view: wave, fly, hands_on_head, drive_car (the
    // default demo, issue 13: cover_eyes and drink put the hands over the face, which the face
    // analysers cannot see through; modalities/actions/README.md "Demo")
    kDreamFaceVisible,
  };
  GestureSet gestures = GestureSet::kClassic;
  std::vector<CustomGesture> custom;
  // Non-empty: replaces the random schedule (segments in time order, tiling [0, duration));
  // kCustom segments name their gesture by ActionSegment::custom.
  std::vector<ActionSegment> schedule;
  Status check() const;
};

// Rests (none, 0.8-1.6 s) alternating with actions (2-3.5 s): the first actions are a
// seed-dependent permutation of the set's gestures (classic: wave / fly / hands_on_head, so 20 s
// always contains all three; DREAM: all six, which needs about 25 s; DREAM face visible: the
// four), later ones are drawn at random. Segments tile [0, duration_s).
std::vector<ActionSegment> make_action_schedule(
    uint64_t seed, double duration_s,
    DemoScriptOptions::GestureSet set = DemoScriptOptions::GestureSet::kClassic);

// What the child looks at. Fixations tile the session; the eyes jump to each new target at once
// (a saccade is shorter than a frame), the head follows over head_turn_s (after a short lag) and
// turns only part of the way (head_yaw_share / head_pitch_share of the target's direction); the
// eyes rotate in the head for the rest, within kMaxEyeYawDeg / kMaxEyePitchDeg.
enum class GazeTargetKind { kRobot, kObject, kTherapist, kTable, kElsewhere };
std::string_view gaze_target_label(
    GazeTargetKind kind);  // robot, object, therapist, table, elsewhere

struct Fixation {
  double start_s = 0, end_s = 0;
  GazeTargetKind kind = GazeTargetKind::kRobot;
  int object = -1;             // table object id (kObject: its moving top centre is tracked)
  cv::Vec3d point_m{0, 0, 0};  // world target for kRobot, kTherapist, kTable, kElsewhere
  double head_yaw_share = 0.6, head_pitch_share = 0.5;
  double head_turn_s = 0.5;
};

struct GazeState {
  GazeTargetKind kind = GazeTargetKind::kRobot;
  int object = -1;
  cv::Vec3d intended_m{0, 0, 0};  // the target's point
  // The point both eyes fixate: intended_m plus fixational jitter (a few mm), pulled inside the
  // eye-in-head range if the head has not turned far enough yet.
  cv::Vec3d target_m{0, 0, 0};
  double eye_yaw_deg = 0, eye_pitch_deg = 0;  // eye-in-head rotation seen from the head origin
  double eyelid_closure = 0;                  // 0 open .. 1 closed (blinks)
};

struct HeadPose {
  cv::Vec3d position_m{0, 0, 1};  // eye midpoint (world)
  double yaw_deg = 0, pitch_deg = 0, roll_deg = 0;
  cv::Matx33d rotation() const;  // world_from_head = rotation_from_ypr_deg(yaw, pitch, roll)
  cv::Vec3d gaze_dir() const;    // rotation() * (0, 0, -1)
};
// Yaw/pitch (degrees) that point the head gaze from `from` towards `to`.
void look_at_angles(const cv::Vec3d& from, const cv::Vec3d& to, double& yaw_deg, double& pitch_deg);
// Distance from `point` to the ray origin + s * dir (s >= 0).
double ray_point_distance(const cv::Vec3d& origin, const cv::Vec3d& dir, const cv::Vec3d& point);

struct TableObjectSpec {
  int id = 0;
  int label = 0;           // DREAM: 0 car, 1 cup, 2 flower, 3 plane
  std::string label_name;  // "car", "cup", "flower", "plane"
  double width_m = 0.10;   // along the object's x
  double depth_m = 0.075;  // along the object's z
  double height_m = 0.03;
};

struct TableObjectState {
  int id = 0;
  cv::Vec3d position_m{0, 0, 0};  // centre of the top face (world)
  double yaw_deg = 0;             // rotation about the (vertical) world y axis
  std::array<cv::Vec3d, 8>
      corners{};  // 0-3 top face (u,v order: 0 -> +u -> +u+v -> +v), 4-7 bottom
};

class DemoScript {
 public:
  DemoScript(uint64_t seed, double duration_s, DemoGeometry geometry = {},
             DemoScriptOptions options = {});

  const DemoGeometry& geometry() const { return geometry_; }
  uint64_t seed() const { return seed_; }
  double duration_s() const { return duration_s_; }

  static constexpr double kMaxEyeYawDeg = 25, kMaxEyePitchDeg = 18;  // eye-in-head range

  HeadPose head_pose(double t) const;
  GazeState gaze(double t) const;
  const std::vector<Fixation>& fixations() const { return fixations_; }
  const Fixation& fixation_at(double t) const;
  cv::Vec3d fixation_point(const Fixation& f, double t) const;  // world, at time t
  double eyelid_closure(double t) const;
  const std::vector<double>& blink_starts() const { return blinks_; }
  double therapist_side() const { return therapist_side_; }  // +1 world +x, -1 world -x
  cv::Vec3d therapist_head_m() const;

  const std::vector<ActionSegment>& actions() const { return actions_; }
  DemoAction action_at(double t) const;
  const ActionSegment& segment_at(double t) const;
  // Truth label and F20 id of a segment (custom gestures: their label, 7 + index).
  std::string segment_label(const ActionSegment& s) const;
  int segment_dream_id(const ActionSegment& s) const;
  const DemoScriptOptions& script_options() const { return options_; }
  // All 20 Kinect joints (world, noise-free), consistent with head_pose(t).
  std::array<cv::Vec3d, kJointCount> joints(double t) const;

  const std::vector<TableObjectSpec>& objects() const { return objects_; }
  std::vector<TableObjectState> object_states(double t) const;

 private:
  struct Sinusoid {
    double amplitude, freq_hz, phase;
  };
  static double eval(const std::vector<Sinusoid>& s, double t);
  void make_fixations();
  void make_blinks();
  std::array<cv::Vec3d, 6> arm_pose(const ActionSegment& segment, double t,
                                    const cv::Vec3d& head_centre, const cv::Vec3d& shoulder_l,
                                    const cv::Vec3d& shoulder_r) const;
  // The DREAM-set and custom gestures (not in the original demo).
  std::array<cv::Vec3d, 6> extra_arm_pose(const ActionSegment& segment, double t,
                                          const cv::Vec3d& shoulder_l,
                                          const cv::Vec3d& shoulder_r) const;

  uint64_t seed_;
  double duration_s_;
  DemoGeometry geometry_;
  std::vector<Sinusoid> yaw_, pitch_, roll_, pos_x_, pos_y_, pos_z_;
  std::vector<Fixation> fixations_;
  std::vector<double> blinks_;  // blink start times
  double therapist_side_ = 1;
  std::vector<ActionSegment> actions_;
  double wave_hz_ = 1.8, fly_hz_ = 0.8;
  DemoScriptOptions options_;
  // DREAM-set gestures (drawn from their own seed stream, so the classic ones are unchanged).
  double drive_hz_ = 0.45, drive_amp_rad_ = 0.45, drink_hz_ = 0.4, cover_hz_ = 0.6;
  std::vector<TableObjectSpec> objects_;
  struct ObjectPath {
    double x_centre, z_centre;
    Sinusoid x, z, yaw;
  };
  std::vector<ObjectPath> paths_;
};

}  // namespace dreamsense::sim
