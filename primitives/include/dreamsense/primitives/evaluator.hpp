#pragma once
// Evaluates all 25 primitives at each tick from a blackboard snapshot.
// Statuses: ok; no_data (the analyser looked and found nothing); stale (the newest observation is
// older than `freshness`); sensor_offline (the primitive's sensors delivered nothing for
// `offline_after`); disabled (no analyser for it is configured). Values are never invented.

#include "dreamsense/core/blackboard.hpp"
#include "dreamsense/core/camera_model.hpp"
#include "dreamsense/core/multi_frame.hpp"
#include "dreamsense/primitives/catalogue.hpp"
#include "dreamsense/primitives/face_primitives.hpp"

#include <array>
#include <map>
#include <set>
#include <string>
#include <vector>

namespace dreamsense::primitives {

struct EvaluatorOptions {
  Duration freshness = Duration::from_ms(100);  // older observations are stale
  Duration offline_after = Duration::from_seconds(1.0);
  // Default query of trackHand in batch analysis: the right hand's current position, predicted
  // this far ahead.
  double track_hand_dt_s = 0.2;
  // Default query of getSoundDirection: directions with a lower confidence are no_data. The
  // confidence is calibrated (modalities/sound_direction/README.md): >= 0.5 is within 10 deg
  // about 90 % of the time in eval doa's rooms, >= 0.7 (DREAM's consumer) about 98 %.
  double sound_direction_threshold = 0.5;
  FaceGeometryOptions face_geometry;
  // Default query of getHeadGaze (plane), F12: three points (world, m) spanning the plane; the
  // default is the world plane z = 0 (the front sensor's image plane, where the robot stands).
  std::array<cv::Vec3d, 3> head_gaze_plane{cv::Vec3d(0, 0, 0), cv::Vec3d(1, 0, 0),
                                           cv::Vec3d(0, 1, 0)};
  // Default query of trackFace (F23): predict the face this far ahead.
  double track_face_dt_s = 0.2;
  Status check() const;
};

class Evaluator {
 public:
  // `body_sensor`: the skeleton stream the body analyser uses (empty: body primitives disabled).
  // `audio_sensor`: the mic-array stream of the sound direction analyser (empty: disabled).
  Evaluator(EvaluatorOptions options, SensorId body_sensor, SensorId audio_sensor = {});

  // Enables the face primitives (getFaces today) for these cameras (their calibrations give the
  // 3-D positions).
  void enable_faces(std::map<SensorId, CameraModel> cameras);
  // Enables the eye primitives (F1 checkMutualGaze, F5 getEyeGaze, F6 getEyes); needs
  // enable_faces and the eye-centre and gaze analysers.
  void enable_gaze() { gaze_enabled_ = true; }
  // Enables recognizeSpeech (F22) for the speech analyser's audio stream.
  void enable_speech(SensorId audio_sensor) { speech_sensor_ = std::move(audio_sensor); }
  // Enables identifyVoice (F21) for the voice id analyser's audio stream.
  void enable_voice(SensorId audio_sensor) { voice_sensor_ = std::move(audio_sensor); }

  std::vector<PrimitiveRecord> evaluate(const MultiFrame& tick, const BlackboardView& view);

 private:
  // ok / no_data / stale / sensor_offline of an observation from `sensors` (offline when none of
  // them delivered a frame for offline_after).
  template <typename T>
  PrimitiveStatus observation_status(const std::optional<Entry<T>>& entry,
                                     const std::vector<SensorId>& sensors, Timestamp tick) const;
  void evaluate_faces(const MultiFrame& tick, const BlackboardView& view,
                      std::vector<PrimitiveRecord>& out);
  void evaluate_head(const MultiFrame& tick, const BlackboardView& view,
                     std::vector<PrimitiveRecord>& out);
  void evaluate_gaze(const MultiFrame& tick, const BlackboardView& view,
                     std::vector<PrimitiveRecord>& out);
  void evaluate_track_face(const MultiFrame& tick, const BlackboardView& view,
                           std::vector<PrimitiveRecord>& out);
  void evaluate_speech(const MultiFrame& tick, const BlackboardView& view,
                       std::vector<PrimitiveRecord>& out);
  void evaluate_voice(const MultiFrame& tick, const BlackboardView& view,
                      std::vector<PrimitiveRecord>& out);
  PrimitiveRecord base(PrimitiveId id, Timestamp stamp) const;
  void evaluate_body(const MultiFrame& tick, const BlackboardView& view,
                     std::vector<PrimitiveRecord>& out);
  void evaluate_sound_direction(const MultiFrame& tick, const BlackboardView& view,
                                std::vector<PrimitiveRecord>& out);
  EvaluatorOptions options_;
  SensorId body_sensor_;
  SensorId audio_sensor_;
  std::map<SensorId, CameraModel> face_cameras_;
  std::vector<SensorId> face_sensors_;  // the ids of face_cameras_ (their primitives' sensors)
  SensorId speech_sensor_;
  SensorId voice_sensor_;
  bool gaze_enabled_ = false;
  std::map<SensorId, Timestamp> last_seen_;
  Timestamp first_tick_ = Timestamp::unset();
};

}  // namespace dreamsense::primitives
