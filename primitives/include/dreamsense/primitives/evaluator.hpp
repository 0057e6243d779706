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
  // Enables recognizeSpeech (F22) for the speech analyser's audio stream.
  void enable_speech(SensorId audio_sensor) { speech_sensor_ = std::move(audio_sensor); }

  std::vector<PrimitiveRecord> evaluate(const MultiFrame& tick, const BlackboardView& view);

 private:
  // ok / no_data / stale / sensor_offline of an observation from `sensors` (offline when none of
  // them delivered a frame for offline_after).
  template <typename T>
  PrimitiveStatus observation_status(const std::optional<Entry<T>>& entry,
                                     const std::vector<SensorId>& sensors, Timestamp tick) const;
  void evaluate_faces(const MultiFrame& tick, const BlackboardView& view,
                      std::vector<PrimitiveRecord>& out);
  void evaluate_speech(const MultiFrame& tick, const BlackboardView& view,
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
  SensorId speech_sensor_;
  std::map<SensorId, Timestamp> last_seen_;
  Timestamp first_tick_ = Timestamp::unset();
};

}  // namespace dreamsense::primitives
