#pragma once
// Self-calibration of a session (issue 15): the child's 3-D face model and anatomical eyeballs
// from the first seconds of the session itself, with no truth and no calibration recording.
// Every `tick_step`-th tick of the first `max_seconds` is searched for the face in every
// calibrated colour camera (OpenCV cascade on the full frame, dlib's 68 landmarks);
// head_pose::self_calibrate_face triangulates and aligns the ticks; gaze::anatomical_eyeball
// places the eyeballs behind the triangulated eye openings; with a fixation target (the robot's
// head), the frame's level is refined from the gaze's fixations on it (gaze_level.hpp). The
// result is written as a subject folder (face_model.yaml, gaze.yaml, self_calibration.json) that
// `analyze` uses like one from `train face` / `train gaze`. With fewer than two cameras seeing the
// face, or an inconsistent result, nothing is written but the status and its reason (the analysis
// then falls back to the generic face model and the built-in gaze constants, and says so).

#include "dreamsense/core/camera_model.hpp"
#include "dreamsense/core/sensor_frame.hpp"
#include "dreamsense/core/status.hpp"
#include "dreamsense/eye_centers/eye_center_locator.hpp"
#include "dreamsense/gaze/eyeball_model.hpp"
#include "dreamsense/head_pose/self_calibration.hpp"
#include "dreamsense/self_calibration/gaze_level.hpp"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace dreamsense::sources {
struct SessionManifest;
}

namespace dreamsense::self_calibration {

struct SessionSelfCalibrationOptions {
  // The ticks are spread over up to 20 s (every 6th tick at 25 Hz: 0.24 s apart) rather than
  // taken back to back: the same CPU, but the head frame's upright (the median roll over the
  // ticks, head_pose::UprightReference::kMeanWorldRoll) averages a longer stretch of head motion.
  double max_seconds = 20;  // of session time searched from the first frame
  int tick_step = 6;        // every n-th tick
  int enough_frames = 60;   // stop once this many ticks had the face in two or more cameras
  // true: each camera's face is looked for around where it was at the last searched tick (its
  // box grown by 0.75 x its size on every side, 0.6-1.6 x its size), the full frame when it is
  // not there. Half the CPU (10 demo seeds: 11.4 -> 5.1 s), but the gaze got worse (7.66 ->
  // 8.10 deg; the detection boxes move the landmark fits and the level by up to 7 deg), so
  // false (the full frame at every tick) stays the default (modalities/head_pose/README.md).
  bool guided_search = false;
  // true (and guided_search false): the full frame at every tick, shrunk as always, but only face
  // sizes 0.5-2 x the camera's face of the last searched tick; the full range when none is found
  // there. The cascade windows at the sizes kept are the full search's own, so the boxes are the
  // same unless the face's window cluster reached beyond that range (0.6-1.6 x: 1-8 boxes of
  // ~170 per session differed; 0.5-2 x: none on the seeds checked). The small sizes skipped are
  // most of the cascade's windows.
  bool size_guided_search = true;
  // When both upright searches find nothing and the camera's last face (kept through misses)
  // leaned by at least this (deg, from its landmarks' eye line), its region is searched rotated
  // upright by that roll (face_detection's detect_rolled). 0 = upright searches only.
  double rolled_search_min_deg = 10;
  // Colour streams used; empty = every calibrated colour stream with the role child_camera.
  std::vector<std::string> cameras;
  // face.fixation_target_world_m: when unset, the session's metadata robot_head_m (the robot's
  // head, which the child faces from time to time) if present; fixation_from_metadata = false
  // keeps it unset.
  head_pose::SelfCalibrationOptions face;
  bool fixation_from_metadata = true;
  gaze::AnatomicalEyeOptions eyes;
  // With a fixation target: the pupils located in every view (the eye-centre analyser's
  // default method, the iris sized at the triangulated eyes' depth) and the level refined from
  // the gaze's fixations on the target (gaze_level.hpp); gaze_level.enabled = false keeps the
  // head-fixation level.
  eye_centers::EyeCenterLocatorOptions pupils;
  GazeLevelOptions gaze_level;
  Status check() const;
};

struct SessionSelfCalibration {
  head_pose::SelfCalibration face;
  int cameras = 0;  // calibrated colour streams searched
  int ticks_searched = 0;
  int views_with_landmarks = 0;
  double seconds_searched = 0;  // of session time
  // Process CPU time of the self-calibration, without loading dlib's model (shared with the
  // analysis, see shared_dlib_landmarker).
  double cpu_s = 0;
  gaze::EyeballModel right_eyeball, left_eyeball;  // valid when face.converged()
  GazeLevel gaze_level;                            // applied: face.level "gaze_fixations"
  std::string session;
  nlohmann::json to_json() const;
};

// The self-calibration fed one tick at a time: self_calibrate_session feeds it the session's
// chosen ticks (every tick_step-th of the first max_seconds), a live analysis the ticks as they
// arrive (live.hpp). Each add() searches that tick's frames for the face (landmarks, pupils);
// finish() fits the face model, levels it and places the eyeballs. Not thread-safe.
class TickSelfCalibration {
 public:
  // `cameras`: the calibrated colour cameras to search (others' frames are ignored);
  // options.face.fixation_target_world_m as resolved by the caller (with_fixation_target).
  static Result<std::unique_ptr<TickSelfCalibration>> create(
      std::map<SensorId, CameraModel> cameras, const SessionSelfCalibrationOptions& options);
  ~TickSelfCalibration();
  TickSelfCalibration(const TickSelfCalibration&) = delete;
  TickSelfCalibration& operator=(const TickSelfCalibration&) = delete;

  // One tick's frames (stamped within a few ms of `stamp_ns`). Errors: the landmarker's.
  Status add(int64_t stamp_ns, const std::vector<FramePtr>& frames);
  // options.enough_frames ticks had the face in two or more cameras.
  bool enough() const;
  int ticks_searched() const;
  // The result from the ticks added so far (cpu_s and seconds_searched are the caller's).
  SessionSelfCalibration finish(const std::string& session) const;

 private:
  struct State;
  explicit TickSelfCalibration(std::unique_ptr<State> state);
  std::unique_ptr<State> state_;
};

// `options` with face.fixation_target_world_m set from the session's metadata robot_head_m when
// unset and options.fixation_from_metadata; an unreadable value is an error naming `where`.
Result<SessionSelfCalibrationOptions> with_fixation_target(
    const SessionSelfCalibrationOptions& options,
    const std::map<std::string, std::string>& metadata, const std::string& where);

// The cameras a self-calibration searches: options.cameras, or every calibrated colour stream
// with the role child_camera. Camera files are relative to `session_dir` (or absolute).
Result<std::map<SensorId, CameraModel>> self_calibration_cameras(
    const std::filesystem::path& session_dir, const sources::SessionManifest& manifest,
    const SessionSelfCalibrationOptions& options);

// Errors: an unreadable session or one without calibrated colour streams; everything else
// (one camera, the face never seen twice, disagreeing cameras) is a non-converged status.
Result<SessionSelfCalibration> self_calibrate_session(
    const std::filesystem::path& session_dir, const SessionSelfCalibrationOptions& options = {});

// Writes self_calibration.json into `dir` (created), and when converged face_model.yaml and
// gaze.yaml (eyeball method, head_plane) as a subject folder.
Status write_self_calibration(const SessionSelfCalibration& c, const std::filesystem::path& dir);

}  // namespace dreamsense::self_calibration
